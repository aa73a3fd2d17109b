//! The WVRN is complete: routing candidates over it finds exactly the valid paths of the
//! exhaustive enumeration (image method, the reference), on seeded random scenes with
//! occluders and on the built-in living room; and it removes candidates where occluders are.

use bt_testkit::partitioned as common;

use bt_paths::wvrn::Wvrn;
use bt_paths::{AllVisible, enumerate};
use bt_scene::{Scene, Terminals};
use bt_solve::{Solver, trace};

fn random_scene(seed: u64) -> Scene {
    (seed..)
        .find_map(|s| {
            let d = common::random_description(s, 3, 4);
            Scene::from_description(&d, "random", Terminals::default()).ok()
        })
        .unwrap()
}

/// Candidates with and without the WVRN, asserting the same valid paths.
fn compare(scene: &Scene, order: usize) -> (usize, usize, u64) {
    let wvrn = Wvrn::build(scene).unwrap();
    let all = enumerate(scene, order, &AllVisible).unwrap();
    let routed = enumerate(scene, order, &wvrn).unwrap();
    let a = trace(scene, &all, &Solver::Image, true).unwrap();
    let b = trace(scene, &routed, &Solver::Image, true).unwrap();
    assert_eq!(
        a.paths,
        b.paths,
        "scene {}: WVRN lost or changed paths",
        scene.name()
    );
    // Every consecutive pair of every valid path is a WVRN link.
    for p in &a.paths {
        let mut nodes = vec![bt_paths::Node::Tx];
        nodes.extend(p.surfaces.iter().map(|s| bt_paths::Node::Surface(*s)));
        nodes.push(bt_paths::Node::Rx);
        for w in nodes.windows(2) {
            assert!(
                wvrn.link(w[0], w[1]).is_linked(),
                "{:?} -> {:?}",
                w[0],
                w[1]
            );
        }
    }
    (all.len(), routed.len(), a.counts.valid)
}

#[test]
fn random_scenes_keep_every_path_and_lose_candidates_behind_occluders() {
    let (mut total_all, mut total_routed, mut valid) = (0, 0, 0);
    for seed in 0..12 {
        let scene = random_scene(seed * 1000);
        let order = if seed % 3 == 0 { 3 } else { 2 };
        let (all, routed, v) = compare(&scene, order);
        assert!(routed <= all);
        valid += v;
        total_all += all;
        total_routed += routed;
    }
    let ratio = total_routed as f64 / total_all as f64;
    eprintln!(
        "random scenes: {total_routed} of {total_all} candidates kept ({ratio:.3}), {valid} valid paths"
    );
    assert!(valid > 100, "the scenes should have paths to lose: {valid}");
    assert!(
        ratio < 0.95,
        "the partition should remove candidates: ratio {ratio}"
    );
}

#[test]
fn living_room_keeps_every_path() {
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let (all, routed, valid) = compare(&scene, 3);
    assert!(valid > 10);
    eprintln!(
        "living room, order 3: {routed} of {all} candidates kept ({:.3})",
        routed as f64 / all as f64
    );
    let stats = Wvrn::build(&scene).unwrap().stats();
    eprintln!("living room WVRN: {stats:?}");
}
