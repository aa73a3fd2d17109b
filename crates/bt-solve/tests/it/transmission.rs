//! Thin-slab transmission: the beam tree never loses a path that crosses penetrable surfaces
//! (against blind enumeration of every sequence, on random scenes mixing slabs, half-spaces,
//! blockers and surfaces whose material says `"transmission": true`); each path's crossings are
//! exactly the penetrable surfaces its segments pass through (a brute-force scan of every
//! surface, no BVH) and fit the order; opaque-valid paths survive; traces are reciprocal; a
//! wall's transmitted path has free space times the slab's Airy transmission.

use crate::common::{listing, paths_of as paths, scene_from_json, trace_scene};
use bt_geom::{Real, Vec3};
use bt_paths::beamtree::{Culling, TreeCache, TreeOptions};
use bt_scene::{Scene, SurfaceId};
use bt_solve::pipeline::{CandidateMode, DiffractionOptions, TraceOptions};
use bt_solve::{FoundPath, Interaction, Solver};
use bt_testkit::nasty_penetrable_scene;
use proptest::prelude::*;

fn options(
    max_order: usize,
    mode: CandidateMode,
    everywhere: bool,
    diffract: bool,
) -> TraceOptions {
    TraceOptions {
        candidates: mode,
        parallel: false,
        transmission: everywhere,
        diffraction: match diffract {
            true => DiffractionOptions::first_order(),
            false => DiffractionOptions::default(),
        },
        ..TraceOptions::new(max_order)
    }
}

/// The scene as the trace saw it (its penetrable surfaces).
fn seen(scene: &Scene, options: &TraceOptions) -> Scene {
    options.scene_of(scene)
}

