//! Scalar functions the hot loops call often enough that the C library's call costs show.

use crate::Real;

/// √(x² + y²) without undue overflow or underflow, inlined.
///
/// For arguments whose squares neither overflow nor underflow (|x|, |y| in [2⁻⁵¹¹, 2⁵¹¹],
/// the smaller above 2⁻⁵⁴ of the larger), this is C. F. Borges' corrected algorithm ("An
/// Improved Algorithm for hypot(a,b)", 2019): a square root of the rounded sum of squares,
/// then one Newton-like correction from the residual, each operation rounded once (no fused
/// multiply-add). That is the algorithm of glibc's `hypot` since 2.35, written here operation
/// for operation, so that the result does not depend on the C library's version and the
/// common case needs no call (over a loop of independent pairs glibc's `hypot` takes about
/// twice as long; inside a report, where the square root's and the division's latency
/// dominate, the two cost about the same). Every other argument (infinite, NaN, huge, tiny
/// or very unequal) goes to [`f64::hypot`].
#[inline(always)]
pub fn hypot(x: Real, y: Real) -> Real {
    let (x, y) = (x.abs(), y.abs());
    let (ax, ay) = if x < y { (y, x) } else { (x, y) };
    // NaN fails every comparison, so it takes the library's path.
    if ax <= LARGE && ay >= TINY && ay > ax * EPS {
        corrected(ax, ay)
    } else {
        x.hypot(y)
    }
}

/// √(x² + y²) where a chain of roots and divisions waits for it: the square root of the
/// rounded sum of squares where that sum is a normal number (within about an ulp of
/// [`hypot`]'s correctly rounded result, without its correction's division, which doubled the
/// latency), [`hypot`] where a square would overflow or lose its precision (the sum infinite,
/// NaN, zero or subnormal).
#[inline(always)]
pub fn root_sum_squares(x: Real, y: Real) -> Real {
    let square = x * x + y * y;
    match square.is_normal() {
        true => square.sqrt(),
        false => hypot(x, y),
    }
}

/// 2⁵¹¹: above it a square may overflow.
const LARGE: Real = f64::from_bits(0x5fe0_0000_0000_0000);
/// 2⁻⁵¹¹: below it a square may underflow.
const TINY: Real = f64::from_bits(0x2000_0000_0000_0000);
/// 2⁻⁵⁴: a smaller side below this fraction of the larger does not change the sum.
const EPS: Real = f64::from_bits(0x3c90_0000_0000_0000);

