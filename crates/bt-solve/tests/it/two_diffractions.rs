//! Two diffractions per path (issue 28): the beam tree's join never loses a twice-diffracted
//! path (against blind enumeration of every reflection/edge sequence on random scenes with
//! wedges, screens, concave corners, coplanar neighbours and grazing terminals), both points
//! obey Keller's law, IPC finds the image method's paths, traces are reciprocal, one
//! diffraction gives the first-order trace's paths, and the path over two screens carries the
//! gain of the channel model.

use crate::common::{listing, paths_of, scene_from_json};
use bt_geom::{Real, Vec3};
use bt_scene::Scene;
use bt_solve::pipeline::{CandidateMode, DiffractionOptions, TraceOptions};
use bt_solve::{FoundPath, IpcOptions, Solver, Tracer, UpdateOrder};
use bt_testkit::nasty_scene;
use proptest::prelude::*;

fn options(max_order: usize, mode: CandidateMode, solver: Solver) -> TraceOptions {
    TraceOptions {
        solver,
        candidates: mode,
        parallel: false,
        diffraction: DiffractionOptions {
            max_diffractions: 2,
            min_edge_length: 0.0,
        },
        ..TraceOptions::new(max_order)
    }
}

fn paths(scene: &Scene, max_order: usize, mode: CandidateMode) -> Vec<FoundPath> {
    paths_of(scene, &options(max_order, mode, Solver::Image))
}

/// Largest deviation from Keller's law at the path's diffraction points, |cos β_in − cos β_out|.
fn keller_error(scene: &Scene, path: &FoundPath) -> Real {
    let ends = scene.terminals().unwrap();
    let mut v = vec![ends.tx];
    v.extend_from_slice(&path.points);
    v.push(ends.rx);
    path.diffractions
        .iter()
        .map(|d| {
            let e = scene.edges().get(d.edge).direction;
            let (a, p, b) = (v[d.index], v[d.index + 1], v[d.index + 2]);
            ((p - a).normalize().dot(e) - (b - p).normalize().dot(e)).abs()
        })
        .fold(0.0, Real::max)
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 48,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x2d1f_f7ac),
        ..ProptestConfig::default()
    })]

    /// The beam tree's candidates give exactly the valid paths, specular, once and twice
    /// diffracted, of every sequence enumerated blindly; each diffraction obeys Keller's law.
    #[test]
    fn two_diffractions_equal_exhaustive_enumeration(
        seed in 0u64..1_000_000, n in 1usize..6, terminals in 0u8..3, order in 2usize..4,
    ) {
        let Some(scene) = nasty_scene(seed, n, terminals) else { return Ok(()) };
        let reference = paths(&scene, order, CandidateMode::Exhaustive);
        let tree = paths(&scene, order, CandidateMode::BeamTree);
        prop_assert_eq!(listing(&tree), listing(&reference));
        for p in &tree {
            prop_assert!(keller_error(&scene, p) < 1e-9, "{:?}", p);
        }
        // Allowing a second diffraction adds paths and changes none: the others are the
        // first-order trace's, bit for bit.
        let once = paths_of(&scene, &TraceOptions {
            diffraction: DiffractionOptions::first_order(),
            ..options(order, CandidateMode::BeamTree, Solver::Image)
        });
        let at_most_one: Vec<FoundPath> =
            tree.iter().filter(|p| p.diffractions.len() < 2).cloned().collect();
        prop_assert_eq!(listing(&at_most_one), listing(&once));
    }

    /// One tracer, one receiver at a time: from the second trace on it reuses the TX side
    /// kept in its cache (with the join's TX part), and gives a fresh tracer's candidates and
    /// paths, bit for bit.
    #[test]
    fn a_kept_tracer_gives_a_fresh_tracers_twice_diffracted_paths(
        seed in 0u64..1_000_000, n in 1usize..6,
    ) {
        let Some(scene) = nasty_scene(seed, n, 0) else { return Ok(()) };
        let opts = options(3, CandidateMode::BeamTree, Solver::Image);
        let (tx, rx) = (scene.tx_world().unwrap(), scene.rx_world().unwrap());
        let mut kept = Tracer::new(scene.clone(), opts);
        for k in 0..4 {
            let step = k as Real;
            let moved = rx + Vec3::new(0.37 * step, -0.21 * step, 0.13 * step);
            if scene.with_receiver(moved).is_err() {
                continue;
            }
            let fresh = Tracer::new(scene.clone(), opts).trace(tx, moved).expect("fresh trace");
            let reused = kept.trace(tx, moved).expect("kept trace");
            prop_assert_eq!(&reused.result.paths, &fresh.result.paths);
            prop_assert_eq!(reused.candidates.diffracted, fresh.candidates.diffracted);
        }
    }

    /// Traced from the other end, the same paths come back reversed.
    #[test]
    fn two_diffractions_are_reciprocal(
        seed in 0u64..1_000_000, n in 1usize..6, order in 2usize..4,
    ) {
        let Some(scene) = nasty_scene(seed, n, 0) else { return Ok(()) };
        let ends = (scene.tx_world().unwrap(), scene.rx_world().unwrap());
        let back = scene.with_terminals(ends.1, ends.0).unwrap();
        let forward = paths(&scene, order, CandidateMode::BeamTree);
        let backward = paths(&back, order, CandidateMode::BeamTree);
        let mut a: Vec<_> = forward.iter().map(|p| {
            let mut kinds = p.interactions();
            kinds.reverse();
            let mut points = p.points.to_vec();
            points.reverse();
            (kinds, points)
        }).collect();
        let mut b = listing(&backward);
        let key = |x: &(Vec<bt_solve::Interaction>, Vec<Vec3>)| format!("{:?}", x.0);
        a.sort_by_key(key);
        b.sort_by_key(key);
        prop_assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            prop_assert_eq!(&x.0, &y.0);
            for (p, q) in x.1.iter().zip(&y.1) {
                prop_assert!(p.distance(*q) < 1e-9, "{} vs {}", p, q);
            }
        }
    }

    /// IPC's rounds (each diffraction point at its neighbours' Keller point) converge to the
    /// image method's twice-diffracted paths.
    #[test]
    fn ipc_finds_the_twice_diffracted_paths_of_the_image_method(
        seed in 0u64..1_000_000, n in 1usize..5,
    ) {
        let Some(scene) = nasty_scene(seed, n, 0) else { return Ok(()) };
        let image = paths(&scene, 2, CandidateMode::BeamTree);
        let ipc = Solver::Ipc(IpcOptions::for_scene(&scene, UpdateOrder::GaussSeidel));
        let found = paths_of(&scene, &options(2, CandidateMode::BeamTree, ipc));
        let twice = |v: &[FoundPath]| -> Vec<FoundPath> {
            v.iter().filter(|p| p.diffractions.len() == 2).cloned().collect()
        };
        let (found, image) = (twice(&found), twice(&image));
        prop_assert_eq!(found.len(), image.len());
        for (p, q) in found.iter().zip(&image) {
            prop_assert_eq!(p.interactions(), q.interactions());
            for (x, y) in p.points.iter().zip(&q.points) {
                prop_assert!(x.distance(*y) < 1e-8, "{} vs {}", x, y);
            }
        }
    }
}

