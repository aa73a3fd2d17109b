//! Newton-accelerated IPC against the image method: the same valid paths, to 1e-11 m, on the
//! random scenes of `ipc_vs_image.rs` and on corner reflectors whose bounce points lie
//! within 0.1-10 mm of the edge (where the paper's rounds converge sublinearly).

mod common;
use bt_geom::{Real, Vec3};
use bt_scene::Scene;
use bt_solve::{Acceleration, FoundPath, IpcOptions, Solver, UpdateOrder};
use common::*;
use proptest::prelude::*;

/// Agreement promised by Newton acceleration, metres.
const NEWTON_AGREEMENT: Real = 1e-11;

fn newton(scene: &Scene, order: UpdateOrder) -> Solver {
    Solver::Ipc(IpcOptions {
        acceleration: Acceleration::Newton,
        ..IpcOptions::for_scene(scene, order)
    })
}

/// Two walls meeting at the z axis with dihedral angle `angle` (rad), 2 m wide and 2.5 m high,
/// and a double bounce constructed by the law of reflection: a ray with azimuth `azimuth` and
/// elevation `elevation` (rad) hits wall A `d1` metres from the edge at height `z1`, reflects
/// to wall B (`d2` from the edge, a similar distance) and on to RX; TX and RX lie `t1`, `t2`
/// metres from the bounce points. `None` when the construction leaves the wedge.
pub fn corner_scene(
    angle: Real,
    azimuth: Real,
    elevation: Real,
    d1: Real,
    z1: Real,
    t1: Real,
    t2: Real,
) -> Option<Scene> {
    let (w, h) = (2.0, 2.5);
    let da = Vec3::X;
    let db = Vec3::new(angle.cos(), angle.sin(), 0.0);
    let na = Vec3::Y;
    let nb = Vec3::new(angle.sin(), -angle.cos(), 0.0);
    let incoming = Vec3::new(azimuth.cos(), azimuth.sin(), elevation.tan()).normalize();
    let p1 = d1 * da + z1 * Vec3::Z;
    let o = incoming - 2.0 * incoming.dot(na) * na;
    if !(incoming.dot(na) < -0.05 && o.dot(nb) < -0.05) {
        return None;
    }
    let p2 = p1 - (nb.dot(p1) / nb.dot(o)) * o;
    let tx = p1 - t1 * incoming;
    let rx = p2 + t2 * (o - 2.0 * o.dot(nb) * nb);
    let inside = |p: Vec3| {
        p.dot(na) > 0.05 && p.dot(nb) > 0.05 && p.z > 0.05 && p.z < h - 0.05 && p.length() < w
    };
    if !(inside(tx) && inside(rx) && p2.dot(db) > 0.0 && p2.z > 0.05 && p2.z < h - 0.05) {
        return None;
    }
    let wall =
        |d: Vec3| [Vec3::ZERO, w * d, w * d + h * Vec3::Z, h * Vec3::Z].map(|v| v.to_array());
    let json = format!(
        r#"{{ "tx": {:?}, "rx": {:?}, "surfaces": [
            {{ "name": "a", "kind": "reflector", "vertices": {:?} }},
            {{ "name": "b", "kind": "reflector", "vertices": {:?} }} ] }}"#,
        tx.to_array(),
        rx.to_array(),
        wall(da),
        wall(db)
    );
    Some(scene_from_json(&json))
}

