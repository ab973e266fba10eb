//! `--shard K/N`: one of N machines' share of a list of independent work items (keys of
//! a precompute, frames of an animation, converged references of a benchmark). Item `i`
//! belongs to shard `i mod N`, so shards get equal shares whatever the list's length.

/// `K/N`: this is shard K (0-based) of N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which (0 ≤ index < count).
    pub index: u32,
    /// How many.
    pub count: u32,
}

impl Default for Shard {
    /// `0/1`: all the work.
    fn default() -> Self {
        Self { index: 0, count: 1 }
    }
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// Parses `K/N` with 0 ≤ K < N; the error quotes the text and shows the form.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("--shard {s:?}: expected K/N with 0 ≤ K < N, e.g. 0/3");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = k.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }
}

impl std::fmt::Display for Shard {
    /// `K/N`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Whether item `i` belongs to this shard (`i mod N = K`).
    pub fn owns(&self, i: usize) -> bool {
        i % self.count as usize == self.index as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_items() {
        let shards: Vec<Shard> = (0..3).map(|k| format!("{k}/3").parse().unwrap()).collect();
        for i in 0..10 {
            assert_eq!(shards.iter().filter(|s| s.owns(i)).count(), 1, "item {i}");
        }
        assert!(shards[1].owns(4) && !shards[1].owns(5));
        assert_eq!(shards[2].to_string(), "2/3");
        assert!("3/3".parse::<Shard>().is_err());
        assert!("0/0".parse::<Shard>().is_err());
        assert!("1-3".parse::<Shard>().is_err());
    }
}
