//! `beamtrace hls`: every time step of the dynamic living room run through one design and
//! co-simulated bit for bit against the fixed-point model, with the cycle counts equal to the
//! prediction; the GA schedule never longer than the list schedule.

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn beamtrace(args: &[&str]) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(args)
        .output()
        .expect("binary runs");
    (
        o.status.success(),
        format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
    )
}

fn tmp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("beamtrace-hls-{}-{name}", std::process::id()))
}

fn summary(dir: &std::path::Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// CI's multi-step co-simulation: the 10 steps of the dynamic living room (order 1) on ONE
/// design, each step's schedule, start points and TX/RX loaded over the bus, Verilator.
#[test]
fn living_room_steps_run_on_one_design_bit_exact() {
    let dir = tmp("lr1");
    let (ok, out) = beamtrace(&[
        "hls",
        "gen",
        "builtin:living-room-dynamic",
        "--steps",
        "--max-order",
        "1",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{out}");
    let doc: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("steps.json")).unwrap()).unwrap();
    let steps = doc["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 10);
    for s in steps {
        assert!(
            s["fixed_vs_f64"]["max_angle_error_tx_deg"]
                .as_f64()
                .unwrap()
                < 0.1,
            "{s}"
        );
        assert_eq!(s["fixed_vs_f64"]["spurious"], 0, "{s}");
    }
    assert!(dir.join("rtl/bt_top.v").exists());
    assert!(
        !dir.join("step-0/rtl").exists(),
        "one design, not one per step"
    );
    let (ok, out) = beamtrace(&["hls", "sim", dir.to_str().unwrap()]);
    assert!(ok, "{out}");
    assert!(out.contains("verilator (10 steps, 10 runs)"), "{out}");
    assert!(out.contains(" 0 mismatches"), "{out}");
    assert!(out.contains("runs as predicted: true"), "{out}");
    let predicted = steps[0]["predicted_cycles"].as_u64().unwrap();
    assert!(
        out.contains(&format!(
            "CYCLES of run 0 {predicted} (predicted {predicted})"
        )),
        "{out}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn ga_is_never_longer_than_list_and_duplication_helps() {
    let planes_only = tmp("ga");
    let dup = tmp("dup");
    let list = tmp("list");
    for (dir, extra) in [
        (&planes_only, vec!["--schedule", "ga", "--pe-budget", "1"]),
        (&dup, vec!["--schedule", "ga", "--pe-budget", "40"]),
        (&list, vec!["--schedule", "list"]),
    ] {
        let mut args = vec![
            "hls",
            "gen",
            "builtin:living-room",
            "--max-order",
            "2",
            "--plan-only",
            "-o",
            dir.to_str().unwrap(),
        ];
        args.extend(extra);
        let (ok, out) = beamtrace(&args);
        assert!(ok, "{out}");
    }
    let (g, d, l) = (summary(&planes_only), summary(&dup), summary(&list));
    let makespan = |v: &Value| v["stats"]["makespan"].as_u64().unwrap();
    // --pe-budget below the planes used is raised to one PE per plane: no duplicates.
    assert_eq!(g["stats"]["duplicates"], 0);
    assert!(
        makespan(&g) <= makespan(&l),
        "GA {} vs list {}",
        makespan(&g),
        makespan(&l)
    );
    assert!(
        makespan(&d) < makespan(&g),
        "duplication: {} vs {}",
        makespan(&d),
        makespan(&g)
    );
    assert_eq!(l["list_makespan"], l["stats"]["makespan"]);
    for dir in [planes_only, dup, list] {
        std::fs::remove_dir_all(dir).ok();
    }
}

#[test]
fn hls_errors_are_clear() {
    let (ok, out) = beamtrace(&["hls", "sim", "/no/such/dir"]);
    assert!(
        !ok && out.contains("/no/such/dir") && !out.contains("panicked"),
        "{out}"
    );
    let (ok, out) = beamtrace(&[
        "hls",
        "gen",
        "builtin:living-room",
        "--max-order",
        "0",
        "-o",
        tmp("x").to_str().unwrap(),
    ]);
    assert!(!ok && out.contains("--max-order"), "{out}");
}
