//! Printing counts that come from saturating estimates.

use std::fmt;

/// A count or estimate for messages: `u64::MAX`, what a saturating product or sum stops at,
/// prints as "more than 1.8e19" instead of the meaningless 18446744073709551615; every other
/// value prints as itself. Used by every budget error that prints a saturating estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Count(pub u64);

impl fmt::Display for Count {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 == u64::MAX {
            f.write_str("more than 1.8e19")
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// A lower bound for messages ("at least N"): `u64::MAX`, a saturated bound, prints as
/// "more than 1.8e19" like [`Count`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AtLeast(pub u64);

impl fmt::Display for AtLeast {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 == u64::MAX {
            write!(f, "{}", Count(self.0))
        } else {
            write!(f, "at least {}", self.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saturated_counts_print_as_a_bound() {
        assert_eq!(Count(u64::MAX).to_string(), "more than 1.8e19");
        assert_eq!(Count(u64::MAX - 1).to_string(), "18446744073709551614");
        assert_eq!(Count(42).to_string(), "42");
        assert_eq!(AtLeast(u64::MAX).to_string(), "more than 1.8e19");
        assert_eq!(AtLeast(7).to_string(), "at least 7");
    }
}
