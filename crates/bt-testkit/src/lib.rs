//! Seeded test scenes for the tests and benches of the other crates (a dev-dependency only,
//! `publish = false`): one home for the generators that were copied per crate.
//!
//! - [`scene_from_json`], [`box_room`], [`random_scene`]: a furnished box room with random
//!   rectangles (every third a blocker) and random terminals;
//! - [`nasty_scene`]: the beam tree's adversary: folded pairs, coplanar neighbours, L-shaped
//!   panels, blockers, grazing terminals and paths through edges and corners;
//! - [`corner_scene`]: two walls at a dihedral angle with a double bounce near the edge;
//! - [`partitioned`]: a room split by a partition with a doorway, random boxes and tilted
//!   quads, optionally moving over time steps;
//! - [`golden`]: the golden-file check of every golden test, with its update switch
//!   (`UPDATE_GOLDEN=1`);
//! - [`special`]: FIFOs for the tests of outputs (Unix).
//!
//! Same seed, same scene, on every platform (ChaCha8). Scenes are test input: the builders
//! panic when a generated scene does not validate.
#![warn(missing_docs)]

pub mod golden;
pub mod partitioned;
#[cfg(unix)]
pub mod special;

use bt_geom::{Real, Vec3};
use bt_scene::{Scene, SceneDescription, Terminals};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A scene from its JSON description (test input: panics when it does not validate).
pub fn scene_from_json(json: &str) -> Scene {
    let d: SceneDescription = serde_json::from_str(json).expect("test scene parses");
    Scene::from_description(&d, "test", Terminals::default()).expect("test scene is valid")
}

/// An empty box room `[0, size]` with TX and RX inside (each a `Vec3` or an `[x, y, z]`).
pub fn box_room(size: impl Into<Vec3>, tx: impl Into<Vec3>, rx: impl Into<Vec3>) -> Scene {
    let (size, tx, rx) = (size.into(), tx.into(), rx.into());
    scene_from_json(&format!(
        r#"{{ "tx": {:?}, "rx": {:?}, "boxes": [ {{ "name": "room", "min": [0, 0, 0], "max": {:?} }} ] }}"#,
        tx.to_array(),
        rx.to_array(),
        size.to_array()
    ))
}

/// The issue's floor/wall case: a 4 m × 4 m floor at z = 0 and a 3.5 m × 2 m wall in the plane
/// x = 0, whose shared line holds the floor's centroid (IPC from the centroids degenerates on
/// wall -> floor; the image method finds it, 3.960 m).
pub fn wall_floor_scene() -> Scene {
    scene_from_json(
        r#"{ "tx": [-0.3, -1.4, 2.3], "rx": [-0.9, 0.6, 0.9], "surfaces": [
            { "name": "floor", "vertices": [[-2,-2,0],[2,-2,0],[2,2,0],[-2,2,0]] },
            { "name": "wall", "vertices": [[0,-1.75,0.9],[0,1.75,0.9],[0,1.75,2.9],[0,-1.75,2.9]] } ] }"#,
    )
}

/// A random furnished room: a box room with `n` random rectangles inside (random size,
/// orientation and position, some reflectors, some blockers) and random TX/RX.
pub fn random_scene(seed: u64, n: usize) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let size = Vec3::new(
        rng.random_range(3.0..8.0),
        rng.random_range(3.0..8.0),
        rng.random_range(2.2..3.5),
    );
    let mut surfaces = Vec::new();
    for i in 0..n {
        let centre = Vec3::new(
            rng.random_range(0.2..size.x - 0.2),
            rng.random_range(0.2..size.y - 0.2),
            rng.random_range(0.2..size.z - 0.2),
        );
        let normal = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::Z);
        let (u, v) = normal.any_orthonormal_pair();
        let (a, b) = (rng.random_range(0.2..1.2), rng.random_range(0.2..1.2));
        let verts: Vec<[Real; 3]> = [(-a, -b), (a, -b), (a, b), (-a, b)]
            .iter()
            .map(|(x, y)| (centre + *x * u + *y * v).to_array())
            .collect();
        let kind = if i % 3 == 2 { "blocker" } else { "reflector" };
        surfaces.push(format!(
            r#"{{ "name": "s{i}", "kind": "{kind}", "vertices": {verts:?} }}"#
        ));
    }
    // TX/RX: retry until valid (not on a surface); the chance of failure is negligible.
    let pick = |rng: &mut ChaCha8Rng| {
        [
            rng.random_range(0.1..size.x - 0.1),
            rng.random_range(0.1..size.y - 0.1),
            rng.random_range(0.1..size.z - 0.1),
        ]
    };
    let (tx, rx) = (pick(&mut rng), pick(&mut rng));
    let json = format!(
        r#"{{ "tx": {tx:?}, "rx": {rx:?}, "surfaces": [{}], "boxes": [ {{ "name": "room", "min": [0, 0, 0], "max": {:?} }} ] }}"#,
        surfaces.join(","),
        size.to_array()
    );
    let d: SceneDescription = serde_json::from_str(&json).unwrap();
    Scene::from_description(&d, "random", Terminals::default()).expect("random scene is valid")
}

