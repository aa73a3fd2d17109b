//! Shared helpers of the solver tests: scene builders and path checks.

use bt_geom::{Real, Vec3};
use bt_paths::{AllVisible, enumerate};
use bt_scene::{Scene, SurfaceId};
use bt_solve::pipeline::{TraceError, TraceOptions, Traced};
use bt_solve::{FoundPath, IpcOptions, Solver, Tracer, UpdateOrder, trace};

pub use bt_testkit::{box_room, random_scene, scene_from_json, wall_floor_scene};

pub fn run(scene: &Scene, max_order: usize, solver: Solver) -> Vec<FoundPath> {
    let candidates = enumerate(scene, max_order, &AllVisible).unwrap();
    trace(scene, &candidates, &solver, true).unwrap().paths
}

pub fn ipc(scene: &Scene, order: UpdateOrder) -> Solver {
    Solver::Ipc(IpcOptions::for_scene(scene, order))
}

/// Largest deviation from the law of reflection over the path, radians: the outgoing direction
/// must be the mirror of the incoming one.
pub fn reflection_law_error(scene: &Scene, path: &FoundPath) -> Real {
    let mut v = vec![scene.tx().unwrap()];
    v.extend_from_slice(&path.points);
    v.push(scene.rx().unwrap());
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
    paths.iter().map(|p| p.surfaces.to_vec()).collect()
}

/// Largest point distance between matching paths (same sequences in the same order), metres.
pub fn max_point_distance(a: &[FoundPath], b: &[FoundPath]) -> Real {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| p.points.iter().zip(&q.points).map(|(x, y)| x.distance(*y)))
        .fold(0.0, Real::max)
}

/// The proptest settings of the random-scene comparisons (IPC and Newton against the image
/// method): a fixed RNG seed, so every run sees the same scenes (CI is deterministic); raise
/// the case count with PROPTEST_CASES to explore.
pub fn random_scene_config() -> proptest::test_runner::Config {
    proptest::test_runner::Config {
        cases: 24,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x05ee_d1bc),
        ..proptest::test_runner::Config::default()
    }
}

/// The valid paths of `scene` traced between its own terminals under `options`.
pub fn paths_of(scene: &Scene, options: &TraceOptions) -> Vec<FoundPath> {
    trace_scene(scene, options)
        .expect("trace runs")
        .result
        .paths
}

/// Each path as (its interactions, its points): what two traces must agree on.
pub fn listing(paths: &[FoundPath]) -> Vec<(Vec<bt_solve::Interaction>, Vec<Vec3>)> {
    paths
        .iter()
        .map(|p| (p.interactions(), p.points.to_vec()))
        .collect()
}

/// Trace `scene` between its own terminals with a fresh [`Tracer`].
pub fn trace_scene(scene: &Scene, options: &TraceOptions) -> Result<Traced, TraceError> {
    Tracer::new(scene.clone(), *options).trace(scene.tx_world().unwrap(), scene.rx_world().unwrap())
}

/// Trace `scene`'s TX to each of `receivers` (world frame) with a fresh [`Tracer`].
pub fn trace_receivers(
    scene: &Scene,
    receivers: &[Vec3],
    options: &TraceOptions,
) -> Result<Vec<Traced>, TraceError> {
    Tracer::new(scene.clone(), *options).trace_many(scene.tx_world().unwrap(), receivers)
}
