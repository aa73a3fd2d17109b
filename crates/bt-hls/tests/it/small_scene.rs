//! The small scene end to end: lint, co-simulation, golden files, synthesis.

use std::sync::OnceLock;

use crate::common::*;

fn sim() -> &'static bt_hls::SimReport {
    static S: OnceLock<bt_hls::SimReport> = OnceLock::new();
    S.get_or_init(|| bt_hls::simulate(&generated().dir).expect("simulate"))
}

#[test]
fn generated_rtl_is_lint_clean() {
    let g = generated();
    let lint = bt_hls::lint(&g.dir).expect("lint");
    assert!(lint.modules.iter().any(|m| m == "bt_top"));
    assert!(
        lint.warnings.is_empty(),
        "verilator warnings:\n{}",
        lint.warnings.join("\n")
    );
}

#[test]
fn cosimulation_is_bit_exact_and_cycles_match() {
    let g = generated();
    let s = sim();
    eprintln!("{s:#?}");
    assert_eq!(s.mismatches, 0, "{:#?}", s.mismatch_details);
    assert!(s.words_compared > 0);
    assert_eq!(s.cycles, s.predicted_cycles());
    assert_eq!(s.cycles, g.report.predicted.run_cycles[0]);
    assert_eq!(s.irq_cycles, s.predicted.run_cycles);
    assert_eq!(s.tb_cycles, s.predicted.tb_cycles);
    assert!(s.passed());
    assert_eq!(s.vectors, 3);
}

/// The full 40-bit datapath (inputs written before narrowing) stays lint-clean and bit-exact,
/// and on this room it gives the narrowed design's results but for the last bit: the room's
/// points never come near the narrow word's ±32 m, and the narrow PE's 24 halving steps (32 at
/// 40 bits) move an offset by at most 1 LSB (`bt-fixed/tests/it/algorithm3.rs`).
#[test]
fn the_full_width_design_is_bit_exact_and_agrees_with_the_narrow_one() {
    let narrow = small_scene();
    let full = bt_hls::HlsInput {
        coord_bits: bt_fixed::width::COORD,
        ..narrow.clone()
    };
    assert!(narrow.coord_bits < full.coord_bits);
    let run = |input: &bt_hls::HlsInput| input.model().unwrap().run(input.tx, input.rx).unwrap();
    let (narrow_runs, full_runs) = (run(&narrow), run(&full));
    let mut largest = 0;
    for (a, b) in narrow_runs.iter().zip(&full_runs) {
        assert_eq!(
            (a.converged, a.zero_sum, a.overflow, a.left_bounds),
            (b.converged, b.zero_sum, b.overflow, b.left_bounds)
        );
        if a.converged {
            assert!(a.rounds.abs_diff(b.rounds) <= 1, "{a:?} vs {b:?}");
            for (p, q) in a.points.iter().zip(&b.points) {
                for k in 0..3 {
                    largest = largest.max((p[k].0 - q[k].0).abs());
                }
            }
        }
    }
    // 1/64 mm: a few LSB where the last-bit differences feed later rounds.
    assert!(
        largest <= 4,
        "converged points differ by {largest} fine LSB"
    );
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_small_scene_full");
    let _ = std::fs::remove_dir_all(&dir);
    let schedule = small_schedule(&full);
    bt_hls::generate(&full, &schedule, &dir).expect("generate");
    let top = std::fs::read_to_string(dir.join("rtl/bt_top.v")).unwrap();
    assert!(
        top.contains("[119:0] pm_a"),
        "40-bit points: three 40-bit words"
    );
    let lint = bt_hls::lint(&dir).expect("lint");
    assert!(lint.warnings.is_empty(), "{}", lint.warnings.join("\n"));
    let s = bt_hls::simulate(&dir).expect("simulate");
    assert_eq!(s.mismatches, 0, "{:#?}", s.mismatch_details);
    assert_eq!(s.cycles, s.predicted_cycles());
    assert!(s.passed());
}
