//! Dynamic scenes: a scene over discrete time steps, with named objects (groups of surfaces and
//! boxes) that translate and rotate, as in the paper's Figs. 2, 11 and 14-15 (a person walking,
//! a door opening). Format documented in `docs/dynamic-scenes.md`.
//!
//! The pose of an object at step `k` is a rotation by `angle_k` (degrees, right-hand rule) about
//! `axis` through `pivot`, followed by a translation `offset_k` (metres):
//! `x' = pivot + R(axis, angle_k) (x - pivot) + offset_k`. Poses come either from a constant
//! per-step motion (`offset_k = k · translate`, `angle_k = k · rotate_deg`) or from keyframes
//! (linear interpolation between keyframes, held constant before the first and after the last).
//!
//! Every step is validated like a static scene when the [`DynamicScene`] is built, and every
//! problem of every step is reported at once. Surfaces keep their names and [`SurfaceId`]s
//! across steps; TX and RX are fixed unless the file gives `tx_steps` / `rx_steps`.

use crate::description::{BOX_FACES, SceneDescription};
pub use crate::description::{KeyframeDesc, ObjectDesc, PoseDesc};
use crate::frame::to_local;
use crate::model::Scene;
use crate::problem::{Problem, SceneError};
use crate::surface::{Surface, SurfaceId};
use crate::validate::{Terminals, check_terminals};
use bt_geom::{Polygon, Real, Vec3};
use serde::Serialize;
use std::collections::BTreeMap;

/// Largest `steps` a scene file may ask for. Every step is a full [`Scene`] (surfaces copied,
/// BVH built), so without a limit a 100-byte file saying `"steps": 4000000000` asks for
/// 735 GB up front (`docs/fuzzing.md`); the paper's scenes use tens.
pub const MAX_STEPS: u32 = 10_000;

/// Largest `steps` × number of surfaces: the surface copies kept for all steps (about 600 bytes
/// each with the per-step BVH), so a 3 KB file of 70 boxes cannot ask for 10 000 steps of 420
/// surfaces (2.5 GB); the limit is about 150 MB.
pub const MAX_SURFACE_STEPS: usize = 250_000;

/// Pose of an object at one step: rotation about an axis through a pivot, then translation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pose {
    /// Translation applied after the rotation, metres.
    pub offset: Vec3,
    /// Rotation angle, degrees (right-hand rule about `axis`).
    pub angle_deg: Real,
    /// Point on the rotation axis, metres.
    pub pivot: Vec3,
    /// Unit rotation axis.
    pub axis: Vec3,
}

impl Pose {
    /// The identity pose.
    pub const IDENTITY: Pose = Pose {
        offset: Vec3::ZERO,
        angle_deg: 0.0,
        pivot: Vec3::ZERO,
        axis: Vec3::Z,
    };

    /// Whether the pose leaves every point where it is (exactly).
    pub fn is_identity(&self) -> bool {
        self.offset == Vec3::ZERO && self.angle_deg == 0.0
    }

    /// Image of the point `p` (metres).
    pub fn apply(&self, p: Vec3) -> Vec3 {
        if self.angle_deg == 0.0 {
            return p + self.offset;
        }
        let q = glam::DQuat::from_axis_angle(self.axis, self.angle_deg.to_radians());
        self.pivot + q * (p - self.pivot) + self.offset
    }
}

/// An object of a validated dynamic scene.
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicObject {
    /// Object name (a key of the file's `objects`).
    pub name: String,
    /// Its surfaces, ids valid in every step's [`Scene`].
    pub surfaces: Vec<SurfaceId>,
    /// Its pose at each step.
    pub poses: Vec<Pose>,
    /// The pivot of its rotations as the file gives it (world frame, metres); `None` for an
    /// object that only translates, which no pose may rotate.
    pub pivot: Option<Vec3>,
}

