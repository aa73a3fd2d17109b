//! Validation of a [`SceneDescription`] into a [`Scene`], collecting every problem at once.

use crate::description::{BOX_FACES, SceneDescription, SurfaceDesc};
use crate::frame::{to_local, to_world};
use crate::material::{DEFAULT_MATERIAL, Material, MaterialRuns, default_materials};
use crate::model::{Scene, scene_extent, surfaces_box};
use crate::problem::{Collector, Problem, ProblemSink, SceneError};
use crate::surface::{Pending, Place, RawSurface, Surface, SurfaceKind};
use bt_channel::RadioMaterial;
use bt_geom::polygon::MAX_VERTICES;
use bt_geom::{Bvh, Polygon, Real, Vec3};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::sync::Arc;

/// Default carrier frequency when a scene names none: 28 GHz (FR2 mmWave).
pub const DEFAULT_FREQUENCY_HZ: Real = 28e9;

/// Lowest carrier frequency accepted, Hz (1 kHz).
pub const MIN_FREQUENCY_HZ: Real = 1e3;

/// Highest carrier frequency accepted, Hz (1 PHz: beyond, Friis' 4π d f / c overflows for
/// long paths and geometric optics is all that is left anyway).
pub const MAX_FREQUENCY_HZ: Real = 1e15;

/// What is wrong with a carrier frequency, if anything: the one range check of scene files,
/// [`Scene::with_frequency`] and the CLI's `--frequency`, whatever the materials (a constant-loss
/// material needs no frequency, Friis does). The number prints compactly (`1e300`).
pub fn frequency_problem(frequency_hz: Real) -> Option<String> {
    let ok = (MIN_FREQUENCY_HZ..=MAX_FREQUENCY_HZ).contains(&frequency_hz);
    (!ok).then(|| {
        format!(
            "must be between {MIN_FREQUENCY_HZ:e} and {MAX_FREQUENCY_HZ:e} Hz (radio to optical; \
             outside, losses overflow), got {frequency_hz:e}"
        )
    })
}

/// Terminal positions given outside the description (CLI `--tx/--rx`, mesh import).
#[derive(Debug, Clone, Copy, Default)]
pub struct Terminals {
    /// Overrides the description's TX when set, metres.
    pub tx: Option<Vec3>,
    /// Overrides the description's RX when set, metres.
    pub rx: Option<Vec3>,
}

impl Scene {
    /// Validate a description. `source_name` names the file in messages; `terminals` override
    /// the file's TX/RX. A terminal given by neither stays absent (bare geometry, see
    /// [`Scene::terminals`]). Every problem is reported, not just the first.
    pub fn from_description(
        desc: &SceneDescription,
        source_name: &str,
        terminals: Terminals,
    ) -> Result<Scene, SceneError> {
        let surfaces = desc.surfaces.iter().cloned();
        Scene::described(desc, surfaces, source_name, terminals)
    }

    /// [`Scene::from_description`] of a description given up: its surfaces' names and
    /// vertex lists move into the scene instead of being copied (an importer's description of
    /// a city holds 17,803 of them).
    pub fn from_owned_description(
        mut desc: SceneDescription,
        source_name: &str,
        terminals: Terminals,
    ) -> Result<Scene, SceneError> {
        let surfaces = std::mem::take(&mut desc.surfaces);
        Scene::described(&desc, surfaces.into_iter(), source_name, terminals)
    }

