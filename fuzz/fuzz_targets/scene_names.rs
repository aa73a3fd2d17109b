//! Names are data (`docs/reliability.md`): an accepted scene's surface, material and scene names
//! follow `bt_scene::name::check`, and `name::escape` of any string leaves no control character
//! and round-trips printable names unchanged. Input: a name (UTF-8) spliced into a scene.
#![no_main]

use bt_scene::{Scene, SceneDescription, SurfaceDesc, Terminals, name};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let escaped = name::escape(text);
    assert!(!escaped.chars().any(char::is_control), "{escaped:?}");
    if name::check(text).is_ok() && !text.contains(['"', '\\']) {
        assert_eq!(escaped, text);
    }
    let desc = SceneDescription {
        name: Some(text.to_string()),
        tx: Some([-1.5, 1.0, 2.0]),
        rx: Some([2.0, 2.0, 1.0]),
        surfaces: vec![SurfaceDesc {
            name: text.to_string(),
            vertices: vec![
                [-5.0, 0.0, 0.0],
                [5.0, 0.0, 0.0],
                [5.0, 0.0, 3.0],
                [-5.0, 0.0, 3.0],
            ],
            ..Default::default()
        }],
        ..Default::default()
    };
    match Scene::from_description(&desc, "fuzz", Terminals::default()) {
        Ok(scene) => {
            assert!(name::check(scene.name()).is_ok());
            for s in scene.surfaces() {
                assert!(name::check(&s.name).is_ok(), "{:?}", s.name);
            }
        }
        Err(e) => {
            let message = e.to_string();
            assert!(
                !message.chars().any(|c| c.is_control() && c != '\n'),
                "{message:?}"
            );
        }
    }
});
