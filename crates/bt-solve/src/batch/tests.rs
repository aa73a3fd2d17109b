//! IPC runs four at a time in a batch (`solve_batch`), one by one in `solve_candidate_from`:
//! the two must agree bit for bit, whatever the outcome. (A unit test: the batch is crate-private.)

use super::{Batch, Todo, solve_batch};
use crate::{CandidateOutcome, IpcOptions, Solver, UpdateOrder, solve_candidate_from};
use bt_geom::Vec3;
use bt_paths::{AllVisible, CandidateSet, enumerate};
use bt_scene::{Scene, SurfaceId};
use bt_testkit::random_scene;

type Solved = Vec<(usize, CandidateOutcome, Vec<Vec3>)>;

/// How a batch spreads its candidates: on the calling thread, over rayon's pool, or in two
/// halves with a partner thread.
#[derive(Clone, Copy, Debug)]
enum Spread {
    Serial,
    Parallel,
    Partner,
}

/// A partner that spins long enough to take every half of a test.
fn partner() -> crate::partner::Partner {
    crate::partner::Partner::new(std::time::Duration::from_secs(1)).expect("a partner thread")
}

/// Every candidate's outcome and points through the batch, spread as `spread` says.
fn batched(scene: &Scene, set: &CandidateSet, solver: &Solver, spread: Spread) -> Solved {
    let partner = matches!(spread, Spread::Partner).then(partner);
    let batch = Batch {
        scene,
        ends: scene.terminals().unwrap(),
        candidates: set,
        solver,
        parallel: matches!(spread, Spread::Parallel),
        partner: partner.as_ref(),
        counts_blocked: false,
    };
    let keep = |acc: &mut Solved, i: usize, _: &[SurfaceId], o: &CandidateOutcome, p: &[Vec3]| {
        acc.push((i, *o, p.to_vec()))
    };
    solve_batch(&batch, Todo::All, (|_| Solved::new(), |_| None), keep)
        .into_iter()
        .flatten()
        .collect()
}

/// Every candidate's outcome and points, one by one.
fn one_by_one(scene: &Scene, set: &CandidateSet, solver: &Solver) -> Solved {
    let ends = scene.terminals().unwrap();
    (0..set.len())
        .map(|i| {
            let seq = set.get(i);
            let mut points = vec![Vec3::ZERO; seq.len()];
            let mut scratch = points.clone();
            let start = set.start(i);
            let outcome =
                solve_candidate_from(scene, ends, seq, solver, start, &mut points, &mut scratch);
            (i, outcome, points)
        })
        .collect()
}