    /// Validate `desc` whose surfaces are `surfaces` (its own, moved or copied).
    fn described(
        desc: &SceneDescription,
        surfaces: impl ExactSizeIterator<Item = SurfaceDesc>,
        source_name: &str,
        terminals: Terminals,
    ) -> Result<Scene, SceneError> {
        let mut problems = Collector(Vec::new());
        if let Some(name) = &desc.name
            && let Err(e) = crate::name::check(name)
        {
            problems.push("name", e);
        }
        let frequency_hz = desc.frequency_hz.unwrap_or(DEFAULT_FREQUENCY_HZ);
        let frequency_ok = match frequency_problem(frequency_hz) {
            Some(problem) => {
                problems.push("frequency_hz", problem);
                false
            }
            None => true,
        };
        let materials =
            described_materials(desc, frequency_ok.then_some(frequency_hz), &mut problems);
        let mut raw = raw_surfaces(desc, surfaces, &mut problems);
        let given = [
            terminals.tx.or(desc.tx.map(Vec3::from_array)),
            terminals.rx.or(desc.rx.map(Vec3::from_array)),
        ];
        let origin = crate::frame::recentre(&mut raw, given, &mut problems);
        let geometry = build_surfaces(raw, &materials, &mut problems);
        if frequency_ok {
            problems
                .0
                .extend(radio_problems(&geometry.surfaces, &materials, frequency_hz));
        }

        let tx = terminal("tx", given[0], &mut problems).map(|p| to_local(p, origin));
        let rx = terminal("rx", given[1], &mut problems).map(|p| to_local(p, origin));
        let extent = scene_extent(&geometry.surfaces, tx, rx);
        let placed = (geometry.surfaces.as_slice(), geometry.bvh.as_ref());
        if let Err(p) = check_terminals(placed, tx, rx, extent, origin) {
            problems.0.extend(p);
        }
        let name = desc.name.clone().unwrap_or_else(|| source_name.to_string());
        conclude(source_name, problems.0, || {
            Scene::assemble(name, origin, geometry, tx, rx, frequency_hz, materials)
        })
    }
}

impl Scene {
    /// Validate surfaces that an importer made (mesh faces, extracted planes) into a scene
    /// named `name`: every problem is collected (names, materials, polygons, terminals, radio
    /// models at `frequency_hz`) and reported under `source_name`. `raw` and `tx`/`rx` are in
    /// the world frame (metres); the scene is recentred like a scene file. A terminal not given
    /// stays absent (bare geometry, see [`Scene::terminals`]).
    pub fn from_surfaces(
        name: &str,
        source_name: &str,
        raw: Vec<RawSurface>,
        materials: BTreeMap<String, Material>,
        terminals: Terminals,
        frequency_hz: Real,
    ) -> Result<Scene, SceneError> {
        let mut raw: Vec<Pending> = raw.into_iter().map(Pending::from).collect();
        let mut problems = Collector(Vec::new());
        let given = [terminals.tx, terminals.rx];
        let origin = crate::frame::recentre(&mut raw, given, &mut problems);
        let geometry = build_surfaces(raw, &materials, &mut problems);
        let tx = terminal("tx", given[0], &mut problems).map(|p| to_local(p, origin));
        let rx = terminal("rx", given[1], &mut problems).map(|p| to_local(p, origin));
        let mut problems = problems.0;
        let extent = scene_extent(&geometry.surfaces, tx, rx);
        let placed = (geometry.surfaces.as_slice(), geometry.bvh.as_ref());
        if let Err(p) = check_terminals(placed, tx, rx, extent, origin) {
            problems.extend(p);
        }
        problems.extend(radio_problems(&geometry.surfaces, &materials, frequency_hz));
        let name = name.to_string();
        conclude(source_name, problems, || {
            Scene::assemble(name, origin, geometry, tx, rx, frequency_hz, materials)
        })
    }
}

/// Pairs `(i, j)`, `i < j`, of reflectors in one plane whose interiors overlap
/// ([`Polygon::overlaps_coplanar`] at `tol`, metres): a path reflecting there is found once per
/// surface. Only pairs whose boxes meet are compared, through `bvh`, the BVH over the
/// surfaces' polygons (the scene's: a city mesh has 20,000 surfaces, 200 million pairs), and
/// only pairs `wanted` by the caller (tested first: it is cheaper than the overlap).
pub(crate) fn coplanar_overlaps(
    surfaces: &[Surface],
    bvh: &Bvh,
    tol: Real,
    wanted: impl Fn(&Surface, &Surface) -> bool + Sync,
) -> Vec<(usize, usize)> {
    let polygons: Vec<&Polygon> = surfaces.iter().map(|s| &s.polygon).collect();
    let reflector = |i: usize| surfaces[i].kind == SurfaceKind::Reflector;
    // Each reflector's partners on all cores; sorted, so the same on any number of threads.
    let mut pairs: Vec<(usize, usize)> = (0..polygons.len())
        .into_par_iter()
        .filter(|&i| reflector(i))
        .flat_map_iter(|i| {
            let a = polygons[i];
            let (lo, hi) = a.bounds();
            let mut pairs = Vec::new();
            bvh.visit(
                |min, max| (lo - max).max_element() <= tol && (min - hi).max_element() <= tol,
                |j| {
                    let j = j as usize;
                    if j > i
                        && reflector(j)
                        && wanted(&surfaces[i], &surfaces[j])
                        && a.overlaps_coplanar(polygons[j], tol)
                    {
                        pairs.push((i, j));
                    }
                },
            );
            pairs
        })
        .collect();
    pairs.sort_unstable();
    pairs
}