impl DynamicObject {
    /// The pose `desc` (an offset and angle from the file's geometry, about this object's
    /// pivot and axis), or the problems of its fields, located at `location` (such as
    /// `objects.door`): non-finite values, or a rotation of an object without a pivot.
    pub fn pose(&self, desc: &PoseDesc, location: &str) -> Result<Pose, Vec<Problem>> {
        let mut problems = pose_problems(desc);
        if desc.angle_deg.is_some_and(|a| a != 0.0) && self.pivot.is_none() {
            problems.push((
                ".angle_deg".into(),
                "the object has no pivot in the scene file, so it cannot rotate".into(),
            ));
        }
        if !problems.is_empty() {
            return Err(problems
                .into_iter()
                .map(|(field, message)| Problem {
                    location: format!("{location}{field}"),
                    message,
                })
                .collect());
        }
        let axis = self.poses.first().map_or(Vec3::Z, |p| p.axis);
        Ok(Pose {
            offset: Vec3::from_array(desc.offset.unwrap_or([0.0; 3])),
            angle_deg: desc.angle_deg.unwrap_or(0.0),
            pivot: self.pivot.unwrap_or(Vec3::ZERO),
            axis,
        })
    }
}

/// A validated scene over time steps: one [`Scene`] per step, same surfaces (names, ids,
/// kinds, materials) in each, only the geometry of moving objects and the terminals differ.
#[derive(Debug, Clone)]
pub struct DynamicScene {
    /// The file's geometry (every object unmoved) with step 0's terminals: what poses apply to.
    base: Scene,
    scenes: Vec<Scene>,
    objects: Vec<DynamicObject>,
}

impl DynamicScene {
    /// A static scene as a one-step dynamic scene.
    pub fn from_static(scene: Scene) -> Self {
        Self {
            base: scene.clone(),
            scenes: vec![scene],
            objects: Vec::new(),
        }
    }

    /// Validate a description with `steps`, `objects` and optional `tx_steps` / `rx_steps`.
    /// `terminals` (CLI `--tx/--rx`) override the file's terminals at every step. A description
    /// without dynamic fields gives a one-step scene equal to [`Scene::from_description`].
    pub fn from_description(
        desc: &SceneDescription,
        source_name: &str,
        terminals: Terminals,
    ) -> Result<Self, SceneError> {
        let mut problems: Vec<Problem> = Vec::new();
        let steps = step_count(desc.steps, &mut problems);
        let terminals = StepTerminals {
            fixed: terminals,
            tx: terminal_steps("tx_steps", &desc.tx_steps, steps, &mut problems),
            rx: terminal_steps("rx_steps", &desc.rx_steps, steps, &mut problems),
        };
        // Step 0 terminals decide the base scene; validation of the file's geometry happens
        // there (every static problem reported by the static validator).
        let base = Scene::from_description(desc, source_name, terminals.at(0));
        let motions = object_motions(desc, steps, &mut problems);
        let base = match base {
            Ok(base) => base,
            Err(SceneError::Invalid {
                problems: mut base_problems,
                ..
            }) => {
                base_problems.extend(problems);
                return Err(invalid(source_name, base_problems));
            }
            Err(e) => return Err(e),
        };

        let members = members(desc, &base, &mut problems);
        check_surface_copies(steps, base.surfaces().len(), &mut problems);
        if !problems.is_empty() {
            return Err(invalid(source_name, problems));
        }
        let objects: Vec<DynamicObject> = motions
            .into_iter()
            .map(|(name, poses)| DynamicObject {
                surfaces: members.get(&name).cloned().unwrap_or_default(),
                pivot: desc.objects[&name].pivot.map(Vec3::from_array),
                name,
                poses,
            })
            .collect();
        let scenes = (0..steps)
            .map(|k| {
                let poses: Vec<Pose> = objects.iter().map(|o| o.poses[k]).collect();
                let location = format!("steps[{k}] ");
                let at = terminals.at(k);
                posed_scene(&base, &objects, &poses, at, &location, &mut problems)
            })
            .collect();
        if !problems.is_empty() {
            return Err(invalid(source_name, problems));
        }
        Ok(Self {
            base,
            scenes,
            objects,
        })
    }

    /// Number of time steps (at least 1).
    pub fn len(&self) -> usize {
        self.scenes.len()
    }

    /// Always false: a dynamic scene has at least one step.
    pub fn is_empty(&self) -> bool {
        self.scenes.is_empty()
    }

    /// A copy in which every material of every step has the radio model `radio` (CLI
    /// `--material`), see [`Scene::with_radio_material`].
    pub fn with_radio_material(
        &self,
        radio: bt_channel::RadioMaterial,
    ) -> Result<Self, SceneError> {
        self.map_steps(|s| s.with_radio_material(radio))
    }

