//! Mesh files to surfaces: formats, coplanar merging, concave outlines, bad input.

use crate::mesh::common::*;
use bt_import::mesh::{MeshError, Position, read_mesh_path, read_obj, read_ply};
use bt_mesh::{MergeError, MergeOptions, MeshImport};
use glam::{DVec2, DVec3};

const TOL: f64 = 1e-9;

fn opts() -> MergeOptions {
    MergeOptions::default()
}

#[test]
fn box_of_triangles_gives_six_surfaces() {
    let text = obj_text(&box_vertices(), &triangulate(&box_quads()));
    let import = read_obj(text.as_bytes(), Some("box.obj"), &opts()).unwrap();
    assert_eq!(import.faces_read, 12);
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
    assert_surfaces(&import, &box_expected(), TOL);
    for (k, s) in import.surfaces.iter().enumerate() {
        assert_eq!(s.vertices.len(), 4);
        assert_eq!(s.source_faces, 2);
        assert_eq!(s.name, format!("face_{k}"));
        assert_eq!(s.material, None);
    }
}

#[test]
fn box_of_quads_gives_the_same_surfaces() {
    let text = obj_text(&box_vertices(), &box_quads());
    let import = read_obj(text.as_bytes(), None, &opts()).unwrap();
    assert_surfaces(&import, &box_expected(), TOL);
    assert!(import.surfaces.iter().all(|s| s.source_faces == 1));
}

#[test]
fn exporter_style_obj_with_duplicated_rounded_vertices_is_welded() {
    let text = obj_text_per_face(&box_vertices(), &triangulate(&box_quads()), 6);
    let import = read_obj(text.as_bytes(), Some("room.obj"), &opts()).unwrap();
    assert_surfaces(&import, &box_expected(), 1e-6);
    let names: Vec<&str> = import.surfaces.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        ["Room_0", "Room_1", "Room_2", "Room_3", "Room_4", "Room_5"]
    );
}

#[test]
fn ply_ascii_and_binary_give_the_same_surfaces() {
    let (v, f) = (box_vertices(), triangulate(&box_quads()));
    let ascii = read_ply(ply_ascii(&v, &f).as_bytes(), Some("box.ply"), &opts()).unwrap();
    assert_surfaces(&ascii, &box_expected(), TOL);
    let le = read_ply(&ply_binary_le(&v, &f), Some("box_le.ply"), &opts()).unwrap();
    let be = read_ply(&ply_binary_be(&v, &f), Some("box_be.ply"), &opts()).unwrap();
    for binary in [&le, &be] {
        assert_eq!(binary.faces_read, 12);
        assert_eq!(binary.surfaces.len(), ascii.surfaces.len());
        for (a, b) in ascii.surfaces.iter().zip(&binary.surfaces) {
            assert_eq!(a.name, b.name);
            assert_eq!(a.vertices.len(), b.vertices.len());
            // f32 storage in the little-endian file: 2.6 is stored to ~1e-7.
            for (p, q) in a.vertices.iter().zip(&b.vertices) {
                assert!(p.distance(*q) < 1e-6, "{p} vs {q}");
            }
            assert!((a.area_m2 - b.area_m2).abs() < 1e-5);
            assert!(a.normal.distance(b.normal) < 1e-6);
        }
    }
}

#[test]
fn ply_ascii_without_final_newline_and_with_crlf_header() {
    let text = "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\nelement face 1\r\nproperty list uchar uint vertex_index\r\nend_header\r\n0 0 0\n2 0 0\n0 2 0\n3 0 1 2";
    let import = read_ply(text.as_bytes(), None, &opts()).unwrap();
    assert_surfaces(&import, &[(DVec3::Z, 2.0)], TOL);
}

