//! Shared proptest strategies.

use bt_fixed::{FineCoord, FinePoint, FixedPlane};
use proptest::prelude::*;

/// Any unit normal: random directions plus the axis-aligned and diagonal special cases.
pub fn unit_normal() -> impl Strategy<Value = [f64; 3]> {
    prop_oneof![
        (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0)
            .prop_filter("non-zero", |(x, y, z)| x * x + y * y + z * z > 1e-6)
            .prop_map(|(x, y, z)| {
                let len = (x * x + y * y + z * z).sqrt();
                [x / len, y / len, z / len]
            }),
        prop::sample::select(vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, -1.0],
            [0.6, 0.8, 0.0],
            [1.0 / 3f64.sqrt(), 1.0 / 3f64.sqrt(), -1.0 / 3f64.sqrt()],
            [-1.0 / 3f64.sqrt(), -1.0 / 3f64.sqrt(), -1.0 / 3f64.sqrt()],
        ]),
    ]
}

/// Any plane: unit normal and any 40-bit offset word.
pub fn any_plane() -> impl Strategy<Value = FixedPlane> {
    any_plane_in(FineCoord::BITS)
}

/// Any plane of a design with `bits`-bit coordinate words ([`bt_fixed::Widths`]).
pub fn any_plane_in(bits: u32) -> impl Strategy<Value = FixedPlane> {
    (unit_normal(), any_coord_in(bits)).prop_map(|(n, off)| {
        let mut p = FixedPlane::quantize(n, 0.0).unwrap();
        p.offset = off;
        p
    })
}

/// Any `bits`-bit fine coordinate word, biased towards the extremes and indoor scale.
pub fn any_coord_in(bits: u32) -> impl Strategy<Value = FineCoord> {
    let (min, max) = bt_fixed::Widths::for_coord(bits).coord_range();
    let indoor = 5_120_000i64.min(max);
    prop_oneof![
        (min..=max).prop_map(FineCoord),
        prop::sample::select(vec![min, min + 1, -1, 0, 1, max - 1, max]).prop_map(FineCoord),
        (-indoor..indoor).prop_map(FineCoord),
    ]
}

/// Any point of 40-bit words (biased towards the extremes and indoor scale).
pub fn any_point() -> impl Strategy<Value = FinePoint> {
    any_point_in(FineCoord::BITS)
}

/// Any point of `bits`-bit words.
pub fn any_point_in(bits: u32) -> impl Strategy<Value = FinePoint> {
    [any_coord_in(bits), any_coord_in(bits), any_coord_in(bits)]
}

/// Coordinate widths the width proofs run at: the full word and narrowed room designs.
pub const COORD_BITS: [u32; 5] = [40, 32, 24, 20, 16];

/// A coordinate width of [`COORD_BITS`] with a plane and two points of that width.
pub fn any_case() -> impl Strategy<Value = (u32, FixedPlane, FinePoint, FinePoint)> {
    prop::sample::select(COORD_BITS.to_vec())
        .prop_flat_map(|b| (Just(b), any_plane_in(b), any_point_in(b), any_point_in(b)))
}

/// The planes of the corner tests at `bits`-bit coordinates: four unit normals (diagonal,
/// anti-diagonal, axis, 3-4-5 in the xy plane), each with its offset at the coordinate range's
/// minimum, its maximum and zero.
pub fn corner_planes(bits: u32) -> Vec<FixedPlane> {
    let (min, max) = bt_fixed::Widths::for_coord(bits).coord_range();
    let r3 = 1.0 / 3f64.sqrt();
    let normals = [
        [r3, r3, r3],
        [-r3, r3, -r3],
        [1.0, 0.0, 0.0],
        [0.6, -0.8, 0.0],
    ];
    let offsets = [min, max, 0].map(FineCoord);
    let mut planes = Vec::new();
    for normal in normals {
        for offset in offsets {
            let mut plane = FixedPlane::quantize(normal, 0.0).unwrap();
            plane.offset = offset;
            planes.push(plane);
        }
    }
    planes
}

/// Every point whose three axes take values of `values`, x varying fastest.
pub fn grid_points(values: &[FineCoord]) -> Vec<FinePoint> {
    let n = values.len();
    (0..n.pow(3))
        .map(|b| std::array::from_fn(|k| values[(b / n.pow(k as u32)) % n]))
        .collect()
}

/// The corner cases at `bits`-bit coordinates: every [`corner_planes`] plane with both points
/// on the [`grid_points`] of the coordinate range's minimum and maximum (and zero if
/// `with_zero`), planes outermost, then the previous point, then the next.
pub fn corner_cases(bits: u32, with_zero: bool) -> Vec<(FixedPlane, FinePoint, FinePoint)> {
    let (min, max) = bt_fixed::Widths::for_coord(bits).coord_range();
    let values = [min, max, 0].map(FineCoord);
    let points = grid_points(&values[..if with_zero { 3 } else { 2 }]);
    let mut cases = Vec::new();
    for plane in corner_planes(bits) {
        for &prev in &points {
            for &next in &points {
                cases.push((plane, prev, next));
            }
        }
    }
    cases
}

/// `round_half_up(num / 2^shift)` computed by exact Euclidean division (the oracle).
pub fn oracle_round(num: i128, shift: u32) -> i128 {
    if shift == 0 {
        return num;
    }
    // floor((2·num + 2^shift) / 2^(shift+1))
    (2 * num + (1i128 << shift)).div_euclid(1i128 << (shift + 1))
}
