//! Early stopping and the host's reflection-law check never lose a valid path: on the built-in
//! living room (order ≤ 3) and on seeded random furnished rooms (order ≤ 3), every path of the
//! f64 image method is neither frozen by early stopping (`left_bounds`) nor rejected by the
//! reflection-law check; a valid path the host still rejects ran exactly as without early
//! stopping (a round-cap or quantisation effect, not ours).

use bt_geom::{Real, Vec3};
use bt_paths::{AllVisible, enumerate};
use bt_scene::{Scene, SceneDescription, Terminals};
use bt_study::fpga::{HostRejection, hls_input, host_accepts};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SEED: u64 = 0x005e_ede5;

/// A box room with `n` random rectangles (every third a blocker) and random TX/RX.
fn random_scene(seed: u64, n: usize) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let size = Vec3::new(
        rng.random_range(3.0..8.0),
        rng.random_range(3.0..8.0),
        rng.random_range(2.2..3.5),
    );
    let mut surfaces = Vec::new();
    for i in 0..n {
        let centre = Vec3::new(
            rng.random_range(0.2..size.x - 0.2),
            rng.random_range(0.2..size.y - 0.2),
            rng.random_range(0.2..size.z - 0.2),
        );
        let normal = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::Z);
        let (u, v) = normal.any_orthonormal_pair();
        let (a, b) = (rng.random_range(0.2..1.2), rng.random_range(0.2..1.2));
        let verts: Vec<[Real; 3]> = [(-a, -b), (a, -b), (a, b), (-a, b)]
            .iter()
            .map(|(x, y)| (centre + *x * u + *y * v).to_array())
            .collect();
        let kind = if i % 3 == 2 { "blocker" } else { "reflector" };
        surfaces.push(format!(
            r#"{{ "name": "s{i}", "kind": "{kind}", "vertices": {verts:?} }}"#
        ));
    }
    let pick = |rng: &mut ChaCha8Rng| {
        [
            rng.random_range(0.1..size.x - 0.1),
            rng.random_range(0.1..size.y - 0.1),
            rng.random_range(0.1..size.z - 0.1),
        ]
    };
    let (tx, rx) = (pick(&mut rng), pick(&mut rng));
    let json = format!(
        r#"{{ "tx": {tx:?}, "rx": {rx:?}, "surfaces": [{}], "boxes": [ {{ "name": "room", "min": [0, 0, 0], "max": {:?} }} ] }}"#,
        surfaces.join(","),
        size.to_array()
    );
    let d: SceneDescription = serde_json::from_str(&json).unwrap();
    Scene::from_description(&d, "random", Terminals::default()).expect("random scene is valid")
}

#[derive(Debug, Default)]
struct Counts {
    valid: usize,
    lost_to_early_stop: usize,
    lost_to_reflection_check: usize,
    lost_anyway: usize,
    frozen: usize,
    spurious: usize,
    rounds_early: u64,
    rounds_plain: u64,
}

fn check(scene: &Scene, max_order: usize) -> Counts {
    let (input, sequences) = hls_input(scene, max_order, 16, 256);
    let early = input.model().unwrap().run(input.tx, input.rx).unwrap();
    let plain_input = bt_hls::HlsInput {
        early_stop: None,
        ..input.clone()
    };
    let plain = plain_input
        .model()
        .unwrap()
        .run(input.tx, input.rx)
        .unwrap();
    let candidates = enumerate(scene, max_order, &AllVisible);
    let reference = bt_solve::trace(scene, &candidates, &bt_solve::Solver::Image, false);
    let mut c = Counts {
        frozen: early.iter().filter(|r| r.left_bounds).count(),
        rounds_early: early.iter().map(|r| u64::from(r.rounds.max(1))).sum(),
        rounds_plain: plain.iter().map(|r| u64::from(r.rounds.max(1))).sum(),
        ..Counts::default()
    };
    for path in reference.paths.iter().filter(|p| !p.surfaces.is_empty()) {
        let k = sequences
            .iter()
            .position(|s| *s == path.surfaces)
            .expect("every valid path is a candidate");
        c.valid += 1;
        match host_accepts(scene, &sequences[k], &early[k]) {
            Ok(_) => {}
            Err(_) if early[k].left_bounds => c.lost_to_early_stop += 1,
            Err(HostRejection::ReflectionLaw) => c.lost_to_reflection_check += 1,
            Err(_) => {
                assert_eq!(early[k], plain[k], "a valid path not frozen runs unchanged");
                c.lost_anyway += 1;
            }
        }
    }
    for (seq, r) in sequences.iter().zip(&early) {
        if host_accepts(scene, seq, r).is_ok()
            && !reference.paths.iter().any(|p| p.surfaces == *seq)
        {
            c.spurious += 1;
        }
    }
    c
}

#[test]
fn living_room_keeps_every_valid_path() {
    let scene = bt_scene::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let c = check(&scene, 3);
    assert!(c.valid > 30, "{c:?}");
    assert_eq!(c.lost_to_early_stop, 0, "{c:?}");
    assert_eq!(c.lost_to_reflection_check, 0, "{c:?}");
    assert_eq!(c.spurious, 0, "{c:?}");
    assert!(c.frozen > 0, "{c:?}");
    assert!(c.rounds_early * 2 < c.rounds_plain, "{c:?}");
}

#[test]
fn random_rooms_keep_every_valid_path() {
    let mut total = Counts::default();
    for s in 0..12u64 {
        let scene = random_scene(SEED + s, 9);
        let c = check(&scene, 3);
        total.valid += c.valid;
        total.lost_anyway += c.lost_anyway;
        total.frozen += c.frozen;
        total.spurious += c.spurious;
        assert_eq!(c.lost_to_early_stop, 0, "seed {}: {c:?}", SEED + s);
        assert_eq!(c.lost_to_reflection_check, 0, "seed {}: {c:?}", SEED + s);
    }
    assert!(total.valid > 50, "{total:?}");
}
