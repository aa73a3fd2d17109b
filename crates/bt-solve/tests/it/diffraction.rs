//! First-order edge diffraction: the beam tree's join never loses a diffracted path (against
//! blind enumeration of every reflection/edge sequence, on random scenes with wedges, screens,
//! concave corners, coplanar neighbours and grazing terminals), the closed form obeys Keller's
//! law and minimises the length along the edge, and IPC finds what the image method finds.

use crate::common::{angle_between, listing, paths_of, scene_from_json, trace_scene};
use bt_geom::{Real, Vec3};
use bt_scene::{Scene, SurfaceId};
use bt_solve::pipeline::{CandidateMode, DiffractionOptions, TraceOptions};
use bt_solve::{FoundPath, IpcOptions, Solver, UpdateOrder};
use bt_testkit::nasty_scene;
use proptest::prelude::*;

fn options(max_order: usize, mode: CandidateMode, solver: Solver) -> TraceOptions {
    TraceOptions {
        solver,
        candidates: mode,
        parallel: false,
        diffraction: DiffractionOptions::first_order(),
        ..TraceOptions::new(max_order)
    }
}

fn paths(scene: &Scene, max_order: usize, mode: CandidateMode, solver: Solver) -> Vec<FoundPath> {
    paths_of(scene, &options(max_order, mode, solver))
}

/// Largest deviation from Keller's law over the diffracted paths, as |cos β_in − cos β_out|.
fn keller_error(scene: &Scene, path: &FoundPath) -> Real {
    let Some(d) = path.diffractions.first().copied() else {
        return 0.0;
    };
    let ends = scene.terminals().unwrap();
    let mut v = vec![ends.tx];
    v.extend_from_slice(&path.points);
    v.push(ends.rx);
    let e = scene.edges().get(d.edge).direction;
    let (a, p, b) = (v[d.index], v[d.index + 1], v[d.index + 2]);
    ((p - a).normalize().dot(e) - (b - p).normalize().dot(e)).abs()
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x0d1f_f7ac),
        ..ProptestConfig::default()
    })]

    /// The beam tree's candidates (TX tree joined with an RX tree) give exactly the valid
    /// paths, specular and diffracted, of every sequence enumerated blindly.
    #[test]
    fn beam_tree_diffraction_equals_exhaustive_enumeration(
        seed in 0u64..1_000_000, n in 1usize..7, terminals in 0u8..3, order in 1usize..4,
    ) {
        let Some(scene) = nasty_scene(seed, n, terminals) else { return Ok(()) };
        let reference = paths(&scene, order, CandidateMode::Exhaustive, Solver::Image);
        let tree = paths(&scene, order, CandidateMode::BeamTree, Solver::Image);
        prop_assert_eq!(listing(&tree), listing(&reference));
        for p in &tree {
            prop_assert!(keller_error(&scene, p) < 1e-9);
        }
    }

    /// IPC's rounds (Keller's closed form for the diffraction point, the paper's update for
    /// the reflections) converge to the image method's diffracted paths.
    #[test]
    fn ipc_finds_the_diffracted_paths_of_the_image_method(
        seed in 0u64..1_000_000, n in 1usize..5, order in 1usize..3,
    ) {
        let Some(scene) = nasty_scene(seed, n, 0) else { return Ok(()) };
        let image = paths(&scene, order, CandidateMode::BeamTree, Solver::Image);
        let ipc = Solver::Ipc(IpcOptions::for_scene(&scene, UpdateOrder::GaussSeidel));
        let found = paths(&scene, order, CandidateMode::BeamTree, ipc);
        let key = |p: &FoundPath| p.interactions();
        let diffracted = |v: &[FoundPath]| v.iter().filter(|p| !p.diffractions.is_empty()).map(key).collect::<Vec<_>>();
        prop_assert_eq!(diffracted(&found), diffracted(&image));
        for (p, q) in found.iter().zip(&image).filter(|(p, _)| !p.diffractions.is_empty()) {
            for (x, y) in p.points.iter().zip(&q.points) {
                prop_assert!(x.distance(*y) < 1e-9, "{} vs {}", x, y);
            }
        }
    }
}

