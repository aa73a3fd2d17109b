//! The beam-management study on a few positions of the dynamic living room: the exhaustive
//! sweep is always right without measurement error and not with it; a twin that traces what
//! the truth traces from the true position picks the true best pair every time; the stale
//! twin has no person; the truth's poses run from the first step to the last; same seed, same
//! numbers.

use bt_geom::Real;
use bt_study::beam_management::scenario::{ScanSettings, Scenario};
use bt_study::beam_management::{self, BeamManagementConfig, BeamManagementResults};

fn living_room(positions: usize) -> Scenario {
    let options = bt_import::LoadOptions::default();
    let loaded = bt_import::load_dynamic("builtin:living-room-dynamic", &options, &mut |_| {})
        .expect("built-in scene");
    let scan = ScanSettings {
        density_per_m2: 0.0,
        ..BeamManagementConfig::default().scan
    };
    Scenario::living_room("living-room", loaded.scene, positions, &scan).expect("scenario")
}

/// A small, fast configuration: one σ and latency, K = 1 and 4.
fn small() -> BeamManagementConfig {
    BeamManagementConfig {
        positions: 10,
        position_sigmas_m: vec![0.0],
        latencies_s: vec![0.0],
        top_k: vec![1, 4],
        ..BeamManagementConfig::default()
    }
}

fn run(config: &BeamManagementConfig) -> BeamManagementResults {
    beam_management::run(&[living_room(config.positions)], config, &mut |_, _| {}).expect("study")
}

fn method<'a>(r: &'a BeamManagementResults, name: &str) -> &'a beam_management::MethodResult {
    let s = &r.scenarios[0];
    s.methods
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| {
            let names: Vec<&str> = s.methods.iter().map(|m| m.name.as_str()).collect();
            panic!("no method {name} in {names:?}")
        })
}

#[test]
fn exhaustive_sweep_is_exact_without_measurement_error_and_not_with_it() {
    let exact = BeamManagementConfig {
        rsrp_noise_db: 0.0,
        rsrp_step_db: 0.0,
        ..small()
    };
    let r = run(&exact);
    let m = method(&r, "exhaustive");
    assert_eq!(m.metrics.decisions, 10);
    assert_eq!(m.metrics.top1, 1.0);
    assert_eq!(m.metrics.snr_loss_db_p95, 0.0);
    // 1 dB error and 1 dB reports: close pairs swap places at some decisions.
    let noisy = BeamManagementConfig {
        rsrp_noise_db: 2.0,
        positions: 20,
        ..small()
    };
    let r = run(&noisy);
    let m = method(&r, "exhaustive");
    assert!(m.metrics.top1 < 1.0, "{:?}", m.metrics);
    assert!(m.metrics.snr_loss_db_mean > 0.0);
    assert_eq!(m.metrics.beams_measured, 512.0);
}

#[test]
fn a_twin_that_traces_like_the_truth_from_the_true_position_is_always_right() {
    // Same tracer settings as the truth, no position error, no latency: its first-ranked pair
    // is the truth's best, so top-1 at K = 1 is exactly 1 (an end-to-end check of the
    // plumbing: scenes, poses, headings, reports and pair indices agree).
    let config = BeamManagementConfig {
        twin_max_order: 2,
        twin_diffraction: true,
        ..small()
    };
    let r = run(&config);
    let m = method(&r, "twin-exact-s0m-l0ms-top1");
    assert_eq!(m.metrics.top1, 1.0, "{:?}", m.metrics);
    assert_eq!(m.metrics.snr_loss_db_mean, 0.0);
    assert_eq!(m.fallbacks, 0);
    // The stale twin misses the person, and geometry alone (line of sight) is not the truth.
    assert!(method(&r, "twin-stale-s0m-l0ms-top1").metrics.top1 <= 1.0);
    let los = method(&r, "geometric-los-s0m-l0ms-top1");
    assert_eq!(los.metrics.beams_measured, 1.0);
}

