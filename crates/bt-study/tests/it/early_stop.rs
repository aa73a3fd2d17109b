//! Early stopping and the host's reflection-law check never lose a valid path: on the built-in
//! living room (order ≤ 3) and on seeded random furnished rooms (order ≤ 3), every path of the
//! f64 image method is neither frozen by early stopping (`left_bounds`) nor rejected by the
//! reflection-law check; a valid path the host still rejects ran exactly as without early
//! stopping (a round-cap or quantisation effect, not ours).

use bt_accel::{HostRejection, hls_input, host_accepts};
use bt_paths::{AllVisible, enumerate};
use bt_scene::{Scene, Terminals};
use bt_testkit::random_scene;

const SEED: u64 = 0x005e_ede5;

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
    let (input, sequences) = hls_input(scene, max_order, 16, 256).unwrap();
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
    let candidates = enumerate(scene, max_order, &AllVisible).unwrap();
    let reference = bt_solve::trace(scene, &candidates, &bt_solve::Solver::Image, false).unwrap();
    let ends = scene.terminals().unwrap();
    let mut c = Counts {
        frozen: early.iter().filter(|r| r.left_bounds).count(),
        rounds_early: early.iter().map(|r| u64::from(r.rounds.max(1))).sum(),
        rounds_plain: plain.iter().map(|r| u64::from(r.rounds.max(1))).sum(),
        ..Counts::default()
    };
    for path in reference.paths.iter().filter(|p| !p.surfaces.is_empty()) {
        let k = sequences
            .iter()
            .position(|s| s[..] == path.surfaces[..])
            .expect("every valid path is a candidate");
        c.valid += 1;
        match host_accepts(scene, ends, &sequences[k], &early[k]) {
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
        if host_accepts(scene, ends, seq, r).is_ok()
            && !reference.paths.iter().any(|p| p.surfaces[..] == seq[..])
        {
            c.spurious += 1;
        }
    }
    c
}

#[test]
fn living_room_keeps_every_valid_path() {
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
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