/// Check one path's crossings by brute force over every surface: the vertices between
/// crossings (TX, reflection and diffraction points, RX) span segments; every penetrable
/// surface a segment passes through (other than the surfaces its ends lie on) is one of its
/// crossings, or lies on a seam with one (coplanar, same point), and every crossing is such a
/// surface; no opaque surface blocks a segment; the interactions fit the order.
fn check_crossings(scene: &Scene, path: &FoundPath, max_order: usize) -> Result<(), String> {
    let ends = scene.terminals().unwrap();
    let tol = scene.length_tolerance();
    let interactions = path.interactions();
    if interactions.len() > max_order {
        return Err(format!(
            "{} interactions at order {max_order}",
            interactions.len()
        ));
    }
    // (vertex, the surfaces it lies on) for TX, every non-crossing point, RX.
    let mut vertices: Vec<(Vec3, Vec<SurfaceId>)> = vec![(ends.tx, vec![])];
    let mut crossed: Vec<Vec<(Vec3, SurfaceId)>> = vec![vec![]];
    for (p, it) in path.points.iter().zip(&interactions) {
        match *it {
            Interaction::Transmission(s) => crossed.last_mut().unwrap().push((*p, s)),
            Interaction::Reflection(s) => {
                vertices.push((*p, vec![s]));
                crossed.push(vec![]);
            }
            Interaction::Diffraction(e) => {
                vertices.push((*p, scene.edges().get(e).touching.clone()));
                crossed.push(vec![]);
            }
        }
    }
    vertices.push((ends.rx, vec![]));
    for (k, w) in vertices.windows(2).enumerate() {
        let ((a, from), (b, to)) = (&w[0], &w[1]);
        let t_min = tol / a.distance(*b).max(tol);
        let reported = &crossed[k];
        for (i, s) in scene.surfaces().iter().enumerate() {
            let id = SurfaceId(i as u32);
            if from.contains(&id)
                || to.contains(&id)
                || !s.polygon.blocks_segment(*a, *b, t_min, tol)
            {
                continue;
            }
            if !scene.penetrable(id) {
                return Err(format!("segment {k} blocked by opaque {}", s.name));
            }
            let normal = s.polygon.plane().normal;
            let on_seam = |(p, r): &(Vec3, SurfaceId)| {
                let other = scene.surface(*r).polygon.plane().normal;
                s.polygon.plane().signed_distance(*p).abs() <= 2.0 * tol
                    && other.dot(normal).abs() > 0.999_999
            };
            if !reported.iter().any(|c| c.1 == id || on_seam(c)) {
                return Err(format!("segment {k} crosses {} unreported", s.name));
            }
        }
        for (p, s) in reported {
            let polygon = &scene.surface(*s).polygon;
            if !scene.penetrable(*s) || !polygon.blocks_segment(*a, *b, t_min, tol) {
                return Err(format!(
                    "reported crossing of {} is not one",
                    scene.surface(*s).name
                ));
            }
            let off_line = (*p - *a).cross((*b - *a).normalize()).length();
            if off_line > tol || polygon.plane().signed_distance(*p).abs() > tol {
                return Err(format!(
                    "crossing point of {} off its segment or plane",
                    scene.surface(*s).name
                ));
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x7ea5_0001),
        ..ProptestConfig::default()
    })]

    /// Penetrable surfaces neither cull the beam tree nor its RX tree: its candidates give
    /// exactly the valid paths, specular, diffracted and crossing, of every sequence enumerated
    /// blindly; each path's crossings pass the brute-force check.
    #[test]
    fn beam_tree_transmission_equals_exhaustive_enumeration(
        seed in 0u64..1_000_000, n in 1usize..7, terminals in 0u8..3, order in 1usize..4,
        everywhere in any::<bool>(), diffract in any::<bool>(),
    ) {
        let Some(scene) = nasty_penetrable_scene(seed, n, terminals) else { return Ok(()) };
        let reference = options(order, CandidateMode::Exhaustive, everywhere, diffract);
        let exhaustive = paths(&scene, &reference);
        let tree = paths(&scene, &options(order, CandidateMode::BeamTree, everywhere, diffract));
        prop_assert_eq!(listing(&tree), listing(&exhaustive));
        let traced = seen(&scene, &reference);
        for p in &tree {
            if let Err(e) = check_crossings(&traced, p, order) {
                prop_assert!(false, "{:?}: {}", p.interactions(), e);
            }
        }
    }

    /// Every culling policy of the beam tree (the default rarely culls in rooms this small):
    /// penetrable surfaces never cover a window, so forced culling loses no crossing path,
    /// specular or diffracted (the RX tree of the diffraction join culls the same way), with
    /// transmission everywhere (blockers and half-spaces stay opaque) or per material. The
    /// occlusion walks then search the opaque surfaces' own index: one that left an opaque
    /// surface out would lose no path but keep blocked candidates, and one that held a
    /// penetrable one would lose paths, so both are compared against enumeration.
    #[test]
    fn every_culling_policy_keeps_the_crossing_paths(
        seed in 0u64..1_000_000, n in 1usize..7, terminals in 0u8..3, order in 1usize..4,
        policy in 0usize..2, diffract in any::<bool>(), everywhere in any::<bool>(),
    ) {
        let Some(scene) = nasty_penetrable_scene(seed, n, terminals) else { return Ok(()) };
        let culling = [Culling::Always, Culling::Auto { min_work: 0 }][policy];
        let reference = options(order, CandidateMode::Exhaustive, everywhere, diffract);
        let exhaustive = paths(&scene, &reference);
        let traced = seen(&scene, &reference);
        let set = bt_paths::beamtree::candidates_and_diffracted_in(
            &traced,
            TreeOptions { culling, ..TreeOptions::new(order) },
            diffract.then_some(bt_paths::diffraction::Diffracting {
                min_edge_length: 0.0,
                max_diffractions: 1,
            }),
            &mut TreeCache::default(),
            &mut |_| {},
        )
        .expect("tree builds");
        let tree = bt_solve::trace(&traced, &set, &Solver::Image, false).unwrap().paths;
        let mut a = listing(&tree);
        let mut b = listing(&exhaustive);
        let key = |x: &(Vec<Interaction>, Vec<Vec3>)| format!("{x:?}");
        a.sort_by_key(key);
        b.sort_by_key(key);
        prop_assert_eq!(a, b);
    }

    /// The WVRN's occluders are opaque surfaces only: it finds every crossing path too.
    #[test]
    fn wvrn_transmission_equals_exhaustive_enumeration(
        seed in 0u64..1_000_000, n in 1usize..6, order in 1usize..4,
    ) {
        let Some(scene) = nasty_penetrable_scene(seed, n, 0) else { return Ok(()) };
        let exhaustive = paths(&scene, &options(order, CandidateMode::Exhaustive, true, false));
        let wvrn = paths(&scene, &options(order, CandidateMode::Wvrn, true, false));
        prop_assert_eq!(listing(&wvrn), listing(&exhaustive));
    }

    /// A path valid with the slabs opaque crosses nothing, so it stays valid, unchanged, when
    /// waves cross every slab; and a trace from RX to TX finds the same paths backwards.
    #[test]
    fn opaque_paths_survive_and_traces_are_reciprocal(
        seed in 0u64..1_000_000, n in 1usize..6, order in 1usize..4,
    ) {
        let Some(scene) = nasty_penetrable_scene(seed, n, 0) else { return Ok(()) };
        let through = paths(&scene, &options(order, CandidateMode::BeamTree, true, false));
        let opaque = paths(&scene, &options(order, CandidateMode::BeamTree, false, false));
        let all = listing(&through);
        for p in opaque.iter().filter(|p| p.crossings.is_empty()) {
            prop_assert!(all.contains(&(p.interactions(), p.points.to_vec())), "{:?} lost", p.interactions());
        }
        let ends = scene.terminals().unwrap();
        let back = scene.with_terminals(scene.to_world(ends.rx), scene.to_world(ends.tx)).unwrap();
        let mut reversed: Vec<(Vec<Interaction>, Vec<Vec3>)> =
            listing(&paths(&back, &options(order, CandidateMode::BeamTree, true, false)))
                .into_iter()
                .map(|(mut i, mut p)| { i.reverse(); p.reverse(); (i, p) })
                .collect();
        let mut forward = all.clone();
        let key = |x: &(Vec<Interaction>, Vec<Vec3>)| format!("{:?}", x.0);
        reversed.sort_by_key(key);
        forward.sort_by_key(key);
        prop_assert_eq!(reversed.len(), forward.len());
        for ((i, p), (j, q)) in forward.iter().zip(&reversed) {
            prop_assert_eq!(i, j);
            for (x, y) in p.iter().zip(q) {
                prop_assert!(x.distance(*y) < 1e-9, "{} vs {}", x, y);
            }
        }
    }
}