/// Two parallel thin metal screens, TX and RX below their tops on either side: the one path
/// over both top edges, D-D, with its points on the edges straight above the terminals' line.
#[test]
fn two_screens_are_passed_over_both_edges() {
    let scene = scene_from_json(
        r#"{ "tx": [-20, 0, 0], "rx": [30, 0, 0], "frequency_hz": 3.5e9,
            "surfaces": [
              { "name": "first", "material": "metal",
                "vertices": [[0,-40,-30],[0,40,-30],[0,40,3],[0,-40,3]] },
              { "name": "second", "material": "metal",
                "vertices": [[10,-40,-30],[10,40,-30],[10,40,3],[10,-40,3]] } ] }"#,
    );
    let found = paths(&scene, 2, CandidateMode::BeamTree);
    let over: Vec<&FoundPath> = found
        .iter()
        .filter(|p| p.diffractions.len() == 2)
        .filter(|p| p.points.iter().all(|q| (q.z - 3.0).abs() < 1e-9))
        .collect();
    assert_eq!(over.len(), 1, "{found:?}");
    assert!(over[0].points[0].distance(Vec3::new(0.0, 0.0, 3.0)) < 1e-9);
    assert!(over[0].points[1].distance(Vec3::new(10.0, 0.0, 3.0)) < 1e-9);
    // No single diffraction gets over both screens, and nothing passes straight.
    assert!(found.iter().all(|p| p.diffractions.len() == 2), "{found:?}");
}

/// The pairs of reaches the two-diffraction join would test are counted first: beyond
/// `PAIR_TESTS_PER_CANDIDATE` per candidate of the budget the trace stops, saying so.
#[test]
fn the_pair_tests_stop_at_the_budget() {
    let scene = bt_import::builtin_scene("living-room", bt_scene::Terminals::default())
        .unwrap()
        .unwrap();
    let tight = TraceOptions {
        max_candidates: 1500,
        ..options(3, CandidateMode::BeamTree, Solver::Image)
    };
    let error = crate::common::trace_scene(&scene, &tight)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("pairs of edge reaches") && error.contains("--max-candidates 1500"),
        "{error}"
    );
    let roomy = TraceOptions {
        max_candidates: 1_000_000,
        ..tight
    };
    assert!(crate::common::trace_scene(&scene, &roomy).is_ok());
}
