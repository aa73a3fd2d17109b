//! Path gains on traced scenes against independent references: the analytic two-ray ground
//! reflection (gain and phase of each path, and their coherent sum), and reciprocity on the
//! furnished living room (swap TX and RX and their antennas: the same gains).

use bt_beams::{PathReport, RadioOptions, report};
use bt_channel::{Antenna, Complex64, Orientation, Pattern, Polarization};
use bt_import::parse_json;
use bt_scene::{Scene, Terminals};
use bt_solve::Tracer;
use bt_solve::pipeline::TraceOptions;
use std::f64::consts::PI;

const C: f64 = 299_792_458.0;

fn trace(scene: &Scene, max_order: usize, radio: &RadioOptions) -> Vec<PathReport> {
    let mut tracer = Tracer::new(scene.clone(), TraceOptions::new(max_order));
    let traced = tracer
        .trace(scene.tx_world().unwrap(), scene.rx_world().unwrap())
        .unwrap();
    report(scene, &traced.result.paths, radio).unwrap()
}

/// TX at height h1, RX at h2, d apart over a lossy ground (εr = 15, σ = 0.05 S/m) at 3.5 GHz.
#[test]
fn two_ray_ground_reflection_gain_and_phase() {
    let (h1, h2, d, f): (f64, f64, f64, f64) = (10.0, 1.5, 40.0, 3.5e9);
    let (eps, sigma) = (15.0, 0.05);
    let json = format!(
        r#"{{ "frequency_hz": {f}, "tx": [0, 0, {h1}], "rx": [{d}, 0, {h2}],
        "materials": {{ "ground": {{ "relative_permittivity": {eps}, "conductivity": {sigma} }} }},
        "surfaces": [ {{ "name": "ground", "material": "ground",
          "vertices": [[-100, -100, 0], [100, -100, 0], [100, 100, 0], [-100, 100, 0]] }} ] }}"#
    );
    let scene = Scene::from_description(
        &parse_json(&json, "two-ray").unwrap(),
        "two-ray",
        Terminals::default(),
    )
    .unwrap();
    let lambda = C / f;
    let r1 = d.hypot(h1 - h2);
    let r2 = d.hypot(h1 + h2);
    // Hand-written Fresnel for the reference: η = εr − jσ/(ε0·2πf), cos θ = (h1 + h2)/r2.
    let eta = Complex64::new(eps, -sigma / (8.854_187_812_8e-12 * 2.0 * PI * f));
    let cos = (h1 + h2) / r2;
    let s = (eta - (1.0 - cos * cos)).sqrt();
    let gamma_v = (eta * cos - s) / (eta * cos + s);
    let gamma_h = (cos - s) / (cos + s);
    for (pol, gamma, los_sign) in [
        (Polarization::V, gamma_v, 1.0),
        (Polarization::H, gamma_h, -1.0),
    ] {
        let antenna = Antenna {
            polarization: pol,
            ..Antenna::default()
        };
        let radio = RadioOptions {
            tx: antenna,
            rx: antenna,
            ..RadioOptions::default()
        };
        let paths = trace(&scene, 1, &radio);
        assert_eq!(paths.len(), 2);
        let (los, ground) = (&paths[0], &paths[1]);
        assert!((los.length_m - r1).abs() < 1e-9 && (ground.length_m - r2).abs() < 1e-9);
        // V·V at the horizon: +λ/(4πr1). H·H: φ̂ at TX and at RX point opposite ways (the
        // field basis follows each antenna's own azimuth), so −λ/(4πr1): docs/channel.md.
        let expected_los = Complex64::new(los_sign * lambda / (4.0 * PI * r1), 0.0);
        assert!(
            (los.gain - expected_los).norm() < 1e-12 * expected_los.norm(),
            "{pol:?} los"
        );
        // V is TM, H is TE; both keep the LoS sign convention.
        let expected = gamma * (los_sign * lambda / (4.0 * PI * r2));
        assert!(
            (ground.gain - expected).norm() < 1e-9 * expected.norm(),
            "{pol:?}: {} vs {expected}",
            ground.gain
        );
        assert!((ground.gain.arg() - expected.arg()).abs() < 1e-9);
        // The coherent sum at the carrier is the textbook two-ray field.
        let taps = bt_beams::taps(&paths);
        let h = bt_channel::frequency_response(&taps, f, &[0.0])[0];
        let k = 2.0 * PI / lambda;
        let textbook = (Complex64::from_polar(1.0 / r1, -k * r1)
            + gamma * Complex64::from_polar(1.0 / r2, -k * r2))
            * (los_sign * lambda / (4.0 * PI));
        assert!(
            (h - textbook).norm() < 1e-9 * textbook.norm(),
            "{h} vs {textbook}"
        );
    }
}

