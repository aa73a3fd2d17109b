//! Analytic cases: the box room (image-source lattice), a single wall, a corner.

use crate::common::*;
use bt_geom::{Real, Vec3};
use bt_solve::{Solver, UpdateOrder};

/// Lengths of all paths of order <= `max` in an empty box: image sources form a lattice; the
/// image with a_x, a_y, a_z reflections per axis is reached by exactly one valid sequence.
fn lattice_lengths(size: Vec3, tx: Vec3, rx: Vec3, max: i32) -> Vec<Real> {
    let image = |a: i32, l: Real, t: Real| {
        if a % 2 == 0 {
            a as Real * l + t
        } else {
            (a + 1) as Real * l - t
        }
    };
    let mut lengths = Vec::new();
    for a in -max..=max {
        for b in -max..=max {
            for c in -max..=max {
                if a.abs() + b.abs() + c.abs() <= max {
                    let img = Vec3::new(
                        image(a, size.x, tx.x),
                        image(b, size.y, tx.y),
                        image(c, size.z, tx.z),
                    );
                    lengths.push(img.distance(rx));
                }
            }
        }
    }
    lengths.sort_by(Real::total_cmp);
    lengths
}

fn path_lengths(scene: &bt_scene::Scene, paths: &[bt_solve::FoundPath]) -> Vec<Real> {
    let mut l: Vec<Real> = paths
        .iter()
        .map(|p| {
            let mut v = vec![scene.tx().unwrap()];
            v.extend_from_slice(&p.points);
            v.push(scene.rx().unwrap());
            v.windows(2).map(|w| w[0].distance(w[1])).sum()
        })
        .collect();
    l.sort_by(Real::total_cmp);
    l
}

#[test]
fn box_room_matches_the_image_source_lattice_up_to_third_order() {
    let size = Vec3::new(5.0, 4.0, 3.0);
    let (tx, rx) = (Vec3::new(1.1, 0.7, 2.1), Vec3::new(3.6, 2.9, 0.8));
    let scene = box_room(size, tx, rx);
    let expected = lattice_lengths(size, tx, rx, 3);
    assert_eq!(expected.len(), 1 + 6 + 18 + 38);
    for solver in [
        Solver::Image,
        ipc(&scene, UpdateOrder::GaussSeidel),
        ipc(&scene, UpdateOrder::Jacobi),
    ] {
        let paths = run(&scene, 3, solver);
        let got = path_lengths(&scene, &paths);
        assert_eq!(got.len(), expected.len(), "{solver:?}");
        for (g, e) in got.iter().zip(&expected) {
            assert!(
                (g - e).abs() < 1e-9,
                "{solver:?}: length {g} vs lattice {e}"
            );
        }
        for p in &paths {
            assert!(reflection_law_error(&scene, p) < 1e-9);
        }
    }
}

#[test]
fn single_wall_gives_line_of_sight_and_one_reflection() {
    let scene = scene_from_json(
        r#"{ "tx": [0, 1, 1], "rx": [4, 2, 1],
             "surfaces": [ { "name": "wall", "vertices": [[-5, 0, 0], [5, 0, 0], [5, 0, 3], [-5, 0, 3]] } ] }"#,
    );
    let paths = run(&scene, 3, Solver::Image);
    assert_eq!(paths.len(), 2);
    assert!(paths[0].surfaces.is_empty());
    // Reflection point: the image of TX is (0, -1, 1); the line to RX crosses y = 0 at x = 4/3.
    let p = paths[1].points[0];
    assert!((p - Vec3::new(4.0 / 3.0, 0.0, 1.0)).length() < 1e-12, "{p}");
    let ipc_paths = run(&scene, 3, ipc(&scene, UpdateOrder::Jacobi));
    assert!(max_point_distance(&paths, &ipc_paths) < 1e-9);
    // Line of sight has no point to move: its residual is 0, not 0/0 (a NaN in the JSON).
    assert_eq!(ipc_paths[0].residual, Some(0.0));
}

#[test]
fn wall_between_terminals_blocks_line_of_sight_and_reflections() {
    let scene = scene_from_json(
        r#"{ "tx": [0, 1, 1], "rx": [0, -1, 1],
             "surfaces": [ { "name": "wall", "vertices": [[-5, 0, 0], [5, 0, 0], [5, 0, 3], [-5, 0, 3]] } ] }"#,
    );
    assert!(run(&scene, 3, Solver::Image).is_empty());
}

