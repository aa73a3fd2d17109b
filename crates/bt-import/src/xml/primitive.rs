//! Mitsuba's planar primitives, `<shape type="rectangle">` and `<shape type="cube">`, as
//! polygon soups in their object frame (metres before `to_world`), with Mitsuba's extents:
//! the rectangle `[-1, 1]²` at `z = 0` (normal `+z`), the cube `[-1, 1]³`.

use super::Primitive;
use bt_geom::Vec3;
use bt_mesh::RawMesh;

/// The cube's faces as corners `k` (corner `k` is `(x, y, z)` with `x` from bit 0, `y` from
/// bit 1 and `z` from bit 2, a set bit `+1`, a clear one `−1`), counter-clockwise seen from
/// outside: −x, +x, −y, +y, −z, +z.
const CUBE_FACES: [[u32; 4]; 6] = [
    [0, 4, 6, 2],
    [1, 3, 7, 5],
    [0, 1, 5, 4],
    [2, 6, 7, 3],
    [0, 2, 3, 1],
    [4, 5, 7, 6],
];

/// The polygons of `primitive` in its object frame (one quadrilateral per face).
pub(super) fn mesh(primitive: Primitive) -> RawMesh {
    let mut raw = RawMesh::new();
    match primitive {
        Primitive::Rectangle => {
            raw.positions = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(x, y)| Vec3::new(x, y, 0.0))
                .to_vec();
            raw.push_face(&[0, 1, 2, 3], None, None);
        }
        Primitive::Cube => {
            let sign = |k: u32, bit: u32| if k >> bit & 1 == 1 { 1.0 } else { -1.0 };
            raw.positions = (0..8)
                .map(|k| Vec3::new(sign(k, 0), sign(k, 1), sign(k, 2)))
                .collect();
            for face in &CUBE_FACES {
                raw.push_face(face, None, None);
            }
        }
    }
    raw
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Newell's normal of face `f` of `raw`, not normalised.
    fn normal(raw: &RawMesh, f: usize) -> Vec3 {
        let face = raw.face(f);
        let at = |i: usize| raw.positions[face[i % face.len()] as usize];
        (0..face.len()).map(|i| at(i).cross(at(i + 1))).sum()
    }

    #[test]
    fn the_rectangle_faces_plus_z_and_spans_minus_one_to_one() {
        let raw = mesh(Primitive::Rectangle);
        assert_eq!(raw.face_count(), 1);
        assert_eq!(normal(&raw, 0), Vec3::new(0.0, 0.0, 8.0));
    }

    #[test]
    fn every_cube_face_is_a_unit_square_facing_out_through_its_own_side() {
        let raw = mesh(Primitive::Cube);
        assert_eq!(raw.face_count(), 6);
        for f in 0..6 {
            let n = normal(&raw, f);
            // Area 4 (Newell's sum is twice the area times the unit normal).
            assert_eq!(n.length(), 8.0, "face {f}");
            for &v in raw.face(f) {
                // Every corner lies on the face's own side of the cube.
                assert_eq!(raw.positions[v as usize].dot(n / 8.0), 1.0, "face {f}");
            }
        }
    }
}