    /// A copy whose half-space materials are slabs of `thickness` metres at every step (CLI
    /// `--thickness` alone), see [`Scene::with_half_spaces_as_slabs`].
    pub fn with_half_spaces_as_slabs(&self, thickness: bt_geom::Real) -> Result<Self, SceneError> {
        self.map_steps(|s| s.with_half_spaces_as_slabs(thickness))
    }

    /// A copy with carrier `frequency_hz` at every step (CLI `--frequency`), see
    /// [`Scene::with_frequency`].
    pub fn with_frequency(&self, frequency_hz: Real) -> Result<Self, SceneError> {
        self.map_steps(|s| s.with_frequency(frequency_hz))
    }

    /// A copy with `f` applied to the scene of every step (the objects unchanged); the first
    /// error stops it.
    fn map_steps(
        &self,
        f: impl Fn(&Scene) -> Result<Scene, SceneError>,
    ) -> Result<Self, SceneError> {
        Ok(Self {
            base: f(&self.base)?,
            scenes: self.scenes.iter().map(f).collect::<Result<_, _>>()?,
            objects: self.objects.clone(),
        })
    }

    /// The validated scene of step `k` (0-based). Panics when `k >= len()`.
    pub fn step(&self, k: usize) -> &Scene {
        &self.scenes[k]
    }

    /// The scenes of all steps, in order.
    pub fn scenes(&self) -> &[Scene] {
        &self.scenes
    }

    /// The moving objects, by name order.
    pub fn objects(&self) -> &[DynamicObject] {
        &self.objects
    }

    /// The scene with every object at its pose in `poses` (aligned with [`Self::objects`])
    /// and the terminals `terminals` (world frame; an absent one is step 0's): a step of the
    /// same surfaces that the file does not list, validated like its steps (a pose that
    /// breaks a polygon, a terminal on a moved surface). Problems are located at the object
    /// and surface, or at `tx` / `rx`.
    pub fn posed(&self, poses: &[Pose], terminals: Terminals) -> Result<Scene, SceneError> {
        let mut problems = Vec::new();
        if poses.len() != self.objects.len() {
            problems.push(Problem {
                location: "objects".into(),
                message: format!(
                    "{} poses given for {} objects",
                    poses.len(),
                    self.objects.len()
                ),
            });
            return Err(invalid(self.base.name(), problems));
        }
        let scene = posed_scene(
            &self.base,
            &self.objects,
            poses,
            terminals,
            "",
            &mut problems,
        );
        match problems.is_empty() {
            true => Ok(scene),
            false => Err(invalid(self.base.name(), problems)),
        }
    }
}

/// Surfaces whose geometry differs between two steps of the same dynamic scene (vertex lists
/// compared exactly), in id order. `None` when the two scenes do not have the same surfaces
/// (count, names, kinds), i.e. are not steps of one dynamic scene.
pub fn moved_surfaces(prev: &Scene, next: &Scene) -> Option<Vec<SurfaceId>> {
    let (a, b) = (prev.surfaces(), next.surfaces());
    if a.len() != b.len() {
        return None;
    }
    let mut moved = Vec::new();
    for (i, (s, t)) in a.iter().zip(b).enumerate() {
        if s.name != t.name || s.kind != t.kind || s.material != t.material {
            return None;
        }
        if s.polygon.vertices() != t.polygon.vertices() {
            moved.push(SurfaceId(i as u32));
        }
    }
    Some(moved)
}

type FieldProblems = Vec<(String, String)>;

fn invalid(source_name: &str, problems: Vec<Problem>) -> SceneError {
    SceneError::Invalid {
        source_name: source_name.to_string(),
        problems,
    }
}

/// The file's `steps` (default 1), clamped to `1..=MAX_STEPS` so the per-step poses built
/// before an error is returned stay small; a value outside is a problem.
fn step_count(steps: Option<u32>, problems: &mut Vec<Problem>) -> usize {
    let steps = steps.unwrap_or(1);
    let mut push = |message: String| {
        problems.push(Problem {
            location: "steps".into(),
            message,
        })
    };
    if steps == 0 {
        push("must be at least 1".into());
    }
    if steps > MAX_STEPS {
        push(format!("is {steps}, at most {MAX_STEPS}"));
    }
    steps.clamp(1, MAX_STEPS) as usize
}

