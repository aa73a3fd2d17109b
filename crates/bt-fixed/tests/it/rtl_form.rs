//! The register-level form `bt-hls` builds for one PE (`bt_pe_<i>`) equals the model
//! (`intersection_point` before saturation) over the whole input domain. The RTL keeps the
//! model's arithmetic and only re-arranges it:
//! * one CSD network per normal component, shared by `d_prev`, `d_next`, `t_prev`, `t_next`
//!   (the products are exact whatever the order, so sharing cannot change a bit);
//! * `E = B − m·2^G` instead of `B`, `m·2^G` and a comparator (`B < m·2^G` ⇔ `E < 0`);
//! * `A = t_prev·2^G + 2^(G−1) + B_p` kept modulo 2^[`w.point_acc`] instead of `B_p`,
//!   the rounding adder and `t_prev + offset`: `A >> G` is the unsaturated point.
//!
//! This file emulates those registers in i128 with the RTL's widths (wrapping where the RTL
//! wraps) and compares; co-simulation in `bt-hls` then compares the Verilog with the model.

use crate::common::*;
use bt_fixed::{
    FinePoint, FixedPlane, GUARD_BITS, NORMAL_FRAC, Widths, intersection_point_in, width,
};
use proptest::prelude::*;

/// Two's-complement wrap of `v` to `bits` bits.
fn wrap(v: i128, bits: u32) -> i128 {
    let m = 1i128 << bits;
    let r = v.rem_euclid(m);
    if r >= m / 2 { r - m } else { r }
}

/// The unsaturated point as the PE's registers compute it.
fn rtl_pe(plane: &FixedPlane, prev: FinePoint, next: FinePoint, w: Widths) -> ([i128; 3], bool) {
    let g = GUARD_BITS;
    let nf = NORMAL_FRAC;
    let net = |k: usize, x: i128| -> i128 { plane.normal[k].csd().mul(x as i64) };
    let dot = |s: FinePoint| -> i128 {
        let acc: i128 = (0..3).map(|k| net(k, i128::from(s[k].0))).sum::<i128>()
            + (1i128 << (nf - 1))
            - (i128::from(plane.offset.0) << nf);
        wrap(wrap(acc, w.dot_acc) >> nf, w.distance)
    };
    let d_prev = dot(prev);
    let d_next = dot(next);
    let proj = |s: FinePoint, d: i128| -> [i128; 3] {
        std::array::from_fn(|k| {
            let p = wrap(net(k, d) + (1i128 << (nf - 1)), w.proj_acc) >> nf;
            wrap(i128::from(s[k].0) - p, w.projection)
        })
    };
    let t_prev = proj(prev, d_prev);
    let t_next = proj(next, d_next);
    let (m, n) = (d_prev.abs(), d_next.abs());
    let sum = m + n;
    let mut big_l = sum << (g - 1);
    let mut e = (n - m) << (g - 1);
    let mut lp: [i128; 3] = std::array::from_fn(|k| (t_next[k] - t_prev[k]) << (g - 1));
    let mut a: [i128; 3] =
        std::array::from_fn(|k| wrap((t_prev[k] + t_next[k] + 1) << (g - 1), w.point_acc));
    for _ in 0..w.iterations {
        if big_l == 0 {
            continue;
        }
        big_l >>= 1;
        let up = e < 0;
        for k in 0..3 {
            lp[k] >>= 1;
            a[k] = wrap(if up { a[k] + lp[k] } else { a[k] - lp[k] }, w.point_acc);
        }
        e = if up { e + big_l } else { e - big_l };
        assert!(width::fits_signed(e, w.search_diff), "E = {e}");
        assert!(width::fits_unsigned(big_l, w.half_sum));
        assert!(lp.iter().all(|&v| width::fits_signed(v, w.half_delta)));
    }
    (a.map(|v| v >> g), sum == 0)
}

fn check(plane: &FixedPlane, prev: FinePoint, next: FinePoint, bits: u32) {
    let model = intersection_point_in(plane, prev, next, bits);
    let (rtl, zero_sum) = rtl_pe(plane, prev, next, Widths::for_coord(bits));
    let unsat = model.unsaturated.map(i128::from);
    assert_eq!(rtl, unsat, "plane {plane:?} prev {prev:?} next {next:?}");
    assert_eq!(zero_sum, model.proportion.zero_sum);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn register_form_equals_model((bits, plane, prev, next) in any_case()) {
        check(&plane, prev, next, bits);
    }
}

#[test]
fn register_form_equals_model_at_the_corners() {
    for bits in COORD_BITS {
        for (plane, prev, next) in corner_cases(bits, true) {
            check(&plane, prev, next, bits);
        }
    }
}
