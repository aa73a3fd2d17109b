//! Property: a rigidly moved box room still gives six surfaces with the moved normals and the
//! same areas, whatever the file format.

use crate::mesh::common::*;
use bt_import::mesh::{read_obj, read_ply};
use bt_mesh::MergeOptions;
use glam::{DQuat, DVec3};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn rotated_box_keeps_six_surfaces_and_total_area(
        axis in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
        angle in 0.0..std::f64::consts::TAU,
        shift in (-100.0..100.0f64, -100.0..100.0f64, -100.0..100.0f64),
        format in 0usize..4,
        quads in any::<bool>(),
    ) {
        let axis = DVec3::new(axis.0, axis.1, axis.2).try_normalize().unwrap_or(DVec3::Z);
        let rotation = DQuat::from_axis_angle(axis, angle);
        let shift = DVec3::new(shift.0, shift.1, shift.2);
        let vertices: Vec<DVec3> = box_vertices().iter().map(|&v| rotation * v + shift).collect();
        let faces = if quads { box_quads() } else { triangulate(&box_quads()) };
        let opts = MergeOptions::default();
        // Tolerance by storage precision: f64 text, 6 decimals, f32 binary, f64 binary.
        let (import, tol) = match format {
            0 => (read_obj(obj_text(&vertices, &faces).as_bytes(), None, &opts), 1e-9),
            1 => (read_obj(obj_text_per_face(&vertices, &faces, 6).as_bytes(), None, &opts), 1e-5),
            2 => (read_ply(&ply_binary_le(&vertices, &faces), None, &opts), 1e-4),
            _ => (read_ply(&ply_binary_be(&vertices, &faces), None, &opts), 1e-9),
        };
        let import = import.unwrap();
        prop_assert_eq!(import.surfaces.len(), 6, "{:?}", import.warnings);
        let expected = box_expected();
        let total: f64 = import.surfaces.iter().map(|s| s.area_m2).sum();
        let expected_total: f64 = expected.iter().map(|e| e.1).sum();
        prop_assert!((total - expected_total).abs() < tol * expected_total, "total {}", total);
        for (s, (normal, area)) in import.surfaces.iter().zip(expected) {
            prop_assert_eq!(s.vertices.len(), 4);
            prop_assert!(s.normal.distance(rotation * normal) < tol, "{}: {}", s.name, s.normal);
            prop_assert!((s.area_m2 - area).abs() < tol * area, "{}: {}", s.name, s.area_m2);
            // The polygon corners are the moved box corners.
            for v in &s.vertices {
                prop_assert!(vertices.iter().any(|c| c.distance(*v) < 1e3 * tol));
            }
        }
    }
}
