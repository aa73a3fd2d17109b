//! Serve answers exactly what a one-shot `trace --json` answers for the same positions: the
//! same path records, value for value (so the same bytes), whatever came before in the stream.

use crate::common::{ask, assert_same_paths, load, one_shot, options, server};
use bt_scene::dynamic::Pose;
use bt_scene::{PoseDesc, Terminals, Vec3};
use bt_serve::Limits;
use bt_solve::pipeline::DiffractionOptions;
use bt_solve::settings::SolveSettings;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};

/// A seeded random walk of `n` receivers in the living room (6 × 4.5 × 2.7 m), 0.2 m steps,
/// kept 0.3 m from the walls, on a millimetre grid (positions a client would send, which
/// read back from JSON exactly).
fn walk(seed: u64, n: usize) -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut p: [f64; 3] = [2.3, 2.1, 0.72];
    (0..n)
        .map(|_| {
            let bounds: [(f64, f64); 3] = [(0.3, 5.7), (0.3, 4.2), (0.3, 2.4)];
            for (x, (lo, hi)) in p.iter_mut().zip(bounds) {
                let next = (*x + rng.random_range(-0.2..0.2)).clamp(lo, hi);
                *x = (next * 1e3).round() / 1e3;
            }
            p
        })
        .collect()
}

/// Each answer of a walk against the one-shot trace of its position; returns how many paths
/// were compared (so a walk that finds none cannot pass unnoticed).
fn compare_walk(settings: SolveSettings, seed: u64, n: usize) -> usize {
    let mut server = server("builtin:living-room", settings, Limits::default());
    let scene = load("builtin:living-room").step(0).clone();
    let options = options(&scene, settings);
    let tx = [5.6, 0.6, 2.2];
    let positions = walk(seed, n);
    let mut lines: Vec<String> = positions
        .iter()
        .enumerate()
        .map(|(i, rx)| json!({"id": i, "rx": rx}).to_string())
        .collect();
    lines.push(json!({"id": "all", "rx": positions}).to_string());
    let answers = ask(&mut server, &lines);
    assert_eq!(answers.len(), n + 1);
    let mut compared = 0;
    for (i, (answer, rx)) in answers.iter().zip(&positions).enumerate() {
        assert_eq!(answer["id"], json!(i), "answers in request order");
        assert_eq!(answer["rx"], json!(rx));
        assert_eq!(answer["tx"], json!(tx));
        let expected = one_shot(&scene, options, tx, *rx);
        assert_same_paths(
            &answer["paths"],
            &expected,
            &format!("receiver {i} at {rx:?}"),
        );
        let many = &answers[n]["results"][i];
        assert_same_paths(
            &many["paths"],
            &expected,
            &format!("receiver {i} of the list, at {rx:?}"),
        );
        compared += expected.as_array().map_or(0, Vec::len);
    }
    compared
}

#[test]
fn a_random_walk_of_receivers_gets_the_one_shot_paths() {
    let compared = compare_walk(SolveSettings::default(), 30, 30);
    assert!(compared > 30 * 10, "only {compared} paths compared");
}

#[test]
fn a_random_walk_with_diffraction_gets_the_one_shot_paths() {
    let settings = SolveSettings {
        max_order: 2,
        diffraction: DiffractionOptions::first_order(),
        ..SolveSettings::default()
    };
    let compared = compare_walk(settings, 31, 6);
    assert!(compared > 6 * 10, "only {compared} paths compared");
}