/// The scene `assemble` builds when no problem was found, else every problem.
fn conclude(
    source_name: &str,
    problems: Vec<Problem>,
    assemble: impl FnOnce() -> Scene,
) -> Result<Scene, SceneError> {
    if problems.is_empty() {
        Ok(assemble())
    } else {
        Err(SceneError::Invalid {
            source_name: source_name.to_string(),
            problems,
        })
    }
}

/// The built-in materials and the description's own, checked (names, radio models at
/// `frequency_hz` when it is valid).
fn described_materials(
    desc: &SceneDescription,
    frequency_hz: Option<Real>,
    problems: &mut Collector,
) -> std::collections::BTreeMap<String, Material> {
    let mut materials = default_materials();
    for (name, m) in &desc.materials {
        if let Err(e) = crate::name::check(name) {
            problems.push("materials", e);
        }
        let location = format!("materials.{}", crate::name::shown(name));
        if let Some(material) = material_from_desc(&location, m, frequency_hz, &mut *problems) {
            materials.insert(name.clone(), material);
        }
    }
    materials
}

/// The description's surfaces (`surfaces`, in its order) and its boxes' faces, before any
/// geometric check.
fn raw_surfaces(
    desc: &SceneDescription,
    surfaces: impl ExactSizeIterator<Item = SurfaceDesc>,
    problems: &mut Collector,
) -> Vec<Pending> {
    let mut raw: Vec<Pending> = Vec::with_capacity(surfaces.len());
    for (i, s) in surfaces.enumerate() {
        raw.push(Pending {
            place: Place::Described(i),
            name: s.name,
            material: s.material,
            kind: s.kind.unwrap_or(SurfaceKind::Reflector),
            // In place: `[Real; 3]` and `Vec3` have one layout.
            vertices: s.vertices.into_iter().map(Vec3::from_array).collect(),
        });
    }
    for (i, b) in desc.boxes.iter().enumerate() {
        let location = format!("boxes[{i}] \"{}\"", crate::name::shown(&b.name));
        for o in &b.omit {
            if !BOX_FACES.iter().any(|(f, _, _)| f == o) {
                problems.push(
                    format!("{location}.omit"),
                    format!(
                        "unknown face \"{}\" (expected top, bottom, west, east, south or north)",
                        crate::name::shown(o)
                    ),
                );
            }
        }
        let (lo, hi) = (Vec3::from_array(b.min), Vec3::from_array(b.max));
        if !(lo.is_finite() && hi.is_finite()) || lo.cmpge(hi).any() {
            problems.push(
                location,
                "min must be finite and strictly below max on every axis",
            );
            continue;
        }
        for (face, axis, is_max) in BOX_FACES {
            if b.omit.iter().any(|o| o == face) {
                continue;
            }
            raw.push(Pending {
                place: Place::BoxFace(i, face),
                name: format!("{}.{face}", b.name),
                material: b.material.clone(),
                kind: b.kind.unwrap_or(SurfaceKind::Reflector),
                vertices: box_face(lo, hi, axis, is_max),
            });
        }
    }
    raw
}