/// A wall in the plane y = 0 with a 0.9 x 2.1 m door notch, from eight triangles.
#[test]
fn wall_with_door_notch_is_one_concave_polygon() {
    let xz = [
        (0.0, 0.0),
        (1.0, 0.0),
        (1.0, 2.1),
        (1.0, 2.6),
        (0.0, 2.6),
        (1.9, 2.1),
        (1.9, 2.6),
        (4.0, 0.0),
        (4.0, 2.6),
        (1.9, 0.0),
    ];
    let vertices: Vec<DVec3> = xz.iter().map(|&(x, z)| DVec3::new(x, 0.0, z)).collect();
    let faces = [
        [0, 1, 2],
        [0, 2, 3],
        [0, 3, 4],
        [2, 5, 6],
        [2, 6, 3],
        [7, 8, 6],
        [7, 6, 5],
        [7, 5, 9],
    ]
    .map(|f| f.to_vec());
    let text = obj_text_per_face(&vertices, &faces, 6);
    let import = read_obj(text.as_bytes(), None, &opts()).unwrap();
    assert_surfaces(&import, &[(DVec3::NEG_Y, 4.0 * 2.6 - 0.9 * 2.1)], 1e-9);
    let wall = &import.surfaces[0];
    assert_eq!(wall.vertices.len(), 8, "{:?}", wall.vertices);
    assert_eq!(wall.source_faces, 8);
    // Every outline corner is one of the notched wall's corners.
    let corners = [
        (0.0, 0.0),
        (1.0, 0.0),
        (1.0, 2.1),
        (1.9, 2.1),
        (1.9, 0.0),
        (4.0, 0.0),
        (4.0, 2.6),
        (0.0, 2.6),
    ];
    for v in &wall.vertices {
        assert!(
            corners
                .iter()
                .any(|&(x, z)| DVec2::new(v.x, v.z).distance(DVec2::new(x, z)) < 1e-9),
            "unexpected vertex {v}"
        );
    }
}

#[test]
fn coplanar_faces_that_do_not_share_an_edge_stay_separate() {
    // Two disjoint triangles, and a third touching the second only at a corner.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 3 0 0\nv 4 0 0\nv 3 1 0\nv 5 1 0\nv 4 1 0\n\
                f 1 2 3\nf 4 5 6\nf 5 7 8\n";
    let import = read_obj(text.as_bytes(), None, &opts()).unwrap();
    assert_surfaces(
        &import,
        &[(DVec3::Z, 0.5), (DVec3::Z, 0.5), (DVec3::Z, 0.5)],
        TOL,
    );
}

#[test]
fn l_shaped_room_gives_concave_floor_and_ceiling() {
    let h = 2.6;
    // L outline, counter-clockwise seen from +z, with (0, 2) as an extra point on the left side.
    let outline = [
        (0.0, 0.0),
        (6.0, 0.0),
        (6.0, 2.0),
        (3.0, 2.0),
        (3.0, 4.0),
        (0.0, 4.0),
    ];
    let mut vertices: Vec<DVec3> = outline
        .iter()
        .map(|&(x, y)| DVec3::new(x, y, 0.0))
        .collect();
    vertices.extend(outline.iter().map(|&(x, y)| DVec3::new(x, y, h)));
    vertices.push(DVec3::new(0.0, 2.0, 0.0)); // 12
    vertices.push(DVec3::new(0.0, 2.0, h)); // 13
    let floor = vec![
        vec![0, 1, 2],
        vec![0, 2, 3],
        vec![0, 3, 12],
        vec![12, 3, 4],
        vec![12, 4, 5],
    ];
    let ceiling: Vec<Vec<usize>> = floor
        .iter()
        .map(|f| {
            f.iter()
                .rev()
                .map(|&i| if i == 12 { 13 } else { i + 6 })
                .collect()
        })
        .collect();
    let mut faces = floor;
    faces.extend(ceiling);
    let mut expected = vec![(DVec3::Z, 18.0), (DVec3::NEG_Z, 18.0)];
    for i in 0..6 {
        let j = (i + 1) % 6;
        faces.push(vec![i, j, j + 6]);
        faces.push(vec![i, j + 6, i + 6]);
        let d = vertices[j] - vertices[i];
        expected.push((DVec3::new(d.y, -d.x, 0.0).normalize(), d.length() * h));
    }
    let text = obj_text(&vertices, &faces);
    let import = read_obj(text.as_bytes(), None, &opts()).unwrap();
    assert_surfaces(&import, &expected, TOL);
    assert_eq!(import.surfaces[0].vertices.len(), 6);
    assert_eq!(import.surfaces[1].vertices.len(), 6);
}