/// Two walls meeting at the z axis with dihedral angle `angle` (rad), 2 m wide and 2.5 m high,
/// and a double bounce constructed by the law of reflection: a ray with azimuth `azimuth` and
/// elevation `elevation` (rad) hits wall A `d1` metres from the edge at height `z1`, reflects
/// to wall B (`d2` from the edge, a similar distance) and on to RX; TX and RX lie `t1`, `t2`
/// metres from the bounce points. `None` when the construction leaves the wedge.
pub fn corner_scene(
    angle: Real,
    azimuth: Real,
    elevation: Real,
    d1: Real,
    z1: Real,
    t1: Real,
    t2: Real,
) -> Option<Scene> {
    let (w, h) = (2.0, 2.5);
    let da = Vec3::X;
    let db = Vec3::new(angle.cos(), angle.sin(), 0.0);
    let na = Vec3::Y;
    let nb = Vec3::new(angle.sin(), -angle.cos(), 0.0);
    let incoming = Vec3::new(azimuth.cos(), azimuth.sin(), elevation.tan()).normalize();
    let p1 = d1 * da + z1 * Vec3::Z;
    let o = incoming - 2.0 * incoming.dot(na) * na;
    if !(incoming.dot(na) < -0.05 && o.dot(nb) < -0.05) {
        return None;
    }
    let p2 = p1 - (nb.dot(p1) / nb.dot(o)) * o;
    let tx = p1 - t1 * incoming;
    let rx = p2 + t2 * (o - 2.0 * o.dot(nb) * nb);
    let inside = |p: Vec3| {
        p.dot(na) > 0.05 && p.dot(nb) > 0.05 && p.z > 0.05 && p.z < h - 0.05 && p.length() < w
    };
    if !(inside(tx) && inside(rx) && p2.dot(db) > 0.0 && p2.z > 0.05 && p2.z < h - 0.05) {
        return None;
    }
    let wall =
        |d: Vec3| [Vec3::ZERO, w * d, w * d + h * Vec3::Z, h * Vec3::Z].map(|v| v.to_array());
    let json = format!(
        r#"{{ "tx": {:?}, "rx": {:?}, "surfaces": [
            {{ "name": "a", "kind": "reflector", "vertices": {:?} }},
            {{ "name": "b", "kind": "reflector", "vertices": {:?} }} ] }}"#,
        tx.to_array(),
        rx.to_array(),
        wall(da),
        wall(db)
    );
    Some(scene_from_json(&json))
}

/// The seeded corner reflectors of `docs/numerics.md`: `count` scenes from
/// [`corner_scene`] with dihedral angles 60-120°, the double bounce 0.1-10 mm from the edge,
/// drawn from ChaCha8 seeded with `seed` (constructions leaving the wedge are skipped). Returns
/// the scenes and the number of draws it took.
pub fn corner_scenes(seed: u64, count: usize) -> (Vec<Scene>, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut scenes, mut tries) = (Vec::with_capacity(count), 0);
    while scenes.len() < count {
        let scene = corner_scene(
            rng.random_range(60.0f64..120.0).to_radians(),
            rng.random_range(-3.1..-0.05),
            rng.random_range(-0.4..0.4),
            10f64.powf(rng.random_range(-4.0..-2.0)),
            rng.random_range(0.3..2.2),
            rng.random_range(0.3..1.8),
            rng.random_range(0.3..1.8),
        );
        tries += 1;
        scenes.extend(scene);
    }
    (scenes, tries)
}