impl Scene {
    /// Assemble an already validated scene (internal: loaders use it after their checks).
    /// `surfaces`, `tx` and `rx` are in the local frame whose origin is `origin` (world).
    pub(crate) fn assemble(
        name: String,
        origin: Vec3,
        geometry: impl Into<Geometry>,
        tx: Option<Vec3>,
        rx: Option<Vec3>,
        frequency_hz: Real,
        materials: std::collections::BTreeMap<String, Material>,
    ) -> Scene {
        let Geometry { surfaces, bvh } = geometry.into();
        let extent = scene_extent(&surfaces, tx, rx);
        // References, not clones: the BVH needs only the boxes, and copying 17,808 polygons
        // (vertices and local coordinates) was a third of a cached city load's allocations.
        let bvh = bvh.unwrap_or_else(|| {
            let polygons: Vec<&Polygon> = surfaces.iter().map(|s| &s.polygon).collect();
            Bvh::build(&polygons)
        });
        let mut scene = Scene {
            name,
            origin,
            surfaces: surfaces.into(),
            tx,
            rx,
            frequency_hz,
            materials: materials.into(),
            extent,
            bvh: bvh.into(),
            edges: Default::default(),
            penetration: Default::default(),
        };
        scene.penetration = crate::transmission::Penetration::of(&scene, false, usize::MAX);
        scene
    }
}

/// A material entry of a scene file, or `None` with its problems reported under `location`.
/// `frequency_hz` (when valid) derives a missing `reflection_loss_db` from the radio model.
fn material_from_desc(
    location: &str,
    m: &crate::description::MaterialDesc,
    frequency_hz: Option<Real>,
    problems: &mut impl ProblemSink,
) -> Option<Material> {
    let before = problems.count();
    if let Some(loss) = m.reflection_loss_db
        && !(loss.is_finite() && loss >= 0.0)
    {
        problems.report(
            &format!("{location}.reflection_loss_db"),
            "must be a finite number >= 0",
        );
    }
    let radio = match (&m.itu, m.relative_permittivity, m.conductivity) {
        (None, None, None) => {
            if m.thickness.is_some() {
                problems.report(
                    &format!("{location}.thickness"),
                    "needs a radio model: \"itu\" or \"relative_permittivity\" and \"conductivity\"",
                );
            }
            None
        }
        (Some(name), None, None) => RadioMaterial::itu(name, m.thickness)
            .map_err(|e| {
                problems.report(
                    &format!("{location}.{}", field_of(&e, "itu")),
                    e.to_string(),
                )
            })
            .ok(),
        (None, Some(eps), Some(sigma)) => RadioMaterial::custom(eps, sigma, m.thickness)
            .map_err(|e| {
                problems.report(
                    &format!("{location}.{}", field_of(&e, "relative_permittivity")),
                    e.to_string(),
                )
            })
            .ok(),
        (Some(_), _, _) => {
            problems.report(
                location,
                "give either \"itu\" or \"relative_permittivity\" with \"conductivity\", not both",
            );
            None
        }
        (None, eps, _) => {
            let missing = if eps.is_none() {
                "relative_permittivity"
            } else {
                "conductivity"
            };
            problems.report(
                &format!("{location}.{missing}"),
                "missing: a custom material needs both \"relative_permittivity\" and \"conductivity\"",
            );
            None
        }
    };
    if m.transmission == Some(true) && m.thickness.is_none() {
        problems.report(
            &format!("{location}.transmission"),
            "a half-space lets nothing through: give the material a \"thickness\" (metres) to \
             make it a slab waves can cross",
        );
    }
    let reflection_loss_db = match (m.reflection_loss_db, &radio, frequency_hz) {
        (Some(loss), _, _) => loss,
        (None, Some(r), Some(f)) => match r.normal_loss_db(f) {
            Ok(loss) => loss,
            Err(e) => {
                problems.report(location, e.to_string());
                0.0
            }
        },
        (None, Some(_), None) => 0.0,
        (None, None, _) => {
            if problems.count() == before {
                problems.report(
                    location,
                    "give \"reflection_loss_db\", a radio model (\"itu\" or \"relative_permittivity\" and \"conductivity\"), or both",
                );
            }
            0.0
        }
    };
    (problems.count() == before).then_some(Material {
        reflection_loss_db,
        radio,
        transmission: m.transmission.unwrap_or(false),
    })
}