/// Bit-for-bit equality (points by their bits, so that NaN equals NaN); returns how many
/// candidates ended in each kind of outcome.
fn assert_bitwise_equal(a: &Solved, b: &Solved) -> std::collections::BTreeMap<String, usize> {
    assert_eq!(a.len(), b.len());
    let mut kinds = std::collections::BTreeMap::new();
    for ((i, oa, pa), (j, ob, pb)) in a.iter().zip(b) {
        assert_eq!(i, j);
        assert_eq!(format!("{oa:?}"), format!("{ob:?}"), "candidate {i}");
        let bits = |p: &[Vec3]| {
            p.iter()
                .flat_map(|v| v.to_array().map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(pa), bits(pb), "candidate {i}: points differ");
        let kind = format!("{oa:?}")
            .split(['(', ' ', '{'])
            .next()
            .unwrap()
            .to_string();
        *kinds.entry(kind).or_insert(0) += 1;
    }
    kinds
}

fn solvers(scene: &Scene) -> Vec<Solver> {
    [UpdateOrder::GaussSeidel, UpdateOrder::Jacobi]
        .into_iter()
        .flat_map(|order| {
            let options = IpcOptions::for_scene(scene, order);
            [
                Solver::Ipc(options),
                // A tight round cap: runs end at the cap, in lanes and alone.
                Solver::Ipc(IpcOptions {
                    max_iterations: 40,
                    ..options
                }),
            ]
        })
        .collect()
}

#[test]
fn lanes_equal_one_by_one_on_the_living_room() {
    let scene = bt_import::builtin_scene("living-room", bt_scene::Terminals::default())
        .unwrap()
        .unwrap();
    // Exhaustive candidates from the centroids: every kind of ending, many of each order.
    let set = enumerate(&scene, 3, &AllVisible).unwrap();
    let mut kinds = std::collections::BTreeMap::new();
    for solver in solvers(&scene) {
        let reference = one_by_one(&scene, &set, &solver);
        for spread in [Spread::Serial, Spread::Parallel, Spread::Partner] {
            for (k, n) in assert_bitwise_equal(&batched(&scene, &set, &solver, spread), &reference)
            {
                *kinds.entry(k).or_insert(0) += n;
            }
        }
    }
    for kind in ["Solved", "LeftPolygon", "Blocked", "NotConverged"] {
        assert!(
            kinds.get(kind).copied().unwrap_or(0) > 0,
            "no {kind} outcome: {kinds:?}"
        );
    }
}

#[test]
fn lanes_equal_one_by_one_where_ipc_degenerates() {
    // The floor's centroid lies in the wall's plane: from the centroids, IPC on wall -> floor
    // meets a point whose neighbours both lie on its plane (the lanes rerun that lane alone).
    let scene = bt_testkit::wall_floor_scene();
    let set = enumerate(&scene, 3, &AllVisible).unwrap();
    let mut degenerate = 0;
    for solver in solvers(&scene) {
        let kinds = assert_bitwise_equal(
            &batched(&scene, &set, &solver, Spread::Serial),
            &one_by_one(&scene, &set, &solver),
        );
        degenerate += kinds.get("Degenerate").copied().unwrap_or(0);
    }
    assert!(degenerate > 0, "no degenerate run");
}

#[test]
fn lanes_equal_one_by_one_on_random_scenes() {
    for seed in 0..12 {
        let scene = random_scene(seed, 2 + (seed as usize % 5));
        let set = enumerate(&scene, 3, &AllVisible).unwrap();
        for solver in solvers(&scene) {
            assert_bitwise_equal(
                &batched(&scene, &set, &solver, Spread::Serial),
                &one_by_one(&scene, &set, &solver),
            );
        }
    }
}

/// `trace` validates with the thread's hints of where each candidate was blocked
/// ([`crate::hints`]): along a walk of receivers, each trace on this thread (hinted by the
/// previous receivers') gives exactly what a trace on a fresh thread (no hints) gives.
#[test]
fn hinted_traces_equal_fresh_ones_along_a_walk() {
    let scene = bt_import::builtin_scene("living-room", bt_scene::Terminals::default())
        .unwrap()
        .unwrap();
    let mut hinted_blocked = 0;
    for k in 0..8 {
        let rx = Vec3::new(1.5 + 0.3 * f64::from(k), 2.0 + 0.1 * f64::from(k), 1.2);
        let scene = scene.with_receiver(rx).unwrap();
        let set = enumerate(&scene, 3, &AllVisible).unwrap();
        let hints_before = crate::hints::Hints::take();
        let known = set.iter().filter(|s| {
            let key = crate::hints::key(s);
            key.and_then(|key| hints_before.get(key)).is_some()
        });
        hinted_blocked += known.count();
        hints_before.give_back();
        let traced = crate::trace(&scene, &set, &Solver::Image, false).unwrap();
        let fresh = std::thread::scope(|s| {
            s.spawn(|| crate::trace(&scene, &set, &Solver::Image, false).unwrap())
                .join()
                .unwrap()
        });
        assert_eq!(format!("{traced:?}"), format!("{fresh:?}"), "receiver {k}");
    }
    assert!(hinted_blocked > 0, "no candidate had a hint");
}
