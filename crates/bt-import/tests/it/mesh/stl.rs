//! STL meshes (binary and ASCII) to surfaces, and their bad input.

use crate::mesh::common::*;
use bt_import::mesh::{MeshError, Position, read_stl};
use bt_mesh::MergeOptions;
use glam::DVec3;

/// Corners in float32 (2.6 m is not exact): surfaces agree with the box to this, in metres.
const TOL: f64 = 1e-6;

fn triangles() -> Vec<[DVec3; 3]> {
    let v = box_vertices();
    (triangulate(&box_quads()).iter())
        .map(|f| [v[f[0]], v[f[1]], v[f[2]]])
        .collect()
}

fn binary(triangles: &[[DVec3; 3]], header: &[u8]) -> Vec<u8> {
    let mut out = header.to_vec();
    out.resize(80, b' ');
    out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in triangles {
        out.extend_from_slice(&[0u8; 12]); // the normal, ignored
        for p in t {
            for c in p.to_array() {
                out.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

fn ascii(solids: &[(&str, &[[DVec3; 3]])]) -> String {
    let mut out = String::new();
    for (name, triangles) in solids {
        out += &format!("solid {name}\n");
        for t in triangles.iter() {
            out += "  facet normal 0 0 0\n    outer loop\n";
            for p in t {
                out += &format!("      vertex {} {} {}\n", p.x, p.y, p.z);
            }
            out += "    endloop\n  endfacet\n";
        }
        out += &format!("endsolid {name}\n");
    }
    out
}

#[test]
fn binary_and_ascii_boxes_give_six_surfaces() {
    let t = triangles();
    // A binary header may start with "solid" too: the size decides.
    for bytes in [binary(&t, b"solid box, binary"), binary(&t, b"")] {
        let import = read_stl(&bytes, Some("box.stl"), &MergeOptions::default()).unwrap();
        assert_eq!(import.faces_read, 12);
        assert_surfaces(&import, &box_expected(), TOL);
        assert!(import.surfaces.iter().all(|s| s.material.is_none()));
    }
    let text = ascii(&[("box", &t)]);
    let import = read_stl(text.as_bytes(), Some("box.stl"), &MergeOptions::default()).unwrap();
    assert_surfaces(&import, &box_expected(), TOL);
    assert!(import.surfaces.iter().all(|s| s.name.starts_with("box")));
}

#[test]
fn each_ascii_solid_names_its_surfaces() {
    let t = triangles();
    let text = ascii(&[("floor", &t[0..2]), ("walls", &t[4..12])]);
    let import = read_stl(text.as_bytes(), None, &MergeOptions::default()).unwrap();
    assert_eq!(import.surfaces.len(), 5);
    let floors = import
        .surfaces
        .iter()
        .filter(|s| s.name.starts_with("floor"));
    assert_eq!(floors.count(), 1);
    let walls = import
        .surfaces
        .iter()
        .filter(|s| s.name.starts_with("walls"));
    assert_eq!(walls.count(), 4);
}

fn ascii_error(text: &str) -> MeshError {
    read_stl(text.as_bytes(), Some("bad.stl"), &MergeOptions::default()).unwrap_err()
}

#[test]
fn bad_ascii_is_an_error_naming_the_line() {
    let facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n";
    let e = ascii_error(&format!(
        "solid a\n{facet}vertex 0 x 0\nendloop\nendfacet\nendsolid\n"
    ));
    assert_matches!(e, MeshError::Syntax { position: Position::Line(6), detail, .. }
        if detail.contains("coordinate y \"x\" is not a number"));
    assert!(e.to_string().starts_with("bad.stl: line 6:"), "{e}");
    let e = ascii_error(&format!("solid a\n{facet}endloop\nendfacet\nendsolid\n"));
    assert_matches!(
        e,
        MeshError::FaceTooSmall {
            position: Position::Line(6),
            count: 2,
            ..
        }
    );
    let e = ascii_error(&format!("solid a\n{facet}vertex 0 1 0\n"));
    assert_matches!(
        e,
        MeshError::Truncated {
            position: Position::Line(6),
            ..
        }
    );
    let e = ascii_error("solid a\nfacet normal 0 0 1\nvertex 0 0 0\n");
    assert_matches!(e, MeshError::Syntax { position: Position::Line(3), detail, .. }
        if detail.contains("expected \"outer loop\""));
    let e = ascii_error(&format!("solid a\n{facet}vertex 0 1 inf\nendloop\n"));
    assert_matches!(e, MeshError::NonFiniteCoordinate { axis: 'z', .. });
    let e = ascii_error("a cube\n");
    assert_matches!(e, MeshError::Syntax { position: Position::Line(1), detail, .. }
        if detail.contains("not an STL file"));
}

#[test]
fn bad_binary_is_an_error_naming_the_triangle() {
    let mut t = triangles();
    t[3][1].y = f64::NAN;
    let e = read_stl(&binary(&t, b""), None, &MergeOptions::default()).unwrap_err();
    assert_matches!(
        e,
        MeshError::NonFiniteCoordinate {
            position: Position::Element { index: 3, .. },
            axis: 'y',
            ..
        }
    );
    // One byte short: not binary, and not text either.
    let mut bytes = binary(&triangles(), b"");
    bytes.pop();
    let e = read_stl(&bytes, None, &MergeOptions::default()).unwrap_err();
    assert_matches!(e, MeshError::Syntax { detail, .. } if detail.contains("not an STL file"));
}

#[test]
fn a_binary_count_beyond_the_budget_is_refused_before_reading() {
    let opts = MergeOptions {
        max_elements: 11,
        ..MergeOptions::default()
    };
    let e = read_stl(&binary(&triangles(), b""), Some("big.stl"), &opts).unwrap_err();
    assert_matches!(
        e,
        MeshError::Budget {
            element: "faces",
            budget: 11,
            ..
        }
    );
    assert!(e.to_string().contains("--max-mesh-elements"), "{e}");
    let text = ascii(&[("box", &triangles())]);
    let e = read_stl(text.as_bytes(), Some("big.stl"), &opts).unwrap_err();
    assert_matches!(e, MeshError::Budget { .. });
}