/// The field a channel error names, or `default`.
fn field_of(e: &bt_channel::ChannelError, default: &'static str) -> &'static str {
    match e {
        bt_channel::ChannelError::Invalid { field, .. } => field,
        _ => default,
    }
}

/// Problems of the radio models of the materials `surfaces` use at `frequency_hz` (ITU
/// materials outside their validity range).
pub(crate) fn radio_problems(
    surfaces: &[Surface],
    materials: &std::collections::BTreeMap<String, Material>,
    frequency_hz: Real,
) -> Vec<Problem> {
    let mut used: BTreeSet<&str> = BTreeSet::new();
    let mut runs = MaterialRuns::new();
    for s in surfaces {
        runs.get(&s.material, |name| {
            used.insert(name);
        });
    }
    let mut problems = Vec::new();
    for name in used {
        if let Some(Some(radio)) = materials.get(name).map(|m| m.radio)
            && let Err(e) = radio.permittivity(frequency_hz)
        {
            problems.report(&format!("materials.{name}"), e.to_string());
        }
    }
    problems
}

pub(crate) fn build_surfaces(
    mut raw: Vec<Pending>,
    materials: &std::collections::BTreeMap<String, Material>,
    problems: &mut impl ProblemSink,
) -> Geometry {
    // Polygons over the per-surface limit are refused by their own check, before any work.
    let counts = raw.iter().map(|r| r.vertices.len());
    let pairs = bt_geom::polygon::vertex_pairs(counts.filter(|&n| n <= MAX_VERTICES));
    if pairs > bt_geom::polygon::MAX_VERTEX_PAIRS {
        problems.report(
            "surfaces",
            format!(
                "the polygons' simplicity tests would compare {} vertex pairs (the sum of each \
                 polygon's vertex count squared), more than the budget of {:e}: split the \
                 largest polygons",
                bt_geom::AtLeast(pairs),
                bt_geom::polygon::MAX_VERTEX_PAIRS as f64
            ),
        );
        return Vec::new().into();
    }
    // The polygons and their BVH are built on all cores while the names and materials are
    // checked beside them (the vertices are taken out first, so the two share nothing).
    let mut vertices: Vec<Vec<Vec3>> = (raw.iter_mut())
        .map(|r| std::mem::take(&mut r.vertices))
        .collect();
    let ((polygons, bvh), named) = rayon::join(
        || polygons_and_bvh(&mut vertices),
        || name_and_material_problems(&raw, materials),
    );
    // Each surface's problems in order: its name and material, then its polygon.
    let mut named = named.into_iter().peekable();
    for (i, (r, polygon)) in raw.iter().zip(&polygons).enumerate() {
        while let Some((_, location, message)) = named.next_if(|(at, _, _)| *at == i) {
            problems.report(&location, message);
        }
        if let Err(e) = polygon {
            problems.report(&format!("{}.vertices", r.location()), e.to_string());
        }
    }
    let all = polygons.iter().all(Result::is_ok);
    let surfaces = (raw.into_iter().zip(polygons))
        .filter_map(|(r, polygon)| {
            Some(Surface {
                polygon: polygon.ok()?,
                name: r.name,
                material: r.material.unwrap_or_else(|| DEFAULT_MATERIAL.to_string()),
                kind: r.kind,
            })
        })
        .collect();
    Geometry {
        surfaces,
        bvh: all.then_some(bvh),
    }
}

/// The problems of `raw`'s names (not printable, duplicated) and materials (not in
/// `materials`), each as (surface index, location, message), in surface order.
fn name_and_material_problems(
    raw: &[Pending],
    materials: &std::collections::BTreeMap<String, Material>,
) -> Vec<(usize, String, String)> {
    let mut found = Vec::new();
    let mut names = HashSet::with_capacity(raw.len());
    let mut known = MaterialRuns::new();
    for (i, r) in raw.iter().enumerate() {
        if let Err(e) = crate::name::check(&r.name) {
            found.push((i, r.location(), e));
        } else if !names.insert(r.name.as_str()) {
            let message = format!("duplicate surface name \"{}\"", crate::name::shown(&r.name));
            found.push((i, r.location(), message));
        }
        let material = r.material.as_deref().unwrap_or(DEFAULT_MATERIAL);
        if !known.get(material, |m| materials.contains_key(m)) {
            let message = format!(
                "unknown material \"{}\" (add it under \"materials\")",
                crate::name::shown(material)
            );
            found.push((i, r.location(), message));
        }
    }
    found
}

/// The polygons of `vertices` (each list taken) built on all cores, order kept, and beside
/// them the BVH over the vertices' boxes: the boxes [`Polygon::bounds`] gives, to the bit
/// ([`bt_geom::polygon::bounds`]), so it is the BVH of the polygons whenever all are built.
pub(crate) fn polygons_and_bvh<V: AsMut<Vec<Vec3>> + Send>(
    vertices: &mut [V],
) -> (Vec<Result<Polygon, bt_geom::PolygonError>>, Bvh) {
    let boxes: Vec<VertexBox> = (vertices.iter_mut())
        .map(|v| VertexBox(bt_geom::polygon::bounds(v.as_mut())))
        .collect();
    rayon::join(
        || {
            (vertices.par_iter_mut())
                .map(|v| Polygon::new(std::mem::take(v.as_mut())))
                .collect()
        },
        || Bvh::build(&boxes),
    )
}

/// A box `(min, max)` of vertices, metres, as a BVH item.
struct VertexBox((Vec3, Vec3));

impl bt_geom::Occluder for VertexBox {
    fn bounds(&self) -> (Vec3, Vec3) {
        self.0
    }
}

impl AsMut<Vec<Vec3>> for Pending {
    fn as_mut(&mut self) -> &mut Vec<Vec3> {
        &mut self.vertices
    }
}

/// Validated surfaces, and the BVH over their polygons when it is built already.
pub(crate) struct Geometry {
    /// The surfaces in order.
    pub surfaces: Vec<Surface>,
    /// The BVH of `surfaces`' polygons, if built.
    pub bvh: Option<Bvh>,
}

impl From<Vec<Surface>> for Geometry {
    fn from(surfaces: Vec<Surface>) -> Geometry {
        Geometry {
            surfaces,
            bvh: None,
        }
    }
}

/// A terminal given (world frame) when finite; not given is no problem (bare geometry).
fn terminal(field: &str, value: Option<Vec3>, problems: &mut Collector) -> Option<Vec3> {
    match value {
        Some(p) if !p.is_finite() => {
            problems.push(field, "coordinates must be finite numbers");
            None
        }
        value => value,
    }
}

/// TX and RX, where given, must be finite, resolvable and off every surface, and distinct when
/// both are. Surfaces and terminals are in the local frame whose origin is `origin` (world):
/// the resolution check looks at the world coordinates. The BVH beside the surfaces, when
/// given, must be that of their polygons: it answers the box and on-surface tests without a
/// pass over every surface (a sweep places thousands of receivers), with the same answers.
pub(crate) fn check_terminals(
    (surfaces, bvh): (&[Surface], Option<&Bvh>),
    tx: Option<Vec3>,
    rx: Option<Vec3>,
    extent: Real,
    origin: Vec3,
) -> Result<(), Vec<Problem>> {
    let mut problems = Vec::new();
    let eps = crate::frame::scene_tolerance(extent);
    let given: Vec<(&str, Vec3)> = [("tx", tx), ("rx", rx)]
        .into_iter()
        .filter_map(|(field, p)| Some((field, p?)))
        .collect();
    for &(field, p) in &given {
        if !p.is_finite() {
            problems.report(field, "coordinates must be finite numbers");
        }
    }
    for &(field, p) in &given {
        let magnitude = to_world(p, origin).abs().max_element();
        if let Some(why) = crate::frame::unresolvable(magnitude, eps) {
            problems.report(field, why);
        }
    }
    far_terminals(surfaces_box(surfaces, bvh), &given, &mut problems);
    if !problems.is_empty() {
        // A far or unresolvable terminal scales the tolerance: the tests below would blame
        // the other terminal.
        return Err(problems);
    }
    if let (true, Some(tx), Some(rx)) = (problems.is_empty(), tx, rx)
        && tx.distance(rx) <= eps
    {
        problems.report("tx", "tx and rx are at the same position");
    }
    for &(field, p) in &given {
        for s in near(surfaces, bvh, p, eps) {
            if s.polygon.plane().signed_distance(p).abs() <= eps && s.polygon.contains(p, eps) {
                problems.report(
                    field,
                    format!("lies on surface \"{}\"", crate::name::shown(&s.name)),
                );
            }
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems)
    }
}

/// The surfaces, in order, that may hold points within `eps` of `p`: every one, or with the
/// BVH of their polygons those whose box reaches the cube of half-side `4 eps` around `p`
/// (a point within `eps` of a polygon's plane and of its outline lies within `1.5 eps` of its
/// box on every axis; the rest is slack for rounding).
fn near<'a>(
    surfaces: &'a [Surface],
    bvh: Option<&Bvh>,
    p: Vec3,
    eps: Real,
) -> Box<dyn Iterator<Item = &'a Surface> + 'a> {
    let Some(bvh) = bvh else {
        return Box::new(surfaces.iter());
    };
    let mut ids = Vec::new();
    bvh.visit_near(p, 4.0 * eps, |i| ids.push(i as usize));
    ids.sort_unstable();
    Box::new(ids.into_iter().map(|i| &surfaces[i]))
}