fn check_agreement(
    reference: &[FoundPath],
    paths: &[FoundPath],
    what: &str,
) -> Result<(), TestCaseError> {
    prop_assert_eq!(sequences(paths), sequences(reference), "{}", what);
    let d = max_point_distance(paths, reference);
    prop_assert!(d <= NEWTON_AGREEMENT, "{}: points differ by {} m", what, d);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 24,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x05ee_d1bc),
        ..ProptestConfig::default()
    })]

    /// The scenes of `ipc_equals_image_method_on_random_scenes`, with Newton after both orders.
    #[test]
    fn newton_equals_image_method_on_random_scenes(seed in 0u64..1_000_000, n in 1usize..6) {
        let scene = random_scene(seed, n);
        let reference = run(&scene, 3, Solver::Image);
        for order in [UpdateOrder::GaussSeidel, UpdateOrder::Jacobi] {
            let paths = run(&scene, 3, newton(&scene, order));
            check_agreement(&reference, &paths, &format!("{order:?}"))?;
            for p in &paths {
                prop_assert!(p.points.iter().all(|q| q.is_finite()));
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0xc0_4e4),
        ..ProptestConfig::default()
    })]

    /// Corner reflectors, bounce points 0.1-10 mm from the edge, orders up to 3 (A B A chains
    /// bounce near the edge too).
    #[test]
    fn newton_equals_image_method_near_corners(
        angle_deg in 60.0f64..120.0,
        azimuth in -3.1f64..-0.05,
        elevation in -0.4f64..0.4,
        d1_exp in -4.0f64..-2.0,
        z1 in 0.3f64..2.2,
        t1 in 0.3f64..1.8,
        t2 in 0.3f64..1.8,
    ) {
        let scene = corner_scene(angle_deg.to_radians(), azimuth, elevation, 10f64.powf(d1_exp), z1, t1, t2);
        prop_assume!(scene.is_some());
        let scene = scene.unwrap();
        let reference = run(&scene, 3, Solver::Image);
        prop_assert!(reference.iter().any(|p| p.surfaces.len() == 2), "the constructed double bounce is found");
        for order in [UpdateOrder::GaussSeidel, UpdateOrder::Jacobi] {
            let paths = run(&scene, 3, newton(&scene, order));
            check_agreement(&reference, &paths, &format!("{order:?} tx {} rx {}", scene.tx(), scene.rx()))?;
        }
    }
}

/// Measured accuracy near corners (for docs/numerics.md): the worst distance from the image
/// method over 400 seeded corner scenes, plain IPC vs Newton, and the rounds spent.
/// `cargo test -p bt-solve --test newton corner_accuracy_table -- --nocapture` prints it.
#[test]
fn corner_accuracy_table() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2024);
    let solvers = |scene: &Scene| {
        [
            ("gauss-seidel", ipc(scene, UpdateOrder::GaussSeidel)),
            ("jacobi", ipc(scene, UpdateOrder::Jacobi)),
            (
                "gauss-seidel+newton",
                newton(scene, UpdateOrder::GaussSeidel),
            ),
            ("jacobi+newton", newton(scene, UpdateOrder::Jacobi)),
        ]
    };
    // worst distance, cases over 1e-9 m, cases over 1e-11 m, sequence mismatches, iterations
    let mut stats = [(0.0 as Real, 0u32, 0u32, 0u32, 0u64); 4];
    let (mut scenes, mut tries) = (0, 0);
    while scenes < 400 {
        let scene = corner_scene(
            rng.random_range(60.0f64..120.0).to_radians(),
            rng.random_range(-3.1..-0.05),
            rng.random_range(-0.4..0.4),
            10f64.powf(rng.random_range(-4.0..-2.0)),
            rng.random_range(0.3..2.2),
            rng.random_range(0.3..1.8),
            rng.random_range(0.3..1.8),
        );
        tries += 1;
        let Some(scene) = scene else { continue };
        scenes += 1;
        let reference = run(&scene, 3, Solver::Image);
        for (s, (_, solver)) in stats.iter_mut().zip(solvers(&scene)) {
            let paths = run(&scene, 3, solver);
            if sequences(&paths) != sequences(&reference) {
                s.3 += 1;
                continue;
            }
            let d = max_point_distance(&paths, &reference);
            s.0 = s.0.max(d);
            s.1 += u32::from(d > 1e-9);
            s.2 += u32::from(d > 1e-11);
            s.4 += paths
                .iter()
                .map(|p| u64::from(p.iterations.unwrap_or(0)))
                .sum::<u64>();
        }
    }
    eprintln!("{scenes} corner scenes of {tries} tries");
    for ((name, _), s) in solvers(&random_scene(0, 1)).iter().zip(&stats) {
        eprintln!(
            "{name:>20}: worst {:.2e} m, >1e-9 m: {}, >1e-11 m: {}, sequence mismatches: {}, iterations of valid paths: {}",
            s.0, s.1, s.2, s.3, s.4
        );
    }
    for s in &stats[2..] {
        assert_eq!(s.3, 0, "newton: same valid paths as the image method");
        assert!(s.0 <= NEWTON_AGREEMENT, "newton: worst {} m", s.0);
    }
}