/// ITU-R P.2040 concrete at `f` Hz: η = a·f^b − j·σ/(2π·f·ε0), σ = c·f^d (f in GHz).
fn concrete(frequency_hz: Real) -> bt_channel::Complex64 {
    let f = frequency_hz / 1e9;
    let sigma = 0.0462 * f.powf(0.7822);
    let eps0 = 8.854_187_812_8e-12;
    bt_channel::Complex64::new(
        5.24,
        -sigma / (2.0 * std::f64::consts::PI * frequency_hz * eps0),
    )
}

/// The TE amplitude transmission of a slab (relative permittivity `eta`, `d` metres) in
/// vacuum at incidence `theta`: Airy's sum of the multiple internal reflections,
/// t = (1 − r²)·e^{−jδ} / (1 − r²·e^{−2jδ}), r the TE Fresnel coefficient, δ = k0·d·√(η − sin²θ).
fn airy_te(eta: bt_channel::Complex64, theta: Real, d: Real, frequency_hz: Real) -> Real {
    let cos = theta.cos();
    let root = (eta - theta.sin().powi(2)).sqrt();
    let r = (cos - root) / (cos + root);
    let k0 = 2.0 * std::f64::consts::PI * frequency_hz / 299_792_458.0;
    let j = bt_channel::Complex64::i();
    let delta = k0 * d * root;
    ((1.0 - r * r) * (-j * delta).exp() / (1.0 - r * r * (-2.0 * j * delta).exp())).norm()
}

/// A 20 cm concrete wall between TX and RX: with transmission the one path is the straight
/// crossing, and its gain (isotropic, vertically polarised ends: the field is TE to the
/// horizontal plane of incidence) is free space times the Airy slab transmission, at 0°, 30°
/// and 60° incidence, within 0.05 dB. Without transmission the wall blocks everything.
#[test]
fn a_wall_passes_free_space_times_the_slab_transmission() {
    let frequency_hz = 3.5e9;
    for theta_deg in [0.0, 30.0, 60.0] {
        let theta: Real = (theta_deg as Real).to_radians();
        let (d, h) = (2.0, 1.5);
        let tx = [-d * theta.cos(), -d * theta.sin(), h];
        let rx = [0.7 * d * theta.cos(), 0.7 * d * theta.sin(), h];
        let scene = scene_from_json(&format!(
            r#"{{ "frequency_hz": {frequency_hz}, "tx": {tx:?}, "rx": {rx:?},
                 "materials": {{ "slab": {{ "itu": "concrete", "thickness": 0.2 }} }},
                 "surfaces": [ {{ "name": "wall", "material": "slab",
                   "vertices": [[0, -20, 0], [0, 20, 0], [0, 20, 6], [0, -20, 6]] }} ] }}"#
        ));
        let opaque = paths(&scene, &options(2, CandidateMode::BeamTree, false, false));
        assert!(opaque.is_empty(), "{theta_deg}°: the wall blocks");
        let found = paths(&scene, &options(2, CandidateMode::BeamTree, true, false));
        assert_eq!(found.len(), 1, "{theta_deg}°: {found:?}");
        let path = &found[0];
        assert_eq!(
            path.interactions(),
            vec![Interaction::Transmission(SurfaceId(0))]
        );
        let traced = seen(&scene, &options(2, CandidateMode::BeamTree, true, false));
        let report = bt_beams::describe(&traced, path, &bt_beams::RadioOptions::default()).unwrap();
        let length = Vec3::from_array(tx).distance(Vec3::from_array(rx));
        let wavelength = 299_792_458.0 / frequency_hz;
        let t = airy_te(concrete(frequency_hz), theta, 0.2, frequency_hz);
        let expected_db = 20.0 * (wavelength / (4.0 * std::f64::consts::PI * length) * t).log10();
        let got_db = report.gain_db.unwrap();
        assert!(
            (got_db - expected_db).abs() < 0.05,
            "{theta_deg}°: {got_db} vs {expected_db} dB"
        );
        assert!((report.incidence_deg[0].unwrap() - theta_deg).abs() < 1e-9);
        let t_loss = -20.0 * t.log10();
        assert!(
            report.transmission_loss_db > 0.0 && report.transmission_loss_db < 2.0 * t_loss + 1.0
        );
    }
}

