//! `FixedIpc` outcomes and validation.

use bt_fixed::{Coord, DegenerateKind, EarlyStop, FixedError, FixedIpc, FixedOutcome, PlaneInput};

fn floor() -> PlaneInput {
    PlaneInput {
        normal: [0.0, 0.0, 1.0],
        offset_m: 0.0,
    }
}

/// One path bouncing once off the floor from `start`, 16 LSB threshold.
fn floor_bounce(start: [f64; 3], max_rounds: u32) -> FixedIpc {
    FixedIpc::new(&[floor()], &[vec![0]], &[vec![start]], 16, max_rounds).unwrap()
}

/// The one path of [`floor_bounce`] from (0.5, 0.5, 0) run between `tx` and `rx` (metres).
fn bounce_path(max_rounds: u32, tx: [f64; 3], rx: [f64; 3]) -> bt_fixed::PathResult {
    let ipc = floor_bounce([0.5, 0.5, 0.0], max_rounds);
    ipc.run(tx, rx).unwrap().swap_remove(0)
}

#[test]
fn single_floor_bounce_converges_to_the_mirror_point() {
    let r = &bounce_path(50, [0.0, 0.0, 1.0], [3.0, 0.0, 2.0]);
    assert!(
        matches!(r.outcome(), FixedOutcome::Converged { rounds: 1 | 2 }),
        "{r:?}"
    );
    // Mirror point: x = 3 · 1/(1+2) = 1 m.
    assert!((r.points_m[0][0] - 1.0).abs() < 1e-5, "{r:?}");
    assert_eq!(r.points[0][2].0, 0);
}

#[test]
fn zero_budget_returns_the_initial_points() {
    let r = &bounce_path(0, [0.0, 0.0, 1.0], [3.0, 0.0, 2.0]);
    let expected = FixedOutcome::NotConverged {
        rounds: 0,
        displacement_lsb: 0,
    };
    assert_eq!(r.outcome(), expected);
    assert_eq!(r.points_m[0], [0.5, 0.5, 0.0]);
}

