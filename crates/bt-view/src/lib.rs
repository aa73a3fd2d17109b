//! A 3-D viewer of a scene and its paths as ONE self-contained HTML page: three.js (vendored,
//! `vendor/`) and the viewer script are inlined, the data is a JSON document inside
//! `<script type="application/json">` read with `textContent` — names from the scene are data
//! and never reach HTML markup (the script writes them with `textContent` only).
//!
//! The page exposes `window.beamtraceView = { steps, step, pathLines, paths, surfaces, ready }`
//! so a browser test can check what was drawn.

#![warn(missing_docs)]

use bt_beams::{PathReport, StepsDocument, TraceDocument};
use bt_geom::Real;
use bt_scene::{Scene, SurfaceKind};
use serde::{Deserialize, Serialize};

const THREE: &str = include_str!("../vendor/three.bundle.min.js");
const VIEWER: &str = include_str!("../assets/viewer.js");
const TEMPLATE: &str = include_str!("../assets/page.html");

/// Version of the embedded document's layout.
pub const FORMAT_VERSION: u32 = 1;

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