#[test]
fn a_moved_transmitter_and_the_receiver_left_out_are_traced_as_one_shot() {
    let settings = SolveSettings::default();
    let mut server = server("builtin:living-room", settings, Limits::default());
    let scene = load("builtin:living-room").step(0).clone();
    let options = options(&scene, settings);
    let lines = [
        json!({"id": 1, "rx": [1.0, 1.0, 1.0]}),
        json!({"id": 2, "tx": [3.0, 3.5, 2.0]}),
        json!({"id": 3, "rx": [[1.5, 1.0, 1.0], [4.0, 2.0, 1.2]]}),
        json!({"id": 4}),
    ];
    let answers = ask(&mut server, &lines.map(|l| l.to_string()));
    let (tx0, tx1) = ([5.6, 0.6, 2.2], [3.0, 3.5, 2.0]);
    assert_same_paths(
        &answers[0]["paths"],
        &one_shot(&scene, options, tx0, [1.0, 1.0, 1.0]),
        "",
    );
    assert_same_paths(
        &answers[1]["paths"],
        &one_shot(&scene, options, tx1, [1.0, 1.0, 1.0]),
        "",
    );
    for (i, rx) in [[1.5, 1.0, 1.0], [4.0, 2.0, 1.2]].into_iter().enumerate() {
        let expected = one_shot(&scene, options, tx1, rx);
        assert_same_paths(
            &answers[2]["results"][i]["paths"],
            &expected,
            &format!("list entry {i}"),
        );
        assert_same_paths(
            &answers[3]["results"][i]["paths"],
            &expected,
            &format!("repeated list entry {i}"),
        );
    }
}

/// The pose of object `name` that `desc` spells, as the scene file's keyframes would give it.
fn pose_of(dynamic: &bt_scene::dynamic::DynamicScene, name: &str, desc: PoseDesc) -> Pose {
    let object = dynamic.objects().iter().find(|o| o.name == name).unwrap();
    object.pose(&desc, name).unwrap()
}

#[test]
fn moved_objects_and_steps_are_traced_as_one_shot_traces_of_that_geometry() {
    let settings = SolveSettings::default();
    let mut server = server("builtin:living-room-dynamic", settings, Limits::default());
    let dynamic = load("builtin:living-room-dynamic");
    let options = options(dynamic.step(0), settings);
    let names: Vec<&str> = dynamic.objects().iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["door", "person"]);
    let (tx, rx, rx2) = ([5.6, 0.6, 2.2], [2.3, 2.1, 0.72], [1.0, 3.0, 1.1]);
    let lines = [
        json!({"id": 0, "objects": {"person": {"offset": [0.6, 1.2, 0]}, "door": {"angle_deg": 40}}}),
        json!({"id": 1, "rx": rx2}),
        json!({"id": 2, "step": 6, "rx": rx}),
        json!({"id": 3, "step": 6, "objects": {"person": {}}, "rx": [rx, rx2]}),
    ];
    let answers = ask(&mut server, &lines.map(|l| l.to_string()));
    let door = pose_of(
        &dynamic,
        "door",
        PoseDesc {
            offset: None,
            angle_deg: Some(40.0),
        },
    );
    let person = PoseDesc {
        offset: Some([0.6, 1.2, 0.0]),
        angle_deg: None,
    };
    let person = pose_of(&dynamic, "person", person);
    let posed = dynamic
        .posed(&[door, person], Terminals::default())
        .unwrap();
    assert_same_paths(&answers[0]["paths"], &one_shot(&posed, options, tx, rx), "");
    assert!(
        answers[0]["stats"]["update"].is_object(),
        "{}",
        answers[0]["stats"]
    );
    assert_same_paths(
        &answers[1]["paths"],
        &one_shot(&posed, options, tx, rx2),
        "",
    );
    assert!(
        answers[1]["stats"]["update"].is_null(),
        "a receiver move is a trace"
    );
    assert_same_paths(
        &answers[2]["paths"],
        &one_shot(dynamic.step(6), options, tx, rx),
        "",
    );
    let still = pose_of(&dynamic, "person", PoseDesc::default());
    let step6_door = dynamic.objects()[0].poses[6];
    let posed = dynamic
        .posed(&[step6_door, still], Terminals::default())
        .unwrap();
    for (i, p) in [rx, rx2].into_iter().enumerate() {
        let expected = one_shot(&posed, options, tx, p);
        assert_same_paths(
            &answers[3]["results"][i]["paths"],
            &expected,
            &format!("entry {i}"),
        );
    }
    let differs = |a: &Value, b: &Value| a["paths"] != b["paths"];
    assert!(
        differs(&answers[2], &answers[3]["results"][0]),
        "the person moved back"
    );
    let _ = Vec3::ZERO;
}
