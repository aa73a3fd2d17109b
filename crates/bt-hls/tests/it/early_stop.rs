//! The small scene with early stopping: paths whose point leaves its wall's box are frozen
//! (`left_bounds`) in the model and in the RTL, bit for bit, and free their schedule slots.

use std::path::PathBuf;

use crate::common::*;

#[test]
fn early_stopping_is_bit_exact_and_shortens_the_schedule() {
    let plain = small_scene();
    let input = small_scene_early();
    let rounds =
        |i: &bt_hls::HlsInput| -> u32 { i.problem().unwrap().paths.iter().map(|p| p.rounds).sum() };
    let results = input.model().unwrap().run(input.tx, input.rx).unwrap();
    let frozen = results.iter().filter(|r| r.left_bounds).count();
    assert!(frozen > 0, "no path left its box");
    assert!(results.iter().all(|r| !(r.left_bounds && r.converged)));
    // A path that is not frozen runs exactly as without early stopping.
    let plain_results = plain.model().unwrap().run(plain.tx, plain.rx).unwrap();
    for (p, (a, b)) in results.iter().zip(&plain_results).enumerate() {
        eprintln!(
            "path {p} {:?}: {:?} (plain {:?})",
            input.paths[p],
            a.outcome(),
            b.outcome()
        );
        if !a.left_bounds {
            assert_eq!(a, b);
        }
    }
    assert!(rounds(&input) < rounds(&plain));

    let schedule = small_schedule(&input);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_small_scene_early");
    let _ = std::fs::remove_dir_all(&dir);
    let report = bt_hls::generate(&input, &schedule, &dir).unwrap();
    let lint = bt_hls::lint(&dir).unwrap();
    assert!(
        lint.warnings.is_empty(),
        "verilator warnings:\n{}",
        lint.warnings.join("\n")
    );
    let sim = bt_hls::simulate(&dir).unwrap();
    assert_eq!(sim.mismatches, 0, "{:#?}", sim.mismatch_details);
    assert!(sim.words_compared > 0);
    assert_eq!(sim.cycles, sim.predicted_cycles());
    assert_eq!(sim.cycles, report.predicted.run_cycles[0]);
    assert!(sim.passed());
    assert_eq!(sim.tb_cycles, sim.predicted.tb_cycles);
    eprintln!(
        "small scene with early stopping: {frozen} paths frozen, {} cycles (plain: {})",
        report.predicted.run_cycles[0],
        generated().report.predicted.run_cycles[0]
    );
    // Dynamic dispatch: a frozen path frees its PEs at once, so the run is shorter than the
    // plain one on the same template and PEs (measured in the RTL above, equal to the twin).
    assert!(sim.cycles < generated().report.predicted.run_cycles[0]);
}