/// A terminal may lie at most this many extents of the surfaces (of at least 1 m) from their
/// bounding box: beyond it, the length tolerance, which scales with the extent of surfaces and
/// terminals together, would grow past the size of the scene's details.
pub const MAX_TERMINAL_DISTANCE_RATIO: Real = 10_000.0;

/// Report each given terminal farther from the surfaces (whose box is `surfaces`) than
/// [`MAX_TERMINAL_DISTANCE_RATIO`] extents, naming it (not the other terminal, whose checks the inflated tolerance would fail).
fn far_terminals(
    surfaces: Option<(Vec3, Vec3)>,
    given: &[(&str, Vec3)],
    problems: &mut Vec<Problem>,
) {
    let Some((lo, hi)) = surfaces else {
        return;
    };
    let limit = MAX_TERMINAL_DISTANCE_RATIO * (hi - lo).length().max(1.0);
    for &(field, p) in given {
        let distance = (p - p.clamp(lo, hi)).length();
        if p.is_finite() && distance > limit {
            problems.report(
                field,
                format!(
                    "lies {distance:.3e} m from the scene's surfaces, beyond {MAX_TERMINAL_DISTANCE_RATIO} \
                     times their extent ({limit:.3e} m): move it nearer"
                ),
            );
        }
    }
}

