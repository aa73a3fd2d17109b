//! The intermediate widths of `bt_fixed::width` (which are the RTL wire widths) hold for the
//! whole input domain: any 40-bit coordinates, any unit normal, any 40-bit offset.

use crate::common::*;
use bt_fixed::{
    FineCoord, FinePoint, FixedPlane, GUARD_BITS, NORMAL_FRAC, PeTrace, intersection_point, width,
};
use proptest::prelude::*;

fn check(plane: &FixedPlane, prev: FinePoint, next: FinePoint) -> PeTrace {
    let t = intersection_point(plane, prev, next);
    let half = 1i128 << (NORMAL_FRAC - 1);
    for s in [prev, next] {
        let acc: i128 = (0..3)
            .map(|k| i128::from(plane.normal[k].0) * i128::from(s[k].0))
            .sum::<i128>()
            - (i128::from(plane.offset.0) << NORMAL_FRAC)
            + half;
        assert!(width::fits_signed(acc, width::DOT_ACC), "dot acc {acc}");
    }
    for d in [t.d_prev, t.d_next] {
        assert!(width::fits_signed(d.into(), width::DISTANCE), "d {d}");
        for k in 0..3 {
            let acc = i128::from(d) * i128::from(plane.normal[k].0) + half;
            assert!(width::fits_signed(acc, width::PROJ_ACC));
        }
    }
    for k in 0..3 {
        assert!(width::fits_signed(t.t_prev[k].into(), width::PROJECTION));
        assert!(width::fits_signed(t.t_next[k].into(), width::PROJECTION));
        assert!(width::fits_signed(t.delta[k].into(), width::DELTA));
        // Initial L_p and worst-case |B_p| (2|L_p0| + iterations) plus the rounding half.
        let lp0 = i128::from(t.delta[k]) << (GUARD_BITS - 1);
        assert!(width::fits_signed(lp0, width::HALF_DELTA));
        assert!(width::fits_signed(
            2 * lp0.abs() + 64 + (1 << (GUARD_BITS - 1)),
            width::ACC_DELTA
        ));
        assert!(width::fits_signed(
            t.proportion.offset[k].into(),
            width::OFFSET
        ));
        assert!(width::fits_signed(
            t.unsaturated[k].into(),
            width::SUM_POINT
        ));
    }
    assert!(width::fits_unsigned(t.m.into(), width::ABS_DISTANCE));
    assert!(width::fits_unsigned(t.n.into(), width::ABS_DISTANCE));
    let sum = i128::from(t.m) + i128::from(t.n);
    assert!(width::fits_unsigned(sum, width::DISTANCE_SUM));
    assert!(width::fits_unsigned(
        sum << (GUARD_BITS - 1),
        width::HALF_SUM
    ));
    assert!(width::fits_unsigned(sum << GUARD_BITS, width::SEARCH));
    assert!(width::fits_unsigned(
        i128::from(t.m) << GUARD_BITS,
        width::SEARCH
    ));
    t
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn widths_hold_everywhere(plane in any_plane(), prev in any_point(), next in any_point()) {
        check(&plane, prev, next);
    }
}

#[test]
fn widths_hold_at_the_corners() {
    let r3 = 1.0 / 3f64.sqrt();
    let corners = [FineCoord::MIN, FineCoord::MAX];
    let mut saw_overflow = false;
    for normal in [
        [r3, r3, r3],
        [-r3, r3, -r3],
        [1.0, 0.0, 0.0],
        [0.6, -0.8, 0.0],
    ] {
        for offset in [FineCoord::MIN, FineCoord::MAX, FineCoord(0)] {
            let mut plane = FixedPlane::quantize(normal, 0.0).unwrap();
            plane.offset = offset;
            for bits_prev in 0..8u32 {
                for bits_next in 0..8u32 {
                    let pt = |bits: u32| -> FinePoint {
                        std::array::from_fn(|k| corners[((bits >> k) & 1) as usize])
                    };
                    let t = check(&plane, pt(bits_prev), pt(bits_next));
                    saw_overflow |= t.overflow;
                }
            }
        }
    }
    // The corners do leave the 40-bit range: the saturation path is exercised.
    assert!(saw_overflow);
}
