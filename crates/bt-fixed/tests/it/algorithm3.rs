//! Algorithm 3 (halving comparison) at its boundaries and against the exact ratio.

use bt_fixed::{
    GUARD_BITS, PROPORTION_ITERATIONS, Widths, halving_proportion, halving_proportion_in, width,
};
use proptest::prelude::*;

/// Largest |d| the PE can produce (34-bit signed distance, |d| < 2^32.45).
const MAX_ABS_D: u64 = 5_876_700_000;

/// The documented bound of `halving_proportion`, as `S · bound` so that it is checked in
/// exact i128 arithmetic: |out·S − l·m| ≤ S/2 + S·i/2^G + |l|·(S·2^-(i+1)·[L_i>0] + 2i/2^G).
fn check_bound(m: u64, n: u64, l: i64, out: i64, iterations: u32) {
    let s = i128::from(m) + i128::from(n);
    if s == 0 {
        return;
    }
    let g = 1i128 << GUARD_BITS;
    let i = i128::from(iterations);
    // L after i iterations: floor(S·2^(G-1) / 2^i).
    let l_final = (s << (GUARD_BITS - 1)) >> iterations;
    let err = (i128::from(out) * s - i128::from(l) * i128::from(m)).abs() * g;
    let bound = s * g / 2 + s * i + i128::from(l).abs() * (l_final + 2 * i);
    assert!(
        err <= bound,
        "m={m} n={n} l={l} out={out} it={iterations}: err·G={err} > {bound}"
    );
}

/// Tight tolerance (1 mm) where the search resolution allows it: the search stops after
/// about log2((m+n)·2^G) iterations, so the ratio resolution is ~1/((m+n)·2^G) and |l| up to
/// 1000·(m+n) keeps its contribution below 1/65 mm; the 32-iteration cap adds |l|·2^-33,
/// below 1/2 mm for |l| < 2^32.
fn tight(m: u64, n: u64, l: i64) -> bool {
    l.unsigned_abs() <= 1000 * (m + n) && l.unsigned_abs() < 1 << 32
}

#[test]
fn m_zero_stays_at_leading_projection() {
    for s in [1u64, 7, 1000, MAX_ABS_D] {
        for l in [0, 1, -1, 12345, -98765, (1 << 34) - 1, -(1 << 34)] {
            let p = halving_proportion(0, s, [l, -l, 0]);
            assert!(!p.zero_sum);
            check_bound(0, s, l, p.offset[0], p.iterations);
            check_bound(0, s, -l, p.offset[1], p.iterations);
            if tight(0, s, l) {
                assert!(
                    p.offset[0].abs() <= 1 && p.offset[1].abs() <= 1,
                    "{s} {l} {p:?}"
                );
            }
        }
    }
}

#[test]
fn n_zero_goes_to_following_projection() {
    for s in [1u64, 7, 1000, MAX_ABS_D] {
        for l in [0, 1, -1, 12345, -98765, (1 << 34) - 1, -(1 << 34)] {
            let p = halving_proportion(s, 0, [l, -l, 0]);
            check_bound(s, 0, l, p.offset[0], p.iterations);
            check_bound(s, 0, -l, p.offset[1], p.iterations);
            if tight(s, 0, l) {
                assert!(
                    (p.offset[0] - l).abs() <= 1 && (p.offset[1] + l).abs() <= 1,
                    "{s} {l} {p:?}"
                );
            }
        }
    }
}

#[test]
fn zero_sum_is_the_midpoint_and_flagged() {
    let p = halving_proportion(0, 0, [10, -11, (1 << 34) - 1]);
    assert!(p.zero_sum);
    assert_eq!(p.iterations, 0);
    // l/2 rounded half up: 5, -5 (-5.5 -> -5), 2^33 - 0.5 -> 2^33.
    assert_eq!(p.offset, [5, -5, 1 << 33]);
}

#[test]
fn maximal_words_do_not_overflow() {
    // m + n at its maximum (2^33.45): the sum register is 34 bits; B stays within SEARCH bits.
    for (m, n) in [
        (MAX_ABS_D, MAX_ABS_D),
        (MAX_ABS_D, 0),
        (0, MAX_ABS_D),
        (MAX_ABS_D, 1),
        (1, MAX_ABS_D),
    ] {
        assert!(width::fits_unsigned(
            i128::from(m) + i128::from(n),
            width::DISTANCE_SUM
        ));
        for l in [(1i64 << 34) - 1, -(1 << 34), 0, 1, -1] {
            assert!(width::fits_signed(i128::from(l), width::DELTA));
            let p = halving_proportion(m, n, [l, -l, l / 3]);
            assert_eq!(p.iterations, PROPORTION_ITERATIONS);
            for k in 0..3 {
                assert!(width::fits_signed(i128::from(p.offset[k]), width::OFFSET));
            }
            check_bound(m, n, l, p.offset[0], p.iterations);
            check_bound(m, n, -l, p.offset[1], p.iterations);
        }
    }
}

