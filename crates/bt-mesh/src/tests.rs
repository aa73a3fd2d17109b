//! The merge on small synthetic meshes: grounds with building footprints, rings, fans, strips,
//! duplicates. Each case checks that nothing is lost or filled: the surfaces' areas add up to
//! the (deduplicated) triangles', no warning says a face was skipped or a hole filled, every
//! surface is a polygon the scene accepts, and a point lies in as many surfaces as triangles.

use bt_geom::poly2::{contains, first_crossing, is_simple};
use bt_geom::{Polygon, Real, Vec2, Vec3};
use proptest::prelude::*;
use std::collections::HashSet;

use crate::{MergeOptions, MeshImport, RawMesh, merge_mesh};

/// Words of warnings that mean geometry was dropped or invented.
const LOSSY_WORDS: &[&str] = &["skipped", "filled", "ignored", "no closed boundary"];

fn raw(points: &[[Real; 3]], faces: &[Vec<u32>]) -> RawMesh {
    let mut mesh = RawMesh::new();
    mesh.positions = points.iter().map(|&p| Vec3::from(p)).collect();
    for f in faces {
        mesh.push_face(f, None, None);
    }
    mesh
}

fn merged(mesh: &RawMesh) -> MeshImport {
    merge_mesh(mesh, &MergeOptions::default(), "test.obj").expect("default options are valid")
}

/// The mesh's triangles (polygon faces fanned), each coincident set once (by vertex
/// positions, either winding), zero-area ones left out.
fn triangles(mesh: &RawMesh) -> Vec<[Vec3; 3]> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for f in 0..mesh.face_count() {
        let vs = mesh.face(f);
        for k in 1..vs.len() - 1 {
            let tri = [vs[0], vs[k], vs[k + 1]].map(|i| mesh.positions[i as usize]);
            let mut key = tri.map(|p| p.to_array().map(Real::to_bits));
            key.sort_unstable();
            if (tri[1] - tri[0]).cross(tri[2] - tri[0]).length() > 1e-12 && seen.insert(key) {
                out.push(tri);
            }
        }
    }
    out
}

fn triangle_area(t: &[Vec3; 3]) -> Real {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// Everything a lossless merge promises, for any mesh.
fn assert_lossless(mesh: &RawMesh, import: &MeshImport) {
    for w in &import.warnings {
        assert!(
            !LOSSY_WORDS.iter().any(|word| w.contains(word)),
            "lossy warning: {w}"
        );
    }
    let expected: Real = triangles(mesh).iter().map(triangle_area).sum();
    let got: Real = import.surfaces.iter().map(|s| s.area_m2).sum();
    assert!(
        (got - expected).abs() <= 1e-9 * expected,
        "area {got} m², triangles {expected} m²: {:#?}",
        import.surfaces
    );
    let mut names = HashSet::new();
    for s in &import.surfaces {
        assert!(names.insert(&s.name), "duplicate name {}", s.name);
        let polygon = Polygon::new(s.vertices.clone())
            .unwrap_or_else(|e| panic!("{}: not a valid polygon: {e}", s.name));
        assert!((polygon.area() - s.area_m2).abs() <= 1e-9 * s.area_m2);
        let local = polygon.local_vertices();
        assert!(
            is_simple(local) && first_crossing(local).is_none(),
            "{}",
            s.name
        );
    }
}

/// For meshes in the plane z = 0: at sample points off every edge, the number of surfaces
/// containing the point equals the number of triangles containing it (0 in a hole).
fn assert_same_cover(mesh: &RawMesh, import: &MeshImport, samples: &[Vec2]) {
    let flat = |vs: &[Vec3]| -> Vec<Vec2> { vs.iter().map(|v| v.truncate()).collect() };
    let tris: Vec<Vec<Vec2>> = triangles(mesh).iter().map(|t| flat(t)).collect();
    let surfaces: Vec<Vec<Vec2>> = import.surfaces.iter().map(|s| flat(&s.vertices)).collect();
    for &p in samples {
        let in_triangles = tris.iter().filter(|t| contains(t, p)).count();
        let in_surfaces = surfaces.iter().filter(|s| contains(s, p)).count();
        assert_eq!(in_surfaces, in_triangles, "point {p}");
    }
}

/// Points on a fine grid over `[lo, hi]²`, offset so that none lies on a mesh edge of the
/// cases here (edges on multiples of 0.25 and their diagonals).
fn samples(lo: Real, hi: Real) -> Vec<Vec2> {
    let steps = ((hi - lo) / 0.1) as usize;
    let mut out = Vec::new();
    for i in 0..=steps {
        for j in 0..=steps {
            out.push(Vec2::new(
                lo + 0.0123 + i as Real * 0.1,
                lo + 0.0371 + j as Real * 0.1,
            ));
        }
    }
    out
}

/// A grid of `nx` × `ny` unit cells at z = 0, two triangles per cell, without the `missing`
/// cells `(i, j)`.
fn grid_without(nx: u32, ny: u32, missing: &[(u32, u32)]) -> RawMesh {
    let points: Vec<[Real; 3]> = (0..=ny)
        .flat_map(|j| (0..=nx).map(move |i| [Real::from(i), Real::from(j), 0.0]))
        .collect();
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            if !missing.contains(&(i, j)) {
                let k = j * (nx + 1) + i;
                faces.push(vec![k, k + 1, k + nx + 2]);
                faces.push(vec![k, k + nx + 2, k + nx + 1]);
            }
        }
    }
    raw(&points, &faces)
}

