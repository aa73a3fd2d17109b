//! glTF 2.0 scenes (`.gltf`, `.glb`) to surfaces: buffers, node transforms, the +Y-up turn,
//! primitive modes, and bad input.

use bt_import::{ImportError, LoadOptions, Loaded, load};
use bt_mesh::MergeOptions;
use serde_json::{Value, json};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bt-gltf-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A unit square (glTF frame, in its y = 0 plane: beamtrace's floor) as two triangles, by
/// index list: its positions then its u16 indices, and the document describing them, with
/// `uri` for its one buffer (`None`: a GLB's chunk).
fn square(mode: u32, indices: &[u16], uri: Option<String>) -> (Value, Vec<u8>) {
    let corners: [[f32; 3]; 4] = [[0., 0., 0.], [2., 0., 0.], [2., 0., -3.], [0., 0., -3.]];
    let mut bytes: Vec<u8> = corners
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let positions = bytes.len();
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let mut buffer = json!({"byteLength": bytes.len()});
    if let Some(uri) = uri {
        buffer["uri"] = json!(uri);
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "floor", "mesh": 0}],
        "materials": [{"name": "itu_concrete"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": mode, "material": 0}]}],
        "buffers": [buffer],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions},
            {"buffer": 0, "byteOffset": positions, "byteLength": 2 * indices.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, -3], "max": [2, 0, 0]},
            {"bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}
        ]
    });
    (doc, bytes)
}

fn base64(bytes: &[u8]) -> String {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

fn load_doc(dir: &std::path::Path, name: &str, doc: &Value) -> Result<Loaded, ImportError> {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
    load(path.to_str().unwrap(), &LoadOptions::default())
}

/// The one surface's corners, sorted (metres, beamtrace's frame).
fn corners(loaded: &Loaded) -> Vec<[i64; 3]> {
    let scene = &loaded.scene;
    assert_eq!(scene.surfaces().len(), 1, "{:?}", scene.surfaces());
    let s = &scene.surfaces()[0];
    let mut c: Vec<[i64; 3]> = (s.polygon.vertices().iter())
        .map(|v| v.to_array().map(|x| (x * 1e6).round() as i64))
        .collect();
    c.sort();
    c
}

const FLOOR: [[i64; 3]; 4] = [
    [0, 0, 0],
    [0, 3_000_000, 0],
    [2_000_000, 0, 0],
    [2_000_000, 3_000_000, 0],
];

#[test]
fn every_buffer_kind_and_mode_gives_the_floor() {
    let dir = scratch("modes");
    for (mode, indices) in [
        (4, vec![0, 1, 2, 0, 2, 3]),
        (5, vec![1, 2, 0, 3]),
        (6, vec![0, 1, 2, 3]),
    ] {
        let (mut doc, bytes) = square(mode, &indices, None);
        doc["buffers"][0]["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64(&bytes)
        ));
        let loaded = load_doc(&dir, "embedded.gltf", &doc).unwrap();
        assert_eq!(corners(&loaded), FLOOR, "mode {mode}");
        let surface = &loaded.scene.surfaces()[0];
        assert!(surface.name.starts_with("floor"), "{}", surface.name);
        assert_eq!(surface.material, "itu_concrete");
        // The same bytes in a file beside it, named with a %-escape.
        let (doc, bytes) = square(mode, &indices, Some("floor%20data.bin".into()));
        std::fs::write(dir.join("floor data.bin"), &bytes).unwrap();
        let loaded = load_doc(&dir, "external.gltf", &doc).unwrap();
        assert_eq!(corners(&loaded), FLOOR);
        assert_eq!(loaded.sources[1], dir.join("floor data.bin"));
        assert_eq!(loaded.digests.len(), 2);
    }
}

#[test]
fn node_transforms_compose_down_the_hierarchy() {
    let dir = scratch("nodes");
    let (mut doc, bytes) = square(4, &[0, 1, 2, 0, 2, 3], None);
    doc["buffers"][0]["uri"] = json!(format!("data:;base64,{}", base64(&bytes)));
    // A parent 5 m up (glTF +Y) and a child turned a quarter about glTF y, then moved 1 m
    // along x: the floor's corner (2, 0, 0) goes to (0, 0, −2) then (1, 0, −2).
    doc["nodes"] = json!([
        {"translation": [0, 5, 0], "children": [1]},
        {"name": "floor", "mesh": 0, "translation": [1, 0, 0],
         "rotation": [0, std::f64::consts::FRAC_1_SQRT_2, 0, std::f64::consts::FRAC_1_SQRT_2]}
    ]);
    let loaded = load_doc(&dir, "nodes.gltf", &doc).unwrap();
    let c = corners(&loaded);
    // glTF (x, y, z) is beamtrace (x, −z, y): all at z = 5 m, the square spans x ∈ [−2, 1],
    // y ∈ [0, 2].
    assert!(c.iter().all(|p| p[2] == 5_000_000), "{c:?}");
    let (xs, ys): (Vec<i64>, Vec<i64>) = c.iter().map(|p| (p[0], p[1])).unzip();
    assert_eq!(
        (*xs.iter().min().unwrap(), *xs.iter().max().unwrap()),
        (-2_000_000, 1_000_000)
    );
    assert_eq!(
        (*ys.iter().min().unwrap(), *ys.iter().max().unwrap()),
        (0, 2_000_000)
    );
}