/// A per-step terminal list of the file (`tx_steps` / `rx_steps`): one finite position per step.
fn terminal_steps(
    field: &str,
    values: &Option<Vec<[Real; 3]>>,
    steps: usize,
    problems: &mut Vec<Problem>,
) -> Option<Vec<Vec3>> {
    let v: Vec<Vec3> = values
        .as_ref()?
        .iter()
        .map(|p| Vec3::from_array(*p))
        .collect();
    if v.len() != steps {
        problems.push(Problem {
            location: field.into(),
            message: format!("has {} positions, expected one per step ({steps})", v.len()),
        });
    }
    if let Some(i) = v.iter().position(|p| !p.is_finite()) {
        problems.push(Problem {
            location: format!("{field}[{i}]"),
            message: "coordinates must be finite numbers".into(),
        });
    }
    Some(v)
}

/// The terminals of each step: the caller's override, else the file's per-step list, else
/// (`None`) the base scene's.
struct StepTerminals {
    fixed: Terminals,
    tx: Option<Vec<Vec3>>,
    rx: Option<Vec<Vec3>>,
}

impl StepTerminals {
    fn at(&self, k: usize) -> Terminals {
        let listed = |v: &Option<Vec<Vec3>>| v.as_ref().and_then(|v| v.get(k).copied());
        Terminals {
            tx: self.fixed.tx.or_else(|| listed(&self.tx)),
            rx: self.fixed.rx.or_else(|| listed(&self.rx)),
        }
    }
}

/// The poses of every object at every step, by object name; the problems of bad motions.
fn object_motions(
    desc: &SceneDescription,
    steps: usize,
    problems: &mut Vec<Problem>,
) -> Vec<(String, Vec<Pose>)> {
    let mut motions = Vec::new();
    for (name, object) in &desc.objects {
        match poses(object, steps) {
            Ok(p) => motions.push((name.clone(), p)),
            Err(list) => problems.extend(list.into_iter().map(|(field, message)| Problem {
                location: format!("objects.{name}{field}"),
                message,
            })),
        }
    }
    motions
}

/// The budget of surface copies kept for all steps ([`MAX_SURFACE_STEPS`]).
fn check_surface_copies(steps: usize, surfaces: usize, problems: &mut Vec<Problem>) {
    let copies = steps.saturating_mul(surfaces.max(1));
    if copies > MAX_SURFACE_STEPS {
        problems.push(Problem {
            location: "steps".into(),
            message: format!(
                "{steps} steps of {surfaces} surfaces make {copies} surface copies, at most \
                 {MAX_SURFACE_STEPS} (every step is a full copy of the scene)"
            ),
        });
    }
}

/// The base scene with every object moved to its pose (`poses`, aligned with `objects`) and
/// the terminals `at` (world frame; an absent one is the base scene's); a polygon a pose
/// breaks and a terminal check that fails are problems, their locations prefixed with
/// `location` (a step's `steps[k] `).
fn posed_scene(
    base: &Scene,
    objects: &[DynamicObject],
    poses: &[Pose],
    at: Terminals,
    location: &str,
    problems: &mut Vec<Problem>,
) -> Scene {
    // Every step shares the base scene's local frame (warm starts and reuse compare positions
    // across steps): world inputs (pivots, terminals) are moved into it.
    let origin = base.origin();
    let mut surfaces: Vec<Surface> = base.surfaces().to_vec();
    for (object, &pose) in objects.iter().zip(poses) {
        if pose.is_identity() {
            continue;
        }
        let pose = Pose {
            pivot: to_local(pose.pivot, origin),
            ..pose
        };
        for id in &object.surfaces {
            let s = &mut surfaces[id.index()];
            let moved = s
                .polygon
                .vertices()
                .iter()
                .map(|p| pose.apply(*p))
                .collect();
            match Polygon::new(moved) {
                Ok(p) => s.polygon = p,
                Err(e) => problems.push(Problem {
                    location: format!(
                        "{location}object \"{}\" surface \"{}\"",
                        object.name, s.name
                    ),
                    message: e.to_string(),
                }),
            }
        }
    }
    let tx = at.tx.map(|p| to_local(p, origin)).or(base.tx());
    let rx = at.rx.map(|p| to_local(p, origin)).or(base.rx());
    let extent = crate::model::scene_extent(&surfaces, tx, rx);
    if let Err(list) = check_terminals((&surfaces, None), tx, rx, extent, origin) {
        problems.extend(list.into_iter().map(|p| Problem {
            location: format!("{location}{}", p.location),
            message: p.message,
        }));
    }
    Scene::assemble(
        base.name().to_string(),
        origin,
        surfaces,
        tx,
        rx,
        base.frequency_hz(),
        base.materials().clone(),
    )
}