#[test]
fn equal_distances_give_the_midpoint() {
    for d in [1u64, 2, 3, 1000, 123_456, MAX_ABS_D] {
        let p = halving_proportion(d, d, [1_000_000, -2_000_001, 7]);
        check_bound(d, d, 1_000_000, p.offset[0], p.iterations);
        check_bound(d, d, -2_000_001, p.offset[1], p.iterations);
        if d >= 1000 {
            assert!((p.offset[0] - 500_000).abs() <= 1, "{d} {p:?}");
            assert!((p.offset[1] + 1_000_000).abs() <= 1, "{d} {p:?}");
        }
    }
}

#[test]
fn search_stops_when_l_reaches_zero() {
    // m + n = 1: L0 = 2^(G-1) reaches zero after G iterations.
    let p = halving_proportion(1, 0, [1000, 0, 0]);
    assert_eq!(p.iterations, GUARD_BITS);
    assert!((p.offset[0] - 1000).abs() <= 1);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    /// The documented error bound holds over the whole input domain.
    #[test]
    fn proportion_within_documented_bound(
        m in prop_oneof![0u64..=MAX_ABS_D, 0u64..100_000, 0u64..10],
        n in prop_oneof![0u64..=MAX_ABS_D, 0u64..100_000, 0u64..10],
        l in prop_oneof![-(1i64 << 34)..(1i64 << 34), -100_000i64..100_000],
    ) {
        let p = halving_proportion(m, n, [l, -l, l / 2]);
        check_bound(m, n, l, p.offset[0], p.iterations);
        check_bound(m, n, -l, p.offset[1], p.iterations);
        check_bound(m, n, l / 2, p.offset[2], p.iterations);
    }

    /// A `c`-bit design stops after `Widths::iterations` = min(32, c) halving steps: the
    /// documented bound still holds, and against the 32 steps of the full design the result
    /// moves by at most 1 LSB (the skipped steps add at most |l|·2^-(c+1) < ½ before the one
    /// rounding), since |l| = |t_next − t_prev| < 2^c in a `c`-bit word.
    #[test]
    fn fewer_iterations_for_a_narrow_word_cost_at_most_one_lsb(
        c in Widths::MIN_COORD..=40u32,
        m_frac in 0.0f64..1.0,
        n_frac in prop_oneof![0.0f64..1.0, 0.0f64..1e-6],
        l_frac in -1.0f64..1.0,
    ) {
        let wd = Widths::for_coord(c);
        // |d| < 2^(c+1) (the narrowed ABS_DISTANCE), |l| < 2^c.
        let m = (m_frac * ((1u64 << wd.abs_distance) - 1) as f64) as u64;
        let n = (n_frac * ((1u64 << wd.abs_distance) - 1) as f64) as u64;
        let l = (l_frac * ((1i64 << c) - 1) as f64) as i64;
        let narrow = halving_proportion_in(m, n, [l, -l, l / 3], wd.iterations);
        let full = halving_proportion(m, n, [l, -l, l / 3]);
        prop_assert!(narrow.iterations <= wd.iterations);
        for k in 0..3 {
            prop_assert!((narrow.offset[k] - full.offset[k]).abs() <= 1, "{narrow:?} vs {full:?}");
        }
        check_bound(m, n, l, narrow.offset[0], narrow.iterations);
        check_bound(m, n, -l, narrow.offset[1], narrow.iterations);
    }

    /// Indoor-scale inputs (distances 0.5–20 m, |l| ≤ 20 m): the result is within 0.6 mm
    /// of the exact proportion.
    #[test]
    fn indoor_scale_error_below_0_6_mm(m in 500u64..20_000, n in 500u64..20_000, l in -20_000i64..20_000) {
        let p = halving_proportion(m, n, [l, 0, 0]);
        let exact = l as f64 * m as f64 / (m + n) as f64;
        prop_assert!((p.offset[0] as f64 - exact).abs() <= 0.6, "{} vs {}", p.offset[0], exact);
    }
}
