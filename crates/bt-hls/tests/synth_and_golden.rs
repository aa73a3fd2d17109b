//! Golden files, determinism and a synthesis smoke test.

mod common;

use std::path::PathBuf;

use bt_hls::{HlsInput, PlaneSpec};
use bt_schedule::{Budget, schedule_list};
use common::*;

#[test]
fn golden_cycle_count() {
    let g = generated();
    let r = &g.report;
    let pinned = serde_json::json!({
        "instances": r.num_instances,
        "makespans": r.makespans,
        "run_cycles": r.run_cycles,
        "predicted_tb_cycles": r.predicted_tb_cycles,
        "status_base": r.status_base,
        "point_base": r.point_base,
        "sched_base": r.sched_base,
    });
    golden(
        "small_scene_cycles.json",
        &(serde_json::to_string_pretty(&pinned).unwrap() + "\n"),
    );
}

#[test]
fn generation_is_deterministic() {
    let g = generated();
    let work = [bt_hls::StepWork {
        input: g.input.clone(),
        schedule: g.schedule.clone(),
    }];
    let again = bt_hls::rtl_modules(&bt_hls::Platform::fitting(&work).unwrap()).unwrap();
    for (name, text) in again {
        let on_disk = std::fs::read_to_string(g.dir.join(format!("rtl/{name}.v"))).unwrap();
        assert_eq!(on_disk, text, "{name} differs between two generations");
    }
    assert!(g.report.docs.contains("PATH_STATUS"));
}

#[test]
fn invalid_input_is_reported_not_panicked() {
    let g = generated();
    let mut bad = g.input.clone();
    bad.paths[0] = vec![99];
    assert!(matches!(
        bt_hls::generate(&bad, &g.schedule, &g.dir.join("never")),
        Err(bt_hls::HlsError::InvalidInput { .. } | bt_hls::HlsError::Fixed(_))
    ));
    let mut short = g.schedule.clone();
    short.slots.truncate(1);
    assert!(matches!(
        bt_hls::generate(&g.input, &short, &g.dir.join("never")),
        Err(bt_hls::HlsError::Schedule(_))
    ));
}

/// A tiny scene (tilted wall + floor, 3 paths) keeps the Yosys run short.
fn tiny_scene() -> HlsInput {
    let mut s = small_scene();
    let keep = [0usize, 4];
    s.planes = keep
        .iter()
        .map(|&i| s.planes[i].clone())
        .collect::<Vec<PlaneSpec>>();
    s.paths = vec![vec![0], vec![1], vec![0, 1]];
    s.init_points = vec![
        vec![[0.0, 2.0, 1.5]],
        vec![[2.5, 2.0, 0.0]],
        vec![[0.0, 2.0, 1.5], [2.5, 2.0, 0.0]],
    ];
    s.max_rounds = 8;
    s.test_vectors.clear();
    s
}

#[test]
fn synthesis_smoke_test_reports_cell_counts() {
    let input = tiny_scene();
    let problem = input.problem().unwrap();
    let schedule = schedule_list(&problem, &Budget::originals_only(&problem)).unwrap();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_tiny_scene");
    let _ = std::fs::remove_dir_all(&dir);
    bt_hls::generate(&input, &schedule, &dir).unwrap();
    // Icarus stays an option (`hls sim --simulator icarus`): it runs the same testbench.
    let sim = bt_hls::simulate_with(&dir, bt_hls::Simulator::Icarus, &mut |_| {}).unwrap();
    assert_eq!(sim.mismatches, 0, "{:#?}", sim.mismatch_details);
    assert_eq!(sim.cycles, sim.predicted_cycles);
    assert!(sim.passed());
    let synth = bt_hls::synthesize(&dir).unwrap();
    eprintln!("tiny scene: {synth:#?}");
    assert!(synth.logic_cells > 100, "{synth:?}");
    assert!(synth.registers > 100, "{synth:?}");
    assert!(synth.percent_of_ep4ce115 > 0.0 && synth.percent_of_ep4ce115 < 100.0);
    // The point memory (two copies of 8 x 120 bits) and the packed schedule memory (the
    // entries rounded up to 32, of 10 bits: 1 column bit, tail, end, last, first, 2 point
    // bits, 2 path bits, valid) are inferred into M9K, not registers.
    assert!(synth.m9k_blocks > 0, "{synth:?}");
    assert_eq!(synth.memory_bits, 2 * 8 * 120 + 32 * 10, "{synth:?}");
}
