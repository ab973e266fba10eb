//! Named counters (photons per second, cache hits, milliseconds per stage), kept next to
//! the code they count and prefixed by technique: `photon_stream.photons_per_s`.

use crate::report::{Cell, Table};

/// An insertion-ordered map from counter name to value.
///
/// ```
/// use illume_metrics::Counters;
/// let mut c = Counters::for_technique("photon_stream");
/// c.set("photons_per_s", 2.5e6);
/// c.add("frames", 1.0);
/// c.add("frames", 1.0);
/// assert_eq!(c.get("photon_stream.frames"), Some(2.0));
/// assert_eq!(c.csv_header(), "photon_stream.photons_per_s,photon_stream.frames");
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Counters {
    prefix: String,
    entries: Vec<(String, f64)>,
}

impl Counters {
    /// Counters without a prefix: names are stored as given.
    pub fn new() -> Self {
        Self::default()
    }

    /// Counters whose names are stored as `technique.name`.
    pub fn for_technique(technique: &str) -> Self {
        Self {
            prefix: format!("{technique}."),
            entries: Vec::new(),
        }
    }

    fn full_name(&self, name: &str) -> String {
        format!("{}{name}", self.prefix)
    }

    /// Sets `name` (prefixed) to `value`, keeping its position if it exists.
    pub fn set(&mut self, name: &str, value: f64) {
        let full = self.full_name(name);
        match self.entries.iter_mut().find(|(n, _)| *n == full) {
            Some(entry) => entry.1 = value,
            None => self.entries.push((full, value)),
        }
    }

    /// Adds `value` to `name` (prefixed), starting from zero.
    pub fn add(&mut self, name: &str, value: f64) {
        let full = self.full_name(name);
        match self.entries.iter_mut().find(|(n, _)| *n == full) {
            Some(entry) => entry.1 += value,
            None => self.entries.push((full, value)),
        }
    }

    /// The value of a counter by its full (prefixed) name.
    pub fn get(&self, full_name: &str) -> Option<f64> {
        self.entries
            .iter()
            .find(|(n, _)| n == full_name)
            .map(|&(_, v)| v)
    }

    /// `(full name, value)` in insertion order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, f64)> {
        self.entries.iter().map(|(n, v)| (n.as_str(), *v))
    }

    /// Number of counters.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when there are no counters.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Copies every counter of `other` (full names) into `self`, overwriting equal names.
    pub fn merge(&mut self, other: &Counters) {
        for (name, value) in other.iter() {
            match self.entries.iter_mut().find(|(n, _)| n == name) {
                Some(entry) => entry.1 = value,
                None => self.entries.push((name.to_owned(), value)),
            }
        }
    }

    /// The CSV header line of these counters (names, comma-separated, quoted if needed).
    pub fn csv_header(&self) -> String {
        let columns: Vec<String> = self.entries.iter().map(|(n, _)| n.clone()).collect();
        crate::report::csv_line(&columns)
    }

    /// The CSV data line of these counters, in header order.
    pub fn csv_row(&self) -> String {
        let cells: Vec<String> = self
            .entries
            .iter()
            .map(|&(_, v)| Cell::Number(v).to_string())
            .collect();
        crate::report::csv_line(&cells)
    }

    /// A table with one row per element of `rows` (e.g. per frame), led by a `label` column;
    /// the columns are the union of all counter names in first-seen order, and a counter
    /// missing from a row is an empty cell.
    pub fn to_table(label: &str, rows: &[(String, Counters)]) -> Table {
        let mut names: Vec<String> = Vec::new();
        for (_, c) in rows {
            for (n, _) in c.iter() {
                if !names.iter().any(|m| m == n) {
                    names.push(n.to_owned());
                }
            }
        }
        let mut columns = vec![label.to_owned()];
        columns.extend(names.iter().cloned());
        let rows = rows
            .iter()
            .map(|(l, c)| {
                std::iter::once(Cell::Text(l.clone()))
                    .chain(
                        names
                            .iter()
                            .map(|n| c.get(n).map_or(Cell::Empty, Cell::Number)),
                    )
                    .collect()
            })
            .collect();
        Table { columns, rows }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_add_and_order() {
        let mut c = Counters::for_technique("selective");
        c.set("b", 1.0);
        c.set("a", 2.0);
        c.set("b", 3.0);
        c.add("a", 0.5);
        let v: Vec<_> = c.iter().collect();
        assert_eq!(v, vec![("selective.b", 3.0), ("selective.a", 2.5)]);
        assert_eq!(c.csv_row(), "3,2.5");
    }

    #[test]
    fn table_takes_the_union_of_names() {
        let mut a = Counters::for_technique("x");
        a.set("n", 1.0);
        let mut b = Counters::for_technique("x");
        b.set("m", 2.0);
        b.set("n", 3.0);
        let t = Counters::to_table("frame", &[("0".into(), a), ("1".into(), b)]);
        assert_eq!(t.columns, vec!["frame", "x.n", "x.m"]);
        assert_eq!(
            t.rows[0],
            vec![Cell::Text("0".into()), Cell::Number(1.0), Cell::Empty]
        );
        assert_eq!(
            t.rows[1],
            vec![Cell::Text("1".into()), Cell::Number(3.0), Cell::Number(2.0)]
        );
    }

    #[test]
    fn merge_overwrites_equal_names() {
        let mut a = Counters::new();
        a.set("x.n", 1.0);
        let mut b = Counters::for_technique("x");
        b.set("n", 5.0);
        b.set("k", 6.0);
        a.merge(&b);
        assert_eq!(a.get("x.n"), Some(5.0));
        assert_eq!(a.len(), 2);
    }
}
