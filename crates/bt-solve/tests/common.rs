//! Shared helpers of the solver tests: scene builders and path checks.
#![allow(dead_code)]

use bt_geom::{Real, Vec3};
use bt_paths::{AllVisible, enumerate};
use bt_scene::{Scene, SceneDescription, SurfaceId, Terminals};
use bt_solve::{FoundPath, IpcOptions, Solver, UpdateOrder, trace};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub fn scene_from_json(json: &str) -> Scene {
    let d: SceneDescription = serde_json::from_str(json).expect("test scene parses");
    Scene::from_description(&d, "test", Terminals::default()).expect("test scene is valid")
}

/// An empty box room `[0, size]` with TX and RX inside.
pub fn box_room(size: Vec3, tx: Vec3, rx: Vec3) -> Scene {
    scene_from_json(&format!(
        r#"{{ "tx": {:?}, "rx": {:?}, "boxes": [ {{ "name": "room", "min": [0, 0, 0], "max": {:?} }} ] }}"#,
        tx.to_array(),
        rx.to_array(),
        size.to_array()
    ))
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

pub fn run(scene: &Scene, max_order: usize, solver: Solver) -> Vec<FoundPath> {
    let candidates = enumerate(scene, max_order, &AllVisible);
    trace(scene, &candidates, &solver, true).paths
}

pub fn ipc(scene: &Scene, order: UpdateOrder) -> Solver {
    Solver::Ipc(IpcOptions::for_scene(scene, order))
}

/// Largest deviation from the law of reflection over the path, radians: the outgoing direction
/// must be the mirror of the incoming one.
pub fn reflection_law_error(scene: &Scene, path: &FoundPath) -> Real {
    let mut v = vec![scene.tx()];
    v.extend_from_slice(&path.points);
    v.push(scene.rx());
    let mut worst: Real = 0.0;
    for (k, id) in path.surfaces.iter().enumerate() {
        let n = scene.surface(*id).polygon.plane().normal;
        let d_in = (v[k + 1] - v[k]).normalize();
        let d_out = (v[k + 2] - v[k + 1]).normalize();
        let mirrored = d_in - 2.0 * d_in.dot(n) * n;
        worst = worst.max(angle_between(mirrored, d_out));
    }
    worst
}

/// Angle between two vectors, radians (robust for tiny angles).
pub fn angle_between(a: Vec3, b: Vec3) -> Real {
    a.cross(b).length().atan2(a.dot(b))
}

pub fn sequences(paths: &[FoundPath]) -> Vec<Vec<SurfaceId>> {
    paths.iter().map(|p| p.surfaces.clone()).collect()
}

/// Largest point distance between matching paths (same sequences in the same order), metres.
pub fn max_point_distance(a: &[FoundPath], b: &[FoundPath]) -> Real {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| p.points.iter().zip(&q.points).map(|(x, y)| x.distance(*y)))
        .fold(0.0, Real::max)
}