#[test]
fn reciprocity_in_the_living_room() {
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let facing_a = Orientation::from_degrees(160.0, -15.0, 0.0);
    let facing_b = Orientation::from_degrees(-30.0, 10.0, 20.0);
    let a = Antenna::new(Pattern::Tr38901, Polarization::Plus45, facing_a);
    let b = Antenna::new(Pattern::Isotropic, Polarization::H, facing_b);
    let forward = trace(
        &scene,
        2,
        &RadioOptions {
            tx: a,
            rx: b,
            ..RadioOptions::default()
        },
    );
    let swapped = scene
        .with_terminals(scene.rx_world().unwrap(), scene.tx_world().unwrap())
        .unwrap();
    let backward = trace(
        &swapped,
        2,
        &RadioOptions {
            tx: b,
            rx: a,
            ..RadioOptions::default()
        },
    );
    assert_eq!(forward.len(), backward.len());
    assert!(forward.len() > 10);
    for p in &forward {
        let reversed: Vec<_> = p.surface_ids.iter().rev().copied().collect();
        let q = backward
            .iter()
            .find(|q| q.surface_ids == reversed)
            .expect("every path exists both ways");
        assert!(
            (p.gain - q.gain).norm() <= 1e-9 * p.gain.norm() + 1e-18,
            "{:?}: {} vs {}",
            p.surfaces,
            p.gain,
            q.gain
        );
        assert!(p.gain.norm() > 0.0);
    }
}

/// Line of sight 30° off both arrays' boresights: the DFT beam with spatial frequency
/// d·sin 30° = 1/4 (index 2 of 8) wins at both ends, with the full array gain 8 × 8.
#[test]
fn beam_sweep_finds_the_line_of_sight_pair() {
    let rx = [10.0, 10.0 * (30f64).to_radians().tan(), 0.0];
    let json = format!(
        r#"{{ "tx": [0, 0, 0], "rx": [{}, {}, 0], "surfaces": [] }}"#,
        rx[0], rx[1]
    );
    let scene = Scene::from_description(
        &parse_json(&json, "los").unwrap(),
        "los",
        Terminals::default(),
    )
    .unwrap();
    let radio = RadioOptions {
        tx_power_dbm: 20.0,
        ..RadioOptions::default()
    };
    let paths = trace(&scene, 1, &radio);
    assert_eq!(paths.len(), 1);
    let tx = bt_channel::Array::new(1, 8, 0.5, Orientation::default()).unwrap();
    let rx_array =
        bt_channel::Array::new(1, 8, 0.5, Orientation::from_degrees(180.0, 0.0, 0.0)).unwrap();
    let expected = 20.0 + 20.0 * (paths[0].gain.norm() * 8.0).log10();
    let sweep = |ranking, max_pairs| {
        let f = scene.frequency_hz();
        bt_beams::sweep(&paths, &tx, &rx_array, f, 20.0, ranking, max_pairs)
    };
    let max_pairs = bt_channel::MAX_BEAM_PAIRS.limit;
    for ranking in [bt_beams::BeamRanking::Power, bt_beams::BeamRanking::Paper] {
        let s = sweep(ranking, max_pairs).unwrap();
        let best = &s.pairs[0];
        assert_eq!((best.tx_beam, best.rx_beam), (2, 2), "{ranking:?}");
        assert!((best.power_dbm.unwrap() - expected).abs() < 1e-9);
        let dir = best.tx_direction_deg.unwrap();
        assert!((dir.azimuth - 30.0).abs() < 1e-9, "{dir:?}");
    }
    let all = sweep(bt_beams::BeamRanking::Power, max_pairs).unwrap();
    assert_eq!(all.pairs.len(), 64);
    // 64 pairs over a budget of 63: refused, naming the option.
    let e = sweep(bt_beams::BeamRanking::Power, 63)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("64 beam pairs") && e.contains("--max-beam-pairs"),
        "{e}"
    );
    assert!(
        all.pairs
            .windows(2)
            .all(|w| w[0].power_dbm.unwrap_or(f64::NEG_INFINITY)
                >= w[1].power_dbm.unwrap_or(f64::NEG_INFINITY))
    );
}
