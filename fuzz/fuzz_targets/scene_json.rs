//! JSON scene files: `parse_json`, then static and dynamic validation. Errors are fine; a panic,
//! an abort (huge allocation) or a non-finite value in an accepted scene is a finding.
#![no_main]

use bt_scene::dynamic::DynamicScene;
use bt_scene::{Scene, Terminals};
use libfuzzer_sys::fuzz_target;

fn check(scene: &Scene) {
    // Terminals belong to a trace: a scene file may have none.
    assert!(scene.tx().is_none_or(|p| p.is_finite()) && scene.rx().is_none_or(|p| p.is_finite()));
    assert!(scene.extent().is_finite() && scene.length_tolerance().is_finite());
    for s in scene.surfaces() {
        assert!(s.polygon.vertices().iter().all(|v| v.is_finite()), "{s:?}");
        assert!(s.polygon.area().is_finite(), "{s:?}");
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(desc) = bt_import::parse_json(text, "fuzz.json") else {
        return;
    };
    if let Ok(scene) = Scene::from_description(&desc, "fuzz", Terminals::default()) {
        check(&scene);
    }
    if let Ok(dynamic) = DynamicScene::from_description(&desc, "fuzz", Terminals::default()) {
        dynamic.scenes().iter().for_each(check);
    }
});
