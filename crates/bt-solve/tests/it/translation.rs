//! Position independence (issue 9): a scene far from the origin (UTM-like coordinates,
//! 10^5-10^7 m) gives the same paths as the same scene at the origin, translated. The reference
//! is the scene at the origin, traced on its own; the far scene is built by moving its file
//! description (`bt_testkit::translated`), so the library sees world coordinates only.

use crate::common::trace_scene;
use bt_beams::{PathReport, RadioOptions, report};
use bt_geom::{Real, Vec3};
use bt_scene::{Scene, SceneDescription, Terminals};
use bt_solve::pipeline::{CandidateMode, TraceOptions};
use bt_solve::{IpcOptions, Solver, UpdateOrder};

const OFFSETS: [[Real; 3]; 4] = [
    [1e5, 1e5, 0.0],
    [1e7, 1e7, 100.0],
    [-3.2e5, 2.7e6, -50.0],
    [-7.5e6, -1.25e6, 10.0],
];

fn living_room() -> SceneDescription {
    serde_json::from_str(bt_import::builtin_json("living-room").unwrap()).unwrap()
}

fn paths(scene: &Scene, solver: Solver, order: usize) -> Vec<PathReport> {
    let options = TraceOptions {
        solver,
        candidates: CandidateMode::BeamTree,
        ..TraceOptions::new(order)
    };
    let traced = trace_scene(scene, &options).expect("trace runs");
    let mut out = report(scene, &traced.result.paths, &RadioOptions::default()).unwrap();
    out.sort_by(|a, b| a.surfaces.cmp(&b.surfaces));
    out
}

fn solvers(scene: &Scene) -> [(&'static str, Solver); 2] {
    [
        ("image", Solver::Image),
        (
            "ipc",
            Solver::Ipc(IpcOptions::for_scene(scene, UpdateOrder::GaussSeidel)),
        ),
    ]
}

/// Largest point deviation (m) and relative length deviation of `far` from `near + offset`.
fn deviation(near: &[PathReport], far: &[PathReport], offset: Vec3) -> (Real, Real) {
    let (mut point, mut length): (Real, Real) = (0.0, 0.0);
    for (a, b) in near.iter().zip(far) {
        length = length.max((a.length_m - b.length_m).abs() / a.length_m);
        for (p, q) in a.points.iter().zip(&b.points) {
            let expected = Vec3::from_array(*p) + offset;
            point = point.max((Vec3::from_array(*q) - expected).abs().max_element());
        }
    }
    (point, length)
}

fn check(name: &str, desc: &SceneDescription, order: usize) {
    let near = Scene::from_description(desc, name, Terminals::default()).unwrap();
    for offset in OFFSETS.map(Vec3::from_array) {
        let moved = bt_testkit::translated(desc, offset);
        let far = Scene::from_description(&moved, name, Terminals::default())
            .unwrap_or_else(|e| panic!("{name} at {offset}: {e}"));
        for ((solver, s_near), (_, s_far)) in solvers(&near).into_iter().zip(solvers(&far)) {
            let (a, b) = (paths(&near, s_near, order), paths(&far, s_far, order));
            let names =
                |p: &[PathReport]| p.iter().map(|r| r.surfaces.join(">")).collect::<Vec<_>>();
            assert_eq!(
                names(&a),
                names(&b),
                "{name} {solver} at {offset}: path sets differ"
            );
            let (point, length) = deviation(&a, &b, offset);
            assert!(
                point <= 1e-6 && length <= 1e-9,
                "{name} {solver} at {offset}: points off by {point:.2e} m, lengths by {length:.2e}"
            );
        }
    }
}

#[test]
fn the_living_room_far_from_the_origin_equals_the_living_room_at_it() {
    check("living-room", &living_room(), 3);
}

#[test]
fn a_hall_far_from_the_origin_equals_the_hall_at_it() {
    check("hall", &bt_testkit::hall_description(), 3);
}

#[test]
fn far_scenes_are_solved_in_a_local_frame_and_reported_in_the_world() {
    let desc = bt_testkit::hall_description();
    let offset = Vec3::new(1e7, 1e7, 100.0);
    let far = Scene::from_description(
        &bt_testkit::translated(&desc, offset),
        "hall",
        Terminals::default(),
    )
    .unwrap();
    assert!(far.origin() != Vec3::ZERO);
    assert!(
        far.tx().unwrap().abs().max_element() < 128.0,
        "tx is local: {}",
        far.tx().unwrap()
    );
    assert_eq!(far.tx_world().unwrap(), Vec3::new(8.0, 20.0, 3.5) + offset);
    let near = Scene::from_description(&desc, "hall", Terminals::default()).unwrap();
    assert_eq!(near.origin(), Vec3::ZERO);
}