/// A 3 x 3 grid of unit quads in the plane at height `z`, without the cells `(i, j)` of
/// `missing`: the grid's 16 vertices and the quads, counter-clockwise seen from +z.
fn unit_grid_without(z: f64, missing: &[(usize, usize)]) -> (Vec<DVec3>, Vec<Vec<usize>>) {
    let vertices = (0..16)
        .map(|k| DVec3::new((k % 4) as f64, (k / 4) as f64, z))
        .collect();
    let mut faces = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            if !missing.contains(&(i, j)) {
                let k = j * 4 + i;
                faces.push(vec![k, k + 1, k + 5, k + 4]);
            }
        }
    }
    (vertices, faces)
}

/// Checks that `import` has no warnings, its surfaces are consistent polygons in the plane
/// z = `z` with normal +z holding `area` m² together, and the in-plane point `hole` lies in none.
fn assert_holed_floor(import: &MeshImport, z: f64, area: f64, hole: DVec2) {
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
    let total: f64 = import.surfaces.iter().map(|s| s.area_m2).sum();
    assert!((total - area).abs() < TOL, "area {total}, expected {area}");
    for s in &import.surfaces {
        assert_polygon_consistent(s, TOL);
        assert!(s.normal.distance(DVec3::Z) < TOL);
        assert!(s.vertices.iter().all(|v| (v.z - z).abs() < TOL));
        let flat: Vec<DVec2> = s.vertices.iter().map(|v| v.truncate()).collect();
        assert!(
            !bt_geom::poly2::contains(&flat, hole),
            "{} covers the hole",
            s.name
        );
    }
}

#[test]
fn ring_with_hole_is_split_into_simple_pieces() {
    // 3 x 3 unit grid without its centre cell: a hole is no reflector, so the ring is cut into
    // pieces of its own faces, none covering the hole.
    let (vertices, faces) = unit_grid_without(1.0, &[(1, 1)]);
    let text = format!("o floor\n{}", obj_text(&vertices, &faces));
    let import = read_obj(text.as_bytes(), Some("ring.obj"), &opts()).unwrap();
    assert_holed_floor(&import, 1.0, 8.0, DVec2::new(1.5, 1.5));
    let names: Vec<&str> = import.surfaces.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["floor_0", "floor_1"]);
    assert_eq!(
        import
            .surfaces
            .iter()
            .map(|s| s.source_faces)
            .sum::<usize>(),
        8
    );
}

#[test]
fn pieces_of_a_large_region_reflect() {
    // The ring's pieces are judged by the ring's area, 8 m², not by their own: a threshold
    // above the smaller piece still makes every piece a reflector.
    let (vertices, faces) = unit_grid_without(1.0, &[(1, 1)]);
    let import = read_obj(obj_text(&vertices, &faces).as_bytes(), None, &opts()).unwrap();
    let smallest = import
        .surfaces
        .iter()
        .map(|s| s.area_m2)
        .fold(f64::INFINITY, f64::min);
    assert!(smallest < 7.5, "{:#?}", import.surfaces);
    let options = bt_import::LoadOptions {
        min_reflector_area_m2: smallest + 0.5,
        ..Default::default()
    };
    let loaded = bt_import::mesh::scene::from_mesh(import, "ring", "ring.obj", &options).unwrap();
    assert_eq!(loaded.scene.surfaces().len(), 2);
    assert!(
        loaded
            .scene
            .surfaces()
            .iter()
            .all(|s| s.kind == bt_scene::SurfaceKind::Reflector)
    );
}

