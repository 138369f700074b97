//! How every message and report says how many of something: the number, then the words
//! that agree with it. Not a stage: the stages, the reports and the CLI all use it.

/// `n` and the words that agree with it: `count(1, "file", "files")` is `1 file`,
/// `count(0, "file", "files")` is `0 files`; a verb agrees too (`1 loses energy`).
pub fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

#[cfg(test)]
mod tests {
    use super::count;

    #[test]
    fn a_count_agrees_with_its_number() {
        assert_eq!(count(1, "lobe", "lobes"), "1 lobe");
        assert_eq!(count(0, "lobe", "lobes"), "0 lobes");
        assert_eq!(count(2, "loses energy", "lose energy"), "2 lose energy");
    }
}
