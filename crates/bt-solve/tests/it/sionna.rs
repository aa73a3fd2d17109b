//! Against Sionna RT 2.2 with first-order diffraction (`testdata/sionna-reference`, written by
//! `tools/sionna_reference.py` from Sionna's own scenes in `testdata/scenes/sionna-rt`):
//! every path Sionna found is found here, with its interaction kinds in order and its points
//! within 1 cm; specular gains agree within 0.05 dB; diffracted gains are compared and their
//! spread reported (Sionna 2.2's coefficient is not Kouyoumjian–Pathak's:
//! docs/sionna-diffraction-notes.md, docs/channel.md §8).

use bt_beams::{InteractionKind, PathReport, RadioOptions};
use bt_channel::DiffractionCoefficient;
use bt_geom::{Real, Vec3};
use bt_scene::Terminals;
use bt_solve::Tracer;
use bt_solve::pipeline::{DiffractionOptions, TraceOptions};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The reference cases (one file each).
const CASES: [&str; 6] = [
    "wedge-shadow-d1",
    "wedge-shadow-d2",
    "wedge-lit-d2",
    "box-edges-d2",
    "canyon-d3",
    "florence-mast-d3",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn vec3(v: &Value) -> Vec3 {
    let a: Vec<Real> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    Vec3::new(a[0], a[1], a[2])
}

/// One Sionna path: interaction kinds, vertices (world frame), gain (dB).
struct Expected {
    kinds: Vec<InteractionKind>,
    vertices: Vec<Vec3>,
    gain_db: Real,
}

fn expected(path: &Value) -> Expected {
    let kind = |k: &Value| match k.as_str().unwrap() {
        "reflection" => InteractionKind::Reflection,
        "diffraction" => InteractionKind::Diffraction,
        other => panic!("unexpected interaction {other}"),
    };
    Expected {
        kinds: path["kinds"].as_array().unwrap().iter().map(kind).collect(),
        vertices: path["vertices"]
            .as_array()
            .unwrap()
            .iter()
            .map(vec3)
            .collect(),
        gain_db: path["gain_db"].as_f64().unwrap(),
    }
}

/// Ours matching `e`: the same kinds in order, every point within `tolerance` metres.
fn matching<'a>(ours: &'a [PathReport], e: &Expected, tolerance: Real) -> Option<&'a PathReport> {
    ours.iter().find(|p| {
        p.interactions == e.kinds
            && p.points
                .iter()
                .zip(&e.vertices)
                .all(|(a, b)| Vec3::from(*a).distance(*b) <= tolerance)
    })
}

/// One diffracted path found in both: ours − Sionna's gain (dB), and whether Sionna diffracts
/// on a free edge (a screen, n = 2) where our edge is a wedge (n < 2): Florence's eaves, where
/// Sionna sees a wall mesh and a roof mesh meeting, and we one wedge (docs/channel.md §8).
#[derive(Clone, Copy)]
struct Diffracted {
    diff_db: Real,
    screen_there_wedge_here: bool,
    /// The path reflects after its diffraction.
    reflected_after: bool,
}

/// Sionna's diffraction of `path` is on a free edge of a mesh (a screen).
fn screen_there(path: &Value) -> bool {
    let edges = path["edges"].as_array().unwrap();
    edges.iter().any(|e| e["free"] == true)
}

/// Gain differences (ours − Sionna's, dB) of the specular and the diffracted paths.
#[derive(Default)]
struct Differences {
    specular: Vec<Real>,
    diffracted: Vec<Diffracted>,
    missing: Vec<String>,
    /// Sionna paths diffracting where our scene has no edge.
    no_edge: Vec<String>,
}

/// Reference case `case` and the scene it was traced in, loaded as Sionna sees it: at the
/// case's frequency, every face a reflector.
fn reference(case: &str) -> (Value, bt_scene::Scene) {
    let file = root().join(format!("testdata/sionna-reference/{case}.json"));
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    let xml = root().join(doc["scene"]["xml"].as_str().unwrap());
    let options = bt_import::LoadOptions {
        frequency_hz: doc["frequency_hz"].as_f64().unwrap(),
        // Sionna reflects on every face, however small.
        min_reflector_area_m2: 0.0,
        terminals: Terminals::default(),
        ..bt_import::LoadOptions::default()
    };
    let scene = bt_import::load(xml.to_str().unwrap(), &options)
        .unwrap()
        .scene;
    (doc, scene)
}