#[test]
fn hole_touching_the_outline_at_a_vertex_is_kept_open() {
    // 3 x 3 unit grid without the centre cell (1, 1) and the corner cell (2, 2): the hole and
    // the outer boundary meet at the vertex (2, 2).
    let (vertices, faces) = unit_grid_without(0.0, &[(1, 1), (2, 2)]);
    let import = read_obj(
        obj_text(&vertices, &triangulate(&faces)).as_bytes(),
        None,
        &opts(),
    )
    .unwrap();
    assert_holed_floor(&import, 0.0, 7.0, DVec2::new(1.5, 1.5));
    assert!(import.surfaces.len() <= 2, "{:#?}", import.surfaces);
}

#[test]
fn materials_and_objects_split_surfaces() {
    let text = "mtllib missing.mtl\no slab\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                usemtl concrete\nf 1 2 3\nusemtl glass\nf 1 3 4\n";
    let import = read_obj(text.as_bytes(), None, &opts()).unwrap();
    assert_surfaces(&import, &[(DVec3::Z, 0.5), (DVec3::Z, 0.5)], TOL);
    assert_eq!(import.surfaces[0].name, "slab_0");
    assert_eq!(import.surfaces[0].material.as_deref(), Some("concrete"));
    assert_eq!(import.surfaces[1].name, "slab_1");
    assert_eq!(import.surfaces[1].material.as_deref(), Some("glass"));
}

#[test]
fn bent_faces_merge_only_within_angle_and_distance_tolerances() {
    // Two unit triangles sharing an edge, folded by `deg`; the far vertex rises tan(deg) m.
    let loose = MergeOptions {
        dist_tol_m: 0.1,
        ..MergeOptions::default()
    };
    for (deg, options, expected) in [(2.0f64, loose, 2), (0.5, loose, 1), (0.5, opts(), 2)] {
        let z = deg.to_radians().tan();
        let text = format!("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 {z}\nf 1 2 3\nf 1 3 4\n");
        let import = read_obj(text.as_bytes(), None, &options).unwrap();
        assert_eq!(
            import.surfaces.len(),
            expected,
            "fold {deg} deg, {options:?}"
        );
        for s in &import.surfaces {
            assert_polygon_consistent(s, 1e-9);
        }
    }
}

#[test]
fn degenerate_faces_are_dropped_with_a_warning() {
    let mut text = obj_text(&box_vertices(), &triangulate(&box_quads()));
    // A zero-area triangle on the floor edge and one with a repeated vertex.
    text += "v 2 0 0\nf 1 9 2\nf 1 1 2\n";
    let import = read_obj(text.as_bytes(), None, &opts()).unwrap();
    assert_eq!(import.faces_read, 14);
    assert_surfaces(&import, &box_expected(), TOL);
    assert!(
        import.warnings.iter().any(|w| w.contains("2 degenerate")),
        "{:?}",
        import.warnings
    );
}

#[test]
fn non_manifold_edges_do_not_crash() {
    // Edge (0,0,0)-(1,0,0) shared by two coplanar triangles, a perpendicular fin and an
    // overlapping coplanar triangle.
    let text = "v 0 0 0\nv 1 0 0\nv 0.5 1 0\nv 0.5 -1 0\nv 0.5 0 1\nv 0.5 0.5 0\n\
                f 1 2 3\nf 2 1 4\nf 1 2 5\nf 1 2 6\n";
    let import = read_obj(text.as_bytes(), None, &opts()).unwrap();
    assert!(!import.surfaces.is_empty());
    for s in &import.surfaces {
        assert_polygon_consistent(s, 1e-9);
    }
    assert!(
        import
            .surfaces
            .iter()
            .any(|s| s.normal.distance(DVec3::NEG_Y) < 1e-12)
    );
}

#[test]
fn non_planar_quad_is_split() {
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0.1\nv 0 1 0\nf 1 2 3 4\n";
    let import = read_obj(text.as_bytes(), None, &opts()).unwrap();
    assert_eq!(import.surfaces.len(), 2);
    assert!(import.warnings.iter().any(|w| w.contains("non-planar")));
}

const MAX_BYTES: u64 = bt_import::MAX_FILE_BYTES.limit;

