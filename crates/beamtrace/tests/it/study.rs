//! `beamtrace study 2d` end to end: the binary writes the CSV, the summary and every figure
//! as SVG and PNG; and `beamtrace trace --solver sbr` works on a scene file.

use crate::common::*;
use serde_json::Value;

#[test]
fn study_2d_writes_csv_summary_and_figures() {
    let dir = scratch("study-2d");
    let out = dir.join("out");
    let stdout = stdout(&run_ok(&cli(
        "study 2d --rooms 4 --steps 2 --sbr-step-deg 2 --seed 5 --out {}",
        &[out.to_str().unwrap()],
    )));
    assert!(stdout.contains("seed 5"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    // Header plus 4 rooms × 2 steps × 4 solvers.
    assert_eq!(csv.lines().count(), 1 + 4 * 2 * 4);
    assert!(csv.lines().skip(1).all(|l| l.starts_with("5,")));
    let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(summary.contains("Seed 5"));
    for fig in ["fig5-rooms", "fig6-angular-error", "fig7-elapsed-time"] {
        let svg = std::fs::read_to_string(out.join(format!("{fig}.svg"))).unwrap();
        assert!(svg.contains("<svg"), "{fig}.svg");
        let png = std::fs::read(out.join(format!("{fig}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{fig}.png");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn study_rejects_bad_settings() {
    let out = scratch("study-bad").join("out");
    let run = beamtrace(&cli(
        "study 2d --rooms 0 --out {}",
        &[out.to_str().unwrap()],
    ));
    assert!(!run.status.success());
    assert!(stderr(&run).contains("rooms must be at least 1"));
}

#[test]
fn trace_with_sbr_on_a_scene_file() {
    let dir = scratch("study-sbr-scene");
    let scene = dir.join("box.json");
    std::fs::write(
        &scene,
        r#"{ "tx": [1.1, 0.9, 1.2], "rx": [3.2, 2.1, 1.6],
            "boxes": [ { "name": "room", "min": [0, 0, 0], "max": [4, 3, 2.5] } ] }"#,
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    let json = |extra: &[&str]| {
        run_json(&[&["trace", scene, "--max-order", "2", "--json"], extra].concat())
    };
    let image = json(&["--solver", "image"]);
    let sbr = json(&["--solver", "sbr", "--sbr-step-deg", "0.5"]);
    assert_eq!(sbr["solver"]["solver"], "sbr");
    let count = |v: &Value| v["paths"].as_array().unwrap().len();
    assert_eq!(count(&sbr), count(&image));
    let fib = json(&["--solver", "sbr", "--sbr-rays", "100000"]);
    assert_eq!(fib["solver"]["launch"]["pattern"], "fibonacci");
    let bad = beamtrace(&["trace", scene, "--solver", "sbr", "--sbr-step-deg", "-1"]);
    assert!(!bad.status.success());
    std::fs::remove_dir_all(&dir).unwrap();
}
