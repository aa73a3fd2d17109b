//! `beamtrace study 2d` end to end: the binary writes the CSV, the summary and every figure
//! as SVG and PNG; and `beamtrace trace --solver sbr` works on a scene file.

use std::path::PathBuf;
use std::process::Command;

fn beamtrace() -> Command {
    Command::new(env!("CARGO_BIN_EXE_beamtrace"))
}

/// Runs `command` and asserts it succeeded (its stderr as the message).
fn succeed(command: &mut Command) -> std::process::Output {
    let run = command.output().unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    run
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("beamtrace-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn study_2d_writes_csv_summary_and_figures() {
    let out = temp_dir("study");
    let run = succeed(
        beamtrace()
            .args([
                "study",
                "2d",
                "--rooms",
                "4",
                "--steps",
                "2",
                "--sbr-step-deg",
                "2",
                "--seed",
                "5",
            ])
            .arg("--out")
            .arg(&out),
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
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
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn study_rejects_bad_settings() {
    let run = beamtrace()
        .args(["study", "2d", "--rooms", "0", "--out"])
        .arg(temp_dir("bad"))
        .output()
        .unwrap();
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("rooms must be at least 1"));
}

#[test]
fn trace_with_sbr_on_a_scene_file() {
    let dir = temp_dir("sbr-scene");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("box.json");
    std::fs::write(
        &scene,
        r#"{ "tx": [1.1, 0.9, 1.2], "rx": [3.2, 2.1, 1.6],
            "boxes": [ { "name": "room", "min": [0, 0, 0], "max": [4, 3, 2.5] } ] }"#,
    )
    .unwrap();
    let json = |extra: &[&str]| {
        let run = succeed(
            beamtrace()
                .arg("trace")
                .arg(&scene)
                .args(["--max-order", "2", "--json"])
                .args(extra),
        );
        serde_json::from_slice::<serde_json::Value>(&run.stdout).unwrap()
    };
    let image = json(&["--solver", "image"]);
    let sbr = json(&["--solver", "sbr", "--sbr-step-deg", "0.5"]);
    assert_eq!(sbr["solver"]["solver"], "sbr");
    let count = |v: &serde_json::Value| v["paths"].as_array().unwrap().len();
    assert_eq!(count(&sbr), count(&image));
    let fib = json(&["--solver", "sbr", "--sbr-rays", "100000"]);
    assert_eq!(fib["solver"]["launch"]["pattern"], "fibonacci");
    let bad = beamtrace()
        .arg("trace")
        .arg(&scene)
        .args(["--solver", "sbr", "--sbr-step-deg", "-1"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    std::fs::remove_dir_all(&dir).unwrap();
}
