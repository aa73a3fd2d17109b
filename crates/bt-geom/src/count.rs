//! Printing counts that come from saturating estimates, and the one budget check every crate
//! uses for work that grows with its input (`docs/reliability.md`, "Budgets").

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

/// An estimate over its budget: the quantity, the (saturating) estimate, the budget and the
/// option that raises it. Every crate's error type wraps it, so every budget error reads the
/// same: "beam pairs budget exceeded: 16777216 beam pairs, more than the budget of 1000000;
/// raise it with --max-beam-pairs".
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{quantity} budget exceeded: {} {quantity}, more than the budget of {budget}; raise it with {option}",
    Count(*.estimate)
)]
pub struct OverBudget {
    /// What is counted, plural ("beam pairs", "subcarriers").
    pub quantity: &'static str,
    /// The estimate, saturating (`u64::MAX` prints as "more than 1.8e19").
    pub estimate: u64,
    /// The budget.
    pub budget: u64,
    /// The option that raises the budget (CLI spelling; Python uses the same name with `_`).
    pub option: &'static str,
}

/// A named budget: a quantity, its limit and the option that sets it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    /// What is counted, plural.
    pub quantity: &'static str,
    /// The option that sets the limit.
    pub option: &'static str,
    /// The limit.
    pub limit: u64,
}

impl Budget {
    /// A budget of `limit` `quantity`, raised by `option`.
    pub const fn new(quantity: &'static str, option: &'static str, limit: u64) -> Self {
        Budget {
            quantity,
            option,
            limit,
        }
    }

    /// The same budget with another limit.
    pub const fn with_limit(self, limit: u64) -> Self {
        Budget { limit, ..self }
    }

    /// Refuse `estimate` (computed before the work, saturating) when it exceeds the limit.
    pub fn check(&self, estimate: u64) -> Result<(), OverBudget> {
        if estimate <= self.limit {
            return Ok(());
        }
        Err(OverBudget {
            quantity: self.quantity,
            estimate,
            budget: self.limit,
            option: self.option,
        })
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

    #[test]
    fn a_budget_refuses_above_its_limit_naming_estimate_and_option() {
        let b = Budget::new("beam pairs", "--max-beam-pairs", 10);
        assert!(b.check(10).is_ok());
        let e = b.check(11).unwrap_err().to_string();
        assert_eq!(
            e,
            "beam pairs budget exceeded: 11 beam pairs, more than the budget of 10; \
             raise it with --max-beam-pairs"
        );
        let e = b.with_limit(0).check(u64::MAX).unwrap_err().to_string();
        assert!(e.contains("more than 1.8e19 beam pairs"), "{e}");
    }
}