/// Borges' correction of √(ax² + ay²) for ax ≥ ay > 0 whose squares and their difference's
/// neither overflow nor underflow.
#[inline(always)]
fn corrected(ax: Real, ay: Real) -> Real {
    let h = (ax * ax + ay * ay).sqrt();
    let (t1, t2) = if h <= 2.0 * ay {
        let delta = h - ay;
        (ax * (2.0 * delta - ax), (delta - 2.0 * (ax - ay)) * delta)
    } else {
        let delta = h - ax;
        (
            2.0 * delta * (ax - 2.0 * ay),
            (4.0 * delta - ay) * ay + delta * delta,
        )
    };
    h - (t1 + t2) / (2.0 * h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `v` = m·2^e with an integer m < 2⁵³ (v finite, positive).
    fn split(v: Real) -> (u128, i32) {
        let bits = v.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32;
        let frac = (bits & ((1 << 52) - 1)) as u128;
        match exp {
            0 => (frac, -1074),
            _ => (frac | (1 << 52), exp - 1075),
        }
    }

    /// Whether r lies within `halves` half-units in the last place of √(x² + y²), decided
    /// exactly in integers: with r = m·2^e and u = 2^e, |r − √S| ≤ k·u/2 iff
    /// (2m − k)²·2^(2e−2) ≤ S ≤ (2m + k)²·2^(2e−2), S = x² + y².
    fn within(x: Real, y: Real, r: Real, halves: u128) -> bool {
        let ((mx, ex), (my, ey), (mr, er)) = (split(x), split(y), split(r));
        // Every term is an integer times 2^base; the exponents differ by little in the
        // generated cases, so the shifts stay within u128.
        let base = (2 * ex).min(2 * ey).min(2 * er - 2);
        let s = ((mx * mx) << (2 * ex - base)) + ((my * my) << (2 * ey - base));
        let shift = (2 * er - 2 - base) as u32;
        let (lo, hi) = (2 * mr - halves, 2 * mr + halves);
        ((lo * lo) << shift) <= s && s <= ((hi * hi) << shift)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// The inlined path is within one unit in the last place of the exact value (it
        /// rounds correctly in nearly all cases; one ulp is the bound Borges gives), the root
        /// of the rounded sum within two (a rounding of each square, of the sum and of the
        /// root), and both are symmetric in their arguments and their signs.
        #[test]
        fn roots_are_within_their_ulps_of_the_exact_root(
            mx in 1.0f64..2.0, my in 1.0f64..2.0, ex in -8i32..8, dy in -4i32..4,
            sx in any::<bool>(), sy in any::<bool>(),
        ) {
            let x = mx * (2.0f64).powi(ex);
            let y = my * (2.0f64).powi(ex + dy);
            let (sx, sy) = (if sx { -x } else { x }, if sy { -y } else { y });
            for (name, root, halves) in [
                ("hypot", hypot as fn(Real, Real) -> Real, 2),
                ("root_sum_squares", root_sum_squares, 4),
            ] {
                let r = root(sx, sy);
                prop_assert!(within(x, y, r, halves), "{name}({x:e}, {y:e}) = {r:e}");
                prop_assert_eq!(r.to_bits(), root(y, x).to_bits());
            }
        }
    }

    #[test]
    fn root_sum_squares_leaves_overflow_and_underflow_to_hypot() {
        for (x, y) in [
            (0.0, 0.0),
            (-0.0, 0.0),
            (1e200, 3e200),
            (Real::MAX, 1.0),
            (1e-170, 2e-170),
            (5e-324, 0.0),
            (Real::INFINITY, 1.0),
        ] {
            let (fast, careful) = (root_sum_squares(x, y), hypot(x, y));
            assert_eq!(fast.to_bits(), careful.to_bits(), "({x:e}, {y:e})");
        }
        assert!(root_sum_squares(Real::NAN, 1.0).is_nan());
        assert_eq!(root_sum_squares(3.0, 4.0), 5.0);
    }

    #[test]
    fn most_results_round_correctly() {
        // A fixed sweep: the share of correctly rounded results, decided exactly (19,860 of
        // the 20,000; the others are one ulp off, which the property test bounds).
        let mut correct = 0;
        let n = 20_000;
        for i in 0..n {
            let x = 1.0 + (i as Real) * 0.618_033_988_749_895 % 1.0;
            let y = 0.25 + (i as Real) * 0.414_213_562_373_095 % 1.5;
            if within(x, y, hypot(x, y), 1) {
                correct += 1;
            }
        }
        assert!(
            correct * 100 >= n * 99,
            "{correct} of {n} correctly rounded"
        );
    }

    #[test]
    fn edge_arguments_take_the_library_path() {
        let cases = [
            (0.0, 0.0),
            (-0.0, 3.0),
            (3.0, 4.0),
            (Real::INFINITY, Real::NAN),
            (Real::NAN, 1.0),
            (1e300, 1e300),
            (1e-300, 1e-300),
            (1.0, 1e-17),
            (Real::MIN_POSITIVE, 5e-324),
            (Real::MAX, Real::MAX),
        ];
        for (x, y) in cases {
            let (mine, lib) = (hypot(x, y), x.hypot(y));
            assert!(
                mine.to_bits() == lib.to_bits() || (mine.is_nan() && lib.is_nan()),
                "hypot({x:e}, {y:e}): {mine:e} against {lib:e}"
            );
        }
        assert_eq!(hypot(3.0, 4.0), 5.0);
    }
}