#[test]
fn bad_gltf_is_an_error_naming_what() {
    let dir = scratch("bad");
    let message = |doc: &Value| load_doc(&dir, "bad.gltf", doc).unwrap_err().to_string();
    let (doc, bytes) = square(4, &[0, 1, 2, 0, 2, 3], Some("../escape.bin".into()));
    std::fs::write(dir.join("ok.bin"), &bytes).unwrap();
    assert!(message(&doc).contains("only data: URIs and files in the scene's folder"));
    let (mut doc, _) = square(4, &[0, 1, 2, 0, 2, 7], Some("ok.bin".into()));
    let (_, wrong) = square(4, &[0, 1, 2, 0, 2, 7], None);
    std::fs::write(dir.join("ok.bin"), &wrong).unwrap();
    assert!(
        message(&doc).contains("vertex index 7 out of range"),
        "{}",
        message(&doc)
    );
    doc["accessors"][0]["count"] = json!(40);
    assert!(
        message(&doc).contains("elements beyond the buffer view"),
        "{}",
        message(&doc)
    );
    doc["buffers"][0]["byteLength"] = json!(4000);
    assert!(
        message(&doc).contains("4000 bytes declared"),
        "{}",
        message(&doc)
    );
    let path = dir.join("syntax.gltf");
    std::fs::write(
        &path,
        "{\n\"asset\": {\"version\": \"2.0\"},\n\"nodes\": [{\"mesh\": oops}]\n}",
    )
    .unwrap();
    let e = load(path.to_str().unwrap(), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 3"), "{e}");
}

#[test]
fn budgets_and_skipped_lines_are_reported() {
    let dir = scratch("budget");
    let (mut doc, bytes) = square(4, &[0, 1, 2, 0, 2, 3], None);
    doc["buffers"][0]["uri"] = json!(format!("data:;base64,{}", base64(&bytes)));
    let options = LoadOptions {
        merge: MergeOptions {
            max_elements: 1,
            ..MergeOptions::default()
        },
        ..LoadOptions::default()
    };
    let path = dir.join("big.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let e = load(path.to_str().unwrap(), &options)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--max-mesh-elements"), "{e}");
    // Two parents of one node: refused, not walked twice.
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    doc["nodes"] = json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]);
    let e = load_doc(&dir, "dag.gltf", &doc).unwrap_err().to_string();
    assert!(e.contains("two parents"), "{e}");
    // A line primitive beside the triangles: skipped with a warning.
    doc["nodes"] = json!([{"mesh": 0}]);
    doc["scenes"] = json!([{"nodes": [0]}]);
    let triangles = doc["meshes"][0]["primitives"][0].clone();
    let mut line = triangles.clone();
    line["mode"] = json!(1);
    doc["meshes"][0]["primitives"] = json!([triangles, line]);
    let loaded = load_doc(&dir, "lines.gltf", &doc).unwrap();
    assert_eq!(corners(&loaded), FLOOR);
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("1 primitives of points or lines skipped"))
    );
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// Hostile numbers in a glTF's views and accessors are an error or a result, never a
    /// panic or a read out of bounds.
    #[test]
    fn hostile_numbers_do_not_panic(
        field in 0usize..8,
        value in proptest::prelude::prop_oneof![0u64..64, proptest::prelude::any::<u64>()],
        mode in 0u32..8,
    ) {
        let dir = scratch(&format!("hostile-{field}-{mode}"));
        let (mut doc, bytes) = square(4, &[0, 1, 2, 0, 2, 3], None);
        doc["buffers"][0]["uri"] = json!(format!("data:;base64,{}", base64(&bytes)));
        doc["meshes"][0]["primitives"][0]["mode"] = json!(mode);
        let target = match field {
            0 => &mut doc["accessors"][0]["count"],
            1 => &mut doc["accessors"][1]["count"],
            2 => &mut doc["accessors"][0]["byteOffset"],
            3 => &mut doc["accessors"][1]["byteOffset"],
            4 => &mut doc["bufferViews"][0]["byteLength"],
            5 => &mut doc["bufferViews"][1]["byteOffset"],
            6 => &mut doc["bufferViews"][0]["byteStride"],
            _ => &mut doc["accessors"][1]["componentType"],
        };
        *target = json!(value);
        let _ = load_doc(&dir, "hostile.gltf", &doc);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn gltf_from_bytes_reads_no_file_and_gives_the_files_surfaces() {
    // The embedded document through `read_gltf` gives the surfaces the file load gives.
    let (mut doc, bytes) = square(4, &[0, 1, 2, 0, 2, 3], None);
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64(&bytes)
    ));
    let text = serde_json::to_vec(&doc).unwrap();
    let dir = scratch("bytes");
    let loaded = load_doc(&dir, "embedded.gltf", &doc).unwrap();
    let import = bt_import::mesh::read_gltf(&text, None, &MergeOptions::default()).unwrap();
    assert_eq!(import.surfaces.len(), 1);
    let from_file = &loaded.scene.surfaces()[0];
    let mut got = import.surfaces[0].vertices.clone();
    let mut want = from_file.polygon.vertices().to_vec();
    let key = |v: &bt_geom::Vec3| v.to_array().map(f64::to_bits);
    got.sort_by_key(key);
    want.sort_by_key(key);
    assert_eq!(got, want);
    // A buffer in a file is refused before any file is looked for: there is no folder.
    let (doc, _) = square(4, &[0, 1, 2, 0, 2, 3], Some("floor.bin".into()));
    let text = serde_json::to_vec(&doc).unwrap();
    let e = bt_import::mesh::read_gltf(&text, Some("x.gltf"), &MergeOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("x.gltf") && e.contains("has no folder"), "{e}");
    std::fs::remove_dir_all(dir).ok();
}