#[test]
fn read_mesh_path_dispatches_on_extension() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata");
    let import = read_mesh_path(&dir.join("box_quads.OBJ"), &opts(), MAX_BYTES).unwrap();
    assert_surfaces(&import, &box_expected(), TOL);
    let import = read_mesh_path(&dir.join("box_triangles.ply"), &opts(), MAX_BYTES).unwrap();
    assert_surfaces(&import, &box_expected(), 1e-6);
    match read_mesh_path(&dir.join("room.dae"), &opts(), MAX_BYTES) {
        Err(MeshError::UnsupportedExtension { extension, .. }) => assert_eq!(extension, "dae"),
        other => panic!("unexpected {other:?}"),
    }
    match read_mesh_path(&dir.join("missing.obj"), &opts(), MAX_BYTES) {
        Err(e @ MeshError::Io { .. }) => assert!(e.to_string().contains("missing.obj")),
        other => panic!("unexpected {other:?}"),
    }
    // A file over the byte budget is refused from its size, before it is read.
    let e = read_mesh_path(&dir.join("box_quads.OBJ"), &opts(), 10).unwrap_err();
    let e = e.to_string();
    assert!(
        e.contains("box_quads.OBJ") && e.contains("more than the budget of 10"),
        "{e}"
    );
    assert!(e.contains("--max-file-bytes"), "{e}");
}

#[test]
fn invalid_options_are_rejected() {
    let bad = MergeOptions {
        angle_tol_deg: f64::NAN,
        ..MergeOptions::default()
    };
    assert_matches!(
        read_obj(b"", None, &bad),
        Err(MeshError::Merge(MergeError::InvalidOptions { .. }))
    );
}

// ---------------------------------------------------------------------------------------------
// Bad input: each problem is a specific variant naming the file and the line or element.

fn obj_error(text: &str) -> MeshError {
    read_obj(text.as_bytes(), Some("bad.obj"), &opts()).unwrap_err()
}

fn ply_error(bytes: &[u8]) -> MeshError {
    read_ply(bytes, Some("bad.ply"), &opts()).unwrap_err()
}

#[test]
fn malformed_obj_line() {
    let e = obj_error("v 0 0 0\nv 1 0 0\nv 1 abc 0\nf 1 2 3\n");
    assert_matches!(
        e,
        MeshError::Syntax {
            position: Position::Line(3),
            ..
        }
    );
    let message = e.to_string();
    assert!(
        message.contains("bad.obj: line 3") && message.contains("abc"),
        "{message}"
    );
    let e = obj_error("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2/x 3\n");
    assert_matches!(
        e,
        MeshError::Syntax {
            position: Position::Line(4),
            ..
        }
    );
}

#[test]
fn obj_index_out_of_range() {
    let e = obj_error("v 0 0 0\nv 1 0 0\nv 1 1 0\n\nf 1 2 4\n");
    assert_matches!(
        e,
        MeshError::IndexOutOfRange {
            position: Position::Line(5),
            index: 4,
            vertex_count: 3,
            ..
        }
    );
    assert!(e.to_string().contains("bad.obj: line 5"), "{e}");
    let e = obj_error("v 0 0 0\nv 1 0 0\nf 1 2 -3\n");
    assert_matches!(e, MeshError::IndexOutOfRange { index: -3, .. });
    let e = obj_error("v 0 0 0\nv 1 0 0\nf 0 1 2\n");
    assert_matches!(e, MeshError::IndexOutOfRange { index: 0, .. });
}

#[test]
fn obj_face_with_two_vertices() {
    let e = obj_error("v 0 0 0\nv 1 0 0\nf 1 2\n");
    assert_matches!(
        e,
        MeshError::FaceTooSmall {
            position: Position::Line(3),
            count: 2,
            ..
        }
    );
}

#[test]
fn obj_nan_vertex() {
    let e = obj_error("v 0 0 0\nv 1 NaN 0\n");
    assert_matches!(
        e,
        MeshError::NonFiniteCoordinate {
            position: Position::Line(2),
            axis: 'y',
            ..
        }
    );
    assert!(e.to_string().contains("line 2"));
    assert_matches!(
        obj_error("v inf 0 0\n"),
        MeshError::NonFiniteCoordinate { .. }
    );
}

