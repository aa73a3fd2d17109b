/// One non-zero digit of a canonical-signed-digit number: `±2^shift`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub struct CsdDigit {
    /// Bit position (power of two).
    pub shift: u32,
    /// `true` for `-2^shift`.
    pub negative: bool,
}

/// Canonical-signed-digit (non-adjacent form) decomposition of an integer constant:
/// `value = Σ ±2^shift`, no two non-zero digits adjacent, minimal number of non-zero digits.
///
/// Verilog twin: each digit becomes one term `±(x <<< shift)` of the adder network that
/// `bt-hls` emits for a constant product inside `bt_pe_<i>` (no multiplier is ever inferred).
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct Csd {
    /// Non-zero digits, least significant first.
    pub digits: Vec<CsdDigit>,
}

impl Csd {
    /// Non-adjacent form of `v`. Terminates for every `i64`, including `i64::MIN`.
    pub fn of(v: i64) -> Csd {
        let mut digits = Vec::new();
        let mut rest = i128::from(v);
        let mut shift = 0;
        while rest != 0 {
            if rest & 1 == 1 {
                // rest mod 4 == 1 -> +1, == 3 -> -1: leaves a multiple of 4, so the next digit is 0.
                let negative = rest.rem_euclid(4) == 3;
                rest -= if negative { -1 } else { 1 };
                digits.push(CsdDigit { shift, negative });
            }
            rest >>= 1;
            shift += 1;
        }
        Csd { digits }
    }

    /// The represented integer.
    pub fn value(&self) -> i128 {
        self.mul(1)
    }

    /// `x × value` by shift-add: `Σ ±(x << shift)` at full precision (no rounding, no overflow
    /// for |x| < 2^63 and shifts < 64).
    ///
    /// Verilog twin: the sum of sign-extended, left-shifted copies of the input wire.
    pub fn mul(&self, x: i64) -> i128 {
        self.digits.iter().fold(0i128, |acc, d| {
            let term = i128::from(x) << d.shift;
            if d.negative { acc - term } else { acc + term }
        })
    }
}

/// `round_half_up(acc / 2^shift)`: add `2^(shift-1)` then one arithmetic (floor) right shift.
/// `shift == 0` returns `acc`. Ties go towards +∞ (so -2.5 -> -2, 2.5 -> 3).
///
/// Verilog twin: `(acc + HALF)[W-1:shift]`, the slice being the floor of a signed value; the
/// `HALF` constant is folded into the adder network's constant term.
pub fn round_shift(acc: i128, shift: u32) -> i128 {
    if shift == 0 {
        acc
    } else {
        (acc + (1i128 << (shift - 1))) >> shift
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_values() {
        assert_eq!(Csd::of(0).digits, vec![]);
        assert_eq!(
            Csd::of(1 << 30).digits,
            vec![CsdDigit {
                shift: 30,
                negative: false
            }]
        );
        // 7 = 8 - 1
        assert_eq!(
            Csd::of(7).digits,
            vec![
                CsdDigit {
                    shift: 0,
                    negative: true
                },
                CsdDigit {
                    shift: 3,
                    negative: false
                }
            ]
        );
        assert_eq!(Csd::of(-3).value(), -3);
        assert_eq!(Csd::of(i64::MIN).value(), i128::from(i64::MIN));
        assert_eq!(Csd::of(i64::MAX).value(), i128::from(i64::MAX));
    }

    #[test]
    fn round_shift_ties_up() {
        assert_eq!(round_shift(5, 1), 3);
        assert_eq!(round_shift(-5, 1), -2);
        assert_eq!(round_shift(-6, 1), -3);
        assert_eq!(round_shift(7, 0), 7);
    }
}
