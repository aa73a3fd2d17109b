//! `beamtrace study beam-management` on a few positions of the living room (the CI-sized run):
//! summary.json has exactly the issue's shape, the same seed gives the same bytes (apart from
//! the computing-time field `latency_us`), the figures and CSVs are written, and bad options
//! are refused by name.

use crate::common::*;
use serde_json::Value;
use std::path::Path;

const SMALL: &str = "study beam-management --scenario living-room --positions 6 --scan-density 0 \
                     --position-sigmas 0,0.3 --latencies-ms 0 --top-k 1,4 --seed 7 --out {}";

/// `summary.json` without its `latency_us` fields (the only ones that vary between runs).
fn without_latency(summary: &Value) -> Value {
    let mut v = summary.clone();
    for s in v["scenarios"].as_object_mut().unwrap().values_mut() {
        for m in s["methods"].as_object_mut().unwrap().values_mut() {
            m.as_object_mut().unwrap().remove("latency_us");
        }
    }
    v
}

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn small_study_is_reproducible_and_has_the_issues_shape() {
    let dir = scratch("beam-management");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let out = run_ok(&cli(SMALL, &[a.to_str().unwrap()]));
    assert!(
        stdout(&out).contains("exhaustive: top-1"),
        "{}",
        stdout(&out)
    );
    run_ok(&cli(SMALL, &[b.to_str().unwrap()]));
    for name in ["details.json", "decisions.csv", "trajectory.csv"] {
        assert_eq!(read(&a, name), read(&b, name), "{name}");
    }
    let summary: Value = serde_json::from_str(&read(&a, "summary.json")).unwrap();
    let again: Value = serde_json::from_str(&read(&b, "summary.json")).unwrap();
    assert_eq!(without_latency(&summary), without_latency(&again));

    let scenarios = summary["scenarios"].as_object().unwrap();
    assert_eq!(scenarios.keys().collect::<Vec<_>>(), ["living-room"]);
    let top = summary.as_object().unwrap();
    assert_eq!(top.keys().collect::<Vec<_>>(), ["scenarios"]);
    let methods = scenarios["living-room"]["methods"].as_object().unwrap();
    let keys = [
        "beams_measured",
        "latency_us",
        "snr_loss_db_mean",
        "snr_loss_db_p95",
        "top1",
        "top1_1db",
        "top1k",
        "topk1",
    ];
    for (name, m) in methods {
        let m = m.as_object().unwrap();
        assert_eq!(m.keys().collect::<Vec<_>>(), keys, "{name}");
        for k in keys {
            let x = m[k]
                .as_f64()
                .unwrap_or_else(|| panic!("{name}.{k}: {}", m[k]));
            assert!(x.is_finite() && x >= 0.0, "{name}.{k} = {x}");
        }
    }
    // 3 baselines + (exact, stale, geometric LoS) × 2 σ × 1 latency × 2 K (no scan).
    assert_eq!(methods.len(), 3 + 3 * 2 * 2, "{:?}", methods.keys());
    assert_eq!(methods["exhaustive"]["beams_measured"], 512.0);
    assert_eq!(methods["twin-exact-s0.3m-l0ms-top4"]["beams_measured"], 4.0);
    let rows = read(&a, "decisions.csv").lines().count();
    assert_eq!(rows, 1 + methods.len() * 6);
    for figure in ["accuracy-vs-overhead", "snr-loss-cdf"] {
        for ext in ["svg", "png"] {
            assert!(
                a.join(format!("{figure}.{ext}")).is_file(),
                "{figure}.{ext}"
            );
        }
    }
}

#[test]
fn bad_beam_management_options_are_refused_by_name() {
    let dir = scratch("beam-management-bad");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let line = "study beam-management --scenario living-room --positions 1 --top-k 0 --out {}";
    assert_clear_error(&cli(line, &[out]), &["--positions", "--top-k"]);
    let line = "study beam-management --scenario living-room --position-sigmas=-1 --out {}";
    assert_clear_error(&cli(line, &[out]), &["--position-sigmas"]);
    let line = "study beam-management --scenario no-such-scene.json --positions 3 --out {}";
    assert_clear_error(&cli(line, &[out]), &["--scenario no-such-scene.json"]);
    assert!(!Path::new(out).join("summary.json").exists());
}
