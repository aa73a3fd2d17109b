//! Small mesh builders shared by the integration tests. All lengths in metres.

use bt_mesh::{MeshImport, MeshSurface};

/// Asserts that `value` matches `pattern` (with an optional `if` guard), printing the value
/// when it does not: `assert!(matches!(..))` says only that it failed, and the standard
/// library's `assert_matches!` is not stable yet.
macro_rules! assert_matches {
    ($value:expr, $pattern:pat $(if $guard:expr)?) => {{
        let value = &$value;
        assert!(matches!(value, $pattern $(if $guard)?), "{value:?}");
    }};
}
use glam::DVec3;

/// Room size of the test box: 4 x 5 x 2.6 m.
pub const ROOM: [f64; 3] = [4.0, 5.0, 2.6];

/// The 8 corners of the 4 x 5 x 2.6 m box.
pub fn box_vertices() -> Vec<DVec3> {
    let [x, y, z] = ROOM;
    vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(x, 0.0, 0.0),
        DVec3::new(x, y, 0.0),
        DVec3::new(0.0, y, 0.0),
        DVec3::new(0.0, 0.0, z),
        DVec3::new(x, 0.0, z),
        DVec3::new(x, y, z),
        DVec3::new(0.0, y, z),
    ]
}

/// The box's six quads (0-based), counter-clockwise seen from outside: floor, ceiling, y = 0,
/// x = 4, y = 5, x = 0.
pub fn box_quads() -> Vec<Vec<usize>> {
    vec![
        vec![0, 3, 2, 1],
        vec![4, 5, 6, 7],
        vec![0, 1, 5, 4],
        vec![1, 2, 6, 5],
        vec![2, 3, 7, 6],
        vec![3, 0, 4, 7],
    ]
}

/// Expected (outward normal, area m²) of the box surfaces, in `box_quads` order.
pub fn box_expected() -> Vec<(DVec3, f64)> {
    let [x, y, z] = ROOM;
    vec![
        (DVec3::NEG_Z, x * y),
        (DVec3::Z, x * y),
        (DVec3::NEG_Y, x * z),
        (DVec3::X, y * z),
        (DVec3::Y, x * z),
        (DVec3::NEG_X, y * z),
    ]
}

/// Splits every polygon into a triangle fan.
pub fn triangulate(faces: &[Vec<usize>]) -> Vec<Vec<usize>> {
    faces
        .iter()
        .flat_map(|f| (1..f.len() - 1).map(move |k| vec![f[0], f[k], f[k + 1]]))
        .collect()
}

/// OBJ text with shared vertices, 1-based indices.
pub fn obj_text(vertices: &[DVec3], faces: &[Vec<usize>]) -> String {
    let mut s = String::from("# test mesh\n");
    for v in vertices {
        s += &format!("v {:?} {:?} {:?}\n", v.x, v.y, v.z);
    }
    for f in faces {
        s += "f";
        for i in f {
            s += &format!(" {}", i + 1);
        }
        s += "\n";
    }
    s
}

/// OBJ text the way many exporters write it: vertices duplicated per face, rounded to
/// `decimals`, faces with `v/vt/vn` references.
pub fn obj_text_per_face(vertices: &[DVec3], faces: &[Vec<usize>], decimals: usize) -> String {
    let mut s = String::from("o Room\nvt 0 0\nvn 0 0 1\n");
    for f in faces {
        for &i in f {
            let v = vertices[i];
            s += &format!(
                "v {:.*} {:.*} {:.*}\n",
                decimals, v.x, decimals, v.y, decimals, v.z
            );
        }
        s += "f";
        for k in 0..f.len() {
            s += &format!(" {}/1/1", k as i64 - f.len() as i64);
        }
        s += "\n";
    }
    s
}

/// ASCII PLY text.
pub fn ply_ascii(vertices: &[DVec3], faces: &[Vec<usize>]) -> String {
    let mut s = format!(
        "ply\nformat ascii 1.0\ncomment test\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        vertices.len(),
        faces.len()
    );
    for v in vertices {
        s += &format!("{} {} {}\n", v.x, v.y, v.z);
    }
    for f in faces {
        s += &f.len().to_string();
        for i in f {
            s += &format!(" {i}");
        }
        s += "\n";
    }
    s
}

/// Binary little-endian PLY: float x y z, `uchar int vertex_indices`.
pub fn ply_binary_le(vertices: &[DVec3], faces: &[Vec<usize>]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        vertices.len(),
        faces.len()
    )
    .into_bytes();
    for v in vertices {
        for c in v.to_array() {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    for f in faces {
        out.push(f.len() as u8);
        for &i in f {
            out.extend_from_slice(&(i as i32).to_le_bytes());
        }
    }
    out
}

/// Binary big-endian PLY: double x y z plus an extra `uchar red`, `int vertex_index` lists with
/// `uint` indices, and an extra face flag.
pub fn ply_binary_be(vertices: &[DVec3], faces: &[Vec<usize>]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_big_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nelement face {}\nproperty uchar flags\nproperty list int uint vertex_index\nend_header\n",
        vertices.len(),
        faces.len()
    )
    .into_bytes();
    for v in vertices {
        for c in v.to_array() {
            out.extend_from_slice(&c.to_be_bytes());
        }
        out.push(200);
    }
    for f in faces {
        out.push(7);
        out.extend_from_slice(&(f.len() as i32).to_be_bytes());
        for &i in f {
            out.extend_from_slice(&(i as u32).to_be_bytes());
        }
    }
    out
}

/// Checks that `import` holds exactly the expected surfaces, in order, and that each polygon is
/// planar, counter-clockwise about its normal and has the reported area.
pub fn assert_surfaces(import: &MeshImport, expected: &[(DVec3, f64)], tol: f64) {
    assert_eq!(
        import.surfaces.len(),
        expected.len(),
        "surfaces: {:#?}\nwarnings: {:?}",
        import.surfaces,
        import.warnings
    );
    for (s, &(normal, area)) in import.surfaces.iter().zip(expected) {
        assert!(
            s.normal.distance(normal) < tol,
            "{}: normal {} expected {normal}",
            s.name,
            s.normal
        );
        assert!(
            (s.area_m2 - area).abs() < tol * area.max(1.0),
            "{}: area {} expected {area}",
            s.name,
            s.area_m2
        );
        assert_polygon_consistent(s, tol);
    }
}

/// The polygon's own area vector matches `normal * area_m2`, and all vertices lie on one plane.
pub fn assert_polygon_consistent(s: &MeshSurface, tol: f64) {
    let p0 = s.vertices[0];
    let mut area_vec = DVec3::ZERO;
    for w in s.vertices[1..].windows(2) {
        area_vec += 0.5 * (w[0] - p0).cross(w[1] - p0);
    }
    assert!(
        area_vec.distance(s.normal * s.area_m2) < tol * s.area_m2.max(1.0),
        "{}: polygon area vector {area_vec} vs normal*area {}",
        s.name,
        s.normal * s.area_m2
    );
    for v in &s.vertices {
        assert!(
            (*v - p0).dot(s.normal).abs() < 1e-9,
            "{}: vertex off plane",
            s.name
        );
    }
    assert!((s.normal.length() - 1.0).abs() < 1e-12);
}