#[test]
fn ground_with_a_footprint_is_split_not_filled() {
    // Outer square 0..3, footprint 1..2, triangulated as a ring of eight triangles.
    let points = [
        [0.0, 0.0, 0.0],
        [3.0, 0.0, 0.0],
        [3.0, 3.0, 0.0],
        [0.0, 3.0, 0.0],
        [1.0, 1.0, 0.0],
        [2.0, 1.0, 0.0],
        [2.0, 2.0, 0.0],
        [1.0, 2.0, 0.0],
    ];
    let faces = [
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ]
    .map(|f| f.to_vec());
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_same_cover(&mesh, &import, &samples(-0.5, 3.5));
    assert_eq!(import.surfaces.len(), 2, "{:#?}", import.surfaces);
    let total_sources: usize = import.surfaces.iter().map(|s| s.source_faces).sum();
    assert_eq!(total_sources, 8);
    // Both pieces are judged by the ground's area: a small one still reflects.
    assert!(import.surfaces.iter().all(|s| s.region_area_m2 == 8.0));
}

#[test]
fn ground_with_two_footprints_is_split_not_filled() {
    let mesh = grid_without(5, 3, &[(1, 1), (3, 1)]);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_same_cover(&mesh, &import, &samples(-0.5, 5.5));
    assert!(
        (2..=3).contains(&import.surfaces.len()),
        "{:#?}",
        import.surfaces
    );
}

#[test]
fn hole_touching_the_outline_at_a_vertex_is_kept_open() {
    // 3 x 3 grid without the centre cell and the corner cell (2, 2): the hole and the outside
    // meet at the vertex (2, 2).
    let mesh = grid_without(3, 3, &[(1, 1), (2, 2)]);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_same_cover(&mesh, &import, &samples(-0.5, 3.5));
}

#[test]
fn annulus_of_a_triangle_strip_is_split_in_two() {
    let n = 16u32;
    let ring = |r: Real, k: u32| {
        let a = Real::from(k) * std::f64::consts::TAU / Real::from(n);
        [r * a.cos(), r * a.sin(), 0.0]
    };
    let points: Vec<[Real; 3]> = (0..n)
        .map(|k| ring(2.0, k))
        .chain((0..n).map(|k| ring(1.0, k)))
        .collect();
    let faces: Vec<Vec<u32>> = (0..n)
        .flat_map(|k| {
            let next = (k + 1) % n;
            [vec![k, next, n + next], vec![k, n + next, n + k]]
        })
        .collect();
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_same_cover(&mesh, &import, &samples(-2.5, 2.5));
    assert_eq!(import.surfaces.len(), 2, "{:#?}", import.surfaces);
}

#[test]
fn three_triangles_on_one_edge_each_stay() {
    // Edge (0,0,0)-(1,0,0): two coplanar triangles on either side and a perpendicular fin.
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.5, 1.0, 0.0],
        [0.5, -1.0, 0.0],
        [0.5, 0.0, 1.0],
    ];
    let faces = [vec![0, 1, 2], vec![1, 0, 3], vec![0, 1, 4]];
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_eq!(import.surfaces.len(), 2);
    // A third coplanar triangle on the same side as the first overlaps it: a surface of its
    // own, not a reason to drop the region.
    let mut faces = faces.to_vec();
    faces[2] = vec![0, 1, 4];
    let mut points = points.to_vec();
    points[4] = [0.5, 0.5, 0.0];
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_same_cover(&mesh, &import, &samples(-0.5, 1.5));
}

