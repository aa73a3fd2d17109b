//! Seeded random scenes: a room split by a partition with a doorway, random boxes and tilted
//! quads, random terminals; optionally with moving objects.

use bt_scene::dynamic::{DynamicScene, ObjectDesc};
use bt_scene::{BoxDesc, SceneDescription, SurfaceDesc, SurfaceKind, Terminals};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The room: `[0, ROOM]`, metres.
pub const ROOM: [f64; 3] = [8.0, 6.0, 3.0];

fn quad(c: [f64; 3], u: [f64; 3], v: [f64; 3]) -> Vec<[f64; 3]> {
    let p = |a: f64, b: f64| [0, 1, 2].map(|i| c[i] + a * u[i] + b * v[i]);
    vec![p(-1., -1.), p(1., -1.), p(1., 1.), p(-1., 1.)]
}

fn random_unit(rng: &mut ChaCha8Rng) -> [f64; 3] {
    loop {
        let v = [0; 3].map(|_| rng.random_range(-1.0..1.0f64));
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if n > 0.2 && n <= 1.0 {
            return v.map(|x| x / n);
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn inside(rng: &mut ChaCha8Rng, margin: f64) -> [f64; 3] {
    [0, 1, 2].map(|i| rng.random_range(margin..ROOM[i] - margin))
}

/// A random scene description (static) with `boxes` boxes and `quads` tilted quads.
pub fn random_description(seed: u64, boxes: usize, quads: usize) -> SceneDescription {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut d = SceneDescription {
        name: Some(format!("random-{seed}")),
        tx: Some(inside(&mut rng, 0.3)),
        rx: Some(inside(&mut rng, 0.3)),
        ..SceneDescription::default()
    };
    d.boxes.push(BoxDesc {
        name: "room".into(),
        min: [0.0; 3],
        max: ROOM,
        ..BoxDesc::default()
    });
    // Partition at x = 4 with a doorway in y.
    let g0 = rng.random_range(1.0..3.5);
    let g1 = g0 + rng.random_range(0.6..1.4);
    let h = ROOM[2];
    d.surfaces.push(SurfaceDesc {
        name: "partition-a".into(),
        vertices: vec![[4.0, 0.0, 0.0], [4.0, g0, 0.0], [4.0, g0, h], [4.0, 0.0, h]],
        ..SurfaceDesc::default()
    });
    d.surfaces.push(SurfaceDesc {
        name: "partition-b".into(),
        vertices: vec![
            [4.0, g1, 0.0],
            [4.0, ROOM[1], 0.0],
            [4.0, ROOM[1], h],
            [4.0, g1, h],
        ],
        ..SurfaceDesc::default()
    });
    for i in 0..boxes {
        let size = [0; 3].map(|_| rng.random_range(0.2..1.0));
        let min = [0, 1, 2].map(|k| rng.random_range(0.1..ROOM[k] - size[k] - 0.1));
        d.boxes.push(BoxDesc {
            name: format!("box{i}"),
            kind: Some(if rng.random_bool(0.3) {
                SurfaceKind::Blocker
            } else {
                SurfaceKind::Reflector
            }),
            min,
            max: [0, 1, 2].map(|k| min[k] + size[k]),
            ..BoxDesc::default()
        });
    }
    for i in 0..quads {
        let n = random_unit(&mut rng);
        let helper = if n[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let u = cross(n, helper);
        let un = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        let u = u.map(|x| x / un);
        let v = cross(n, u);
        let (a, b) = (rng.random_range(0.2..0.8), rng.random_range(0.2..0.8));
        d.surfaces.push(SurfaceDesc {
            name: format!("quad{i}"),
            vertices: quad(inside(&mut rng, 0.9), u.map(|x| x * a), v.map(|x| x * b)),
            ..SurfaceDesc::default()
        });
    }
    d
}

/// A random dynamic scene: the random scene with some boxes and quads moving over `steps`
/// steps (translations, and rotations of quads about one of their corners). Seeds whose steps
/// put a terminal on a surface are skipped by trying the next seed.
pub fn random_dynamic(seed: u64, steps: u32) -> (u64, DynamicScene) {
    for s in seed.. {
        let mut rng = ChaCha8Rng::seed_from_u64(s ^ 0x5eed);
        let mut d = random_description(s, 3, 4);
        d.steps = Some(steps);
        for (i, b) in d.boxes.iter_mut().enumerate().skip(1) {
            if i % 2 == 1 {
                let name = format!("mover{i}");
                b.object = Some(name.clone());
                let t = [0; 3].map(|_| rng.random_range(-0.15..0.15));
                d.objects.insert(
                    name,
                    ObjectDesc {
                        translate: Some([t[0], t[1], 0.0]),
                        ..ObjectDesc::default()
                    },
                );
            }
        }
        for (i, q) in d.surfaces.iter_mut().enumerate().skip(2) {
            if i % 2 == 0 {
                let name = format!("spinner{i}");
                q.object = Some(name.clone());
                d.objects.insert(
                    name,
                    ObjectDesc {
                        pivot: Some(q.vertices[0]),
                        axis: Some(random_unit(&mut rng)),
                        rotate_deg: Some(rng.random_range(-12.0..12.0)),
                        translate: Some([0; 3].map(|_| rng.random_range(-0.05..0.05))),
                        ..ObjectDesc::default()
                    },
                );
            }
        }
        if let Ok(scene) = DynamicScene::from_description(&d, "random", Terminals::default()) {
            return (s, scene);
        }
    }
    unreachable!()
}