fn compare_case(case: &str, radio: &RadioOptions, out: &mut Differences) {
    let (doc, scene) = reference(case);
    let trace = TraceOptions {
        diffraction: DiffractionOptions::first_order(),
        ..TraceOptions::new(doc["max_depth"].as_u64().unwrap() as usize)
    };
    let mut tracer = Tracer::new(scene, trace);
    let tx = vec3(&doc["tx"]["position"]);
    for receiver in doc["receivers"].as_array().unwrap() {
        let rx = vec3(&receiver["position"]);
        let traced = tracer.trace(tx, rx).unwrap();
        let scene = tracer.scene().with_terminals(tx, rx).unwrap();
        let ours = bt_beams::report(&scene, &traced.result.paths, radio).unwrap();
        for path in receiver["paths"].as_array().unwrap() {
            let e = expected(path);
            match matching(&ours, &e, 0.01) {
                Some(p) => {
                    let diff_db = p.gain_db.unwrap() - e.gain_db;
                    match p.diffraction {
                        Some(d) => out.diffracted.push(Diffracted {
                            diff_db,
                            screen_there_wedge_here: screen_there(path)
                                && scene.edges().get(d.edge).n < 2.0,
                            reflected_after: d.index + 1 < p.points.len(),
                        }),
                        None => out.specular.push(diff_db),
                    }
                }
                None => {
                    // A Sionna diffraction on a junction our scene has no edge at (Sionna
                    // diffracts on every mesh boundary, e.g. a wall's foot on the ground, which
                    // is a concave junction: docs/channel.md §8) is explained, not missing.
                    let edge_here = |p: Vec3| {
                        let local = tracer.scene().to_local(p);
                        tracer.scene().edges().all().iter().any(|edge| {
                            let t = edge.parameter(local).clamp(0.0, edge.length);
                            edge.point(t).distance(local) <= 0.01
                        })
                    };
                    let at = e
                        .kinds
                        .iter()
                        .position(|k| *k == InteractionKind::Diffraction);
                    match at {
                        Some(k) if !edge_here(e.vertices[k]) => out
                            .no_edge
                            .push(format!("{case} rx {rx}: {:?} at {:?}", e.kinds, e.vertices)),
                        _ => out
                            .missing
                            .push(format!("{case} rx {rx}: {:?} at {:?}", e.kinds, e.vertices)),
                    }
                }
            }
        }
    }
}

/// How many of `paths` lie within `db` of Sionna's gain.
fn within(paths: &[Diffracted], db: Real) -> usize {
    paths.iter().filter(|p| p.diff_db.abs() <= db).count()
}

/// Compare every case with `coefficient`, printing per case how many diffracted gains lie
/// within 0.1, 1, 3 and 6 dB of Sionna's (and of those on Sionna's screens that are our
/// wedges, how many within 3 dB).
fn compare_all(coefficient: DiffractionCoefficient) -> Differences {
    let radio = RadioOptions {
        diffraction_coefficient: coefficient,
        ..RadioOptions::default()
    };
    let mut d = Differences::default();
    eprintln!("coefficient {coefficient}: diffracted gains within 0.1 / 1 / 3 / 6 dB of Sionna's");
    for case in CASES {
        let before = d.diffracted.len();
        compare_case(case, &radio, &mut d);
        let mine = &d.diffracted[before..];
        let eaves: Vec<Diffracted> = (mine.iter().copied())
            .filter(|p| p.screen_there_wedge_here)
            .collect();
        eprintln!(
            "  {case:17} {:3} paths: {:3} {:3} {:3} {:3}; mean diff {:6.2} dB, worst {:6.2}; \
             screens there, wedges here: {} ({} within 3 dB)",
            mine.len(),
            within(mine, 0.1),
            within(mine, 1.0),
            within(mine, 3.0),
            within(mine, 6.0),
            mine.iter().map(|p| p.diff_db).sum::<Real>() / mine.len().max(1) as Real,
            mine.iter().fold(0.0, |a: Real, p| a.max(p.diff_db.abs())),
            eaves.len(),
            within(&eaves, 3.0),
        );
    }
    let all = &d.diffracted;
    eprintln!(
        "  all               {:3} paths: {:3} {:3} {:3} {:3}",
        all.len(),
        within(all, 0.1),
        within(all, 1.0),
        within(all, 3.0),
        within(all, 6.0),
    );
    d
}