#[test]
fn overlapping_walls_with_a_t_junction_keep_every_face() {
    // As in Sionna's Munich (Alter_Hof): a gable wall (0, 1, 5, 6, 4 up to the ridge 6) and a
    // lower wall (0, 1, 3, 2) drawn over it in the same plane x = 0, sharing the edge 0-1 in
    // the same direction; vertex 2 lies on the gable's edge 4-0.
    let points = [
        [0.0, 0.0, 0.0],
        [0.0, 4.0, 0.0],
        [0.0, 0.0, 2.0],
        [0.0, 4.0, 2.0],
        [0.0, 0.0, 3.0],
        [0.0, 4.0, 3.0],
        [0.0, 2.0, 4.0],
    ];
    let faces = [
        vec![0, 1, 3],
        vec![0, 3, 2],
        vec![4, 0, 1],
        vec![1, 5, 6],
        vec![1, 6, 4],
    ];
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_eq!(import.surfaces.len(), 2, "{:#?}", import.surfaces);
}

#[test]
fn ring_closed_by_a_t_junction_splits_where_it_touches() {
    // Bottom B, left L, top T and right R around a hole; R's bottom edge lies inside B's top
    // edge (no shared vertex): connected B-L-T-R, but the union's boundary touches itself.
    let points = [
        [0.0, 0.0, 0.0],
        [3.0, 0.0, 0.0],
        [3.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 2.0, 0.0],
        [0.0, 2.0, 0.0],
        [2.0, 2.0, 0.0],
        [2.0, 3.0, 0.0],
        [0.0, 3.0, 0.0],
        [2.0, 1.0, 0.0],
        [2.8, 1.0, 0.0],
        [2.8, 3.0, 0.0],
    ];
    let faces = [
        vec![0, 1, 2, 3, 4],
        vec![4, 3, 5, 6],
        vec![6, 5, 7, 8, 9],
        vec![10, 11, 12, 8, 7],
    ];
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_same_cover(&mesh, &import, &samples(-0.5, 3.5));
    let areas: Vec<Real> = import.surfaces.iter().map(|s| s.area_m2).collect();
    assert_eq!(areas.len(), 2, "{:#?}", import.surfaces);
    assert!((areas[0] - 6.0).abs() < 1e-12 && (areas[1] - 1.6).abs() < 1e-12);
    assert!(
        import
            .surfaces
            .iter()
            .all(|s| (s.region_area_m2 - 7.6).abs() < 1e-12)
    );
}

#[test]
fn open_strip_keeps_every_face() {
    // A zig-zag strip along x bent up at x = 2: floor triangles, then a wall.
    let points = [
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 1.0, 0.0],
        [2.0, 0.0, 1.0],
        [2.0, 1.0, 1.0],
    ];
    let faces: Vec<Vec<u32>> = (0..6u32)
        .map(|k| {
            if k % 2 == 0 {
                vec![k, k + 2, k + 1]
            } else {
                vec![k, k + 1, k + 2]
            }
        })
        .collect();
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_eq!(import.surfaces.len(), 2, "{:#?}", import.surfaces);
}

#[test]
fn duplicated_faces_are_merged_with_a_warning() {
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    // The two triangles of a unit square, the first again, and the second again reversed.
    let faces = [vec![0, 1, 2], vec![0, 2, 3], vec![1, 2, 0], vec![3, 2, 0]];
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_eq!(import.surfaces.len(), 1);
    assert_eq!(import.surfaces[0].area_m2, 1.0);
    assert!(
        import
            .warnings
            .iter()
            .any(|w| w.starts_with("test.obj: 2 duplicate faces")),
        "{:?}",
        import.warnings
    );
}

#[test]
fn concave_l_region_stays_one_polygon() {
    let mesh = grid_without(2, 2, &[(1, 1)]);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_same_cover(&mesh, &import, &samples(-0.5, 2.5));
    assert_eq!(import.surfaces.len(), 1);
    assert_eq!(import.surfaces[0].vertices.len(), 6);
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
}

