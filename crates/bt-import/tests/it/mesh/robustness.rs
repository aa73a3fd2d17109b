//! Properties: arbitrary input never panics, and whatever comes out is well formed.

use crate::mesh::common::*;
use bt_import::mesh::{read_obj, read_ply, read_stl};
use bt_mesh::MergeOptions;
use glam::DVec3;
use proptest::prelude::*;

/// Grid points on the floor z = 0 and the wall x = 0 (shared column at x = 0, z = 0).
fn grid_point(k: usize) -> DVec3 {
    let (i, j) = ((k % 4) as f64, ((k / 4) % 4) as f64);
    if k < 16 {
        DVec3::new(i, j, 0.0)
    } else {
        DVec3::new(0.0, i, j)
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Random triangle soups with shared, overlapping, flipped and non-manifold faces.
    #[test]
    fn random_soups_give_well_formed_surfaces(
        triangles in prop::collection::vec((0usize..32, 0usize..32, 0usize..32), 1..40),
    ) {
        let vertices: Vec<DVec3> = (0..32).map(grid_point).collect();
        let faces: Vec<Vec<usize>> = triangles.iter().map(|&(a, b, c)| vec![a, b, c]).collect();
        let import = read_obj(obj_text(&vertices, &faces).as_bytes(), None, &MergeOptions::default())
            .unwrap();
        prop_assert_eq!(import.faces_read, faces.len());
        let mut names = std::collections::HashSet::new();
        for s in &import.surfaces {
            prop_assert!(s.vertices.len() >= 3);
            prop_assert!(s.area_m2 > 0.0 && s.area_m2.is_finite());
            prop_assert!(s.vertices.iter().all(|v| v.is_finite()));
            prop_assert!(names.insert(s.name.clone()), "duplicate name {}", s.name);
            assert_polygon_consistent(s, 1e-9);
        }
    }

    /// Arbitrary bytes, with or without a plausible PLY header, are an error or a result.
    #[test]
    fn arbitrary_bytes_do_not_panic(
        body in prop::collection::vec(any::<u8>(), 0..200),
        count in any::<u64>(),
        binary in any::<bool>(),
    ) {
        let _ = read_obj(&body, None, &MergeOptions::default());
        let _ = read_ply(&body, None, &MergeOptions::default());
        let _ = read_stl(&body, None, &MergeOptions::default());
        // A binary STL whose size fits the count it claims.
        let n = body.len() / 50;
        let mut stl = vec![b' '; 80];
        stl.extend_from_slice(&(n as u32).to_le_bytes());
        stl.extend_from_slice(&body[..50 * n]);
        let _ = read_stl(&stl, None, &MergeOptions::default());
        let format = if binary { "binary_little_endian" } else { "ascii" };
        let mut ply = format!(
            "ply\nformat {format} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {count}\nproperty list uchar int vertex_indices\nend_header\n",
            count % 16
        )
        .into_bytes();
        ply.extend_from_slice(&body);
        let _ = read_ply(&ply, None, &MergeOptions::default());
    }
}

/// Found by fuzzing: one triangle repeated thousands of times made coplanar merging quadratic
/// in the faces sharing an edge (8,000 copies took 23 s; 20,000 would take minutes). Now
/// linear: this finishes in milliseconds. (Not a timed assertion: a regression shows as a hang.)
#[test]
fn many_faces_on_one_edge_merge_in_linear_time() {
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for _ in 0..20_000 {
        obj.push_str("f 1 2 3\n");
    }
    let import =
        bt_import::mesh::read_obj(obj.as_bytes(), None, &bt_mesh::MergeOptions::default()).unwrap();
    assert_eq!(import.faces_read, 20_000);
    assert!(
        import.surfaces.len() <= 1,
        "identical triangles give at most one surface"
    );
}
