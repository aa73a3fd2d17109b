//! The intermediate widths of `bt_fixed::width` (which are the RTL wire widths) hold for the
//! whole input domain: any 40-bit coordinates, any unit normal, any 40-bit offset.

use crate::common::*;
use bt_fixed::{
    FineCoord, FinePoint, FixedPlane, GUARD_BITS, NORMAL_FRAC, PeTrace, Widths,
    intersection_point_in, width,
};
use proptest::prelude::*;

fn check(plane: &FixedPlane, prev: FinePoint, next: FinePoint, bits: u32) -> PeTrace {
    let w = Widths::for_coord(bits);
    let t = intersection_point_in(plane, prev, next, bits);
    let half = 1i128 << (NORMAL_FRAC - 1);
    for s in [prev, next] {
        let acc: i128 = (0..3)
            .map(|k| i128::from(plane.normal[k].0) * i128::from(s[k].0))
            .sum::<i128>()
            - (i128::from(plane.offset.0) << NORMAL_FRAC)
            + half;
        assert!(width::fits_signed(acc, w.dot_acc), "dot acc {acc}");
    }
    for d in [t.d_prev, t.d_next] {
        assert!(width::fits_signed(d.into(), w.distance), "d {d}");
        for k in 0..3 {
            let acc = i128::from(d) * i128::from(plane.normal[k].0) + half;
            assert!(width::fits_signed(acc, w.proj_acc));
        }
    }
    for k in 0..3 {
        assert!(width::fits_signed(t.t_prev[k].into(), w.projection));
        assert!(width::fits_signed(t.t_next[k].into(), w.projection));
        assert!(width::fits_signed(t.delta[k].into(), w.delta));
        // Initial L_p and worst-case |B_p| (2|L_p0| + iterations) plus the rounding half.
        let lp0 = i128::from(t.delta[k]) << (GUARD_BITS - 1);
        assert!(width::fits_signed(lp0, w.half_delta));
        assert!(width::fits_signed(
            2 * lp0.abs() + 64 + (1 << (GUARD_BITS - 1)),
            w.acc_delta
        ));
        assert!(width::fits_signed(t.proportion.offset[k].into(), w.offset));
        assert!(width::fits_signed(t.unsaturated[k].into(), w.sum_point));
    }
    assert!(width::fits_unsigned(t.m.into(), w.abs_distance));
    assert!(width::fits_unsigned(t.n.into(), w.abs_distance));
    let sum = i128::from(t.m) + i128::from(t.n);
    assert!(width::fits_unsigned(sum, w.distance_sum));
    assert!(width::fits_unsigned(sum << (GUARD_BITS - 1), w.half_sum));
    assert!(width::fits_unsigned(sum << GUARD_BITS, w.search));
    assert!(width::fits_unsigned(
        i128::from(t.m) << GUARD_BITS,
        w.search
    ));
    t
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn widths_hold_everywhere((bits, plane, prev, next) in any_case()) {
        check(&plane, prev, next, bits);
    }
}

#[test]
fn widths_hold_at_the_corners() {
    for bits in COORD_BITS {
        let mut saw_overflow = false;
        for (plane, prev, next) in corner_cases(bits, false) {
            saw_overflow |= check(&plane, prev, next, bits).overflow;
        }
        // The corners do leave the coordinate range: the saturation path is exercised.
        assert!(saw_overflow, "{bits} bits");
    }
}

#[test]
fn the_full_design_is_the_width_constants() {
    let w = Widths::FULL;
    assert_eq!(w.coord, width::COORD);
    assert_eq!(w.dot_acc, width::DOT_ACC);
    assert_eq!(w.search_diff, width::SEARCH_DIFF);
    assert_eq!(w.point_acc, width::POINT_ACC);
    assert_eq!(w.sum_point, width::SUM_POINT);
}

#[test]
fn a_room_gets_a_narrow_word_and_a_city_a_wider_one() {
    // 6 m: 1,536,000 fine LSB = 21 magnitude bits, + sign + 2 of headroom.
    assert_eq!(bt_fixed::coord_bits_for(6.0), 24);
    assert_eq!(bt_fixed::coord_bits_for(-6.0), 24);
    // 2 km: 512,000,000 = 29 bits → 32.
    assert_eq!(bt_fixed::coord_bits_for(2000.0), 32);
    assert_eq!(bt_fixed::coord_bits_for(0.0), Widths::MIN_COORD);
    assert_eq!(bt_fixed::coord_bits_for(f64::NAN), 40);
    assert_eq!(bt_fixed::coord_bits_for(1e9), 40);
    // The room's extent itself fits, with 4× to spare.
    let (_, max) = Widths::for_coord(24).coord_range();
    assert!(FineCoord(max).dequantize() >= 4.0 * 6.0);
}