/// Poses of one object at steps `0..steps`.
fn poses(object: &ObjectDesc, steps: usize) -> Result<Vec<Pose>, FieldProblems> {
    let mut problems = motion_problems(object);
    let rotates = keyframe_problems(object, steps, &mut problems)
        || object.rotate_deg.is_some_and(|r| r != 0.0);
    if rotates && object.pivot.is_none() {
        problems.push((
            ".pivot".into(),
            "missing: a rotating object needs a pivot [x, y, z]".into(),
        ));
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    Ok(interpolate(object, steps))
}

/// Whether every coordinate is a finite number.
fn finite3(v: &[Real; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The problems of an object's axis, pivot and per-step motion fields.
fn motion_problems(object: &ObjectDesc) -> FieldProblems {
    let mut problems: FieldProblems = Vec::new();
    let axis = object.axis.unwrap_or([0.0, 0.0, 1.0]);
    let axis_v = Vec3::from_array(axis);
    if !finite3(&axis) || axis_v.length() == 0.0 || !axis_v.length().is_normal() {
        problems.push((".axis".into(), "must be a finite non-zero vector".into()));
    }
    if object.pivot.as_ref().is_some_and(|p| !finite3(p)) {
        problems.push((".pivot".into(), "coordinates must be finite numbers".into()));
    }
    if object.translate.as_ref().is_some_and(|t| !finite3(t)) {
        problems.push((
            ".translate".into(),
            "must be three finite numbers (metres per step)".into(),
        ));
    }
    if object.rotate_deg.is_some_and(|r| !r.is_finite()) {
        problems.push((
            ".rotate_deg".into(),
            "must be a finite number of degrees".into(),
        ));
    }
    let per_step = object.translate.is_some() || object.rotate_deg.is_some();
    if per_step && !object.keyframes.is_empty() {
        problems.push((
            String::new(),
            "give either a per-step motion (translate, rotate_deg) or keyframes, not both".into(),
        ));
    }
    problems
}

/// The problems of a pose's values (`.offset`, `.angle_deg`): one home for the keyframes of
/// scene files and the poses of `beamtrace serve`.
fn pose_problems(pose: &PoseDesc) -> FieldProblems {
    let mut problems = FieldProblems::new();
    if pose.offset.is_some_and(|o| !finite3(&o)) {
        problems.push((".offset".into(), "must be three finite numbers".into()));
    }
    if pose.angle_deg.is_some_and(|a| !a.is_finite()) {
        problems.push((".angle_deg".into(), "must be a finite number".into()));
    }
    problems
}

/// Appends the problems of an object's keyframes (steps in range and increasing, finite
/// values); returns whether a keyframe rotates the object.
fn keyframe_problems(object: &ObjectDesc, steps: usize, problems: &mut FieldProblems) -> bool {
    let mut rotates = false;
    for (i, k) in object.keyframes.iter().enumerate() {
        if k.step as usize >= steps {
            problems.push((
                format!(".keyframes[{i}].step"),
                format!("is {}, must be below steps ({steps})", k.step),
            ));
        }
        if i > 0 && k.step <= object.keyframes[i - 1].step {
            problems.push((
                format!(".keyframes[{i}].step"),
                "keyframe steps must be strictly increasing".into(),
            ));
        }
        for (field, message) in pose_problems(&k.pose()) {
            problems.push((format!(".keyframes[{i}]{field}"), message));
        }
        rotates |= k.angle_deg.is_some_and(|a| a != 0.0);
    }
    rotates
}

/// The poses of a validated object at steps `0..steps`: its per-step motion times the step,
/// or its keyframes interpolated linearly (held before the first and after the last).
fn interpolate(object: &ObjectDesc, steps: usize) -> Vec<Pose> {
    let pivot = Vec3::from_array(object.pivot.unwrap_or([0.0; 3]));
    let axis = Vec3::from_array(object.axis.unwrap_or([0.0, 0.0, 1.0])).normalize();
    let pose = |offset: Vec3, angle_deg: Real| Pose {
        offset,
        angle_deg,
        pivot,
        axis,
    };
    let keys: Vec<(Real, Vec3, Real)> = object
        .keyframes
        .iter()
        .map(|k| {
            (
                k.step as Real,
                Vec3::from_array(k.offset.unwrap_or([0.0; 3])),
                k.angle_deg.unwrap_or(0.0),
            )
        })
        .collect();
    (0..steps)
        .map(|k| {
            let t = k as Real;
            if keys.is_empty() {
                let offset = Vec3::from_array(object.translate.unwrap_or([0.0; 3])) * t;
                return pose(offset, object.rotate_deg.unwrap_or(0.0) * t);
            }
            let (first, last) = (keys[0], keys[keys.len() - 1]);
            if t <= first.0 {
                return pose(first.1, first.2);
            }
            if t >= last.0 {
                return pose(last.1, last.2);
            }
            let i = keys.iter().rposition(|key| key.0 <= t).unwrap_or(0);
            let (a, b) = (keys[i], keys[i + 1]);
            if t == a.0 {
                return pose(a.1, a.2);
            }
            let f = (t - a.0) / (b.0 - a.0);
            pose(a.1 + (b.1 - a.1) * f, a.2 + (b.2 - a.2) * f)
        })
        .collect()
}

/// Surfaces of each object: from `object` fields of surfaces and boxes, and from `members`.
fn members(
    desc: &SceneDescription,
    base: &Scene,
    problems: &mut Vec<Problem>,
) -> BTreeMap<String, Vec<SurfaceId>> {
    let mut owner: BTreeMap<SurfaceId, String> = BTreeMap::new();
    let mut assign =
        |object: &str, location: String, ids: Vec<SurfaceId>, problems: &mut Vec<Problem>| {
            if !desc.objects.contains_key(object) {
                problems.push(Problem {
                    location,
                    message: format!("unknown object \"{object}\" (define it under \"objects\")"),
                });
                return;
            }
            for id in ids {
                match owner.get(&id) {
                    Some(other) if other != object => problems.push(Problem {
                        location: location.clone(),
                        message: format!(
                            "surface \"{}\" is already a member of object \"{other}\"",
                            base.surface(id).name
                        ),
                    }),
                    _ => {
                        owner.insert(id, object.to_string());
                    }
                }
            }
        };
    let box_faces = |name: &str| -> Vec<SurfaceId> {
        BOX_FACES
            .iter()
            .filter_map(|(face, _, _)| base.find(&format!("{name}.{face}")))
            .collect()
    };
    for (i, s) in desc.surfaces.iter().enumerate() {
        if let Some(object) = &s.object {
            let ids = base.find(&s.name).into_iter().collect();
            assign(
                object,
                format!("surfaces[{i}] \"{}\".object", crate::name::shown(&s.name)),
                ids,
                problems,
            );
        }
    }
    for (i, b) in desc.boxes.iter().enumerate() {
        if let Some(object) = &b.object {
            assign(
                object,
                format!("boxes[{i}] \"{}\".object", b.name),
                box_faces(&b.name),
                problems,
            );
        }
    }
    for (name, object) in &desc.objects {
        for (i, member) in object.members.iter().enumerate() {
            let location = format!("objects.{name}.members[{i}]");
            let ids: Vec<SurfaceId> = if let Some(id) = base.find(member) {
                vec![id]
            } else if desc.boxes.iter().any(|b| &b.name == member) {
                box_faces(member)
            } else {
                problems.push(Problem {
                    location,
                    message: format!("no surface or box named \"{member}\""),
                });
                continue;
            };
            assign(name, location, ids, problems);
        }
    }
    let mut by_object: BTreeMap<String, Vec<SurfaceId>> = BTreeMap::new();
    for (id, object) in owner {
        by_object.entry(object).or_default().push(id);
    }
    for name in desc.objects.keys() {
        if !by_object.contains_key(name) {
            problems.push(Problem {
                location: format!("objects.{name}"),
                message: "has no members (give \"object\": \"NAME\" on surfaces or boxes, or \"members\")".into(),
            });
        }
    }
    by_object
}

#[cfg(test)]
mod tests {
    use super::*;

    fn door_scene(extra: &str) -> SceneDescription {
        let json = format!(
            r#"{{ "tx": [1, 1, 1], "rx": [3, 2, 1.5], "steps": 4,
            "boxes": [ {{ "name": "room", "min": [0, 0, 0], "max": [4, 3, 2.5] }},
                       {{ "name": "crate", "kind": "blocker", "min": [2, 0.2, 0], "max": [2.5, 0.6, 0.5], "object": "crate" }} ],
            "surfaces": [ {{ "name": "door", "object": "door", "vertices": [[3.9, 1, 0], [3.9, 1.8, 0], [3.9, 1.8, 2], [3.9, 1, 2]] }} ],
            "objects": {{
               "door": {{ "pivot": [3.9, 1, 0], "keyframes": [ {{ "step": 0 }}, {{ "step": 3, "angle_deg": 90 }} ] }},
               "crate": {{ "translate": [0.1, 0.2, 0] }} {extra} }} }}"#
        );
        serde_json::from_str(&json).unwrap()
    }

    #[test]
    fn a_far_dynamic_scene_moves_in_one_local_frame_like_at_the_origin() {
        let near = DynamicScene::from_description(&door_scene(""), "t", Terminals::default());
        let near = near.unwrap();
        let offset = Vec3::new(1e7, -3e6, 50.0);
        let mut far = door_scene("");
        let shift = |p: &mut [Real; 3]| *p = (Vec3::from_array(*p) + offset).to_array();
        far.surfaces
            .iter_mut()
            .for_each(|s| s.vertices.iter_mut().for_each(shift));
        for b in &mut far.boxes {
            shift(&mut b.min);
            shift(&mut b.max);
        }
        far.tx.iter_mut().chain(far.rx.iter_mut()).for_each(shift);
        far.objects
            .values_mut()
            .for_each(|o| o.pivot.iter_mut().for_each(shift));
        let far = DynamicScene::from_description(&far, "t", Terminals::default()).unwrap();
        let origin = far.step(0).origin();
        assert!(origin.abs().max_element() > 1e6, "recentred: {origin}");
        for k in 0..near.len() {
            let (a, b) = (near.step(k), far.step(k));
            assert_eq!(b.origin(), origin, "one frame for every step");
            let tx = b.tx().unwrap();
            assert!(tx.abs().max_element() < 16.0, "local tx {tx}");
            assert_eq!(b.tx_world(), Some(a.tx().unwrap() + offset));
            for (s, t) in a.surfaces().iter().zip(b.surfaces()) {
                for (p, q) in s.polygon.vertices().iter().zip(t.polygon.vertices()) {
                    let error = (b.to_world(*q) - (*p + offset)).abs().max_element();
                    assert!(error <= 4e-9, "step {k} {}: {error:e}", s.name);
                }
            }
        }
    }

    #[test]
    fn door_rotates_about_its_hinge_and_crate_translates() {
        let d = DynamicScene::from_description(&door_scene(""), "t", Terminals::default()).unwrap();
        assert_eq!(d.len(), 4);
        let door = d.step(0).find("door").unwrap();
        let last = d.step(3).surface(door).polygon.vertices();
        // 90° about +z through the hinge (3.9, 1): the free edge (3.9, 1.8) goes to (3.1, 1).
        assert!(
            (last[1] - Vec3::new(3.1, 1.0, 0.0)).length() < 1e-12,
            "{last:?}"
        );
        assert!((last[0] - Vec3::new(3.9, 1.0, 0.0)).length() < 1e-12);
        let mid = d.step(1).surface(door).polygon.vertices()[1];
        let a = 30f64.to_radians();
        assert!((mid - Vec3::new(3.9 - 0.8 * a.sin(), 1.0 + 0.8 * a.cos(), 0.0)).length() < 1e-12);
        let top = d.step(0).find("crate.top").unwrap();
        let c2 =
            d.step(2).surface(top).polygon.centroid() - d.step(0).surface(top).polygon.centroid();
        assert!((c2 - Vec3::new(0.2, 0.4, 0.0)).length() < 1e-12);
        // Names and ids stay; moved surfaces are the door and the crate's five faces.
        let moved = moved_surfaces(d.step(0), d.step(1)).unwrap();
        assert_eq!(moved.len(), 1 + 6);
        for k in 1..4 {
            assert_eq!(d.step(k).surfaces().len(), d.step(0).surfaces().len());
        }
    }

    #[test]
    fn posed_with_a_steps_poses_is_that_step_and_bad_poses_are_named() {
        let d = DynamicScene::from_description(&door_scene(""), "t", Terminals::default()).unwrap();
        for k in 0..d.len() {
            let poses: Vec<Pose> = d.objects().iter().map(|o| o.poses[k]).collect();
            let posed = d.posed(&poses, Terminals::default()).unwrap();
            for (a, b) in posed.surfaces().iter().zip(d.step(k).surfaces()) {
                assert_eq!(a.polygon.vertices(), b.polygon.vertices(), "step {k}");
            }
        }
        let names: Vec<&str> = d.objects().iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["crate", "door"]);
        let (crate_, door) = (&d.objects()[0], &d.objects()[1]);
        let turn = PoseDesc {
            offset: None,
            angle_deg: Some(45.0),
        };
        let err = crate_.pose(&turn, "objects.crate").unwrap_err();
        assert_eq!(err[0].location, "objects.crate.angle_deg", "{err:?}");
        assert!(err[0].message.contains("no pivot"), "{err:?}");
        let bad = PoseDesc {
            offset: Some([f64::NAN, 0.0, 0.0]),
            angle_deg: Some(f64::INFINITY),
        };
        let err = door.pose(&bad, "objects.door").unwrap_err();
        let located: Vec<&str> = err.iter().map(|p| p.location.as_str()).collect();
        assert_eq!(located, ["objects.door.offset", "objects.door.angle_deg"]);
        // The crate pushed onto the RX: a problem of the RX, not a panic.
        let onto_rx = PoseDesc {
            offset: Some([0.7, 1.6, 0.0]),
            angle_deg: None,
        };
        let poses = [
            crate_.pose(&onto_rx, "objects.crate").unwrap(),
            door.poses[0],
        ];
        let rx = Some(Vec3::new(2.7, 2.0, 0.25));
        let err = d.posed(&poses, Terminals { tx: None, rx }).unwrap_err();
        assert!(err.to_string().contains("rx: lies on surface"), "{err}");
        let err = d.posed(&poses[..1], Terminals::default()).unwrap_err();
        assert!(
            err.to_string().contains("1 poses given for 2 objects"),
            "{err}"
        );
    }

    /// Every problem `desc` is refused with, as printed.
    fn problem_texts(desc: &SceneDescription) -> Vec<String> {
        let err = DynamicScene::from_description(desc, "t", Terminals::default()).unwrap_err();
        let SceneError::Invalid { problems, .. } = &err else {
            panic!("{err}")
        };
        problems.iter().map(|p| p.to_string()).collect()
    }

    #[test]
    fn problems_are_all_reported() {
        let mut desc = door_scene(
            r#", "ghost": { "translate": [1, 0, 0] }, "spin": { "rotate_deg": 5, "members": ["nothing"] }"#,
        );
        desc.objects.get_mut("door").unwrap().keyframes[1].step = 7;
        desc.tx_steps = Some(vec![[1.0, 1.0, 1.0]]);
        let text = problem_texts(&desc);
        let has = |s: &str| text.iter().any(|t| t.contains(s));
        assert!(has("tx_steps: has 1 positions"), "{text:#?}");
        assert!(has("objects.door.keyframes[1].step: is 7"), "{text:#?}");
        assert!(has("objects.spin.pivot: missing"), "{text:#?}");
        // Motion errors stop before membership checks; fix them and see the rest.
        desc.objects.get_mut("door").unwrap().keyframes[1].step = 3;
        desc.objects.get_mut("spin").unwrap().pivot = Some([0.0; 3]);
        desc.tx_steps = None;
        let text = problem_texts(&desc);
        let has = |s: &str| text.iter().any(|t| t.contains(s));
        assert!(has("objects.ghost: has no members"), "{text:#?}");
        assert!(
            has("objects.spin.members[0]: no surface or box named \"nothing\""),
            "{text:#?}"
        );
    }

    #[test]
    fn terminal_on_a_moved_surface_is_reported_with_its_step() {
        let mut desc = door_scene("");
        // RX where the crate's west face will be at step 2 (x = 2.2).
        desc.rx = Some([2.2, 0.8, 0.25]);
        let err = DynamicScene::from_description(&desc, "t", Terminals::default()).unwrap_err();
        let SceneError::Invalid { problems, .. } = err else {
            panic!()
        };
        assert!(
            problems
                .iter()
                .any(|p| p.location == "steps[2] rx" && p.message.contains("crate.west")),
            "{problems:#?}"
        );
    }
}