/// Crossings count in the order: a path through two walls needs order 2.
#[test]
fn crossings_count_in_the_order() {
    let scene = scene_from_json(
        r#"{ "tx": [-3, 0.3, 1.5], "rx": [3, -0.2, 1.5],
             "surfaces": [
               { "name": "a", "material": "glass", "vertices": [[-1, -9, 0], [-1, 9, 0], [-1, 9, 4], [-1, -9, 4]] },
               { "name": "b", "material": "glass", "vertices": [[1, -9, 0], [1, 9, 0], [1, 9, 4], [1, -9, 4]] } ] }"#,
    );
    for (order, expected) in [(1, 0), (2, 1), (3, 1)] {
        let found = paths(
            &scene,
            &options(order, CandidateMode::BeamTree, true, false),
        );
        let through: Vec<_> = found.iter().filter(|p| p.surfaces.is_empty()).collect();
        assert_eq!(through.len(), expected, "order {order}: {found:?}");
        if let Some(p) = through.first() {
            let kinds = p.interactions();
            assert_eq!(
                kinds,
                vec![
                    Interaction::Transmission(SurfaceId(0)),
                    Interaction::Transmission(SurfaceId(1))
                ]
            );
        }
    }
}

/// A material's `"transmission": true` opens its surfaces without the switch; a half-space
/// given the key is refused at load, naming the field.
#[test]
fn a_materials_key_opens_its_surfaces_alone() {
    let scene = scene_from_json(
        r#"{ "tx": [-2, 0, 1.5], "rx": [2, 0, 1.5],
             "materials": { "curtain": { "itu": "wood", "thickness": 0.01, "transmission": true } },
             "surfaces": [ { "name": "c", "material": "curtain", "kind": "blocker",
                 "vertices": [[0, -5, 0], [0, 5, 0], [0, 5, 3], [0, -5, 3]] } ] }"#,
    );
    let found = paths(&scene, &options(1, CandidateMode::BeamTree, false, false));
    assert_eq!(found.len(), 1);
    assert_eq!(
        found[0].interactions(),
        vec![Interaction::Transmission(SurfaceId(0))]
    );
    let desc: bt_scene::SceneDescription = serde_json::from_str(
        r#"{ "materials": { "m": { "itu": "wood", "transmission": true } },
             "surfaces": [ { "name": "c", "material": "m", "vertices": [[0, -5, 0], [0, 5, 0], [0, 5, 3]] } ] }"#,
    )
    .unwrap();
    let e = Scene::from_description(&desc, "s.json", Default::default()).unwrap_err();
    assert!(e.to_string().contains("materials.m.transmission"), "{e}");
}

/// SBR does not transmit: asked to trace a scene with penetrable surfaces, it refuses.
#[test]
fn sbr_refuses_penetrable_scenes() {
    let scene = scene_from_json(
        r#"{ "tx": [-2, 0, 1.5], "rx": [2, 0, 1.5],
             "surfaces": [ { "name": "g", "material": "glass",
                 "vertices": [[0, -5, 0], [0, 5, 0], [0, 5, 3], [0, -5, 3]] } ] }"#,
    );
    let sbr = TraceOptions {
        solver: Solver::Sbr(bt_solve::SbrOptions::default()),
        ..options(1, CandidateMode::BeamTree, true, false)
    };
    let e = trace_scene(&scene, &sbr).unwrap_err();
    assert!(
        e.to_string().contains("SBR solver does not transmit"),
        "{e}"
    );
}