/// A floating square screen between TX and RX: no line of sight, one path over each of its
/// four free edges, each the shortest way round that edge.
#[test]
fn a_screen_is_passed_round_each_of_its_edges() {
    let scene = scene_from_json(
        r#"{ "tx": [0, 0.3, 0.2], "rx": [0.2, 4, -0.1],
            "surfaces": [ { "name": "screen", "material": "metal",
              "vertices": [[-1,2,-1],[1,2,-1],[1,2,1],[-1,2,1]] } ] }"#,
    );
    let found = paths(&scene, 1, CandidateMode::BeamTree, Solver::Image);
    assert_eq!(found.len(), 4, "{found:?}");
    let ends = scene.terminals().unwrap();
    for p in &found {
        let d = p.diffractions.first().copied().expect("diffracted");
        let edge = scene.edges().get(d.edge);
        assert!(edge.is_free() && (edge.n - 2.0).abs() < 1e-12);
        let at = |t: Real| ends.tx.distance(edge.point(t)) + edge.point(t).distance(ends.rx);
        let t = edge.parameter(p.points[0]);
        for dt in [-1e-3, 1e-3] {
            assert!(at(t + dt) > at(t), "the Keller point minimises the length");
        }
        assert!(keller_error(&scene, p) < 1e-12);
    }
}

/// Round a building corner (a 270° wedge of two walls): the receiver round the corner in
/// shadow gets the diffracted path; inside the concave corner nothing diffracts.
#[test]
fn a_corner_diffracts_on_its_reflex_side_only() {
    let scene = scene_from_json(
        r#"{ "tx": [-3, 1, 1], "rx": [1, -3, 1.5],
            "surfaces": [
              { "name": "wx", "vertices": [[0,0,0],[0,5,0],[0,5,3],[0,0,3]] },
              { "name": "wy", "vertices": [[0,0,0],[5,0,0],[5,0,3],[0,0,3]] } ] }"#,
    );
    let found = paths(&scene, 1, CandidateMode::BeamTree, Solver::Image);
    let corner: Vec<&FoundPath> = found
        .iter()
        .filter(|p| {
            p.diffractions
                .first()
                .copied()
                .is_some_and(|d| !scene.edges().get(d.edge).is_free())
        })
        .collect();
    assert_eq!(corner.len(), 1, "{found:?}");
    let edge = scene
        .edges()
        .get(corner[0].diffractions.first().copied().unwrap().edge);
    assert!((edge.n - 1.5).abs() < 1e-12);
    // The same corner from inside (both terminals in x, y > 0): no path round the corner.
    let inside = scene
        .with_terminals(Vec3::new(2.0, 1.0, 1.0), Vec3::new(1.0, 2.0, 1.5))
        .unwrap();
    let found = paths(&inside, 1, CandidateMode::BeamTree, Solver::Image);
    assert!(found.iter().all(|p| {
        p.diffractions
            .first()
            .copied()
            .is_none_or(|d| scene.edges().get(d.edge).is_free())
    }));
    assert!(angle_between(Vec3::X, Vec3::Y) > 1.5);
}

/// The property above is not vacuous: the random scenes have diffracted paths at every
/// position (D, R-D, D-R, R-D-R, ...), and the join proposes far fewer candidates than blind
/// enumeration.
#[test]
fn random_scenes_diffract_at_every_position() {
    let (mut positions, mut tree_candidates, mut blind) = ([0usize; 3], 0, 0);
    for seed in 0..12 {
        let Some(scene) = nasty_scene(seed, 6, (seed % 3) as u8) else {
            continue;
        };
        for p in paths(&scene, 3, CandidateMode::BeamTree, Solver::Image) {
            if let Some(d) = p.diffractions.first().copied() {
                positions[d.index] += 1;
            }
        }
        let count = |mode| {
            bt_solve::pipeline::candidates(&scene, &options(3, mode, Solver::Image))
                .unwrap()
                .diffracted
                .len()
        };
        tree_candidates += count(CandidateMode::BeamTree);
        blind += count(CandidateMode::Exhaustive);
    }
    eprintln!(
        "diffracted paths by position {positions:?}; candidates {tree_candidates} of {blind}"
    );
    assert!(positions.iter().all(|&n| n > 0), "{positions:?}");
    assert!(tree_candidates * 5 < blind, "{tree_candidates} of {blind}");
}

