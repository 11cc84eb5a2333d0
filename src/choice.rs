//! Options that take one of a few named values (a smoothing method, a subdivision scheme, a
//! relaxation operator): their names, one line on each, and the message for a name that is
//! none of them live here, once, so that every front end accepts the same words and refuses
//! the others with the same message.

use std::fmt;

/// A closed set of named values.
pub trait Choice: Copy + Sized + 'static {
    /// What the values are, for messages ("smoothing method").
    const WHAT: &'static str;
    /// Every value, in the order front ends list them.
    const ALL: &'static [Self];

    /// The value's name, as front ends spell it (`inverse-edge`).
    fn name(self) -> &'static str;

    /// One line on what the value does, for help texts.
    fn about(self) -> &'static str;

    /// The value called `name`.
    fn parse(name: &str) -> Result<Self, UnknownChoice> {
        Self::ALL
            .iter()
            .copied()
            .find(|value| value.name() == name)
            .ok_or_else(|| UnknownChoice {
                what: Self::WHAT,
                got: name.to_string(),
                expected: Self::ALL.iter().map(|value| value.name()).collect(),
            })
    }
}

/// A name that is none of a [`Choice`]'s values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownChoice {
    /// What the values are ([`Choice::WHAT`]).
    pub what: &'static str,
    /// The name given.
    pub got: String,
    /// The names of the values.
    pub expected: Vec<&'static str>,
}

impl fmt::Display for UnknownChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown {} {:?}: expected one of {}",
            self.what,
            self.got,
            self.expected.join(", ")
        )
    }
}

impl std::error::Error for UnknownChoice {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relax::RelaxKind;

    #[test]
    fn every_value_parses_back_from_its_name_and_other_names_are_refused() {
        for &kind in RelaxKind::ALL {
            assert_eq!(RelaxKind::parse(kind.name()), Ok(kind));
        }
        let refused = RelaxKind::parse("laplace").expect_err("not a relaxation");
        assert_eq!(
            refused.to_string(),
            "unknown relaxation \"laplace\": expected one of second-difference, mcm, normal"
        );
    }
}
