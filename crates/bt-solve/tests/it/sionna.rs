//! Against Sionna RT 2.2 with first-order diffraction (`testdata/sionna-reference`, written by
//! `tools/sionna_reference.py` from Sionna's own scenes in `testdata/scenes/sionna-rt`):
//! every path Sionna found is found here, with its interaction kinds in order and its points
//! within 1 cm; specular gains agree within 0.05 dB; diffracted gains are compared and their
//! spread reported (Sionna 2.2's coefficient is not Kouyoumjian–Pathak's:
//! docs/sionna-diffraction-notes.md, docs/channel.md §8); with Sionna's coefficient and
//! Sionna's diffracted leg (`bt_channel::path_gain_sionna_rt22`), every diffracted gain where
//! Sionna's wedge is ours is Sionna's within 0.1 dB. With Sionna's refraction (its thin slab),
//! every path it finds through walls is one of ours under `--transmission`, with its gain. On
//! a scene of Mitsuba's rectangle and cube (ours, loaded by Sionna through Mitsuba), every
//! specular path is ours with its gain.

use bt_beams::{InteractionKind, PathReport, RadioOptions};
use bt_channel::DiffractionCoefficient;
use bt_geom::{Real, Vec3};
use bt_scene::Terminals;
use bt_solve::pipeline::{DiffractionOptions, TraceOptions};
use bt_solve::{FoundPath, Tracer};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The reference cases (one file each).
const CASES: [&str; 8] = [
    "one-screen-d2",
    "two-screens-d2",
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
        "refraction" => InteractionKind::Transmission,
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
fn matching<'a, T>(
    ours: &'a [(PathReport, T)],
    e: &Expected,
    tolerance: Real,
) -> Option<&'a (PathReport, T)> {
    ours.iter().find(|(p, _)| {
        p.interactions == e.kinds
            && p.points
                .iter()
                .zip(&e.vertices)
                .all(|(a, b)| Vec3::from(*a).distance(*b) <= tolerance)
    })
}

/// How our gains are taken: from the report with a coefficient, as the CLI and Python give
/// them (the trace's order as Sionna's `max_depth`: with `sionna-rt-2.2` Sionna's diffracted
/// leg, which grows for paths that reflect after the edge and are shorter than `max_depth`),
/// or with `sionna-rt-2.2` and UTD's unfolded leg (`RadioOptions::sionna_max_depth` unset).
#[derive(Clone, Copy)]
enum Gains {
    Report(DiffractionCoefficient),
    UnfoldedLeg,
}

impl Gains {
    fn name(self) -> String {
        match self {
            Gains::Report(c) => c.to_string(),
            Gains::UnfoldedLeg => "sionna-rt-2.2 with the unfolded leg".into(),
        }
    }

    /// The report's radio options for a case traced to `max_depth`.
    fn radio(self, max_depth: usize) -> RadioOptions {
        match self {
            Gains::Report(c) => RadioOptions {
                diffraction_coefficient: c,
                ..RadioOptions::default()
            }
            .for_order(max_depth),
            Gains::UnfoldedLeg => RadioOptions {
                diffraction_coefficient: DiffractionCoefficient::SionnaRt22,
                ..RadioOptions::default()
            },
        }
    }
}

/// One diffracted path found in both: ours − Sionna's gain (dB), and whether Sionna's wedge is
/// another than ours (docs/channel.md §8). Sionna diffracts on the edges of one mesh at a time;
/// our edges are made of the faces around them, whichever mesh they come from. Where our wedge
/// has faces of two meshes, Sionna's is a different one: at Florence's eaves a screen (the
/// wall's or the roof's free edge, n = 2) where ours is the wedge wall and roof make
/// (n ≈ 1.5); where two buildings' walls meet almost flush at a corner, each building's own
/// corner (n ≈ 1.5) where ours is the nearly flat junction of the two walls (n ≈ 1.01).
#[derive(Clone)]
struct Diffracted {
    /// Case, receiver, interaction kinds and Sionna's gain, for messages.
    what: String,
    diff_db: Real,
    other_wedge_there: bool,
    /// The path reflects after its diffraction and has fewer interactions than the case's
    /// `max_depth`: Sionna lengthens its diffracted leg (`bt_channel::sionna`).
    leg_grown_by_sionna: bool,
}