/// The join stops at the candidate budget with an error that names diffraction.
#[test]
fn the_diffracted_candidates_stop_at_the_budget() {
    let scene = bt_import::builtin_scene("living-room", bt_scene::Terminals::default())
        .unwrap()
        .unwrap();
    let options = TraceOptions {
        max_candidates: 1000,
        ..options(3, CandidateMode::BeamTree, Solver::Image)
    };
    let error = trace_scene(&scene, &options).unwrap_err().to_string();
    assert!(error.contains("1000 diffracted candidates"), "{error}");
}

/// The one rule for a reflection point on a boundary: at a wedge's edge it is no reflection
/// (it touches the edge, counted as grazing), and with diffraction on, the path through that
/// point is found as the diffraction it is.
#[test]
fn a_reflection_point_on_an_edge_is_a_diffraction_not_a_reflection() {
    // Walls x = 0 (y in 0..5) and y = 0 (x in 0..5) meet at the z axis; TX and RX mirror each
    // other through y = 0, so the mirror image through x = 0 puts the reflection point on the
    // corner (0, 0, 1).
    let scene = scene_from_json(
        r#"{ "tx": [-2, -1, 1], "rx": [-2, 1, 1],
            "surfaces": [
              { "name": "wx", "vertices": [[0,0,0],[0,5,0],[0,5,3],[0,0,3]] },
              { "name": "wy", "vertices": [[0,0,0],[5,0,0],[5,0,3],[0,0,3]] } ] }"#,
    );
    let corner = Vec3::new(0.0, 0.0, 1.0) - scene.origin();
    let at_corner = |p: &FoundPath| p.points.iter().any(|q| q.distance(corner) < 1e-6);
    let specular = TraceOptions {
        diffraction: DiffractionOptions::default(),
        ..options(1, CandidateMode::Exhaustive, Solver::Image)
    };
    let traced = trace_scene(&scene, &specular).unwrap();
    assert!(
        !traced.result.paths.iter().any(at_corner),
        "{:?}",
        traced.result.paths
    );
    assert!(traced.result.counts.grazing >= 1);
    let found = paths(&scene, 1, CandidateMode::BeamTree, Solver::Image);
    let through: Vec<&FoundPath> = found.iter().filter(|p| at_corner(p)).collect();
    assert_eq!(through.len(), 1, "{found:?}");
    assert!(!through[0].diffractions.is_empty());
}

/// The same rule on a seam between coplanar faces, which is no edge: the point reflects, once,
/// on the face of the lowest id (before the rule both halves of a split floor reported it).
#[test]
fn a_reflection_point_on_a_seam_reflects_once() {
    // A floor split at x = 0 into two coplanar halves; TX and RX mirror each other through
    // x = 0, so the floor's reflection point lies on the seam (0, 0, 0).
    let scene = scene_from_json(
        r#"{ "tx": [-1, 0, 1], "rx": [1, 0, 1],
            "surfaces": [
              { "name": "east", "vertices": [[0,-2,0],[3,-2,0],[3,2,0],[0,2,0]] },
              { "name": "west", "vertices": [[-3,-2,0],[0,-2,0],[0,2,0],[-3,2,0]] } ] }"#,
    );
    for mode in [CandidateMode::Exhaustive, CandidateMode::BeamTree] {
        for diffraction in [
            DiffractionOptions::default(),
            DiffractionOptions::first_order(),
        ] {
            let options = TraceOptions {
                diffraction,
                ..options(1, mode, Solver::Image)
            };
            let traced = trace_scene(&scene, &options).unwrap();
            let reflected: Vec<&FoundPath> = traced
                .result
                .paths
                .iter()
                .filter(|p| p.points.len() == 1 && p.diffractions.first().copied().is_none())
                .collect();
            assert_eq!(reflected.len(), 1, "{mode:?}: {reflected:?}");
            assert_eq!(reflected[0].surfaces[..], [SurfaceId(0)]);
        }
    }
}

