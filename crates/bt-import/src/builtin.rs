//! Built-in scenes, shipped inside the binary: their JSON lives in `crates/bt-import/scenes/`
//! (parsing it is this crate's job, so the texts live here too); `city` is generated.

use crate::{ImportError, parse_json};
use bt_scene::dynamic::DynamicScene;
use bt_scene::{Scene, Terminals};

const LIVING_ROOM: &str = include_str!("../scenes/living-room.json");
const LIVING_ROOM_DYNAMIC: &str = include_str!("../scenes/living-room-dynamic.json");

/// Names accepted by [`builtin_scene`].
pub fn builtin_names() -> &'static [&'static str] {
    &["living-room", "living-room-dynamic", "city"]
}

/// The JSON text of a built-in scene, as a documented example of the scene format.
pub fn builtin_json(name: &str) -> Option<&'static str> {
    match name {
        "living-room" => Some(LIVING_ROOM),
        // Load it with `builtin_dynamic_scene` for all 10 steps; as a static scene
        // it is step 0 (person at its start, door closed).
        "living-room-dynamic" => Some(LIVING_ROOM_DYNAMIC),
        _ => None,
    }
}

/// A built-in scene by name: `living-room` is a furnished 6 × 4.5 × 2.7 m living room with 25
/// reflecting surfaces, a lamp shade and a standing person as blockers, TX at router height
/// (2.2 m) and RX at laptop height (0.72 m).
///
/// `city` is the seeded synthetic city of [`crate::city`] (a triangle mesh through the mesh
/// pipeline), TX on a 10 m mast in a street, RX at 1.5 m 180 m down the same street.
pub fn builtin_scene(name: &str, terminals: Terminals) -> Option<Result<Scene, ImportError>> {
    if name == "city" {
        return Some(city_scene(terminals));
    }
    let json = builtin_json(name)?;
    let source = format!("builtin:{name}");
    Some(
        parse_json(json, &source)
            .and_then(|d| Ok(Scene::from_description(&d, &source, terminals)?)),
    )
}

fn city_scene(terminals: Terminals) -> Result<Scene, ImportError> {
    let city = crate::city::CityOptions::default();
    let terminals = Terminals {
        tx: terminals.tx.or(Some(city.street_point(10, 1000.0, 10.0))),
        rx: terminals.rx.or(Some(city.street_point(10, 1180.0, 1.5))),
    };
    crate::city::city_scene(&city, terminals)
}

/// Names accepted by [`builtin_dynamic_scene`].
pub fn builtin_dynamic_names() -> &'static [&'static str] {
    &["living-room-dynamic"]
}

/// A built-in dynamic scene by name: `living-room-dynamic` is the built-in living room over 10
/// steps with a person (0.4 × 0.3 × 1.75 m blocker) walking across the room through the
/// line of sight, and the door swinging open about its hinge from 0° to 90° (10° per step).
/// Static built-in scenes are returned as one-step dynamic scenes.
pub fn builtin_dynamic_scene(
    name: &str,
    terminals: Terminals,
) -> Option<Result<DynamicScene, ImportError>> {
    let json = builtin_json(name)?;
    let source = format!("builtin:{name}");
    Some(
        parse_json(json, &source)
            .and_then(|d| Ok(DynamicScene::from_description(&d, &source, terminals)?)),
    )
}
