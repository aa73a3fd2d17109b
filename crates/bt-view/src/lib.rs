//! A 3-D viewer of a scene and its paths as ONE self-contained HTML page: three.js (vendored,
//! `vendor/`) and the viewer script are inlined, the data is a JSON document inside
//! `<script type="application/json">` read with `textContent` — names from the scene are data
//! and never reach HTML markup (the script writes them with `textContent` only).
//!
//! The page exposes `window.beamtraceView = { steps, step, pathLines, paths, surfaces, edges,
//! diffractionPoints, ready }` so a browser test can check what was drawn.
//!
//! Each step carries the scene's diffracting edges (all of them up to [`ALL_EDGES_CAP`], else
//! the ones a shown path diffracts on) as world-frame segments; the viewer marks each path's
//! diffraction points from the paths' own `interactions` and `points`.

#![warn(missing_docs)]

use bt_beams::{InteractionKind, PathReport, StepsDocument, TraceDocument};
use bt_geom::{Real, Vec3};
use bt_scene::{Edge, EdgeId, Scene, SurfaceKind};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;

const THREE: &str = include_str!("../vendor/three.bundle.min.js");
const VIEWER: &str = include_str!("../assets/viewer.js");
const TEMPLATE: &str = include_str!("../assets/page.html");

/// Version of the embedded document's layout. Still 1 with the steps' `edges` and
/// `edge_count`: fields were only added, and the document is read by the viewer script of its
/// own page, never by another reader.
pub const FORMAT_VERSION: u32 = 1;

/// A time step whose scene has at most this many diffracting edges shows all of them; a larger
/// one shows only the edges a shown path diffracts on. 5,000 edges are about 0.5 MB of JSON per
/// step (the size of the inlined three.js) and one cheap line batch to draw, and as many edges
/// as that still read as the outline of a building; a city mesh's 10⁵ edges would multiply the
/// page's size and hide the paths in grey lines.
pub const ALL_EDGES_CAP: usize = 5_000;

/// Why a page could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The paths document is not a `beamtrace trace --json` (or `--steps --json`) document.
    #[error("{path}: not a beamtrace trace --json document: {message}")]
    PathsDocument {
        /// The file.
        path: String,
        /// What serde said (with line and column).
        message: String,
    },
    /// The paths document has another number of steps than the scene.
    #[error("{path}: {found} time steps of paths, but the scene has {expected}")]
    StepCount {
        /// The file.
        path: String,
        /// Steps in the document.
        found: usize,
        /// Steps of the scene.
        expected: usize,
    },
    /// A path of the document names a surface the scene does not have: the document belongs
    /// to another scene.
    #[error(
        "{path}: step {step}: a path names surface \"{surface}\", which scene {scene} does not have; \
         give the document traced from this scene"
    )]
    ForeignDocument {
        /// The file.
        path: String,
        /// Time step, from 0.
        step: usize,
        /// The unknown surface name (escaped).
        surface: String,
        /// The scene's name (escaped).
        scene: String,
    },
}

/// The paths of one time step with the terminals they were traced for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepPaths {
    /// Transmitter, metres, world frame; `None` for bare geometry (drawn without terminals).
    pub tx: Option<[Real; 3]>,
    /// Receiver, metres, world frame; `None` for bare geometry.
    pub rx: Option<[Real; 3]>,
    /// The paths (the trace documents' record).
    pub paths: Vec<PathReport>,
}

impl StepPaths {
    /// The ranked reports of a trace of `scene`, with the terminals it has.
    pub fn from_reports(scene: &Scene, paths: &[PathReport]) -> Self {
        StepPaths {
            tx: scene.tx_world().map(|p| p.to_array()),
            rx: scene.rx_world().map(|p| p.to_array()),
            paths: paths.to_vec(),
        }
    }

    /// Bare geometry: no terminal, no path.
    pub fn none() -> Self {
        StepPaths {
            tx: None,
            rx: None,
            paths: Vec::new(),
        }
    }
}

/// A document `--paths` reads: a trace's or every step's.
#[derive(Deserialize)]
#[serde(untagged)]
enum PathsDocument {
    Steps(StepsDocument),
    One(Box<TraceDocument>),
}