#[test]
fn ply_with_three_billion_claimed_vertices_is_rejected_before_allocating() {
    let text = "ply\nformat binary_little_endian 1.0\nelement vertex 3000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\0\0\0\0";
    let e = ply_error(text.as_bytes());
    assert_matches!(
        e,
        MeshError::CountTooLarge {
            count: 3_000_000_000,
            body_bytes: 4,
            ..
        }
    );
    assert!(e.to_string().contains("\"vertex\""), "{e}");
    let ascii = text.replace("binary_little_endian", "ascii");
    assert_matches!(ply_error(ascii.as_bytes()), MeshError::CountTooLarge { .. });
    // Lists with a huge count in a small body end in truncation, not allocation.
    let mut huge_list = ply_binary_le(&box_vertices(), &[vec![0, 1, 2]]);
    let n = huge_list.len();
    huge_list.truncate(n - 13);
    huge_list.extend_from_slice(&[0xff; 1]);
    huge_list.extend_from_slice(&[0; 4]);
    assert_matches!(ply_error(&huge_list), MeshError::Truncated { .. });
}

#[test]
fn truncated_binary_ply() {
    let mut bytes = ply_binary_le(&box_vertices(), &triangulate(&box_quads()));
    bytes.truncate(bytes.len() - 5);
    let e = ply_error(&bytes);
    assert_matches!(
        e,
        MeshError::Truncated { position: Position::Element { element, index: 11, line: None }, .. }
            if element == "face"
    );
    assert!(e.to_string().contains("face 11"), "{e}");
    // The count check catches a body too short for the declared element counts outright.
    let header = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    bytes.truncate(header + 100);
    assert_matches!(ply_error(&bytes), MeshError::CountTooLarge { .. });
}

#[test]
fn ply_nan_vertex_and_bad_index() {
    let mut vertices = box_vertices();
    vertices[5].z = f64::NAN;
    let e = ply_error(&ply_binary_le(&vertices, &triangulate(&box_quads())));
    assert_matches!(
        e,
        MeshError::NonFiniteCoordinate {
            position: Position::Element { index: 5, .. },
            axis: 'z',
            ..
        }
    );
    let text = ply_ascii(&box_vertices(), &[vec![0, 1, 2], vec![0, 1, 8]]);
    let e = ply_error(text.as_bytes());
    assert_matches!(
        e,
        MeshError::IndexOutOfRange {
            position: Position::Element {
                index: 1,
                line: Some(20),
                ..
            },
            index: 8,
            ..
        }
    );
    assert!(e.to_string().contains("face 1 (line 20)"), "{e}");
    let text = ply_ascii(&box_vertices(), &[vec![0, 1]]);
    assert_matches!(
        ply_error(text.as_bytes()),
        MeshError::FaceTooSmall { count: 2, .. }
    );
}

#[test]
fn unsupported_ply_formats() {
    let text = ply_ascii(&box_vertices(), &box_quads()).replace("ascii", "binary_middle_endian");
    let e = ply_error(text.as_bytes());
    assert_matches!(e, MeshError::Unsupported { .. });
    assert!(e.to_string().contains("binary_middle_endian"));
    assert_matches!(ply_error(b"solid stl\n"), MeshError::Syntax { .. });
    let no_faces = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
    assert_matches!(
        ply_error(no_faces.as_bytes()),
        MeshError::Unsupported { .. }
    );
    let header_only = "ply\nformat ascii 1.0\nelement vertex 1\n";
    assert_matches!(
        ply_error(header_only.as_bytes()),
        MeshError::Truncated { .. }
    );
    let bad_value = ply_ascii(&box_vertices(), &box_quads()).replace("\n0 5 0\n", "\n0 zero 0\n");
    assert_matches!(ply_error(bad_value.as_bytes()), MeshError::Syntax { .. });
}
