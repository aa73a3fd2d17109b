//! `beamtrace sweep`: every grid point against its own `beamtrace trace --rx` run, a golden
//! CSV of a tiny grid (with a point at the TX, marked skipped), determinism across thread
//! counts, and bad grids refused with a clear message.

use crate::common::*;
use serde_json::Value;
use std::path::PathBuf;

/// Sweeps the living room over `grid` into a new folder `out` (in the scratch folder `name`):
/// that folder and the CSV.
fn sweep(grid: &str, extra: &[&str], name: &str) -> (PathBuf, String) {
    let dir = scratch(&format!("sweep-{name}")).join("out");
    let d = dir.display().to_string();
    let mut args = vec!["sweep", "builtin:living-room", "--grid", grid, "--out", &d];
    args.extend_from_slice(extra);
    run_ok(&args);
    let csv = std::fs::read_to_string(dir.join("coverage.csv")).unwrap();
    (dir, csv)
}

/// `trace --json` of the living room at order 2 to the receiver of a CSV row's fields.
fn trace_at(fields: &[&str]) -> Value {
    let rx = format!("{},{},{}", fields[0], fields[1], fields[2]);
    run_json(&cli(
        "trace builtin:living-room --rx {} --max-order 2 --json",
        &[&rx],
    ))
}

#[test]
fn every_point_equals_its_own_trace() {
    let grid = "0.7:5.2:1.5,0.6:3.9:1.1,1.1";
    let (dir, csv) = sweep(grid, &["--max-order", "2"], "points");
    for ext in ["svg", "png"] {
        assert!(
            std::fs::metadata(dir.join(format!("coverage.{ext}")))
                .unwrap()
                .len()
                > 1000
        );
    }
    let lines: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(lines.len(), 4 * 4);
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f[3], "ok", "{line}");
        let doc = trace_at(&f);
        let paths = doc["paths"].as_array().unwrap();
        assert_eq!(f[4].parse::<usize>().unwrap(), paths.len(), "{line}");
        let delay = paths
            .iter()
            .map(|p| p["delay_s"].as_f64().unwrap())
            .fold(f64::INFINITY, f64::min);
        assert!(
            (f[5].parse::<f64>().unwrap() - delay * 1e9).abs() < 1e-6,
            "{line}"
        );
        let best = paths
            .iter()
            .min_by(|a, b| {
                a["loss_db"]
                    .as_f64()
                    .unwrap()
                    .total_cmp(&b["loss_db"].as_f64().unwrap())
            })
            .unwrap();
        assert_eq!(
            f[6].parse::<u64>().unwrap(),
            best["order"].as_u64().unwrap(),
            "{line}"
        );
        assert!((f[7].parse::<f64>().unwrap() - best["loss_db"].as_f64().unwrap()).abs() < 1e-4);
        let names: Vec<&str> = best["surfaces"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap())
            .collect();
        assert_eq!(f[9], names.join(" > "), "{line}");
    }
    let _ = std::fs::remove_dir_all(dir.parent().unwrap());
}

#[test]
fn tiny_grid_matches_the_golden_csv_and_marks_the_tx() {
    // (5.6, 0.6, 2.2) is the living room's TX: skipped with empty fields, the rest traced.
    let (dir, csv) = sweep("5.0:5.6:0.3,0.6:1.2:0.6,2.2", &[], "golden");
    assert_golden(golden::dir().join("sweep-living-room.csv"), &csv);
    assert!(
        csv.contains(
            "5.600000,0.600000,2.200000,skipped,,,,,,,,tx and rx are at the same position"
        )
    );
    // The heat map's legend says what the grey crossed cell is.
    let svg = std::fs::read_to_string(dir.join("coverage.svg")).unwrap();
    assert!(
        svg.contains("skipped: on a surface or at the TX"),
        "no legend"
    );
    let (dir1, single) = sweep(
        "5.0:5.6:0.3,0.6:1.2:0.6,2.2",
        &["--single-thread"],
        "single",
    );
    assert_eq!(csv, single, "output depends on the thread count");
    let _ = std::fs::remove_dir_all(dir.parent().unwrap());
    let _ = std::fs::remove_dir_all(dir1.parent().unwrap());
}

#[test]
fn bad_grids_are_refused_with_the_field_named() {
    let cases = [
        ("0:1:0.5,0:1:0.5", "2 comma-separated fields, expected 3"),
        ("0:1:0.5,0:1,1", "y axis \"0:1\" has 2"),
        ("0:1:x,0:1:0.5,1", "x step \"x\" is not a number"),
        ("1:0:0.5,0:1:0.5,1", "x stop 0 is below its start 1"),
        ("0:1:0.5,0:1:-1,1", "y step must be positive"),
        (
            "0:100:0.01,0:100:0.01,1",
            "use a coarser step or raise the budget with --max-points",
        ),
    ];
    let dir = scratch("sweep-bad").join("out");
    for (grid, message) in cases {
        let out = dir.display().to_string();
        let o = beamtrace(&cli(
            "sweep builtin:living-room --grid {} --out {}",
            &[grid, &out],
        ));
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{grid}: {err}");
        assert!(err.contains(message), "{grid}: {err}");
        assert!(!dir.exists(), "{grid}: wrote output");
    }
    let o = beamtrace(&cli(
        "sweep builtin:living-room --grid 0:1:1,0:1:1,1 --rx 1,1,1 --out x",
        &[],
    ));
    assert!(stderr(&o).contains("--rx is not used"));
}

#[test]
fn received_power_column_equals_trace_json_received_power() {
    let (dir, csv) = sweep(
        "1.0:4.0:3.0,1.5:1.5:1.0,1.1",
        &["--max-order", "2"],
        "power",
    );
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let column = header
        .iter()
        .position(|h| *h == "received_power_dbm")
        .unwrap();
    let lines: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(lines.len(), 2);
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let doc = trace_at(&f);
        let expected = doc["stats"]["received_power_dbm"].as_f64().unwrap();
        let got: f64 = f[column].parse().unwrap();
        assert!((got - expected).abs() < 1e-4, "{line}: {got} vs {expected}");
        assert!(got < -40.0 && got > -120.0, "{line}: {got} dBm");
    }
    let _ = std::fs::remove_dir_all(dir.parent().unwrap());
}

/// Piped (stderr not a terminal), a long sweep still shows progress: a plain line every
/// heartbeat period (5 s; 20 ms here, through `BEAMTRACE_HEARTBEAT_MS`).
#[test]
fn a_piped_sweep_prints_progress_lines() {
    let dir = scratch("sweep-heartbeat").join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(["sweep", "builtin:living-room", "--single-thread", "--out"])
        .arg(&dir)
        .args(["--grid", "0.25:5.75:0.125,0.25:4.25:0.125,1.2"])
        .env("BEAMTRACE_HEARTBEAT_MS", "20")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.lines()
            .any(|l| l.starts_with("sweep: ") && l.contains("/1485")),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir.parent().unwrap());
}
