//! The small scene on generic PEs (any PE takes any plane's job, its plane's coefficients
//! loaded from the plane table): the same bits as the model with early stopping on (its box
//! chosen by the job's plane), the twin's cycles, lint-clean RTL, a golden file per module that
//! differs from the plane PEs' design, and the refusals.

use std::path::PathBuf;

use bt_hls::{HlsError, Platform, StepWork};
use bt_schedule::{PeInstance, generic_round_template};

use crate::common::*;

/// The early-stopping small scene on `pes` generic PEs.
fn work(pes: u32) -> Vec<StepWork> {
    let input = small_scene_early();
    let schedule = generic_round_template(&input.one_round_problem(), pes).unwrap();
    vec![StepWork { input, schedule }]
}

#[test]
fn generic_pes_are_bit_exact_with_early_stopping_and_the_twins_cycles() {
    let work = work(3);
    let platform = Platform::fitting(&work).unwrap();
    assert!(platform.is_generic());
    assert_eq!(platform.instances.len(), 3);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_small_scene_generic");
    let _ = std::fs::remove_dir_all(&dir);
    let report = bt_hls::generate_steps(&platform, &work, &dir).unwrap();
    assert!(report.address_map.plane_base.is_some());
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
    assert_eq!(sim.irq_cycles, sim.predicted.run_cycles);
    assert_eq!(sim.vectors, 3);
    assert!(sim.passed());
    // Some paths leave their plane's box in every vector: the box table is exercised.
    let input = &work[0].input;
    let frozen = input.model().unwrap().run(input.tx, input.rx).unwrap();
    assert!(frozen.iter().any(|r| r.left_bounds));
}

#[test]
fn the_generic_design_matches_its_golden_files_and_shares_the_core() {
    let generic = bt_hls::rtl_modules(&Platform::fitting(&work(3)).unwrap()).unwrap();
    let names: Vec<&str> = generic.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["bt_pe_core", "bt_pe_generic", "bt_top"]);
    let input = small_scene_early();
    let schedule = small_schedule(&input);
    let planes =
        bt_hls::rtl_modules(&Platform::fitting(&[StepWork { input, schedule }]).unwrap()).unwrap();
    assert_eq!(generic[0], planes[0], "one core for both kinds of PE");
    for (name, text) in &generic[1..] {
        golden(&format!("small_scene_generic/{name}.v"), text);
    }
}

#[test]
fn a_platform_that_mixes_pe_kinds_or_lacks_multipliers_is_refused() {
    let work = work(3);
    let mut platform = Platform::fitting(&work).unwrap();
    platform.multiplier_budget = 3 * 12 - 1;
    let text = bt_hls::rtl_modules(&platform)
        .and_then(|_| {
            bt_hls::generate_steps(
                &platform,
                &work,
                &PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_generic_refused"),
            )
        })
        .unwrap_err()
        .to_string();
    assert!(text.contains("36 18 x 18 multiplier blocks"), "{text}");
    let mut mixed = Platform::fitting(&work).unwrap();
    mixed.instances[0] = PeInstance { plane: 0, copy: 0 };
    let e = bt_hls::generate_steps(
        &mixed,
        &work,
        &PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_generic_mixed"),
    )
    .unwrap_err();
    assert!(matches!(e, HlsError::InvalidInput { .. }), "{e}");
    assert!(e.to_string().contains("mixes generic PEs"), "{e}");
}
