//! Counters in reports: the [`Counters`] type lives in `illume_core` (techniques report
//! through it); this module writes them as CSV lines and report tables.

use crate::report::{Cell, Table};
pub use illume_core::Counters;

/// CSV and table output of [`Counters`].
///
/// ```
/// use illume_metrics::{Counters, CounterReport};
/// let mut c = Counters::for_technique("photon_stream");
/// c.set("photons_per_s", 2.5e6);
/// c.add("frames", 1.0);
/// assert_eq!(c.csv_header(), "photon_stream.photons_per_s,photon_stream.frames");
/// ```
pub trait CounterReport {
    /// The CSV header line of these counters (names, comma-separated, quoted if needed).
    fn csv_header(&self) -> String;
    /// The CSV data line of these counters, in header order.
    fn csv_row(&self) -> String;
}

impl CounterReport for Counters {
    /// The CSV header line of these counters (names, comma-separated, quoted if needed).
    fn csv_header(&self) -> String {
        let columns: Vec<String> = self.names().map(str::to_owned).collect();
        crate::report::csv_line(&columns)
    }

    /// The CSV data line of these counters, in header order.
    fn csv_row(&self) -> String {
        let cells: Vec<String> = self
            .iter()
            .map(|(_, v)| Cell::Number(v).to_string())
            .collect();
        crate::report::csv_line(&cells)
    }
}

/// A table with one row per element of `rows` (e.g. per frame), led by a `label` column;
/// the columns are the union of all counter names in first-seen order, and a counter
/// missing from a row is an empty cell.
pub fn counters_table(label: &str, rows: &[(String, Counters)]) -> Table {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_row_follows_insertion_order() {
        let mut c = Counters::for_technique("selective");
        c.set("b", 1.0);
        c.set("a", 2.0);
        c.set("b", 3.0);
        c.add("a", 0.5);
        assert_eq!(c.csv_header(), "selective.b,selective.a");
        assert_eq!(c.csv_row(), "3,2.5");
    }

    #[test]
    fn table_takes_the_union_of_names() {
        let mut a = Counters::for_technique("x");
        a.set("n", 1.0);
        let mut b = Counters::for_technique("x");
        b.set("m", 2.0);
        b.set("n", 3.0);
        let t = counters_table("frame", &[("0".into(), a), ("1".into(), b)]);
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
}
