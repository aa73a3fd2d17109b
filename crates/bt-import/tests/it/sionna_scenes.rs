//! Sionna RT's scenes (Mitsuba XML + PLY meshes) load without losing or filling geometry: for
//! every shape, the area of its loaded surfaces equals the area of its mesh's triangles (read
//! here with ply-rs, an independent reader, through the shape's `to_world`; coincident
//! duplicates and degenerate triangles left out), and no warning says a face was skipped or a
//! hole filled.
//!
//! The scenes come from the `sionna-rt` wheel (`pip download sionna-rt --no-deps`, unzip,
//! `sionna/rt/scenes/<scene>/`), copied to `testdata/scenes/sionna-rt/<scene>/`.

use bt_import::LoadOptions;
use bt_import::xml::{XmlScene, parse_xml};
use glam::{DMat4, DVec3};
use ply_rs::parser::Parser;
use ply_rs::ply::{DefaultElement, Property};
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// The scenes checked, each expected at `testdata/scenes/sionna-rt/<scene>/<scene>.xml`.
const SCENES: &[&str] = &[
    "simple_street_canyon",
    "florence",
    "etoile",
    "munich",
    "box_one_screen",
    "box_two_screens",
    "simple_street_canyon_with_cars",
];

/// Largest relative difference between a shape's loaded area and its mesh's triangle area.
const REL_AREA: f64 = 1e-6;

/// Words of the import warnings that mean geometry was dropped or invented.
const LOSSY_WORDS: &[&str] = &["skipped", "filled", "ignored", "no closed boundary"];

#[test]
fn sionna_scenes_lose_no_face_and_fill_no_hole() {
    let missing: Vec<String> = SCENES
        .iter()
        .map(|scene| scene_path(scene))
        .filter(|path| !path.is_file())
        .map(|path| path.display().to_string())
        .collect();
    assert!(
        missing.is_empty(),
        "Sionna RT scenes missing; each is expected at testdata/scenes/sionna-rt/<scene>/<scene>.xml \
         with its meshes/ folder, as in the sionna-rt wheel (sionna/rt/scenes/<scene>/): {missing:?}"
    );
    let mut problems = Vec::new();
    for scene in SCENES {
        problems.extend(check_scene(&scene_path(scene)));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// `testdata/scenes/sionna-rt/<scene>/<scene>.xml` of the workspace.
fn scene_path(scene: &str) -> PathBuf {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let workspace = crate_dir
        .parent()
        .and_then(Path::parent)
        .unwrap_or(crate_dir);
    workspace
        .join("testdata/scenes/sionna-rt")
        .join(scene)
        .join(format!("{scene}.xml"))
}

/// Loads one scene and returns what is wrong with it, one line per problem.
fn check_scene(path: &Path) -> Vec<String> {
    let shown = path.display().to_string();
    let loaded = match bt_import::load(&shown, &LoadOptions::default()) {
        Ok(loaded) => loaded,
        Err(e) => return vec![format!("{shown}: does not load: {e}")],
    };
    let mut problems: Vec<String> = loaded
        .warnings
        .iter()
        .filter(|w| LOSSY_WORDS.iter().any(|word| w.contains(word)))
        .map(|w| format!("{shown}: lossy warning: {w}"))
        .collect();
    let xml = parse_xml(&std::fs::read_to_string(path).unwrap(), &shown).unwrap();
    let loaded_area = loaded_area_by_shape(&loaded.scene, &xml);
    let folder = path.parent().unwrap();
    let (mut mesh_total, mut loaded_total, mut worst) = (0.0, 0.0, 0.0f64);
    for shape in &xml.shapes {
        let mesh = mesh_area(
            &folder.join(shape.filename.as_deref().unwrap()),
            shape.to_world,
        );
        let got = loaded_area.get(shape.name.as_str()).copied().unwrap_or(0.0);
        mesh_total += mesh;
        loaded_total += got;
        worst = worst.max((got - mesh).abs() / mesh.max(f64::MIN_POSITIVE));
        if (got - mesh).abs() > REL_AREA * mesh {
            problems.push(format!(
                "{shown}: shape {}: loaded {got:.6} m², mesh {mesh:.6} m² (relative {:.2e})",
                shape.name,
                (got - mesh).abs() / mesh
            ));
        }
    }
    println!(
        "{shown}: {} surfaces, {} import warnings, loaded {loaded_total:.3} m², mesh \
         {mesh_total:.3} m², worst shape off by {worst:.1e}",
        loaded.scene.surfaces().len(),
        loaded.warnings.len()
    );
    problems
}

/// The area of the loaded surfaces of each shape, by shape id: surfaces are named
/// `<shape>.face_<k>` (PLY meshes carry no object names, so the piece name has no dot).
fn loaded_area_by_shape<'a>(scene: &bt_scene::Scene, xml: &'a XmlScene) -> BTreeMap<&'a str, f64> {
    let mut areas: BTreeMap<&str, f64> =
        xml.shapes.iter().map(|s| (s.name.as_str(), 0.0)).collect();
    for surface in scene.surfaces() {
        let shape = surface.name.rsplit_once('.').map_or("", |(shape, _)| shape);
        match areas.get_mut(shape) {
            Some(area) => *area += surface.polygon.area(),
            None => panic!("surface {} belongs to no shape", surface.name),
        }
    }
    areas
}

/// The area of the triangles of the PLY mesh at `path` mapped through `to_world`: every
/// polygon face fanned, coincident duplicates counted once, triangles whose height is within
/// the weld tolerance (degenerate) left out.
fn mesh_area(path: &Path, to_world: DMat4) -> f64 {
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut std::fs::File::open(path).unwrap())
        .unwrap();
    let vertices: Vec<DVec3> = ply.payload["vertex"]
        .iter()
        .map(|v| {
            to_world.transform_point3(DVec3::new(
                scalar(&v["x"]),
                scalar(&v["y"]),
                scalar(&v["z"]),
            ))
        })
        .collect();
    let mut seen = HashSet::new();
    let mut area = 0.0;
    for face in &ply.payload["face"] {
        let ids = indices(&face["vertex_indices"]);
        for k in 1..ids.len().saturating_sub(1) {
            let tri = [ids[0], ids[k], ids[k + 1]].map(|i| vertices[i]);
            let mut key = tri.map(|p| p.to_array().map(f64::to_bits));
            key.sort_unstable();
            let double_area = (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
            let longest = (0..3)
                .map(|i| tri[i].distance(tri[(i + 1) % 3]))
                .fold(0.0, f64::max);
            if double_area > bt_mesh::DEFAULT_WELD_TOL_M * longest && seen.insert(key) {
                area += 0.5 * double_area;
            }
        }
    }
    area
}

fn scalar(p: &Property) -> f64 {
    match *p {
        Property::Float(x) => f64::from(x),
        Property::Double(x) => x,
        ref other => panic!("coordinate {other:?}"),
    }
}

fn indices(p: &Property) -> Vec<usize> {
    match p {
        Property::ListInt(v) => v.iter().map(|&i| i as usize).collect(),
        Property::ListUInt(v) => v.iter().map(|&i| i as usize).collect(),
        other => panic!("vertex_indices {other:?}"),
    }
}
