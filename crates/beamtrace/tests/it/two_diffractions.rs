//! `--max-diffractions 2` from the CLI (issue 28): the golden document of the two-walls
//! example, the path over both tops that one diffraction cannot give, every front end showing
//! twice-diffracted paths, and the refusal of a third diffraction.

use crate::common::*;
use serde_json::Value;

const TWO_WALLS: &str = "examples/two-walls.json";

fn example() -> String {
    repo().join(TWO_WALLS).display().to_string()
}

/// The paths of a document that pass both walls (a surface of each wall among their
/// interactions), as (interactions, surfaces).
fn over_both(doc: &Value) -> Vec<(Vec<String>, Vec<String>)> {
    kinds_and_surfaces(doc)
        .into_iter()
        .filter(|(_, names)| {
            names.iter().any(|n| n == "wall-a") && names.iter().any(|n| n == "wall-b")
        })
        .collect()
}

#[test]
fn golden_json_of_the_two_walls_with_two_diffractions() {
    let mut doc = run_json(&["trace", &example(), "--max-diffractions", "2", "--json"]);
    doc["stats"].as_object_mut().unwrap().remove("time_s");
    let text = serde_json::to_string_pretty(&doc).unwrap() + "\n";
    assert_golden(golden::dir().join("two-walls-two-diffractions.json"), text);
}

/// With one diffraction nothing passes both walls; with two the shortest path goes over both
/// tops, its points on the top edges (z = 4 m), and its loss is counted as diffraction.
#[test]
fn only_two_diffractions_pass_both_walls() {
    let once = run_json(&["trace", &example(), "--diffraction", "--json"]);
    assert!(over_both(&once).is_empty(), "{once}");
    let twice = run_json(&["trace", &example(), "--max-diffractions", "2", "--json"]);
    let paths = twice["paths"].as_array().unwrap();
    let over = paths
        .iter()
        .filter(|p| p["interactions"] == serde_json::json!(["diffraction", "diffraction"]))
        .min_by(|a, b| {
            a["length_m"]
                .as_f64()
                .unwrap()
                .total_cmp(&b["length_m"].as_f64().unwrap())
        })
        .expect("a path over both walls");
    assert_eq!(over["surfaces"], serde_json::json!(["wall-a", "wall-b"]));
    for point in over["points"].as_array().unwrap() {
        assert!((point[2].as_f64().unwrap() - 4.0).abs() < 1e-9, "{point}");
    }
    assert!(
        over["diffraction_loss_db"].as_f64().unwrap() > 20.0,
        "{over}"
    );
    assert_eq!(over["incidence_deg"], serde_json::json!([null, null]));
}

/// A third diffraction per path is refused, naming the option.
#[test]
fn a_third_diffraction_is_refused() {
    assert_clear_error(
        &["trace", &example(), "--max-diffractions", "3"],
        &["--max-diffractions", "0, 1 or 2", "3"],
    );
}

/// `sweep`, `channel` and `beams` take `--max-diffractions 2`: behind the walls every
/// receiver of a sweep gets power, its strongest path over both walls; the impulse response
/// holds the path over both tops; `beams` sweeps more paths than with one diffraction.
#[test]
fn sweeps_channels_and_beams_see_two_diffractions() {
    let dir = scratch("two-diffractions-fronts");
    let out = dir.join("sweep");
    run_ok(&[
        "sweep",
        &example(),
        "--max-diffractions",
        "2",
        "--grid",
        "12:14:2,-2:0:2,1.5",
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv = std::fs::read_to_string(out.join("coverage.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    assert!(
        rows.iter()
            .all(|r| r.contains(",ok,") && r.contains("wall-a > wall-b")),
        "{csv}"
    );
    let cir = dir.join("cir.csv");
    let channel = ["channel", &example(), "--max-diffractions", "2"];
    run_ok(&[&channel[..], &["--out", cir.to_str().unwrap()]].concat());
    let text = std::fs::read_to_string(&cir).unwrap();
    assert!(text.contains("wall-a > wall-b"), "{text}");
    let paths = |extra: &str| {
        run_json(&["beams", &example(), extra, "--json"])["paths"]
            .as_u64()
            .unwrap()
    };
    assert!(paths("--max-diffractions=2") > paths("--diffraction"));
    std::fs::remove_dir_all(dir).ok();
}
