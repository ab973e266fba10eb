//! Named counters (photons per second, records alive, milliseconds per stage), kept next
//! to the code they count. A technique reports its counters unprefixed
//! (`photons_per_s`); the engine files them under the technique's name
//! (`photon_stream.photons_per_s`) with [`Counters::prefixed`].

/// An insertion-ordered map from counter name to value.
///
/// ```
/// use illume_core::Counters;
/// let mut c = Counters::new();
/// c.set("photons_per_s", 2.5e6);
/// c.add("frames", 1.0);
/// c.add("frames", 1.0);
/// let c = c.prefixed("photon_stream");
/// assert_eq!(c.get("photon_stream.frames"), Some(2.0));
/// assert_eq!(c.names().collect::<Vec<_>>(), ["photon_stream.photons_per_s", "photon_stream.frames"]);
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

    /// Full names in insertion order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.entries.iter().map(|(n, _)| n.as_str())
    }

    /// Number of counters.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when there are no counters.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The same counters with every full name filed under `prefix` (`prefix.name`).
    pub fn prefixed(&self, prefix: &str) -> Counters {
        Counters {
            prefix: String::new(),
            entries: self
                .entries
                .iter()
                .map(|(n, v)| (format!("{prefix}.{n}"), *v))
                .collect(),
        }
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
    }

    #[test]
    fn prefixed_files_every_name_under_the_prefix() {
        let mut c = Counters::new();
        c.set("n", 1.0);
        c.set("m", 2.0);
        let p = c.prefixed("reference");
        assert_eq!(p.get("reference.n"), Some(1.0));
        assert_eq!(p.get("n"), None);
        assert_eq!(p.len(), 2);
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