fn rect(name: &str, kind: &str, c: Vec3, u: Vec3, v: Vec3) -> String {
    let verts: Vec<[Real; 3]> = [(-1., -1.), (1., -1.), (1., 1.), (-1., 1.)]
        .iter()
        .map(|(x, y)| (c + *x * u + *y * v).to_array())
        .collect();
    format!(r#"{{ "name": "{name}", "kind": "{kind}", "vertices": {verts:?} }}"#)
}

fn random_unit(rng: &mut ChaCha8Rng) -> Vec3 {
    Vec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
    .normalize_or(Vec3::Z)
}

/// A box room with `n` random pieces of each nasty kind inside: free rectangles (some blockers),
/// folded pairs sharing an edge, coplanar neighbours sharing an edge, L-shaped (concave) panels.
/// `terminals` picks how TX and RX are placed (0: random, 1: RX mirrored through an edge
/// point of a surface, 2: TX in the plane of a surface).
pub fn nasty_scene(seed: u64, n: usize, terminals: u8) -> Option<Scene> {
    let d = nasty_description(seed, n, terminals);
    // Random pieces may cross each other or put a terminal outside the room or on a surface:
    // such draws are skipped (the scene validator says why), not forced.
    Scene::from_description(&d, "nasty", Terminals::default()).ok()
}

/// [`nasty_scene`] with materials drawn per surface (seeded by `seed`): 6 mm glass or
/// 12.5 mm plasterboard (slabs, penetrable under transmission), concrete (a half-space,
/// opaque), or a 1 cm "curtain" slab whose material says `"transmission": true` (penetrable
/// even without `--transmission`, blockers included); the room's walls plasterboard or
/// concrete. For the transmission property tests.
pub fn nasty_penetrable_scene(seed: u64, n: usize, terminals: u8) -> Option<Scene> {
    let mut d = nasty_description(seed, n, terminals);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x7ea5_5e1f);
    d.materials.insert(
        "curtain".into(),
        bt_scene::MaterialDesc {
            itu: Some("wood".into()),
            thickness: Some(0.01),
            transmission: Some(true),
            ..Default::default()
        },
    );
    const KINDS: [&str; 4] = ["glass", "plasterboard", "concrete", "curtain"];
    for s in &mut d.surfaces {
        s.material = Some(KINDS[rng.random_range(0..KINDS.len())].into());
    }
    for b in &mut d.boxes {
        b.material = Some(["plasterboard", "concrete"][rng.random_range(0..2)].into());
    }
    Scene::from_description(&d, "nasty-penetrable", Terminals::default()).ok()
}

/// The description of [`nasty_scene`] (default materials).
fn nasty_description(seed: u64, n: usize, terminals: u8) -> SceneDescription {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let size = Vec3::new(
        rng.random_range(3.0..7.0),
        rng.random_range(3.0..7.0),
        rng.random_range(2.2..3.2),
    );
    let inside = |rng: &mut ChaCha8Rng, m: Real| {
        Vec3::new(
            rng.random_range(m..size.x - m),
            rng.random_range(m..size.y - m),
            rng.random_range(m..size.z - m),
        )
    };
    let mut surfaces = Vec::new();
    let mut edge_points = Vec::new();
    for i in 0..n {
        let c = inside(&mut rng, 0.6);
        let normal = random_unit(&mut rng);
        let (u0, v0) = normal.any_orthonormal_pair();
        let (a, b) = (rng.random_range(0.15..0.6), rng.random_range(0.15..0.6));
        let (u, v) = (u0 * a, v0 * b);
        match i % 4 {
            0 => {
                let kind = if rng.random_bool(0.3) {
                    "blocker"
                } else {
                    "reflector"
                };
                surfaces.push(rect(&format!("r{i}"), kind, c, u, v));
            }
            1 => {
                // folded pair sharing the edge c + v*t: a concave or convex dihedral
                let fold: Real = rng.random_range(0.3..2.8);
                let w = (u0 * fold.cos() + normal * fold.sin()) * a;
                surfaces.push(rect(&format!("f{i}a"), "reflector", c + u, u, v));
                surfaces.push(rect(&format!("f{i}b"), "reflector", c + w, w, v));
            }
            2 => {
                // coplanar neighbours sharing an edge
                surfaces.push(rect(&format!("c{i}a"), "reflector", c - u, u, v));
                surfaces.push(rect(&format!("c{i}b"), "reflector", c + u, u, v));
            }
            _ => {
                let l: Vec<[Real; 3]> =
                    [(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)]
                        .iter()
                        .map(|(x, y)| (c + (*x - 1.0) * u + (*y - 1.0) * v).to_array())
                        .collect();
                surfaces.push(format!(
                    r#"{{ "name": "l{i}", "kind": "reflector", "vertices": {l:?} }}"#
                ));
            }
        }
        edge_points.push((c + u + v * rng.random_range(-1.0..1.0), normal));
        edge_points.push((c + u + v, normal));
    }
    let tx = inside(&mut rng, 0.1);
    let (tx, rx) = match terminals {
        1 => {
            // RX on the mirror ray of TX through a surface's edge point (or corner): a path
            // whose reflection point lies exactly on a polygon boundary.
            let (p, normal) = edge_points[rng.random_range(0..edge_points.len())];
            let d = p - tx;
            let r = d - 2.0 * d.dot(normal) * normal;
            (tx, p + r.normalize() * rng.random_range(0.3..2.0))
        }
        2 => {
            let (p, normal) = edge_points[rng.random_range(0..edge_points.len())];
            let (u, _) = normal.any_orthonormal_pair();
            (p + u * rng.random_range(0.2..1.5), inside(&mut rng, 0.1))
        }
        _ => (tx, inside(&mut rng, 0.1)),
    };
    let json = format!(
        r#"{{ "tx": {:?}, "rx": {:?}, "surfaces": [{}], "boxes": [ {{ "name": "room", "min": [0, 0, 0], "max": {:?} }} ] }}"#,
        tx.to_array(),
        rx.to_array(),
        surfaces.join(","),
        size.to_array()
    );
    serde_json::from_str(&json).unwrap()
}