#[test]
fn the_stale_twin_has_no_person_and_the_truth_walks_every_step() {
    let scenario = living_room(5);
    let truth = &scenario.truth;
    let stale = scenario.stale.as_ref().expect("a stale twin");
    let person = truth
        .objects()
        .iter()
        .find(|o| o.name == "person")
        .expect("person");
    assert_eq!(
        stale.surfaces().len(),
        truth.step(0).surfaces().len() - person.surfaces.len()
    );
    assert!(
        stale
            .surfaces()
            .iter()
            .all(|s| !s.name.starts_with("person"))
    );
    let vertices = |s: &bt_scene::Scene| -> Vec<Vec<bt_geom::Vec3>> {
        s.surfaces()
            .iter()
            .map(|s| s.polygon.vertices().to_vec())
            .collect()
    };
    let last = truth.len() - 1;
    let close = |a: &bt_scene::Scene, b: &bt_scene::Scene| {
        vertices(a)
            .iter()
            .flatten()
            .zip(vertices(b).iter().flatten())
            .all(|(p, q)| (*p - *q).length() < 1e-9)
    };
    assert!(close(&scenario.truth_at(0).unwrap(), truth.step(0)));
    assert!(close(&scenario.truth_at(4).unwrap(), truth.step(last)));
    assert!(!close(&scenario.truth_at(2).unwrap(), truth.step(0)));
    assert_eq!(scenario.trajectory.len(), 5);
}

#[test]
fn same_seed_same_numbers_other_seed_other_draws() {
    let config = BeamManagementConfig {
        positions: 8,
        rsrp_noise_db: 3.0,
        position_sigmas_m: vec![0.3],
        ..small()
    };
    let text = |r: &BeamManagementResults| {
        let details = serde_json::to_string(&beam_management::report::details(r)).unwrap();
        details + &beam_management::report::decisions_csv(r)
    };
    let (a, b) = (run(&config), run(&config));
    assert_eq!(text(&a), text(&b));
    let other = run(&BeamManagementConfig { seed: 2, ..config });
    assert_ne!(text(&a), text(&other));
}

#[test]
fn bad_settings_name_their_options() {
    let bad = BeamManagementConfig {
        positions: 1,
        top_k: vec![0],
        rsrp_noise_db: Real::NAN,
        position_sigmas_m: vec![-1.0],
        ..small()
    };
    let e = beam_management::run(&[], &bad, &mut |_, _| {})
        .unwrap_err()
        .to_string();
    for option in [
        "--positions",
        "--top-k",
        "--rsrp-noise-db",
        "--position-sigmas",
    ] {
        assert!(e.contains(option), "{option} in {e}");
    }
}

#[test]
fn the_extracted_twin_is_scanned_from_the_empty_room() {
    // The default scan (2,000 points/m², 5 mm noise): every extracted plane lies on a surface
    // of the stale room (its centroid within 2 cm of that surface's plane and over it, 10 cm
    // of slack for the traced boundary), so none comes from the walking person.
    let options = bt_import::LoadOptions::default();
    let loaded = bt_import::load_dynamic("builtin:living-room-dynamic", &options, &mut |_| {})
        .expect("built-in scene");
    let scan = BeamManagementConfig::default().scan;
    let scenario = Scenario::living_room("living-room", loaded.scene, 4, &scan).expect("scenario");
    let stale = scenario.stale.as_ref().expect("stale twin");
    let extracted = scenario.extracted.as_ref().expect("extracted twin");
    assert!(
        (15..=60).contains(&extracted.surfaces().len()),
        "{} planes",
        extracted.surfaces().len()
    );
    for plane in extracted.surfaces() {
        let c = extracted.to_world(plane.polygon.centroid());
        let on = stale.surfaces().iter().any(|s| {
            let local = stale.to_local(c);
            s.polygon.plane().signed_distance(local).abs() < 0.02 && s.polygon.contains(local, 0.1)
        });
        assert!(
            on,
            "{} at {c} lies on no surface of the empty room",
            plane.name
        );
    }
    assert!(
        scenario
            .notes
            .iter()
            .any(|n| n.contains("every plane concrete"))
    );
}