/// Read the paths of a `beamtrace trace --json` document (one step) or of a
/// `trace --steps --json` document (every step); `path` names the file in errors.
pub fn read_paths(text: &str, path: &str) -> Result<Vec<StepPaths>, ViewError> {
    let doc: PathsDocument = serde_json::from_str(text).map_err(|e| ViewError::PathsDocument {
        path: path.to_string(),
        message: e.to_string(),
    })?;
    Ok(match doc {
        PathsDocument::Steps(doc) => doc
            .steps
            .into_iter()
            .map(|s| StepPaths {
                tx: Some(s.tx),
                rx: Some(s.rx),
                paths: s.paths,
            })
            .collect(),
        PathsDocument::One(doc) => vec![StepPaths {
            tx: Some(doc.tx),
            rx: Some(doc.rx),
            paths: doc.paths,
        }],
    })
}

/// Check that every surface the paths of `paths[k]` name (a diffraction's `"A|B"` names two,
/// split by [`bt_scene::name::split_edge`]) is a surface of `scenes[k]`: a document traced from
/// another scene is refused.
pub fn check_surfaces(paths: &[StepPaths], scenes: &[&Scene], path: &str) -> Result<(), ViewError> {
    for (step, (step_paths, scene)) in paths.iter().zip(scenes).enumerate() {
        let found = |name: &str| scene.find(name).is_some();
        let known = |kind: Option<&InteractionKind>, name: &str| match kind {
            Some(InteractionKind::Diffraction) => bt_scene::name::split_edge(name)
                .is_some_and(|(face0, face_n)| found(&face0) && face_n.is_none_or(|f| found(&f))),
            _ => found(name),
        };
        for p in &step_paths.paths {
            for (k, name) in p.surfaces.iter().enumerate() {
                if !known(p.interactions.get(k), name) {
                    return Err(ViewError::ForeignDocument {
                        path: path.to_string(),
                        step,
                        surface: bt_scene::name::shown(name),
                        scene: bt_scene::name::shown(scene.name()),
                    });
                }
            }
        }
    }
    Ok(())
}

/// Check that `paths` has one entry per scene step.
pub fn check_steps(paths: &[StepPaths], steps: usize, path: &str) -> Result<(), ViewError> {
    if paths.len() == steps {
        Ok(())
    } else {
        Err(ViewError::StepCount {
            path: path.to_string(),
            found: paths.len(),
            expected: steps,
        })
    }
}

#[derive(Serialize)]
struct Document<'a> {
    format_version: u32,
    scene: &'a str,
    materials: Vec<MaterialColour<'a>>,
    steps: Vec<StepDocument<'a>>,
}

#[derive(Serialize)]
struct MaterialColour<'a> {
    name: &'a str,
    colour: &'static str,
}

#[derive(Serialize)]
struct StepDocument<'a> {
    surfaces: Vec<SurfaceDocument<'a>>,
    /// `null` on bare geometry: the viewer draws no marker.
    tx: Option<[Real; 3]>,
    rx: Option<[Real; 3]>,
    paths: &'a [PathReport],
    /// The diffracting edges drawn: all, or those a path diffracts on ([`ALL_EDGES_CAP`]),
    /// ascending by edge id.
    edges: Vec<EdgeDocument>,
    /// How many diffracting edges the step's scene has (more than `edges` over the cap).
    edge_count: usize,
}

#[derive(Serialize)]
struct EdgeDocument {
    /// Start and end, metres, world frame.
    segment: [[Real; 3]; 2],
    /// A free edge (a screen's boundary) rather than a wedge of two faces.
    free: bool,
}

#[derive(Serialize)]
struct SurfaceDocument<'a> {
    name: &'a str,
    material: &'a str,
    kind: SurfaceKind,
    colour: &'static str,
    vertices: Vec<[Real; 3]>,
}