/// A wall hides a small screen's four edges from TX entirely: the join starts no candidate
/// from TX straight onto them (their TX reaches are dropped as hidden), and the paths are
/// still exactly those of blind enumeration.
#[test]
fn edges_a_wall_hides_from_tx_start_no_candidate_and_lose_no_path() {
    let scene = scene_from_json(
        r#"{ "tx": [0.2, 0, 0.1], "rx": [0.3, 6, 2.5],
            "surfaces": [
              { "name": "wall", "material": "metal",
                "vertices": [[-3,2,-3],[3,2,-3],[3,2,3],[-3,2,3]] },
              { "name": "screen", "material": "metal",
                "vertices": [[-1,4,-1],[1,4,-1],[1,4,1],[-1,4,1]] } ] }"#,
    );
    let screen = SurfaceId(1);
    let on_screen = |e: bt_scene::EdgeId| scene.edges().get(e).touching.contains(&screen);
    let set = bt_paths::beamtree::candidates_and_diffracted_in(
        &scene,
        bt_paths::beamtree::TreeOptions::new(2),
        Some(bt_paths::diffraction::Diffracting {
            min_edge_length: 0.0,
            max_diffractions: 1,
        }),
        &mut bt_paths::beamtree::TreeCache::default(),
        &mut |_| {},
    )
    .unwrap();
    let diffracted = &set.diffracted;
    let from_tx = (0..diffracted.len())
        .map(|i| diffracted.get(i))
        .filter(|c| c.position == 0 && on_screen(c.edge))
        .count();
    assert_eq!(from_tx, 0, "a hidden edge starts no candidate from TX");
    // Without the wall's shadow the pair (TX, RX) would be a candidate on the screen's top
    // edge: both lie in its exterior, and their Keller point lies on it.
    let ends = scene.terminals().unwrap();
    let tol = scene.length_tolerance();
    let top = (0..scene.edges().len() as u32)
        .map(bt_scene::EdgeId)
        .filter(|&e| on_screen(e))
        .map(|e| scene.edges().get(e))
        .find(|edge| {
            edge.keller(ends.tx, ends.rx)
                .is_some_and(|t| t > 0.0 && t < edge.length)
        })
        .expect("an edge of the screen between TX and RX");
    assert!(top.in_exterior(ends.tx, tol) && top.in_exterior(ends.rx, tol));
    for order in 1..=2 {
        let reference = paths(&scene, order, CandidateMode::Exhaustive, Solver::Image);
        let tree = paths(&scene, order, CandidateMode::BeamTree, Solver::Image);
        assert_eq!(listing(&tree), listing(&reference), "order {order}");
    }
}

/// The reaches of both trees are found in chunks of nodes on all cores: the diffracted
/// candidates (one and two diffractions) are those found on one thread, in a city whose
/// levels span many chunks (19,300 nodes at depth 2 with one diffraction at order 3).
#[test]
fn diffracted_candidates_on_all_cores_are_those_on_one() {
    let scene = bt_import::builtin_scene("city", bt_scene::Terminals::default())
        .unwrap()
        .unwrap();
    for (order, max_diffractions) in [(3, 1), (2, 2)] {
        let [one, all] = [false, true].map(|parallel| {
            bt_paths::beamtree::candidates_and_diffracted_in(
                &scene,
                bt_paths::beamtree::TreeOptions {
                    parallel,
                    ..bt_paths::beamtree::TreeOptions::new(order)
                },
                Some(bt_paths::diffraction::Diffracting {
                    min_edge_length: 0.0,
                    max_diffractions,
                }),
                &mut bt_paths::beamtree::TreeCache::default(),
                &mut |_| {},
            )
            .unwrap()
        });
        assert!(
            one.diffracted.len() > 1000,
            "order {order}: a real workload"
        );
        assert!(
            one.diffracted == all.diffracted,
            "order {order}, {max_diffractions} diffractions: the sets differ"
        );
        assert_eq!(one.tree, all.tree, "order {order}");
    }
}