#[test]
fn terminals_on_the_plane_are_degenerate_not_a_panic() {
    let r = &bounce_path(50, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    let expected = FixedOutcome::Degenerate {
        kind: DegenerateKind::ZeroDistanceSum,
        rounds: 1,
    };
    assert_eq!(r.outcome(), expected);
    assert_eq!(r.points_m[0], [0.5, 0.0, 0.0]); // midpoint
}

#[test]
fn leaving_the_range_is_degenerate_overflow() {
    let r3 = 1.0 / 3f64.sqrt();
    let plane = PlaneInput {
        normal: [r3, r3, r3],
        offset_m: 0.0,
    };
    let ipc = FixedIpc::new(&[plane], &[vec![0]], &[vec![[0.0, 0.0, 0.0]]], 16, 50).unwrap();
    let corner = [Coord(i32::MAX), Coord(i32::MAX), Coord(i32::MIN)];
    let r = &ipc.run_fixed(corner, corner, None)[0];
    assert_eq!(
        r.outcome(),
        FixedOutcome::Degenerate {
            kind: DegenerateKind::CoordinateOverflow,
            rounds: 1
        }
    );
}

#[test]
fn per_path_budgets_override_the_default() {
    let ipc = FixedIpc::new(
        &[floor()],
        &[vec![0], vec![0]],
        &[vec![[9.0, 9.0, 0.0]], vec![[9.0, 9.0, 0.0]]],
        0,
        50,
    )
    .unwrap();
    let tx = [Coord(0), Coord(0), Coord(1000)];
    let rx = [Coord(3000), Coord(0), Coord(2000)];
    let r = ipc.run_fixed(tx, rx, Some(&[1, 3]));
    assert_eq!(r[0].rounds, 1);
    assert!(r[1].rounds >= 2);
}

#[test]
fn validation_reports_every_problem() {
    let bad_plane = PlaneInput {
        normal: [0.0, 0.0, 2.0],
        offset_m: 0.0,
    };
    let err = FixedIpc::new(
        &[floor(), bad_plane],
        &[vec![], vec![7], vec![0, 0]],
        &[vec![], vec![[f64::NAN, 0.0, 0.0]]],
        16,
        10,
    )
    .unwrap_err();
    let FixedError::InvalidInput { problems } = err else {
        panic!("{err:?}")
    };
    let text = problems.join("\n");
    for needle in [
        "plane 1",
        "path 0: has no",
        "plane index 7",
        "path 1 initial point 0",
        "3 paths but 2",
    ] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
}

#[test]
fn early_stopping_freezes_a_point_outside_its_box_and_nothing_else() {
    // The mirror point is x = 1 m; a floor patch x in [0, 0.5] m does not hold it.
    let ipc = || floor_bounce([0.25, 0.0, 0.0], 50);
    let stop = EarlyStop {
        min_rounds: 1,
        ..EarlyStop::default()
    };
    let (tx, rx) = ([0.0, 0.0, 1.0], [3.0, 0.0, 2.0]);
    let small = Some([[0.0, -1.0, 0.0], [0.5, 1.0, 0.0]]);
    let r = &ipc()
        .with_early_stop(stop, &[small])
        .unwrap()
        .run(tx, rx)
        .unwrap()[0];
    // Round 1 moves the point by 0.75 m: the margin covers it; round 2 stalls outside.
    assert_eq!(r.outcome(), FixedOutcome::LeftBounds { rounds: 2 }, "{r:?}");
    assert!(r.left_bounds && !r.converged);
    // Converged before min_rounds: untouched.
    let late = EarlyStop {
        min_rounds: 3,
        ..stop
    };
    let r = &ipc()
        .with_early_stop(late, &[small])
        .unwrap()
        .run(tx, rx)
        .unwrap()[0];
    assert!(
        matches!(r.outcome(), FixedOutcome::Converged { .. }),
        "{r:?}"
    );
    // A box holding the solution, or none: the same result as without early stopping.
    let plain = ipc().run(tx, rx).unwrap();
    for bounds in [Some([[0.0, -1.0, 0.0], [2.0, 1.0, 0.0]]), None] {
        let r = ipc()
            .with_early_stop(stop, &[bounds])
            .unwrap()
            .run(tx, rx)
            .unwrap();
        assert_eq!(r, plain);
    }
}

#[test]
fn early_stopping_settings_are_validated() {
    let ipc = floor_bounce([0.5, 0.5, 0.0], 50);
    let bad = EarlyStop {
        min_rounds: 0,
        displacement_shift: 5,
        margin_lsb: 0,
    };
    let err = ipc
        .with_early_stop(bad, &[Some([[1.0, 0.0, 0.0], [0.0, 1.0, f64::NAN]])])
        .unwrap_err();
    let FixedError::InvalidInput { problems } = err else {
        panic!("{err:?}")
    };
    assert_eq!(problems.len(), 4, "{problems:?}");
}

/// A narrowed coordinate word (a room's 24 bits: ±32.8 m) gives the full word's answer inside
/// its range and refuses what does not fit, naming the value. (Saturation at each width is
/// exercised by `widths::widths_hold_at_the_corners`.)
#[test]
fn a_narrow_coordinate_word_agrees_inside_refuses_outside_and_saturates() {
    let ipc = || floor_bounce([0.5, 0.5, 0.0], 50);
    let narrow = ipc().with_coord_bits(24).unwrap();
    assert_eq!(narrow.coord_bits(), 24);
    let (tx, rx) = ([0.0, 0.0, 1.0], [3.0, 0.0, 2.0]);
    assert_eq!(narrow.run(tx, rx).unwrap(), ipc().run(tx, rx).unwrap());
    // TX 40 m away does not fit.
    let err = narrow.run([40.0, 0.0, 1.0], rx).unwrap_err().to_string();
    assert!(err.contains("TX") && err.contains("24-bit"), "{err}");
    // A plane 40 m out and a start point 50 m out are refused, each named.
    let far = PlaneInput {
        normal: [1.0, 0.0, 0.0],
        offset_m: 40.0,
    };
    let err = FixedIpc::new(
        &[floor(), far],
        &[vec![0]],
        &[vec![[50.0, 0.0, 0.0]]],
        16,
        50,
    )
    .unwrap()
    .with_coord_bits(24)
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("plane 1") && err.contains("initial point 0"),
        "{err}"
    );
    assert!(ipc().with_coord_bits(12).is_err());
}
