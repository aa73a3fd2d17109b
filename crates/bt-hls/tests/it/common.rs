// The small test scene shared by the bt-hls integration tests.

use std::path::PathBuf;
use std::sync::OnceLock;

use bt_hls::{HlsInput, PlaneSpec, Report};
use bt_schedule::{Schedule, round_template};

/// A 5 m x 4 m x 3 m room: four walls (the x = 0 wall tilted by ~5.7 degrees so its PE has a
/// real CSD network), floor and ceiling; all first-order paths and every second-order path
/// between two walls or a wall and the floor (orders <= 2).
pub fn small_scene() -> HlsInput {
    let tilt = [0.995_037_190_209_989_1, 0.099_503_719_020_998_92, 0.0];
    let mut planes = vec![PlaneSpec {
        name: "wall_west_tilted".into(),
        normal: tilt,
        offset_m: tilt[1] * 2.0,
        bounds_m: Some([[-0.2, 0.0, 0.0], [0.2, 4.0, 3.0]]),
    }];
    // The other five faces, axis-aligned: (name, axis, on the far side of the room).
    let room = [5.0, 4.0, 3.0];
    for (name, axis, far) in [
        ("wall_east", 0, true),
        ("wall_south", 1, false),
        ("wall_north", 1, true),
        ("floor", 2, false),
        ("ceiling", 2, true),
    ] {
        let at = if far { room[axis] } else { 0.0 };
        let mut normal = [0.0; 3];
        normal[axis] = if far { -1.0 } else { 1.0 };
        let (mut lo, mut hi) = ([0.0; 3], room);
        (lo[axis], hi[axis]) = (at, at);
        planes.push(PlaneSpec {
            name: name.into(),
            normal,
            offset_m: normal[axis] * at,
            bounds_m: Some([lo, hi]),
        });
    }
    // Each plane's centre of its bounds (the tilted wall's too): the paths' initial points.
    let centroids: Vec<[f64; 3]> = planes
        .iter()
        .map(|p| {
            let [lo, hi] = p.bounds_m.unwrap();
            [0, 1, 2].map(|k| (lo[k] + hi[k]) / 2.0)
        })
        .collect();
    let mut paths: Vec<Vec<u32>> = (0..6).map(|p| vec![p]).collect();
    for a in 0..5u32 {
        for b in 0..5u32 {
            if a != b {
                paths.push(vec![a, b]);
            }
        }
    }
    let init_points = paths
        .iter()
        .map(|p| p.iter().map(|&i| centroids[i as usize]).collect())
        .collect();
    HlsInput {
        planes,
        paths,
        init_points,
        tx: [1.2, 1.0, 1.5],
        rx: [3.9, 2.7, 1.1],
        threshold_lsb: 16,
        max_rounds: 40,
        test_vectors: vec![
            [[0.8, 3.1, 2.2], [4.1, 0.9, 0.6]],
            [[2.5, 2.0, 1.0], [2.6, 2.1, 2.0]],
        ],
        early_stop: None,
        // The room's 5 m extent: a 24-bit coordinate word, as `bt_accel` sizes a room.
        coord_bits: bt_fixed::coord_bits_for(5.0),
        round_order: bt_hls::RoundOrder::Jacobi,
    }
}

/// The small scene with early stopping on (`EarlyStop::default()`), the east wall and the floor
/// cut down to 1 m patches (as a window and a rug would be) so that some paths leave them.
pub fn small_scene_early() -> HlsInput {
    let mut s = small_scene();
    s.planes[1].bounds_m = Some([[5.0, 0.0, 0.0], [5.0, 1.0, 3.0]]);
    s.planes[4].bounds_m = Some([[0.0, 0.0, 0.0], [1.0, 4.0, 0.0]]);
    s.early_stop = Some(bt_fixed::EarlyStop::default());
    s
}

/// The schedule: the round template of dynamic dispatch (no model run) with a second PE for
/// the floor, so that the copies' columns are exercised.
pub fn small_schedule(input: &HlsInput) -> Schedule {
    round_template(&input.one_round_problem(), &[1, 1, 1, 1, 2, 1]).expect("template")
}

pub struct Generated {
    pub dir: PathBuf,
    pub report: Report,
    pub input: HlsInput,
    pub schedule: Schedule,
}

/// Generated once per test binary, in the target's temporary directory.
pub fn generated() -> &'static Generated {
    static G: OnceLock<Generated> = OnceLock::new();
    G.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_small_scene");
        let _ = std::fs::remove_dir_all(&dir);
        let input = small_scene();
        let schedule = small_schedule(&input);
        let report = bt_hls::generate(&input, &schedule, &dir).expect("generate");
        Generated {
            dir,
            report,
            input,
            schedule,
        }
    })
}

/// `testdata/golden/rtl` at the repository root: the generator's golden outputs.
pub fn golden_dir() -> PathBuf {
    bt_testkit::golden::dir().join("rtl")
}

/// Compares `actual` with the golden file `testdata/golden/rtl/<name>`; `UPDATE_GOLDEN=1`
/// rewrites it (`bt_testkit::golden::assert_golden`).
#[track_caller]
pub fn golden(name: &str, actual: &str) {
    bt_testkit::golden::assert_golden(golden_dir().join(name), actual);
}
