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
    assert_eq!(s.cycles, s.predicted_cycles);
    assert_eq!(s.cycles, g.report.run_cycles[0]);
    assert_eq!(s.irq_cycles, s.predicted_run_cycles);
    assert_eq!(s.tb_cycles, s.predicted_tb_cycles);
    assert!(s.passed());
    assert_eq!(s.vectors, 3);
}