/// `desc` moved by `offset` (metres): every surface vertex, box corner, terminal (also per
/// step) and rotation pivot; directions (axes, per-step translations) stay. The reference of
/// the position-independence tests: the same scene far from the origin.
pub fn translated(desc: &SceneDescription, offset: Vec3) -> SceneDescription {
    let shift = |p: [Real; 3]| (Vec3::from_array(p) + offset).to_array();
    let mut d = desc.clone();
    for s in &mut d.surfaces {
        s.vertices.iter_mut().for_each(|v| *v = shift(*v));
    }
    for b in &mut d.boxes {
        (b.min, b.max) = (shift(b.min), shift(b.max));
    }
    d.tx = d.tx.map(shift);
    d.rx = d.rx.map(shift);
    for steps in [&mut d.tx_steps, &mut d.rx_steps].into_iter().flatten() {
        steps.iter_mut().for_each(|p| *p = shift(*p));
    }
    for o in d.objects.values_mut() {
        o.pivot = o.pivot.map(shift);
    }
    d
}

/// A hall of 60 m × 40 m × 12 m (concrete walls, floor and ceiling) with a stage, two pillars,
/// a row of display panels, a metal cabinet and two blockers (crowds), TX on the stage and RX
/// across the hall: the "hall-sized room" of the position-independence tests.
pub fn hall_description() -> SceneDescription {
    let json = r#"{
        "name": "hall",
        "tx": [8.0, 20.0, 3.5], "rx": [47.5, 13.25, 1.5],
        "boxes": [
            { "name": "hall", "min": [0, 0, 0], "max": [60, 40, 12], "material": "concrete" },
            { "name": "stage", "min": [2, 12, 0], "max": [10, 28, 1.25] },
            { "name": "pillar-a", "min": [20, 9.5, 0], "max": [21, 10.5, 12] },
            { "name": "pillar-b", "min": [38, 29.5, 0], "max": [39, 30.5, 12] },
            { "name": "cabinet", "min": [52, 36, 0], "max": [58, 38.5, 2.5], "material": "metal" },
            { "name": "crowd-a", "min": [25, 18, 0], "max": [28, 24, 1.75], "kind": "blocker" },
            { "name": "crowd-b", "min": [33, 5, 0], "max": [36, 8, 1.75], "kind": "blocker" }
        ],
        "surfaces": [
            { "name": "panel-1", "vertices": [[30, 39.5, 2], [34, 39.5, 2], [34, 39.5, 5], [30, 39.5, 5]] },
            { "name": "panel-2", "vertices": [[59.5, 15, 2], [59.5, 22, 2], [59.5, 22, 6], [59.5, 15, 6]] },
            { "name": "banner", "vertices": [[14, 0.5, 6], [26, 0.5, 6], [26, 0.5, 9], [14, 0.5, 9]], "kind": "blocker" }
        ]
    }"#;
    serde_json::from_str(json).expect("hall description parses")
}
