//! A golden file for every module the generator emits: the small scene's PEs and `bt_top`
//! (`testdata/golden/rtl/small_scene/<module>.v`), and with early stopping, which adds the box logic
//! to `bt_top` only (`testdata/golden/rtl/small_scene_early/bt_top.v`; its PEs must equal the plain
//! design's).
//! A change of the generated Verilog fails here; `UPDATE_GOLDEN=1 cargo test -p bt-hls --test it
//! golden_rtl` rewrites the files after a deliberate change (review the diff).

use crate::common::*;
use bt_hls::{HlsInput, Platform, StepWork};

fn modules(input: HlsInput) -> Vec<(String, String)> {
    let schedule = small_schedule(&input);
    let platform = Platform::fitting(&[StepWork { input, schedule }]).unwrap();
    bt_hls::rtl_modules(&platform).unwrap()
}

/// Golden-checks `modules` in `testdata/golden/rtl/<design>/` and that no golden file is stale.
fn check_design(design: &str, modules: &[(String, String)]) {
    for (name, text) in modules {
        golden(&format!("{design}/{name}.v"), text);
    }
    let dir = golden_dir().join(design);
    for entry in std::fs::read_dir(&dir).unwrap() {
        let file = entry.unwrap().file_name().into_string().unwrap();
        let stem = file.strip_suffix(".v").unwrap_or(&file);
        assert!(
            modules.iter().any(|(name, _)| name == stem),
            "{}: stale golden file {file}",
            dir.display()
        );
    }
}

#[test]
fn every_module_of_the_small_scene_matches_its_golden_file() {
    let m = modules(small_scene());
    assert!(m.iter().any(|(name, _)| name == "bt_top"));
    assert!(m.iter().any(|(name, _)| name == "bt_pe_0"));
    check_design("small_scene", &m);
}

#[test]
fn early_stopping_changes_only_bt_top() {
    let plain = modules(small_scene());
    let early = modules(small_scene_early());
    assert_eq!(plain.len(), early.len());
    for ((a, text_a), (b, text_b)) in plain.iter().zip(&early) {
        assert_eq!(a, b);
        if a == "bt_top" {
            assert_ne!(text_a, text_b, "early stopping adds the box logic");
        } else {
            assert_eq!(text_a, text_b, "{a}");
        }
    }
    let top: Vec<(String, String)> = early.into_iter().filter(|(n, _)| n == "bt_top").collect();
    check_design("small_scene_early", &top);
}