/// Rectangle of a box face, counter-clockwise seen from outside the box.
fn box_face(lo: Vec3, hi: Vec3, axis: usize, is_max: bool) -> Vec<Vec3> {
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let c = if is_max { hi[axis] } else { lo[axis] };
    let corner = |u: Real, v: Real| {
        let mut p = Vec3::ZERO;
        p[axis] = c;
        p[a] = u;
        p[b] = v;
        p
    };
    let mut face = vec![
        corner(lo[a], lo[b]),
        corner(hi[a], lo[b]),
        corner(hi[a], hi[b]),
        corner(lo[a], hi[b]),
    ];
    if !is_max {
        face.reverse();
    }
    face
}

impl Scene {
    /// A copy with other TX/RX positions (metres, world frame, like the scene file's),
    /// validated like the originals; on a bare scene this places its terminals.
    ///
    /// The copy keeps the local frame ([`Scene::origin`]); its extent, and with it
    /// [`Scene::length_tolerance`] and every tolerance scaled from it, is recomputed from the
    /// surfaces and the new terminals. So a bare scene plus terminals has the extent and
    /// tolerances of the same file loaded with those terminals, and traces the same, whenever
    /// the origin agrees: always for scenes near the world origin (origin zero). A far scene
    /// (recentred) keeps the origin chosen from its surfaces alone, which terminals outside
    /// the geometry could have moved at load time.
    pub fn with_terminals(&self, tx: Vec3, rx: Vec3) -> Result<Scene, crate::SceneError> {
        let (tx, rx) = (self.to_local(tx), self.to_local(rx));
        let extent = self.extent_with(tx, rx);
        let placed = (self.surfaces.as_slice(), Some(self.bvh.as_ref()));
        check_terminals(placed, Some(tx), Some(rx), extent, self.origin).map_err(|problems| {
            crate::SceneError::Invalid {
                source_name: self.name.clone(),
                problems,
            }
        })?;
        let mut scene = self.clone();
        scene.tx = Some(tx);
        scene.rx = Some(rx);
        scene.extent = extent;
        Ok(scene)
    }

