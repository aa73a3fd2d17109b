//! A sweep over an empty box room against the image-source lattice (every interior point has
//! 1 + 6 + 18 + 38 paths up to third order; the strongest is line of sight), and grid points
//! on a wall or at the TX marked, not failing the sweep.

use bt_coverage::{Grid, PointStatus, sweep};
use bt_geom::Vec3;
use bt_scene::Scene;
use bt_solve::pipeline::TraceOptions;

fn box_room(size: [f64; 3], tx: [f64; 3]) -> Scene {
    bt_testkit::box_room(size, tx, Vec3::splat(0.5))
}

/// Paths of order ≤ `max` in an empty box: one per lattice image with |a|+|b|+|c| ≤ max.
fn lattice_count(max: i32) -> usize {
    let r = -max..=max;
    r.clone()
        .flat_map(|a| {
            r.clone()
                .flat_map(move |b| (-max..=max).map(move |c| (a, b, c)))
        })
        .filter(|(a, b, c)| a.abs() + b.abs() + c.abs() <= max)
        .count()
}

#[test]
fn box_room_sweep_matches_the_image_lattice_at_every_point() {
    let tx = [0.7193, 0.9371, 2.1133];
    let scene = box_room([5.0, 4.0, 3.0], tx);
    let grid: Grid = "0.3137:4.7:0.5521,0.2791:3.7:0.8537,1.3173"
        .parse()
        .unwrap();
    let points = grid.points(1000).unwrap();
    assert_eq!(points.len(), 8 * 5);
    for max_order in [1, 2, 3] {
        let mut calls = Vec::new();
        let rows = sweep(
            &scene,
            &points,
            (
                &TraceOptions::new(max_order),
                &bt_beams::RadioOptions::default(),
            ),
            &mut |d, t| calls.push((d, t)),
        )
        .unwrap();
        assert_eq!(calls.last(), Some(&(40, 40)));
        assert_eq!(rows.len(), points.len());
        for (row, p) in rows.iter().zip(&points) {
            assert_eq!(row.rx, *p);
            let PointStatus::Traced {
                paths,
                shortest_delay_s,
                strongest,
                ..
            } = &row.status
            else {
                panic!("{p}: skipped")
            };
            assert_eq!(
                *paths,
                lattice_count(max_order as i32),
                "{p} order {max_order}"
            );
            let los = p.distance(Vec3::from_array(tx));
            let delay = shortest_delay_s.unwrap();
            assert!((delay * bt_beams::SPEED_OF_LIGHT - los).abs() < 1e-9);
            let s = strongest.as_ref().unwrap();
            assert_eq!(s.order, 0);
            let friis = bt_beams::free_space_loss_db(los, scene.frequency_hz());
            assert!((s.loss_db - friis).abs() < 1e-9);
        }
    }
    assert_eq!(lattice_count(3), 1 + 6 + 18 + 38);
}

#[test]
fn points_on_a_wall_or_at_the_tx_are_skipped_and_the_rest_traced() {
    let scene = box_room([4.0, 4.0, 3.0], [1.0, 2.0, 1.0]);
    // x = 0 lies on the wall, (1, 2, 1) is the TX.
    let grid: Grid = "0:2:1,2:2:1,1".parse().unwrap();
    let rows = sweep(
        &scene,
        &grid.points(10).unwrap(),
        (&TraceOptions::new(1), &bt_beams::RadioOptions::default()),
        &mut |_, _| {},
    )
    .unwrap();
    let status: Vec<_> = rows.iter().map(|r| &r.status).collect();
    match status[..] {
        [
            PointStatus::Skipped(wall),
            PointStatus::Skipped(at_tx),
            PointStatus::Traced { paths, .. },
        ] => {
            assert!(wall.contains("lies on surface"), "{wall}");
            assert!(at_tx.contains("same position"), "{at_tx}");
            assert_eq!(*paths, lattice_count(1));
        }
        _ => panic!("{status:?}"),
    }
    let csv = bt_coverage::csv(&rows);
    let lines: Vec<&str> = csv.lines().collect();
    assert!(
        lines[1].starts_with("0.000000,2.000000,1.000000,skipped,,,,,,,"),
        "{}",
        lines[1]
    );
    assert!(
        lines[3].starts_with("2.000000,2.000000,1.000000,ok,7,"),
        "{}",
        lines[3]
    );
}
