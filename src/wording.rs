//! Counts in messages: "1 vertex", "2 vertices".

use std::fmt;

/// A count with its noun in the right number: `Count(n, "face", "faces")` shows as `1 face` or
/// `3 faces`.
#[derive(Clone, Copy, Debug)]
pub struct Count<'a>(pub usize, pub &'a str, pub &'a str);

impl fmt::Display for Count<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let noun = if self.0 == 1 { self.1 } else { self.2 };
        write!(f, "{} {noun}", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::Count;

    #[test]
    fn one_takes_the_singular_and_every_other_count_the_plural() {
        let shown = [0, 1, 2].map(|n| Count(n, "vertex", "vertices").to_string());
        assert_eq!(shown, ["0 vertices", "1 vertex", "2 vertices"]);
    }
}
