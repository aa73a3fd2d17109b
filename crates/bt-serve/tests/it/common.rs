//! A server on a built-in scene and a way to talk to it.

use bt_beams::{RadioOptions, TraceDocument};
use bt_scene::Scene;
use bt_scene::dynamic::DynamicScene;
use bt_serve::{Limits, Server};
use bt_solve::Tracer;
use bt_solve::pipeline::TraceOptions;
use bt_solve::settings::SolveSettings;
use serde_json::Value;
use std::time::Duration;

/// The dynamic scene `source` (`builtin:NAME`) as `beamtrace serve` loads it.
pub fn load(source: &str) -> DynamicScene {
    let options = bt_import::LoadOptions::default();
    bt_import::load_dynamic(source, &options, &mut |_| {})
        .expect("built-in scene loads")
        .scene
}

/// The CLI's default trace options (order 3, image method, beam tree), with `settings`.
pub fn options(scene: &Scene, settings: SolveSettings) -> TraceOptions {
    settings.trace_options(scene).expect("valid settings")
}

/// A server of `source` under `settings` and `limits`.
pub fn server(source: &str, settings: SolveSettings, limits: Limits) -> Server {
    let dynamic = load(source);
    let options = options(dynamic.step(0), settings);
    Server::new(dynamic, options, RadioOptions::default(), limits)
}

/// Every answer of `server` to `lines` (one request each), parsed; the stream's text must
/// be one line per answer.
pub fn ask(server: &mut Server, lines: &[String]) -> Vec<Value> {
    let input = lines.join("\n");
    let mut output = Vec::new();
    server
        .serve(input.as_bytes(), &mut output)
        .expect("stream runs");
    let text = String::from_utf8(output).expect("UTF-8 answers");
    text.lines()
        .map(|l| serde_json::from_str(l).expect("each answer is one JSON line"))
        .collect()
}

/// The path records `trace --json` prints for `scene` from `tx` to `rx`, by a fresh tracer
/// (the one-shot command's own path: `Tracer::trace`, then `TraceDocument::report`), as
/// JSON text read back: serve's answers are read from text too, and serde_json's reading of
/// a number may be off by one unit in the last place, so both sides go through text and
/// the same reader (equal bytes, equal values).
pub fn one_shot(scene: &Scene, options: TraceOptions, tx: [f64; 3], rx: [f64; 3]) -> Value {
    let (tx, rx) = (bt_geom::Vec3::from_array(tx), bt_geom::Vec3::from_array(rx));
    let scene = scene.with_terminals(tx, rx).expect("valid terminals");
    let mut tracer = Tracer::new(scene.clone(), options);
    let traced = tracer.trace(tx, rx).expect("traces");
    let radio = RadioOptions::default();
    let doc = TraceDocument::report(&scene, &options, &traced, &radio, Duration::ZERO).unwrap();
    serde_json::from_str(&serde_json::to_string(&doc.paths).unwrap()).unwrap()
}

/// The error text of an error answer (panics on an answer that is none).
pub fn error(answer: &Value) -> &str {
    answer["error"]
        .as_str()
        .unwrap_or_else(|| panic!("not an error: {answer}"))
}

/// Asserts that two lists of path records are equal, showing only the first difference.
#[track_caller]
pub fn assert_same_paths(got: &Value, expected: &Value, what: &str) {
    let (Some(g), Some(e)) = (got.as_array(), expected.as_array()) else {
        panic!("{what}: not path lists: {got} / {expected}");
    };
    if let Some(i) = (0..g.len().min(e.len())).find(|&i| g[i] != e[i]) {
        panic!(
            "{what}: path {i} differs:\n  serve:    {}\n  one-shot: {}",
            g[i], e[i]
        );
    }
    assert_eq!(g.len(), e.len(), "{what}: path counts differ");
}