/// Colours of the materials, in the order of the scene's (sorted) material names.
const PALETTE: [&str; 12] = [
    "#4e79a7", "#f28e2b", "#59a14f", "#b07aa1", "#76b7b2", "#edc948", "#9c755f", "#bab0ac",
    "#17becf", "#bcbd22", "#7f7f7f", "#ff9da7",
];
/// Colour of every blocker (they only occlude).
const BLOCKER: &str = "#e15759";

/// The HTML page for the time steps `scenes` (one for a static scene) and their paths
/// (`paths[k]` belongs to `scenes[k]`; the caller checks the counts, see [`check_steps`]).
pub fn page(scenes: &[&Scene], paths: &[StepPaths]) -> String {
    let name = scenes.first().map_or("", |s| s.name());
    let material_names: Vec<&str> = scenes
        .first()
        .map(|s| s.materials().keys().map(String::as_str).collect())
        .unwrap_or_default();
    let colour_of = |material: &str| {
        let i = material_names
            .iter()
            .position(|m| *m == material)
            .unwrap_or(0);
        PALETTE[i % PALETTE.len()]
    };
    let steps = scenes
        .iter()
        .zip(paths)
        .map(|(scene, step)| StepDocument {
            surfaces: scene
                .surfaces()
                .iter()
                .map(|s| SurfaceDocument {
                    name: &s.name,
                    material: &s.material,
                    kind: s.kind,
                    colour: match s.kind {
                        SurfaceKind::Reflector => colour_of(&s.material),
                        SurfaceKind::Blocker => BLOCKER,
                    },
                    vertices: (s.polygon.vertices().iter())
                        .map(|v| scene.to_world(*v).to_array())
                        .collect(),
                })
                .collect(),
            tx: step.tx,
            rx: step.rx,
            paths: &step.paths,
            edges: shown_edges(scene, &step.paths, ALL_EDGES_CAP)
                .into_iter()
                .map(|id| edge_document(scene, scene.edges().get(id)))
                .collect(),
            edge_count: scene.edges().len(),
        })
        .collect();
    let doc = Document {
        format_version: FORMAT_VERSION,
        scene: name,
        materials: material_names
            .iter()
            .map(|m| MaterialColour {
                name: m,
                colour: colour_of(m),
            })
            .collect(),
        steps,
    };
    let json = serde_json::to_string(&doc).expect("the view document serialises");
    fill(
        TEMPLATE,
        &[
            ("{{TITLE}}", &html_text(&format!("beamtrace view: {name}"))),
            ("{{DATA}}", &script_safe_json(&json)),
            ("{{THREE}}", THREE),
            ("{{VIEWER}}", VIEWER),
        ],
    )
}

/// The edges of `scene` to draw with `paths`: every edge when there are at most `cap`, else
/// those a path diffracts on; ascending by id (deterministic).
fn shown_edges(scene: &Scene, paths: &[PathReport], cap: usize) -> Vec<EdgeId> {
    let count = scene.edges().len();
    if count <= cap {
        return (0..count).map(|i| EdgeId(i as u32)).collect();
    }
    let ids: BTreeSet<EdgeId> = paths
        .iter()
        .flat_map(|p| diffracted_edges(scene, p))
        .collect();
    ids.into_iter().collect()
}

/// The edges `path` diffracts on: its edges' ids when it was traced here; for a path read from a
/// trace document (which carries no ids), the edges through its diffraction point (within the
/// edges' own matching tolerance, [`bt_scene::edges::REL_EDGE_MATCH`] of the scene's extent)
/// whose faces have the names the path gives.
fn diffracted_edges(scene: &Scene, path: &PathReport) -> Vec<EdgeId> {
    let edges = scene.edges();
    if !path.diffractions.is_empty() {
        return path
            .diffractions
            .iter()
            .map(|d| d.edge)
            .filter(|e| e.index() < edges.len())
            .collect();
    }
    let tol = bt_geom::tol::scaled(bt_scene::edges::REL_EDGE_MATCH, scene.extent());
    let mut out = Vec::new();
    let interactions = path
        .interactions
        .iter()
        .zip(&path.points)
        .zip(&path.surfaces);
    for ((kind, point), faces) in interactions {
        if *kind != InteractionKind::Diffraction {
            continue;
        }
        let p = scene.to_local(Vec3::from_array(*point));
        let near = |lo: Vec3, hi: Vec3| p.cmpge(lo - tol).all() && p.cmple(hi + tol).all();
        edges.bvh().visit(near, |i| {
            let edge = &edges.all()[i as usize];
            let t = edge.parameter(p).clamp(0.0, edge.length);
            if edge.point(t).distance(p) <= tol && scene.edge_name(edge) == *faces {
                out.push(EdgeId(i));
            }
        });
    }
    out
}

