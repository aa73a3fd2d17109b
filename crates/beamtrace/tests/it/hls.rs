//! `beamtrace hls`: every time step of the dynamic living room run through one design and
//! co-simulated bit for bit against the fixed-point model, with the measured cycle counts
//! equal to the dispatching controller's twin; no model run feeds the host's work.

use crate::common::*;
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

/// Dynamic dispatch needs no model run on the host, on generic PEs (the default) and on PEs
/// per plane with or without copies (`--pe-budget`: 0 gives none; `--generic-pes 0` gives the
/// PEs of planes no path meets to copies), and each path runs its own rounds whatever the PEs.
#[test]
fn no_model_run_feeds_the_host_with_or_without_copies() {
    let root = scratch("hls-dispatch");
    let (plain, dup, default) = (root.join("plain"), root.join("dup"), root.join("default"));
    let per_plane = root.join("per-plane");
    let runs = [
        (&plain, vec!["--pe-budget", "0"]),
        (&dup, vec!["--pe-budget", "40"]),
        (&default, vec![]),
        (&per_plane, vec!["--generic-pes", "0"]),
    ];
    for (dir, extra) in runs {
        let mut args = cli(
            "hls gen builtin:living-room --max-order 2 --plan-only -o {}",
            &[dir.to_str().unwrap()],
        );
        args.extend(extra);
        run_ok(&args);
    }
    let summary = |dir: &std::path::Path| read_json(&dir.join("summary.json"));
    let (p, d, f) = (summary(&plain), summary(&dup), summary(&default));
    let r = summary(&per_plane);
    for s in [&p, &d, &f, &r] {
        assert_eq!(s["host_model_runs"], 0, "{s}");
        assert_eq!(s["schedule"], "dynamic", "{s}");
        assert_eq!(s["fixed_vs_f64"]["missed"], 0, "{s}");
    }
    assert_eq!(p["stats"]["duplicates"], 0);
    assert!(d["stats"]["duplicates"].as_u64().unwrap() > 0, "{d}");
    // The default: 12 generic PEs, no plane's copies.
    assert_eq!(f["platform_instances"], bt_hls::DEFAULT_GENERIC_PES, "{f}");
    assert_eq!(f["stats"]["duplicates"], 0, "{f}");
    // PEs per plane: one per static reflector of the room, some of them copies.
    assert_eq!(r["platform_instances"], r["planes"], "{r}");
    assert!(r["stats"]["duplicates"].as_u64().unwrap() > 0, "{r}");
    // The same PE jobs every way: each path runs its own rounds.
    assert_eq!(p["dispatch"]["jobs"], d["dispatch"]["jobs"]);
    assert_eq!(p["dispatch"]["jobs"], f["dispatch"]["jobs"]);
    assert_eq!(p["dispatch"]["jobs"], r["dispatch"]["jobs"]);
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
    // `hls gen` with `options` into `root/name`: refused, nothing written; its message.
    let refused = |options: &str, name: &str| {
        let dir = root.join(name);
        let o = beamtrace(&cli(
            &format!("hls gen builtin:living-room --plan-only {options} -o {{}}"),
            &[dir.to_str().unwrap()],
        ));
        let out = text(&o);
        assert!(!o.status.success() && !dir.exists(), "{out}");
        out
    };
    // The accelerator is reflection-only: asked for diffraction, it says so and writes nothing.
    let out = refused("--diffraction", "diffraction");
    assert!(
        out.contains("specular paths only") && out.contains("trace --diffraction"),
        "{out}"
    );
    // Generic PEs beyond the device's multipliers: refused even when only planning.
    let out = refused("--generic-pes 30", "generic");
    assert!(
        out.contains("--multiplier-budget") && out.contains("--generic-pes"),
        "{out}"
    );
}