#[test]
fn every_sionna_path_is_found_with_its_gain() {
    let d = compare_all(DiffractionCoefficient::Utd);
    eprintln!(
        "Sionna paths: {} specular, {} diffracted, {} missing, {} on junctions without an edge \
         here; specular worst {:.4} dB",
        d.specular.len(),
        d.diffracted.len(),
        d.missing.len(),
        d.no_edge.len(),
        d.specular.iter().fold(0.0, |a: Real, b| a.max(b.abs())),
    );
    assert!(d.missing.is_empty(), "missing: {:#?}", d.missing);
    assert!(
        d.specular.iter().all(|x| x.abs() <= 0.05),
        "{:?}",
        d.specular
    );
    assert!(d.diffracted.len() > 200, "{}", d.diffracted.len());
    eprintln!("diffracting where we have no edge: {:#?}", d.no_edge);
}

/// On the metal box (a near-perfect conductor) the diffracted gains are Kouyoumjian–Pathak's:
/// the values an independent implementation (numpy/scipy, `tools/sionna_utd_replica.py
/// --check`, column KP-PEC) gives for the same two paths, −85.35 and −93.44 dB; Sionna 2.2's
/// own coefficient gives −91.58 and −93.16 dB (its hard polarisation takes the soft
/// coefficient: docs/sionna-diffraction-notes.md).
#[test]
fn a_metal_box_diffracts_as_kouyoumjian_pathak() {
    let (_, scene) = reference("box-edges-d2");
    let trace = TraceOptions {
        diffraction: DiffractionOptions::first_order(),
        ..TraceOptions::new(1)
    };
    let mut tracer = Tracer::new(scene, trace);
    let tx = Vec3::new(-15.0, 1.0, 2.0);
    for (rx, expected_db) in [
        (Vec3::new(8.0, -1.0, 7.0), -85.35),
        (Vec3::new(12.0, 9.0, 1.5), -93.44),
    ] {
        let traced = tracer.trace(tx, rx).unwrap();
        let scene = tracer.scene().with_terminals(tx, rx).unwrap();
        let ours =
            bt_beams::report(&scene, &traced.result.paths, &RadioOptions::default()).unwrap();
        assert_eq!(ours.len(), 1, "one path over the edge");
        let gain = ours[0].gain_db.unwrap();
        assert!((gain - expected_db).abs() < 0.01, "{gain} vs {expected_db}");
    }
}

/// With Sionna RT 2.2's own coefficient (`--diffraction-coefficient sionna-rt-2.2`), every
/// diffracted path that does not reflect after its diffraction has Sionna's gain within 0.1 dB,
/// except where Sionna diffracts on a screen (Florence's eaves: wall and roof are two meshes)
/// and we on the wedge the two faces make. Paths that reflect after the diffraction come out
/// 3-8 dB above Sionna's (cause not found yet: docs/channel.md §8), so issue 26's "90 % within
/// 3 dB" is not reached: 211 of 308 (68 %); the floor below keeps that from regressing.
#[test]
fn with_sionnas_coefficient_diffracted_gains_are_sionnas() {
    let d = compare_all(DiffractionCoefficient::SionnaRt22);
    assert!(d.missing.is_empty(), "missing: {:#?}", d.missing);
    let n = d.diffracted.len();
    assert!(n > 200, "{n}");
    let last: Vec<Diffracted> = (d.diffracted.iter().copied())
        .filter(|p| !p.reflected_after && !p.screen_there_wedge_here)
        .collect();
    eprintln!(
        "  diffraction last, not at an eave: {} of {} within 0.1 dB",
        within(&last, 0.1),
        last.len()
    );
    let after: Vec<Diffracted> = (d.diffracted.iter().copied())
        .filter(|p| p.reflected_after && !p.screen_there_wedge_here)
        .collect();
    eprintln!(
        "  reflecting after the diffraction, not at an eave: {} of {} within 3 dB",
        within(&after, 3.0),
        after.len()
    );
    assert!(last.len() >= 90 && within(&last, 0.1) == last.len());
    let close = within(&d.diffracted, 3.0);
    assert!(close >= 211, "{close} of {n} within 3 dB");
}