fn edge_document(scene: &Scene, edge: &Edge) -> EdgeDocument {
    EdgeDocument {
        segment: [
            scene.to_world(edge.start).to_array(),
            scene.to_world(edge.end).to_array(),
        ],
        free: edge.is_free(),
    }
}

/// Replace each placeholder of `template` once, in one pass over the template only: a value
/// (a scene name, say) that happens to contain a placeholder is never expanded.
fn fill(template: &str, values: &[(&str, &str)]) -> String {
    let mut out =
        String::with_capacity(template.len() + values.iter().map(|v| v.1.len()).sum::<usize>());
    let mut rest = template;
    while let Some(i) = rest.find("{{") {
        out.push_str(&rest[..i]);
        rest = &rest[i..];
        match values.iter().find(|(key, _)| rest.starts_with(key)) {
            Some((key, value)) => {
                out.push_str(value);
                rest = &rest[key.len()..];
            }
            None => {
                out.push_str("{{");
                rest = &rest[2..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// JSON that can sit inside `<script type="application/json">`: `<`, `>` and `&` as `\u` escapes
/// (so no `</script>` or `<!--` can end or confuse the element; JSON.parse restores them), and
/// U+2028/U+2029 escaped too.
pub fn script_safe_json(json: &str) -> String {
    let mut out = String::with_capacity(json.len());
    for c in json.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out
}

/// Text for an HTML text node (the page title).
fn html_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_safe_json_cannot_close_the_element_and_round_trips() {
        let name = "</script><script>alert(1)</script><!-- & \u{2028}";
        let json = serde_json::to_string(&name).unwrap();
        let safe = script_safe_json(&json);
        assert!(!safe.contains('<') && !safe.contains('>') && !safe.contains('&'));
        let back: String = serde_json::from_str(&safe).unwrap();
        assert_eq!(back, name);
    }

    #[test]
    fn the_vendored_bundle_can_be_inlined() {
        assert!(!THREE.contains("</script") && !THREE.contains("<!--"));
        assert!(!VIEWER.contains("</script") && !VIEWER.contains("<!--"));
        assert!(
            !VIEWER.contains("innerHTML"),
            "names must only reach textContent"
        );
    }

    #[test]
    fn a_far_scene_is_drawn_at_its_world_coordinates() {
        let json = r#"{ "tx": [10000001, 10000001, 101], "rx": [10000004, 10000002, 101.5],
            "boxes": [ { "name": "room", "min": [10000000, 10000000, 100],
                         "max": [10000006, 10000004, 103] } ] }"#;
        let desc: bt_scene::SceneDescription = serde_json::from_str(json).unwrap();
        let scene = Scene::from_description(&desc, "far", Default::default()).unwrap();
        assert!(
            scene.origin() != bt_scene::Vec3::ZERO,
            "solved in a local frame"
        );
        let steps = [StepPaths::from_reports(&scene, &[])];
        let html = page(&[&scene], &steps);
        assert!(html.contains("[10000001.0,10000001.0,101.0]"), "world tx");
        assert!(
            html.contains("[10000006.0,10000004.0,103.0]"),
            "world vertex"
        );
    }

    #[test]
    fn placeholders_inside_values_are_not_expanded() {
        let page = fill("a{{X}}b{{Y}}c", &[("{{X}}", "{{Y}}"), ("{{Y}}", "y")]);
        assert_eq!(page, "a{{Y}}byc");
    }

    /// A floating screen between TX and RX (no line of sight), traced with diffraction: a
    /// path over each of its four free edges.
    fn screen_and_paths() -> (Scene, Vec<PathReport>) {
        let json = r#"{ "tx": [0.3, -3, 1.8], "rx": [-0.2, 3, 1.6],
            "surfaces": [ { "name": "screen",
                "vertices": [[-2, 0, 0], [2, 0, 0], [2, 0, 2], [-2, 0, 2]] } ] }"#;
        let desc: bt_scene::SceneDescription = serde_json::from_str(json).unwrap();
        let scene = Scene::from_description(&desc, "screen", Default::default()).unwrap();
        let options = bt_solve::pipeline::TraceOptions {
            parallel: false,
            diffraction: bt_solve::pipeline::DiffractionOptions::first_order(),
            ..bt_solve::pipeline::TraceOptions::new(1)
        };
        let ends = scene.terminals().unwrap();
        let traced = bt_solve::Tracer::new(scene.clone(), options)
            .trace(scene.to_world(ends.tx), scene.to_world(ends.rx))
            .unwrap();
        let reports = bt_beams::report(&scene, &traced.result.paths, &Default::default());
        (scene, reports.unwrap())
    }

    /// The JSON document embedded in a page.
    fn embedded(html: &str) -> serde_json::Value {
        let start = html.find("id=\"beamtrace-data\">").unwrap() + "id=\"beamtrace-data\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        serde_json::from_str(&html[start..end]).unwrap()
    }

    #[test]
    fn a_screen_puts_its_free_edges_and_the_diffractions_in_the_document() {
        let (scene, reports) = screen_and_paths();
        let html = page(&[&scene], &[StepPaths::from_reports(&scene, &reports)]);
        let step = &embedded(&html)["steps"][0];
        assert_eq!(step["edge_count"], 4);
        let edges = step["edges"].as_array().unwrap();
        assert_eq!(edges.len(), 4, "a screen has four free edges");
        assert!(edges.iter().all(|e| e["free"] == true));
        let top = [[-2.0, 0.0, 2.0], [2.0, 0.0, 2.0]];
        let segment = |e: &serde_json::Value| -> [[Real; 3]; 2] {
            serde_json::from_value(e["segment"].clone()).unwrap()
        };
        assert!(
            edges.iter().any(|e| {
                let s = segment(e);
                s == top || s == [top[1], top[0]]
            }),
            "the top edge, world frame: {edges:?}"
        );
        let paths = step["paths"].as_array().unwrap();
        assert_eq!(paths.len(), 4, "one path over each edge: {paths:?}");
        for p in paths {
            assert_eq!(p["interactions"], serde_json::json!(["diffraction"]));
            assert_eq!(p["surfaces"], serde_json::json!(["screen"]));
        }
    }

    /// Two parallel screens, TX and RX below their tops: the page holds the paths over both
    /// screens (two diffractions each), and over the cap it draws both edges of a shown path,
    /// from its ids and, read back from a document, from its points and names.
    #[test]
    fn twice_diffracted_paths_and_both_their_edges_are_shown() {
        let json = r#"{ "tx": [0, -3, 0.5], "rx": [0.3, 6, 0.4],
            "surfaces": [
              { "name": "near", "vertices": [[-30, 0, -30], [30, 0, -30], [30, 0, 2], [-30, 0, 2]] },
              { "name": "far", "vertices": [[-30, 3, -30], [30, 3, -30], [30, 3, 2], [-30, 3, 2]] } ] }"#;
        let desc: bt_scene::SceneDescription = serde_json::from_str(json).unwrap();
        let scene = Scene::from_description(&desc, "screens", Default::default()).unwrap();
        let options = bt_solve::pipeline::TraceOptions {
            parallel: false,
            diffraction: bt_solve::pipeline::DiffractionOptions {
                max_diffractions: 2,
                min_edge_length: 0.0,
            },
            ..bt_solve::pipeline::TraceOptions::new(2)
        };
        let ends = scene.terminals().unwrap();
        let traced = bt_solve::Tracer::new(scene.clone(), options)
            .trace(scene.to_world(ends.tx), scene.to_world(ends.rx))
            .unwrap();
        let reports = bt_beams::report(&scene, &traced.result.paths, &Default::default()).unwrap();
        let over: Vec<&PathReport> = reports
            .iter()
            .filter(|r| r.surfaces == ["near", "far"] && r.points.iter().all(|p| p[2] == 2.0))
            .collect();
        assert_eq!(over.len(), 1, "one path over both tops: {reports:?}");
        let html = page(&[&scene], &[StepPaths::from_reports(&scene, &reports)]);
        let paths = embedded(&html)["steps"][0]["paths"]
            .as_array()
            .unwrap()
            .clone();
        assert!(
            paths
                .iter()
                .any(|p| p["interactions"] == serde_json::json!(["diffraction", "diffraction"])),
            "{paths:?}"
        );
        let shown = shown_edges(&scene, &[over[0].clone()], 0);
        assert_eq!(shown.len(), 2, "both edges of the path");
        let json = serde_json::to_string(&[over[0].clone()]).unwrap();
        let read: Vec<PathReport> = serde_json::from_str(&json).unwrap();
        assert_eq!(shown_edges(&scene, &read, 0), shown);
    }

    #[test]
    fn over_the_cap_only_the_edges_of_the_shown_paths_are_drawn() {
        let (scene, reports) = screen_and_paths();
        assert_eq!(shown_edges(&scene, &reports, 4).len(), 4, "at the cap: all");
        assert!(shown_edges(&scene, &[], 3).is_empty(), "no path, no edge");
        let over = shown_edges(&scene, &reports[..1], 3);
        assert_eq!(over, vec![reports[0].diffractions[0].edge]);
        // A path read back from a trace document has no edge id: found by its point and name.
        let json = serde_json::to_string(&reports[..1]).unwrap();
        let read: Vec<PathReport> = serde_json::from_str(&json).unwrap();
        assert!(read[0].diffractions.is_empty());
        assert_eq!(shown_edges(&scene, &read, 3), over);
        let mut renamed = read.clone();
        renamed[0].surfaces = vec!["other".to_string()];
        assert!(
            shown_edges(&scene, &renamed, 3).is_empty(),
            "faces must match"
        );
    }

    /// A document's diffraction entries are split as `bt_scene::name::edge` wrote them: the
    /// faces `a|b` and `c` (`a\|b|c`) are this scene's, the unescaped `a|b|c` is no edge name.
    #[test]
    fn edge_names_are_split_at_their_unescaped_separator() {
        let json = r#"{ "surfaces": [
            { "name": "a|b", "vertices": [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]] },
            { "name": "c", "vertices": [[0, 2, 0], [1, 2, 0], [1, 2, 1], [0, 2, 1]] } ] }"#;
        let desc: bt_scene::SceneDescription = serde_json::from_str(json).unwrap();
        let scene = Scene::from_description(&desc, "pipes", Default::default()).unwrap();
        let document = |kind: InteractionKind, surface: &str| {
            let mut path = PathReport::example();
            path.interactions = vec![kind];
            path.surfaces = vec![surface.to_string()];
            vec![StepPaths {
                tx: None,
                rx: None,
                paths: vec![path],
            }]
        };
        let check = |kind, surface| check_surfaces(&document(kind, surface), &[&scene], "p.json");
        assert!(check(InteractionKind::Diffraction, "a\\|b|c").is_ok());
        assert!(
            check(InteractionKind::Diffraction, "a\\|b").is_ok(),
            "a free edge"
        );
        assert!(check(InteractionKind::Reflection, "a|b").is_ok());
        for (kind, surface) in [
            (InteractionKind::Diffraction, "a|b|c"),
            (InteractionKind::Diffraction, "a|b"),
            (InteractionKind::Reflection, "a\\|b"),
        ] {
            let e = check(kind, surface).unwrap_err().to_string();
            assert!(e.contains("a path names surface"), "{surface}: {e}");
        }
    }

    #[test]
    fn bad_paths_documents_name_the_file() {
        let e = read_paths("{\"paths\": 3}", "p.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("p.json: not a beamtrace trace --json document"),
            "{e}"
        );
        let e = check_steps(&[], 2, "p.json").unwrap_err().to_string();
        assert_eq!(e, "p.json: 0 time steps of paths, but the scene has 2");
    }
}