/// Sionna's diffraction of `path` is on a free edge of a mesh (a screen).
fn screen_there(path: &Value) -> bool {
    let edges = path["edges"].as_array().unwrap();
    edges.iter().any(|e| e["free"] == true)
}

/// The mesh a surface of ours comes from: its name without the `.face_k` bt-import appends.
fn mesh_of(scene: &bt_scene::Scene, id: bt_scene::SurfaceId) -> &str {
    let name = scene.surface(id).name.as_str();
    name.rsplit_once(".face").map_or(name, |(mesh, _)| mesh)
}

/// Sionna's wedge for `path` is another than our `edge`: a screen where ours is a wedge, or
/// ours has faces of two meshes (see [`Diffracted`]).
fn other_wedge_there(scene: &bt_scene::Scene, path: &Value, edge: &bt_scene::Edge) -> bool {
    let two_meshes = !edge.is_free() && mesh_of(scene, edge.face0) != mesh_of(scene, edge.face_n);
    (screen_there(path) && !edge.is_free()) || two_meshes
}

/// Gain differences (ours − Sionna's, dB) of the specular and the diffracted paths.
#[derive(Default)]
struct Differences {
    specular: Vec<Real>,
    diffracted: Vec<Diffracted>,
    missing: Vec<String>,
    /// Sionna paths diffracting where our scene has no edge.
    no_edge: Vec<String>,
    /// Sionna paths reflecting on their diffracting wedge's own face ([`Explained::OwnFace`]).
    own_face: Vec<String>,
    /// Sionna paths ours has with a point over 1 cm away ([`Explained::IllConditioned`]).
    ill_conditioned: Vec<String>,
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

/// Our paths from `tx` to `rx` (world frame), each described with `radio`, and the scene
/// with those terminals.
fn described(
    tracer: &mut Tracer,
    (tx, rx): (Vec3, Vec3),
    radio: &RadioOptions,
) -> (bt_scene::Scene, Vec<(PathReport, FoundPath)>) {
    let traced = tracer.trace(tx, rx).unwrap();
    let scene = tracer.scene().with_terminals(tx, rx).unwrap();
    let ours = (traced.result.paths.into_iter())
        .map(|p| (bt_beams::describe(&scene, &p, radio).unwrap(), p))
        .collect();
    (scene, ours)
}

fn compare_case(case: &str, gains: Gains, out: &mut Differences) {
    let (doc, scene) = reference(case);
    let max_depth = doc["max_depth"].as_u64().unwrap() as usize;
    let trace = TraceOptions {
        diffraction: DiffractionOptions::first_order(),
        ..TraceOptions::new(max_depth)
    };
    let radio = gains.radio(max_depth);
    let mut tracer = Tracer::new(scene, trace);
    let tx = vec3(&doc["tx"]["position"]);
    for receiver in doc["receivers"].as_array().unwrap() {
        let rx = vec3(&receiver["position"]);
        let (scene, ours) = described(&mut tracer, (tx, rx), &radio);
        for path in receiver["paths"].as_array().unwrap() {
            let e = expected(path);
            match matching(&ours, &e, 0.01) {
                Some((p, _)) => {
                    let gain_db = p.gain_db.unwrap();
                    let diff_db = gain_db - e.gain_db;
                    match p.diffractions.first().copied() {
                        Some(d) => {
                            let reflected_after = d.index + 1 < p.points.len();
                            out.diffracted.push(Diffracted {
                                what: format!(
                                    "{case} {}: {:?}, Sionna {:.2} dB on {}, ours on {} (n {:.3})",
                                    receiver["name"],
                                    e.kinds,
                                    e.gain_db,
                                    path["shapes"][d.index],
                                    p.surfaces[d.index],
                                    scene.edges().get(d.edge).n
                                ),
                                diff_db,
                                other_wedge_there: other_wedge_there(
                                    &scene,
                                    path,
                                    scene.edges().get(d.edge),
                                ),
                                leg_grown_by_sionna: reflected_after && p.points.len() < max_depth,
                            })
                        }
                        None => out.specular.push(diff_db),
                    }
                }
                None => {
                    let what = format!("{case} rx {rx}: {:?} at {:?}", e.kinds, e.vertices);
                    match explained(tracer.scene(), &ours, &e, (tx, rx)) {
                        Some(Explained::NoEdge) => out.no_edge.push(what),
                        Some(Explained::OwnFace) => out.own_face.push(what),
                        Some(Explained::IllConditioned) => out.ill_conditioned.push(what),
                        None => out.missing.push(what),
                    }
                }
            }
        }
    }
}

/// Why a Sionna path has no match of ours within 1 cm, when it is not missing.
enum Explained {
    /// Sionna diffracts on a junction our scene has no edge at (Sionna diffracts on every mesh
    /// boundary, e.g. a wall's foot on the ground, a concave junction: docs/channel.md §8).
    NoEdge,
    /// Next to its diffraction the path reflects on a face of the wedge it diffracts on: the
    /// segment between them lies in that face's plane, grazing by our rule
    /// (`bt_solve::diffraction`: UTD's coefficient already holds the face's reflection).
    OwnFace,
    /// Ours has the path (the same kinds, its length within 1 mm: a stationary length), but
    /// some point lies more than 1 cm away (within 0.5 m): a grazing reflection or a ray
    /// nearly along the edge, where Sionna's float32 geometry moves the point along its surface
    /// or edge far more than the length changes.
    IllConditioned,
}

/// Why Sionna's path `e` from `tx` to `rx` (world frame) has no match in `ours` (see
/// [`Explained`]), or `None` when it is missing.
fn explained(
    scene: &bt_scene::Scene,
    ours: &[(PathReport, FoundPath)],
    e: &Expected,
    (tx, rx): (Vec3, Vec3),
) -> Option<Explained> {
    let length = |points: &mut dyn Iterator<Item = Vec3>| {
        let all: Vec<Vec3> = std::iter::once(tx).chain(points).chain([rx]).collect();
        all.windows(2).map(|w| w[0].distance(w[1])).sum::<Real>()
    };
    let sionna = length(&mut e.vertices.iter().copied());
    let same_length = |p: &PathReport| {
        (length(&mut p.points.iter().map(|&q| Vec3::from(q))) - sionna).abs() <= 1e-3
    };
    if matching(ours, e, 0.5).is_some_and(|(p, _)| same_length(p)) {
        return Some(Explained::IllConditioned);
    }
    let k = e
        .kinds
        .iter()
        .position(|k| *k == InteractionKind::Diffraction)?;
    let local = |p: Vec3| scene.to_local(p);
    let d = local(e.vertices[k]);
    let edge = scene.edges().all().iter().find(|edge| {
        let t = edge.parameter(d).clamp(0.0, edge.length);
        edge.point(t).distance(d) <= 0.01
    });
    let Some(edge) = edge else {
        return Some(Explained::NoEdge);
    };
    let neighbours = [k.checked_sub(1), Some(k + 1)];
    let reflections = neighbours
        .into_iter()
        .flatten()
        .filter(|&j| e.kinds.get(j) == Some(&InteractionKind::Reflection));
    let on_a_face = |p: Vec3| {
        (edge.touching.iter())
            .any(|f| scene.surface(*f).polygon.plane().signed_distance(p).abs() <= 0.01)
    };
    reflections
        .into_iter()
        .any(|j| on_a_face(local(e.vertices[j])))
        .then_some(Explained::OwnFace)
}

/// How many of `paths` lie within `db` of Sionna's gain.
fn within(paths: &[Diffracted], db: Real) -> usize {
    paths.iter().filter(|p| p.diff_db.abs() <= db).count()
}

/// Compare every case with our gains taken as `gains` says, printing per case how many
/// diffracted gains lie within 0.1, 1, 3 and 6 dB of Sionna's (and of those on Sionna's
/// screens that are our wedges, how many within 3 dB).
fn compare_all(gains: Gains) -> Differences {
    let mut d = Differences::default();
    eprintln!(
        "{}: diffracted gains within 0.1 / 1 / 3 / 6 dB of Sionna's",
        gains.name()
    );
    for case in CASES {
        let before = d.diffracted.len();
        compare_case(case, gains, &mut d);
        let mine = &d.diffracted[before..];
        let other: Vec<Diffracted> = (mine.iter())
            .filter(|p| p.other_wedge_there)
            .cloned()
            .collect();
        eprintln!(
            "  {case:17} {:3} paths: {:3} {:3} {:3} {:3}; mean diff {:6.2} dB, worst {:6.2}; \
             Sionna's wedge another: {} ({} within 3 dB)",
            mine.len(),
            within(mine, 0.1),
            within(mine, 1.0),
            within(mine, 3.0),
            within(mine, 6.0),
            mine.iter().map(|p| p.diff_db).sum::<Real>() / mine.len().max(1) as Real,
            mine.iter().fold(0.0, |a: Real, p| a.max(p.diff_db.abs())),
            other.len(),
            within(&other, 3.0),
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
    let d = compare_all(Gains::Report(DiffractionCoefficient::Utd));
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

/// The street canyon with parked cars (`canyon-cars-d2`, a Sionna scene first traced in this
/// test, order 2): every Sionna path is ours, specular gains within 0.05 dB, and with Sionna's
/// coefficient its 150 diffracted gains within 1 dB, all but one within 0.1 dB (rx2's
/// reflection then diffraction on car_3's bottom edge, 0.24 dB: Sionna's reflection vertex
/// lies 3.4 mm from the specular point of its own edge point, on a path grazing the car's
/// underside; docs/channel.md). Apart from `CASES` so that the others keep their 0.1 dB bound.
#[test]
fn in_the_canyon_with_cars_every_sionna_path_is_found() {
    let mut d = Differences::default();
    compare_case(
        "canyon-cars-d2",
        Gains::Report(DiffractionCoefficient::SionnaRt22),
        &mut d,
    );
    assert!(d.missing.is_empty(), "missing: {:#?}", d.missing);
    assert!(
        d.specular.iter().all(|x| x.abs() <= 0.05),
        "{:?}",
        d.specular
    );
    let all = &d.diffracted;
    assert!(all.len() >= 150, "{}", all.len());
    assert!(
        within(all, 1.0) == all.len(),
        "{} of {}",
        within(all, 1.0),
        all.len()
    );
    assert!(
        within(all, 0.1) + 1 >= all.len(),
        "{} of {}",
        within(all, 0.1),
        all.len()
    );
}

/// Munich (Sionna RT's 40k-triangle city), TX 1 m above a roof, three street receivers,
/// order 3: every Sionna path is ours or explained ([`Explained`]), specular gains within
/// 0.05 dB. Apart from the other cases: its diffracted gains are not held to the others'
/// statistics (most of its wedges join two meshes, where Sionna's wedge is another).
#[test]
fn in_munich_every_sionna_path_is_found() {
    let mut d = Differences::default();
    compare_case(
        "munich-roof-d3",
        Gains::Report(DiffractionCoefficient::Utd),
        &mut d,
    );
    let all = &d.diffracted;
    eprintln!(
        "munich-roof-d3: {} specular, {} diffracted ({} {} {} {} within 0.1 / 1 / 3 / 6 dB), \
         {} missing, {} without an edge here, {} on their wedge's own face, {} ill-conditioned: \
         {:#?}",
        d.specular.len(),
        all.len(),
        within(all, 0.1),
        within(all, 1.0),
        within(all, 3.0),
        within(all, 6.0),
        d.missing.len(),
        d.no_edge.len(),
        d.own_face.len(),
        d.ill_conditioned.len(),
        (&d.own_face, &d.ill_conditioned)
    );
    assert!(d.missing.is_empty(), "missing: {:#?}", d.missing);
    assert!(
        d.specular.iter().all(|x| x.abs() <= 0.05),
        "{:?}",
        d.specular
    );
    assert!(all.len() > 400, "{}", all.len());
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

/// Diffracted paths where Sionna's wedge is ours, split by whether Sionna lengthens their
/// diffracted leg: (not lengthened, lengthened).
fn split_by_leg(d: &Differences) -> (Vec<Diffracted>, Vec<Diffracted>) {
    (d.diffracted.iter())
        .filter(|p| !p.other_wedge_there)
        .cloned()
        .partition(|p| !p.leg_grown_by_sionna)
}

/// With Sionna RT 2.2's own coefficient (`--diffraction-coefficient sionna-rt-2.2`, the
/// report's gain, the trace's order as Sionna's `max_depth`), every diffracted gain where
/// Sionna's wedge is ours is Sionna's within 0.1 dB, the paths whose leg Sionna lengthens
/// included (`bt_channel::path_gain_sionna_rt22`); with Sionna's other wedges ([`Diffracted`]:
/// Florence's eaves and two buildings' flush corners), 281 of 308 (91 %) are within 3 dB.
#[test]
fn with_sionnas_coefficient_diffracted_gains_are_sionnas() {
    let d = compare_all(Gains::Report(DiffractionCoefficient::SionnaRt22));
    assert!(d.missing.is_empty(), "missing: {:#?}", d.missing);
    let (plain, grown) = split_by_leg(&d);
    eprintln!(
        "  Sionna's wedge ours: {} of {} within 0.1 dB ({} of {} with the leg grown by Sionna)",
        within(&plain, 0.1) + within(&grown, 0.1),
        plain.len() + grown.len(),
        within(&grown, 0.1),
        grown.len()
    );
    let off: Vec<String> = (plain.iter().chain(&grown))
        .filter(|p| p.diff_db.abs() > 0.1)
        .map(|p| format!("{} (ours {:+.2} dB)", p.what, p.diff_db))
        .collect();
    eprintln!("  Sionna's wedge ours, off by more than 0.1 dB: {off:#?}");
    assert!(grown.len() >= 60 && within(&grown, 0.1) == grown.len());
    assert!(plain.len() >= 190 && within(&plain, 0.1) == plain.len());
    // Issue 26's "90 % within 3 dB", Sionna's other wedges included.
    let (close, n) = (within(&d.diffracted, 3.0), d.diffracted.len());
    assert!(n > 300 && 10 * close >= 9 * n, "{close} of {n} within 3 dB");
}

/// With Sionna's coefficient but UTD's unfolded diffracted leg (the library's
/// `sionna-rt-2.2` without `sionna_max_depth`), the paths whose leg Sionna lengthens (those
/// that reflect after the edge and have fewer interactions than `max_depth`: here
/// [diffraction, reflection] at depth 3) come out 2-9 dB above Sionna's, none within 1 dB,
/// and the others stay within 0.1 dB: the whole difference is Sionna's leg
/// (`bt_channel::sionna`, docs/channel.md "Reflections after the edge in Sionna RT 2.2").
#[test]
fn with_the_unfolded_leg_only_paths_reflecting_after_the_edge_differ() {
    let d = compare_all(Gains::UnfoldedLeg);
    assert!(d.missing.is_empty(), "missing: {:#?}", d.missing);
    let (plain, grown) = split_by_leg(&d);
    eprintln!(
        "  unfolded leg, Sionna's wedge ours: {} of {} within 0.1 dB; \
         leg grown by Sionna: {} of {} within 3 dB",
        within(&plain, 0.1),
        plain.len(),
        within(&grown, 3.0),
        grown.len()
    );
    assert!(plain.len() >= 190 && within(&plain, 0.1) == plain.len());
    assert!(grown.len() >= 60 && within(&grown, 1.0) == 0);
    assert!(grown.iter().all(|p| p.diff_db > 2.0 && p.diff_db < 9.0));
}

/// What [`sionnas_paths_are_ours`] counted: Sionna's paths, those through a surface, ours, and
/// the largest gain difference (dB).
struct Tally {
    theirs: usize,
    crossing: usize,
    ours: usize,
    worst_db: Real,
}

/// Every path Sionna finds in reference `case` (specular, no diffraction) is one of ours
/// traced with `trace` (same kinds in order, points within 1 cm), with its gain within
/// 0.05 dB.
fn sionnas_paths_are_ours(case: &str, trace: impl Fn(usize) -> TraceOptions) -> Tally {
    let (doc, scene) = reference(case);
    let max_depth = doc["max_depth"].as_u64().unwrap() as usize;
    let radio = RadioOptions::default().for_order(max_depth);
    let mut tracer = Tracer::new(scene, trace(max_depth));
    let tx = vec3(&doc["tx"]["position"]);
    let mut tally = Tally {
        theirs: 0,
        crossing: 0,
        ours: 0,
        worst_db: 0.0,
    };
    for receiver in doc["receivers"].as_array().unwrap() {
        let rx = vec3(&receiver["position"]);
        let (_, ours) = described(&mut tracer, (tx, rx), &radio);
        let theirs = receiver["paths"].as_array().unwrap();
        for path in theirs {
            let e = expected(path);
            let Some((p, _)) = matching(&ours, &e, 0.01) else {
                panic!(
                    "{case} rx {rx}: Sionna's {:?} at {:?} not found",
                    e.kinds, e.vertices
                );
            };
            let diff = p.gain_db.unwrap() - e.gain_db;
            tally.crossing += usize::from(e.kinds.contains(&InteractionKind::Transmission));
            tally.worst_db = tally.worst_db.max(diff.abs());
            assert!(
                diff.abs() <= 0.05,
                "{case} rx {rx}: {:?} ours {:.4} dB, Sionna {:.4} dB",
                e.kinds,
                p.gain_db.unwrap(),
                e.gain_db
            );
        }
        tally.ours += ours.len();
        tally.theirs += theirs.len();
    }
    eprintln!(
        "{case}: Sionna {} paths ({} through walls), ours {}; worst gain difference {:.4} dB",
        tally.theirs, tally.crossing, tally.ours, tally.worst_db
    );
    tally
}

/// Sionna RT's refraction on the street canyon (`canyon-refraction-d2`: every material an ITU
/// slab 0.1 m thick, no diffraction, `max_depth` 2): every path Sionna finds, through walls or
/// not, is one of ours traced with transmission, with its gain within 0.05 dB; and we find at
/// least as many (Sionna samples its rays).
#[test]
fn sionnas_refracted_paths_are_ours_with_their_gains() {
    let tally = sionnas_paths_are_ours("canyon-refraction-d2", |max_depth| TraceOptions {
        transmission: true,
        ..TraceOptions::new(max_depth)
    });
    assert!(tally.crossing > 0 && tally.ours >= tally.theirs);
}

/// Mitsuba's rectangle and cube as Sionna loads them through Mitsuba (`primitives-d2`, our
/// scene `testdata/scenes/mitsuba-primitives.xml`): Sionna's specular paths are ours, gains
/// within 0.05 dB, so the primitives' extents and transforms are Mitsuba's.
#[test]
fn sionnas_paths_off_mitsubas_rectangle_and_cube_are_ours() {
    let tally = sionnas_paths_are_ours("primitives-d2", TraceOptions::new);
    assert!(
        tally.theirs >= 8 && tally.ours >= tally.theirs,
        "{}",
        tally.theirs
    );
}
