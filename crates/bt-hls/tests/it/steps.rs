//! One platform, several time steps: the host loads each step's schedule, start points and
//! TX/RX over the bus and the RTL matches the model bit for bit in every run (Verilator).

use std::path::PathBuf;

use crate::common::*;
use bt_hls::{Platform, StepWork};
use bt_schedule::round_template;

/// A step's work for dynamic dispatch: its round template, built without any model run.
fn list_work(input: bt_hls::HlsInput) -> StepWork {
    let schedule = round_template(&input.one_round_problem(), &[]).unwrap();
    StepWork { input, schedule }
}

/// Step 0: the small scene (Jacobi rounds). Step 1: other TX/RX, every second candidate, start
/// points moved 0.3 m, red-black rounds. Step 2: five paths only (a shorter schedule than the
/// ones loaded before it, so stale entries would show), red-black, one of order 3 with both
/// ends on the floor (its first phase takes the floor's PE twice) and one of order 4 (two
/// points in each phase).
fn three_steps() -> Vec<StepWork> {
    let s0 = small_scene();
    let mut s1 = small_scene();
    let keep: Vec<usize> = (0..s1.paths.len()).step_by(2).collect();
    s1.paths = keep.iter().map(|&p| s1.paths[p].clone()).collect();
    s1.init_points = keep
        .iter()
        .map(|&p| {
            s1.init_points[p]
                .iter()
                .map(|q| [q[0] * 0.9 + 0.3, q[1] * 0.9 + 0.2, q[2]])
                .collect()
        })
        .collect();
    s1.tx = [0.7, 3.0, 2.0];
    s1.rx = [4.2, 1.1, 0.9];
    s1.test_vectors = vec![[[1.5, 1.5, 1.5], [3.5, 2.5, 1.0]]];
    s1.round_order = bt_hls::RoundOrder::RedBlack;
    let mut s2 = small_scene();
    s2.paths = vec![
        vec![4],
        vec![1, 4],
        vec![2],
        vec![4, 5, 4],
        vec![2, 4, 3, 5],
    ];
    s2.init_points = vec![
        vec![[2.5, 2.0, 0.0]],
        vec![[5.0, 2.0, 1.5], [2.5, 2.0, 0.0]],
        vec![[2.5, 0.0, 1.5]],
        vec![[2.0, 1.8, 0.0], [2.5, 2.0, 3.0], [3.0, 2.2, 0.0]],
        vec![
            [1.5, 0.0, 1.0],
            [2.0, 1.0, 0.0],
            [2.5, 4.0, 1.5],
            [3.0, 2.5, 3.0],
        ],
    ];
    s2.test_vectors.clear();
    s2.round_order = bt_hls::RoundOrder::RedBlack;
    vec![list_work(s0), list_work(s1), list_work(s2)]
}

#[test]
fn one_design_runs_every_step_bit_exact() {
    let work = three_steps();
    let platform = Platform::fitting(&work).unwrap();
    assert_eq!(platform.instances.len(), 6, "one PE per plane");
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_steps");
    let _ = std::fs::remove_dir_all(&dir);
    let report = bt_hls::generate_steps(&platform, &work, &dir).unwrap();
    let lint = bt_hls::lint(&dir).unwrap();
    assert!(lint.warnings.is_empty(), "{}", lint.warnings.join("\n"));
    let mut seen = Vec::new();
    let sim =
        bt_hls::simulate_with(&dir, bt_hls::Simulator::Verilator, &mut |p| seen.push(p)).unwrap();
    eprintln!("{sim:#?}");
    assert_eq!(sim.mismatches, 0, "{:#?}", sim.mismatch_details);
    assert!(sim.passed());
    assert_eq!(sim.steps, 3);
    assert_eq!(sim.vectors, 3 + 2 + 1);
    assert_eq!(sim.irq_cycles, report.predicted.run_cycles);
    // The last step (5 paths) holds the fewest groups, and every run of it is shorter than
    // every run of the first step (26 paths): a stale group of an earlier step would show.
    assert!(report.makespans[2] < report.makespans[1] && report.makespans[2] < report.makespans[0]);
    let runs = &report.predicted.run_cycles;
    assert!(runs[5] < *runs[..3].iter().min().unwrap(), "{runs:?}");
    assert_eq!(
        seen.last(),
        Some(&bt_hls::SimProgress::Runs { done: 6, total: 6 })
    );
}

#[test]
fn steps_that_do_not_fit_the_platform_are_rejected() {
    let work = three_steps();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_steps_never");
    // Step 2's platform has no PE for plane 0 (no path of step 2 meets it), which step 0 needs.
    let mut platform = Platform::fitting(&work[2..]).unwrap();
    assert!(platform.instances.iter().all(|i| i.plane != 0));
    match bt_hls::generate_steps(&platform, &work, &dir) {
        Err(bt_hls::HlsError::Schedule(e)) => assert!(e.contains("not on the platform"), "{e}"),
        other => panic!("{other:?}"),
    }
    // With every PE, its RAMs (sized for step 2) are still too small for step 0.
    platform.instances = Platform::fitting(&work).unwrap().instances;
    assert!(matches!(
        bt_hls::generate_steps(&platform, &work, &dir),
        Err(bt_hls::HlsError::TooLarge(_))
    ));
    let mut moved = work[2].clone();
    moved.input.planes[1].offset_m = -4.9;
    assert!(matches!(
        bt_hls::generate_steps(&platform, &[moved], &dir),
        Err(bt_hls::HlsError::InvalidInput { .. })
    ));
}
