//! Terminals per trace: a bare scene (no TX/RX) traces through the `Tracer` with terminals
//! given per call exactly as the same scene loaded with them, and every entry point that
//! reads the scene's own terminals fails with `MissingTerminal` naming them.

use crate::common::scene_from_json;
use bt_geom::Vec3;
use bt_paths::beamtree::{BeamTree, TreeError, TreeOptions};
use bt_scene::{SceneError, Terminal};
use bt_solve::Tracer;
use bt_solve::pipeline::{CandidateMode, TraceError, TraceOptions, candidates};
use bt_solve::steps::trace_scratch;

const ROOM: &str = r#""boxes": [ { "name": "room", "min": [0, 0, 0], "max": [6, 5, 3] } ],
    "surfaces": [ { "name": "shelf", "vertices": [[1, 1, 1], [2, 1, 1], [2, 2, 1], [1, 2, 1]] } ]"#;

/// `options` under each candidate generator.
fn in_every_mode(options: TraceOptions) -> [TraceOptions; 3] {
    [
        CandidateMode::BeamTree,
        CandidateMode::Wvrn,
        CandidateMode::Exhaustive,
    ]
    .map(|candidates| TraceOptions {
        candidates,
        ..options
    })
}

fn missing(e: &TraceError) -> Vec<Terminal> {
    match e {
        TraceError::Scene(SceneError::MissingTerminal { missing, .. }) => missing.clone(),
        other => panic!("not a missing terminal: {other}"),
    }
}

#[test]
fn a_bare_scene_traces_like_the_scene_with_its_terminals() {
    let bare = scene_from_json(&format!("{{ {ROOM} }}"));
    let full = scene_from_json(&format!(
        r#"{{ "tx": [1, 4, 2], "rx": [5, 1, 1.5], {ROOM} }}"#
    ));
    assert_eq!((bare.tx(), bare.rx()), (None, None));
    // The extent of a bare scene comes from its surfaces; placing the terminals (inside the
    // room) gives the loaded scene's extent and tolerance.
    assert_eq!(bare.extent(), full.extent());
    let (tx, rx) = (Vec3::new(1.0, 4.0, 2.0), Vec3::new(5.0, 1.0, 1.5));
    for options in in_every_mode(TraceOptions::new(2)) {
        let mode = options.candidates;
        let a = Tracer::new(bare.clone(), options).trace(tx, rx).unwrap();
        let b = Tracer::new(full.clone(), options).trace(tx, rx).unwrap();
        assert_eq!(a.result.paths, b.result.paths, "{mode:?}");
        assert!(!a.result.paths.is_empty());
        let many = Tracer::new(bare.clone(), options)
            .trace_many(tx, &[rx, Vec3::new(4.0, 3.0, 2.0)])
            .unwrap();
        assert_eq!(many[0].result.paths, b.result.paths, "{mode:?}");
    }
}

#[test]
fn entry_points_name_the_missing_terminal() {
    let bare = scene_from_json(&format!("{{ {ROOM} }}"));
    let rx_only = scene_from_json(&format!(r#"{{ "rx": [5, 1, 1.5], {ROOM} }}"#));
    for options in in_every_mode(TraceOptions::new(2)) {
        let mode = options.candidates;
        let e = candidates(&bare, &options).unwrap_err();
        assert_eq!(missing(&e), [Terminal::Tx, Terminal::Rx], "{mode:?}");
        let e = candidates(&rx_only, &options).unwrap_err();
        assert_eq!(missing(&e), [Terminal::Tx], "{mode:?}");
        let e = trace_scratch(&bare, 0, &options).unwrap_err();
        assert_eq!(missing(&e), [Terminal::Tx, Terminal::Rx], "{mode:?}");
        let mut tracer = Tracer::new(bare.clone(), options);
        let e = tracer.update(&bare).unwrap_err();
        assert_eq!(missing(&e), [Terminal::Tx, Terminal::Rx], "{mode:?}");
    }
    let e = BeamTree::build(&rx_only, TreeOptions::new(2)).unwrap_err();
    assert!(
        matches!(&e, TreeError::Scene(SceneError::MissingTerminal { missing, .. }) if missing == &[Terminal::Tx]),
        "{e}"
    );
    let e = bt_paths::wvrn::Wvrn::build(&bare).unwrap_err();
    assert!(e.to_string().contains("no tx and rx given"), "{e}");
    let e = bt_solve::trace(
        &bare,
        &bt_paths::CandidateSet::default(),
        &bt_solve::Solver::Image,
        false,
    )
    .unwrap_err();
    assert!(matches!(e, SceneError::MissingTerminal { .. }), "{e}");
    // A receiver alone needs the scene's TX.
    assert!(matches!(
        bare.with_receiver(Vec3::new(5.0, 1.0, 1.5)),
        Err(SceneError::MissingTerminal { .. })
    ));
}
