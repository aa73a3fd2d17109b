//! Inputs found by fuzzing (`fuzz/`, see `docs/fuzzing.md`), kept so the fixes stay fixed. Each
//! file under `testdata/fuzz-regressions/` must give an error, not a panic or an abort.

use bt_import::parse_json;
use bt_scene::dynamic::{DynamicScene, MAX_STEPS, MAX_SURFACE_STEPS};
use bt_scene::{SceneDescription, SceneError, Terminals};

fn regression(name: &str) -> String {
    let path = format!(
        "{}/testdata/fuzz-regressions/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// `desc` is refused with a problem at `steps` that names `limit`.
fn assert_steps_refused(desc: &SceneDescription, file: &str, limit: impl std::fmt::Display) {
    let err = DynamicScene::from_description(desc, file, Terminals::default()).unwrap_err();
    let SceneError::Invalid { problems, .. } = &err else {
        panic!("{err}")
    };
    assert!(
        problems
            .iter()
            .any(|p| p.location == "steps" && p.message.contains(&limit.to_string())),
        "{err}"
    );
}

/// A 150-byte file with `"steps": 4000000000` made `DynamicScene::from_description` reserve
/// one `Scene` per step up front: a 735 GB allocation and an abort.
#[test]
fn huge_step_count_is_a_problem_not_an_allocation() {
    let desc = parse_json(&regression("huge-steps.json"), "huge-steps.json").unwrap();
    assert_steps_refused(&desc, "huge-steps.json", MAX_STEPS);
}

#[test]
fn step_count_at_the_limit_is_accepted() {
    let mut desc = parse_json(&regression("huge-steps.json"), "huge-steps.json").unwrap();
    desc.steps = Some(MAX_STEPS);
    let scene = DynamicScene::from_description(&desc, "limit", Terminals::default()).unwrap();
    assert_eq!(scene.len(), MAX_STEPS as usize);
}

/// 3 KB: 70 boxes (420 surfaces) over 10 000 steps, within `MAX_STEPS`, asked for 4.2 million
/// surface copies (3.6 GB and 40 s in the fuzzing build).
#[test]
fn many_surfaces_times_many_steps_is_a_problem_not_an_allocation() {
    let text = regression("many-surface-steps.json");
    let desc = parse_json(&text, "many-surface-steps.json").unwrap();
    assert_steps_refused(&desc, "many-surface-steps.json", MAX_SURFACE_STEPS);
    // The same boxes over fewer steps are fine.
    let mut desc = desc;
    desc.steps = Some(10);
    let scene = DynamicScene::from_description(&desc, "fewer", Terminals::default()).unwrap();
    assert_eq!(scene.step(0).surfaces().len(), 420);
}
