//! `beamtrace hls`: every time step of the dynamic living room run through one design and
//! co-simulated bit for bit against the fixed-point model, with the cycle counts equal to the
//! prediction; the GA schedule never longer than the list schedule.

use crate::common::*;
use serde_json::Value;
use std::path::PathBuf;

/// `hls gen` with the arguments `line` and `values` (see [`cli`]) followed by `-o` into a fresh
/// folder named `name`, then `hls sim` of the design, which must report no mismatch and every
/// run as predicted: the scratch folder, the design's folder in it and the simulator's report.
fn generate_and_cosimulate(name: &str, line: &str, values: &[&str]) -> (PathBuf, PathBuf, String) {
    let root = scratch(name);
    let dir = root.join("out");
    let mut args = cli(line, values);
    args.extend(["-o", dir.to_str().unwrap()]);
    run_ok(&[&["hls", "gen"][..], &args].concat());
    let out = text(&run_ok(&["hls", "sim", dir.to_str().unwrap()]));
    assert!(out.contains(" 0 mismatches"), "{out}");
    assert!(out.contains("runs as predicted: true"), "{out}");
    (root, dir, out)
}

/// CI's multi-step co-simulation: the 10 steps of the dynamic living room (order 1) on ONE
/// design, each step's schedule, start points and TX/RX loaded over the bus, Verilator.
#[test]
fn living_room_steps_run_on_one_design_bit_exact() {
    let (root, dir, out) = generate_and_cosimulate(
        "hls-steps",
        "builtin:living-room-dynamic --steps --max-order 1",
        &[],
    );
    let doc = read_json(&dir.join("steps.json"));
    let steps = doc["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 10);
    for s in steps {
        assert!(fixed_point_tx_error_deg(s) < 0.1, "{s}");
        assert_eq!(s["fixed_vs_f64"]["spurious"], 0, "{s}");
    }
    assert!(dir.join("rtl/bt_top.v").exists());
    assert!(
        !dir.join("step-0/rtl").exists(),
        "one design, not one per step"
    );
    assert!(out.contains("verilator (10 steps, 10 runs)"), "{out}");
    let predicted = steps[0]["predicted_cycles"].as_u64().unwrap();
    assert!(
        out.contains(&format!(
            "CYCLES of run 0 {predicted} (predicted {predicted})"
        )),
        "{out}"
    );
    std::fs::remove_dir_all(&root).ok();
}

/// The stress design: a 37-plane street at order 2 with every candidate (683 paths,
/// 1,343 points: schedule entries wider than the 32-bit bus word, loaded through SCHED_HI)
/// co-simulates bit for bit in Verilator in seconds (it ran for over 20 minutes in Icarus).
#[test]
fn the_street_of_37_planes_cosimulates_with_wide_schedule_entries() {
    let (root, dir, _) = generate_and_cosimulate(
        "hls-street",
        "{} --max-order 2 --candidates exhaustive",
        &[&testdata("street-37.json")],
    );
    let summary = read_json(&dir.join("summary.json"));
    assert_eq!(summary["planes"], 37, "{summary}");
    assert_eq!(summary["paths"], 683, "{summary}");
    let top = std::fs::read_to_string(dir.join("rtl/bt_top.v")).unwrap();
    assert!(top.contains("sched_hi"), "entries wider than 32 bits");
    std::fs::remove_dir_all(&root).ok();
}

/// The README's form, run in the folder that is to hold the design: `hls builtin:living-room
/// --max-order 1 -o hw`, then `hls sim hw` with that relative name, in Verilator (whose
/// binary runs inside `hw/tb/`, where a path relative to the caller's folder names nothing).
#[test]
fn hls_sim_takes_the_readmes_relative_directory() {
    let root = scratch("hls-relative");
    run_ok_in(
        &root,
        &cli("hls builtin:living-room --max-order 1 -o hw", &[]),
    );
    let out = text(&run_ok_in(&root, &["hls", "sim", "hw"]));
    assert!(out.contains("hw: verilator ("), "{out}");
    assert!(out.contains(" 0 mismatches"), "{out}");
    assert!(out.contains("runs as predicted: true"), "{out}");
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn ga_is_never_longer_than_list_and_duplication_helps() {
    let root = scratch("hls-schedules");
    let (planes_only, dup, list) = (root.join("ga"), root.join("dup"), root.join("list"));
    for (dir, extra) in [
        (&planes_only, vec!["--schedule", "ga", "--pe-budget", "1"]),
        (&dup, vec!["--schedule", "ga", "--pe-budget", "40"]),
        (&list, vec!["--schedule", "list"]),
    ] {
        let mut args = cli(
            "hls gen builtin:living-room --max-order 2 --plan-only -o {}",
            &[dir.to_str().unwrap()],
        );
        args.extend(extra);
        run_ok(&args);
    }
    let summary = |dir: &std::path::Path| read_json(&dir.join("summary.json"));
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
    // The list scheduler keeps the shorter of most-jobs-first and the index-order baseline.
    assert!(makespan(&l) <= l["list_makespan"].as_u64().unwrap(), "{l}");
    std::fs::remove_dir_all(root).ok();
}

#[test]
fn hls_errors_are_clear() {
    let o = beamtrace(&["hls", "sim", "/no/such/dir"]);
    let (ok, out) = (o.status.success(), text(&o));
    assert!(
        !ok && out.contains("/no/such/dir") && !out.contains("panicked"),
        "{out}"
    );
    let root = scratch("hls-errors");
    let out = root.join("x");
    let o = beamtrace(&cli(
        "hls gen builtin:living-room --max-order 0 -o {}",
        &[out.to_str().unwrap()],
    ));
    let (ok, out) = (o.status.success(), text(&o));
    assert!(!ok && out.contains("--max-order"), "{out}");
    // The accelerator is reflection-only: asked for diffraction, it says so and writes nothing.
    let dir = root.join("diffraction");
    let o = beamtrace(&cli(
        "hls gen builtin:living-room --plan-only --diffraction -o {}",
        &[dir.to_str().unwrap()],
    ));
    let (ok, out) = (o.status.success(), text(&o));
    assert!(
        !ok && out.contains("specular paths only") && out.contains("trace --diffraction"),
        "{out}"
    );
    assert!(!dir.exists());
}
