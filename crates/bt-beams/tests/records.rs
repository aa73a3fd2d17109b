//! Reports into reused records ([`bt_beams::Records`]) are the fresh reports: receivers of
//! the living room traced in turn with and without diffraction and transmission, so that each
//! report refills records left by a larger or a smaller one, with other names, interactions
//! and lengths.

use bt_beams::{RadioOptions, Records, report};
use bt_geom::Vec3;
use bt_solve::Tracer;
use bt_solve::pipeline::DiffractionOptions;
use bt_solve::settings::SolveSettings;

#[test]
fn reused_records_are_the_fresh_report() {
    let scene = living_room();
    let tx = scene.tx_world().unwrap();
    let base = SolveSettings::default();
    let settings = [
        base,
        SolveSettings {
            max_order: 1,
            ..base
        },
        SolveSettings {
            max_order: 2,
            diffraction: DiffractionOptions::first_order(),
            transmission: true,
            ..base
        },
        base,
    ];
    let receivers = [[1.0, 1.0, 1.0], [2.3, 2.1, 0.72], [4.1, 3.3, 1.9]];
    let radio = RadioOptions::default();
    let mut records = Records::default();
    let mut sizes = Vec::new();
    for settings in settings {
        let mut tracer = Tracer::new(scene.clone(), settings.trace_options(&scene).unwrap());
        for rx in receivers.map(Vec3::from_array) {
            let traced = tracer.trace(tx, rx).unwrap();
            let moved = tracer.scene().with_terminals(tx, rx).unwrap();
            let fresh = report(&moved, &traced.result.paths, &radio).unwrap();
            let reused = records
                .report(&moved, &traced.result.paths, &radio)
                .unwrap();
            assert_eq!(reused, fresh.as_slice(), "{settings:?} at {rx}");
            sizes.push(fresh.len());
        }
    }
    // The reports grew and shrank, and some had diffracted paths (edge names).
    assert!(sizes.windows(2).any(|w| w[0] > w[1]) && sizes.windows(2).any(|w| w[0] < w[1]));
    assert!(sizes.iter().max() > Some(&100), "{sizes:?}");
}

/// Records keep the surfaces' responses from report to report in a scene of the same
/// surfaces, materials and frequency ([`bt_scene::RadioKey`]): the same paths reported in
/// turn in the scene, with other materials, at another frequency and in the scene again are
/// each time the fresh report (a response kept across a change of materials or frequency
/// would give the old gains and losses).
#[test]
fn kept_responses_follow_the_materials_and_the_frequency() {
    let scene = living_room();
    let (tx, rx) = (scene.tx_world().unwrap(), Vec3::new(2.3, 2.1, 0.72));
    let settings = SolveSettings::default();
    let mut tracer = Tracer::new(scene.clone(), settings.trace_options(&scene).unwrap());
    let paths = tracer.trace(tx, rx).unwrap().result.paths;
    let scene = tracer.scene().with_terminals(tx, rx).unwrap();
    let metal = bt_channel::RadioMaterial::itu("metal", None).unwrap();
    let scenes = [
        scene.clone(),
        scene.with_radio_material(metal).unwrap(),
        scene.with_frequency(60e9).unwrap(),
        scene.clone(),
    ];
    let radio = RadioOptions::default();
    let mut records = Records::default();
    let mut gains = Vec::new();
    for (k, scene) in scenes.iter().enumerate() {
        let fresh = report(scene, &paths, &radio).unwrap();
        let reused = records.report(scene, &paths, &radio).unwrap();
        assert_eq!(reused, fresh.as_slice(), "scene {k}");
        gains.push(fresh.iter().map(|p| p.gain).collect::<Vec<_>>());
    }
    // The materials and the frequency changed the gains: the reports tell them apart.
    assert!(gains[0] != gains[1] && gains[0] != gains[2] && gains[0] == gains[3]);
}

/// The living room's first step.
fn living_room() -> bt_scene::Scene {
    let options = bt_import::LoadOptions::default();
    let dynamic = bt_import::load_dynamic("builtin:living-room", &options, &mut |_| {});
    dynamic.unwrap().scene.step(0).clone()
}