#[test]
fn right_angle_corner_has_three_images() {
    // A 90-degree wedge has 2n - 1 = 3 image sources: two first-order, one second-order, and
    // no third-order path.
    let scene = scene_from_json(
        r#"{ "tx": [1, 2, 1], "rx": [3, 1, 1.5],
             "surfaces": [
               { "name": "a", "vertices": [[0, 0, 0], [10, 0, 0], [10, 0, 3], [0, 0, 3]] },
               { "name": "b", "vertices": [[0, 0, 0], [0, 0, 3], [0, 10, 3], [0, 10, 0]] } ] }"#,
    );
    for solver in [Solver::Image, ipc(&scene, UpdateOrder::GaussSeidel)] {
        let paths = run(&scene, 3, solver);
        let orders: Vec<usize> = paths.iter().map(|p| p.surfaces.len()).collect();
        assert_eq!(orders, vec![0, 1, 1, 2], "{solver:?}");
        // The second-order path is as long as the distance from the double image (-1, -2).
        let double = Vec3::new(-1.0, -2.0, 1.0);
        let l = path_lengths(&scene, &paths[3..]);
        assert!((l[0] - double.distance(scene.rx().unwrap())).abs() < 1e-9);
    }
}

#[test]
fn a_path_through_a_room_edge_is_reported_as_grazing() {
    // TX and RX chosen so that the double image through two walls lines up with their common
    // edge: the path touches the edge, where "which wall reflects" is undefined. Both orders
    // must be rejected as grazing instead of reported (twice).
    let size = Vec3::new(5.0, 4.0, 3.0);
    let (tx, rx) = (Vec3::new(1.1, 0.7, 2.1), Vec3::new(3.7, 2.9, 0.8));
    let scene = box_room(size, tx, rx);
    let candidates = bt_paths::enumerate(&scene, 3, &bt_paths::AllVisible).unwrap();
    let result = bt_solve::trace(&scene, &candidates, &Solver::Image, false).unwrap();
    assert_eq!(result.counts.grazing, 6);
    assert_eq!(result.paths.len(), 63 - 3);
}

#[test]
fn a_segment_passing_within_the_tolerance_of_a_blockers_edge_is_blocked() {
    // Validation counts a segment that passes within the length tolerance of a polygon's
    // boundary as blocked (grazing an edge is occlusion). The BVH that finds the candidates
    // must then reach polygons the segment misses by less than the tolerance: their exact
    // boxes do not hold the crossing point.
    let json = |tx: Vec3, rx: Vec3| {
        format!(
            r#"{{ "tx": [{}, {}, {}], "rx": [{}, {}, {}], "surfaces": [
                 {{ "name": "screen", "kind": "blocker",
                    "vertices": [[1, -1, 0], [1, 1, 0], [1, 1, 1], [1, -1, 1]] }} ] }}"#,
            tx.x, tx.y, tx.z, rx.x, rx.y, rx.z
        )
    };
    let tol = scene_from_json(&json(Vec3::new(0.0, 0.0, 0.5), Vec3::new(2.0, 0.0, 0.5)))
        .length_tolerance();
    let d = 0.5 * tol;
    for (what, tx, rx) in [
        // Level with the top edge, half a tolerance above it (parallel to the box's faces).
        (
            "over the top",
            Vec3::new(0.0, 0.0, 1.0 + d),
            Vec3::new(2.0, 0.0, 1.0 + d),
        ),
        // Crossing the screen's plane half a tolerance beside its side edge, obliquely.
        (
            "past the side",
            Vec3::new(0.0, 0.9 + d, 0.5),
            Vec3::new(2.0, 1.1 + d, 0.6),
        ),
    ] {
        let scene = scene_from_json(&json(tx, rx));
        let tol = scene.length_tolerance();
        assert!(d < 0.6 * tol, "{what}");
        let by_rule = scene.surfaces().iter().any(|s| {
            let t_min = tol / tx.distance(rx);
            s.polygon.blocks_segment(tx, rx, t_min, tol)
        });
        assert!(by_rule, "{what}: the rule says blocked");
        let found = bt_solve::validate::blocker(&scene, tx, rx, None, None, tol);
        assert!(found.is_some(), "{what}: validation missed the blocker");
        assert!(
            run(&scene, 1, Solver::Image).is_empty(),
            "{what}: a blocked path was reported"
        );
    }
}