#[test]
fn output_does_not_depend_on_hash_order() {
    let mesh = grid_without(6, 5, &[(1, 1), (3, 1), (2, 3), (4, 3), (5, 4)]);
    let first = merged(&mesh);
    assert_lossless(&mesh, &first);
    for _ in 0..4 {
        assert_eq!(merged(&mesh), first);
    }
}

/// Thousands of different coplanar triangles on one edge (all on the same side, overlapping):
/// each is kept, in linear time (a regression would show as a hang, not a failed assertion).
#[test]
fn many_faces_on_one_edge_split_in_linear_time() {
    let n = 20_000u32;
    let mut points = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
    points.extend((0..n).map(|k| [0.5, 1.0 + Real::from(k) * 1e-3, 0.0]));
    let faces: Vec<Vec<u32>> = (0..n).map(|k| vec![0, 1, k + 2]).collect();
    let mesh = raw(&points, &faces);
    let import = merged(&mesh);
    assert_lossless(&mesh, &import);
    assert_eq!(import.surfaces.len(), n as usize);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random triangles over a grid on the floor and a wall (shared, overlapping, flipped,
    /// duplicated and non-manifold faces): the merge is lossless.
    #[test]
    fn random_soups_lose_nothing(
        picks in prop::collection::vec((0u32..32, 0u32..32, 0u32..32), 1..40),
    ) {
        let points: Vec<[Real; 3]> = (0..32u32)
            .map(|k| {
                let (i, j) = (Real::from(k % 4), Real::from((k / 4) % 4));
                if k < 16 { [i, j, 0.0] } else { [0.0, i, j] }
            })
            .collect();
        let faces: Vec<Vec<u32>> = picks.iter().map(|&(a, b, c)| vec![a, b, c]).collect();
        let mesh = raw(&points, &faces);
        let import = merged(&mesh);
        assert_lossless(&mesh, &import);
    }

    /// Random triangles over a 5 x 5 grid in one plane, overlapping and with holes: every
    /// sample point lies in as many surfaces as triangles.
    #[test]
    fn random_floor_soups_cover_the_same_points(
        picks in prop::collection::vec((0u32..25, 0u32..25, 0u32..25), 1..30),
    ) {
        let points: Vec<[Real; 3]> = (0..25u32)
            .map(|k| [Real::from(k % 5), Real::from(k / 5), 0.0])
            .collect();
        let faces: Vec<Vec<u32>> = picks.iter().map(|&(a, b, c)| vec![a, b, c]).collect();
        let mesh = raw(&points, &faces);
        let import = merged(&mesh);
        assert_lossless(&mesh, &import);
        assert_same_cover(&mesh, &import, &samples(-0.5, 4.5));
    }
}

/// The merge of `mesh` cut into parallel work as `parallel` says, as text that shows every
/// bit of the surfaces (`Debug` prints an `f64` as the shortest text that reads back to it)
/// and the warnings in order.
fn merged_text(mesh: &RawMesh, parallel: crate::merge::Parallel) -> String {
    let merged = crate::merge::merge_with(mesh, &MergeOptions::default(), "test.ply", parallel);
    format!("{:?}\n{:?}", merged.surfaces, merged.warnings)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Polygon soups of triangles to hexagons over a wobbly grid (non-planar and self-touching
    /// polygons split into fans, degenerate faces, duplicates in either winding): the merge cut
    /// into tiny pieces of parallel work gives the merge in one piece, to the bit.
    #[test]
    fn parallel_pieces_merge_as_one(
        picks in prop::collection::vec(prop::collection::vec(0u32..36, 3..7), 1..60),
        wobble in prop_oneof![Just(0.0), 1e-4f64..0.2],
        faces in 1usize..5,
    ) {
        let points: Vec<[Real; 3]> = (0..36u32)
            .map(|k| {
                let (i, j) = (Real::from(k % 6), Real::from(k / 6));
                [i, j, wobble * Real::from((k * 7) % 5)]
            })
            .collect();
        let mesh = raw(&points, &picks);
        let serial = crate::merge::Parallel { faces: usize::MAX };
        let tiny = crate::merge::Parallel { faces };
        prop_assert_eq!(merged_text(&mesh, tiny), merged_text(&mesh, serial));
    }
}