    /// A copy with another RX (metres, world frame) and the scene's TX: the receiver of a
    /// sweep grid point. A scene without a TX refuses ([`SceneError::MissingTerminal`]).
    pub fn with_receiver(&self, rx: Vec3) -> Result<Scene, crate::SceneError> {
        let Some(tx) = self.tx_world() else {
            return Err(SceneError::MissingTerminal {
                source_name: self.name.clone(),
                missing: vec![crate::Terminal::Tx],
            });
        };
        self.with_terminals(tx, rx)
    }

    /// A copy at another carrier frequency (Hz), checked against the radio models of the
    /// materials in use (ITU validity ranges).
    pub fn with_frequency(&self, frequency_hz: Real) -> Result<Scene, crate::SceneError> {
        let mut problems = Vec::new();
        if let Some(message) = frequency_problem(frequency_hz) {
            problems.push(crate::Problem {
                location: "frequency_hz".into(),
                message,
            });
        } else {
            problems = radio_problems(&self.surfaces, &self.materials, frequency_hz);
        }
        if !problems.is_empty() {
            return Err(crate::SceneError::Invalid {
                source_name: self.name.clone(),
                problems,
            });
        }
        let mut scene = self.clone();
        scene.frequency_hz = frequency_hz;
        Ok(scene)
    }

    /// A copy in which every material has the radio model `radio` (CLI `--material`), checked
    /// at the scene's frequency. The constant `reflection_loss_db` of each material stays.
    pub fn with_radio_material(
        &self,
        radio: bt_channel::RadioMaterial,
    ) -> Result<Scene, crate::SceneError> {
        self.with_radio_models(|_| Ok(Some(radio)))
    }

    /// A copy in which every material whose radio model is a half-space (no thickness)
    /// is a slab of `thickness` metres instead (CLI `--thickness` without `--material`, so
    /// that `--transmission` can cross it; a finite number ≥ 0), checked at the scene's
    /// frequency. Slabs keep their own thickness; materials without a radio model (a
    /// constant `reflection_loss_db` alone) stay as they are.
    pub fn with_half_spaces_as_slabs(&self, thickness: Real) -> Result<Scene, crate::SceneError> {
        let invalid = |e: bt_channel::ChannelError| crate::SceneError::Invalid {
            source_name: self.name.clone(),
            problems: vec![Problem {
                location: "--thickness".into(),
                message: e.to_string(),
            }],
        };
        self.with_radio_models(|radio| match radio {
            Some(r) if r.thickness.is_none() => {
                r.with_thickness(thickness).map(Some).map_err(invalid)
            }
            other => Ok(other),
        })
    }

    /// A copy in which each material's radio model is `f` of its own, checked at the scene's
    /// frequency, with the penetrable surfaces they give.
    fn with_radio_models(
        &self,
        f: impl Fn(
            Option<bt_channel::RadioMaterial>,
        ) -> Result<Option<bt_channel::RadioMaterial>, crate::SceneError>,
    ) -> Result<Scene, crate::SceneError> {
        let mut scene = self.clone();
        for m in Arc::make_mut(&mut scene.materials).values_mut() {
            m.radio = f(m.radio)?;
        }
        // Which surfaces waves cross depends on the materials: a new mask, and with it a new
        // `geometry_key` when there are penetrable surfaces.
        scene.penetration = crate::transmission::Penetration::of(
            &scene,
            self.transmission_everywhere(),
            self.max_interactions(),
        );
        let problems = radio_problems(&scene.surfaces, &scene.materials, scene.frequency_hz);
        if !problems.is_empty() {
            return Err(crate::SceneError::Invalid {
                source_name: self.name.clone(),
                problems,
            });
        }
        Ok(scene)
    }
}
