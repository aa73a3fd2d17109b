//! Every fixed-point operation against an exact i128 oracle (proptest).

use crate::common::*;
use bt_fixed::{
    Coord, Csd, FineCoord, NORMAL_FRAC, NormalComponent, displacement_linf, project,
    quantize_point, round_shift, signed_distance,
};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// The CSD decomposition represents the constant, is non-adjacent and has at most
    /// ceil((bits+1)/2) non-zero digits.
    #[test]
    fn csd_is_canonical(v in any::<i64>()) {
        let csd = Csd::of(v);
        prop_assert_eq!(csd.value(), i128::from(v));
        for w in csd.digits.windows(2) {
            prop_assert!(w[1].shift >= w[0].shift + 2, "adjacent digits in {:?}", csd);
        }
        prop_assert!(csd.digits.len() <= 33);
    }

    /// Shift-add evaluation equals the exact product.
    #[test]
    fn csd_shift_add_is_exact_product(v in any::<i32>(), x in -(1i64 << 40)..(1i64 << 40)) {
        prop_assert_eq!(Csd::of(i64::from(v)).mul(x), i128::from(v) * i128::from(x));
    }

    /// Q2.30 normal components need at most 16 CSD digits.
    #[test]
    fn normal_csd_digit_count(v in -1.0f64..=1.0) {
        let c = NormalComponent::quantize(v).unwrap();
        prop_assert!(c.csd().digits.len() <= 16);
        prop_assert!((c.dequantize() - v).abs() <= 0.5 / f64::from(1u32 << NORMAL_FRAC));
    }

    /// One rounding shift = round half up of the exact quotient.
    #[test]
    fn round_shift_is_round_half_up(acc in any::<i64>(), shift in 0u32..40) {
        prop_assert_eq!(round_shift(i128::from(acc), shift), oracle_round(i128::from(acc), shift));
    }

    /// Signed distance (CSD shift-add, full-precision accumulation, one rounding) equals the
    /// exact i128 dot product rounded half up.
    #[test]
    fn signed_distance_matches_oracle(plane in any_plane(), s in any_point()) {
        let exact: i128 = (0..3).map(|k| i128::from(plane.normal[k].0) * i128::from(s[k].0)).sum::<i128>()
            - (i128::from(plane.offset.0) << NORMAL_FRAC);
        prop_assert_eq!(i128::from(signed_distance(&plane, s)), oracle_round(exact, NORMAL_FRAC));
    }

    /// Projection equals `s_k − round_half_up(d·n_k / 2^30)` with exact products.
    #[test]
    fn projection_matches_oracle(plane in any_plane(), s in any_point()) {
        let d = signed_distance(&plane, s);
        let t = project(&plane, s, d);
        for k in 0..3 {
            let exact = i128::from(s[k].0) - oracle_round(i128::from(d) * i128::from(plane.normal[k].0), NORMAL_FRAC);
            prop_assert_eq!(i128::from(t[k]), exact);
        }
    }

    /// The projection lies on the plane up to the rounding of the normal and of the product.
    #[test]
    fn projection_lands_on_plane(plane in any_plane(), s in [(-5_120_000i64..5_120_000).prop_map(FineCoord), (-5_120_000i64..5_120_000).prop_map(FineCoord), (-5_120_000i64..5_120_000).prop_map(FineCoord)]) {
        let mut plane = plane;
        plane.offset = FineCoord(plane.offset.0 % 5_120_000);
        let d = signed_distance(&plane, s);
        let t = project(&plane, s, d);
        let t_point = t.map(FineCoord);
        // |d(t)| ≤ rounding of 3 components (≤ 1.5·√3 mm in the worst case) + ...
        prop_assert!(signed_distance(&plane, t_point).abs() <= 2, "d(t) = {}", signed_distance(&plane, t_point));
    }

    /// Quantise/dequantise round trip: exact for every word, ≤ 0.5 mm for every metre value.
    #[test]
    fn quantize_round_trip(raw in any::<i32>(), m in -2_000_000.0f64..2_000_000.0) {
        prop_assert_eq!(Coord::quantize(Coord(raw).dequantize()).unwrap(), Coord(raw));
        let q = Coord::quantize(m).unwrap();
        prop_assert!((q.dequantize() - m).abs() <= 0.0005 + 1e-9 * m.abs());
        let f = FineCoord::from_coord(Coord(raw));
        prop_assert_eq!(FineCoord::quantize(f.dequantize()).unwrap(), f);
        prop_assert_eq!((f.floor_mm(), f.frac()), (Coord(raw), 0));
        let g = FineCoord::quantize(m).unwrap();
        prop_assert!((g.dequantize() - m).abs() <= 0.0005 / 256.0 + 1e-9 * m.abs());
        prop_assert_eq!(i64::from(g.floor_mm().0) * 256 + i64::from(g.frac()), g.0);
    }

    /// Displacement is the exact L∞ norm.
    #[test]
    fn displacement_is_linf(a in any_point(), b in any_point()) {
        let exact = (0..3).map(|k| (i128::from(a[k].0) - i128::from(b[k].0)).abs()).max().unwrap();
        prop_assert_eq!(i128::from(displacement_linf(a, b)), exact);
    }
}

#[test]
fn quantize_point_errors_name_the_value() {
    assert!(quantize_point([0.0, 1.0, 3e6]).is_err());
    assert_eq!(
        quantize_point([0.001, -0.002, 0.0]).unwrap(),
        [Coord(1), Coord(-2), Coord(0)]
    );
}
