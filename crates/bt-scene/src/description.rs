//! The scene file format (JSON or TOML), as parsed, before validation.
//! Documented in `docs/scene-format.md`; unknown fields are errors.

use crate::surface::SurfaceKind;
use bt_geom::Real;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A scene file as written by a user. Validate it with [`crate::Scene::from_description`].
#[serde_with::skip_serializing_none]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SceneDescription {
    /// Scene name (optional; the file stem is used otherwise).
    pub name: Option<String>,
    /// Carrier frequency, Hz (default 28 GHz).
    pub frequency_hz: Option<Real>,
    /// Transmitter position `[x, y, z]`, metres.
    pub tx: Option<[Real; 3]>,
    /// Receiver position `[x, y, z]`, metres.
    pub rx: Option<[Real; 3]>,
    /// Extra or overriding materials by name (the built-ins are always available).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// Planar polygons.
    #[serde(default)]
    pub surfaces: Vec<SurfaceDesc>,
    /// Axis-aligned boxes, expanded into their faces (`<name>.top`, `.bottom`, `.west`,
    /// `.east`, `.south`, `.north` for the -z/+z/-x/+x/-y/+y faces... see the format doc).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub boxes: Vec<BoxDesc>,
    /// Dynamic scenes: number of time steps (default 1). See `docs/dynamic-scenes.md`.
    pub steps: Option<u32>,
    /// Dynamic scenes: moving objects by name (members and motion).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub objects: BTreeMap<String, ObjectDesc>,
    /// Dynamic scenes: TX position per step `[[x, y, z], ...]` (one per step), metres.
    pub tx_steps: Option<Vec<[Real; 3]>>,
    /// Dynamic scenes: RX position per step `[[x, y, z], ...]` (one per step), metres.
    pub rx_steps: Option<Vec<[Real; 3]>>,
}

/// A material entry: a constant loss, a radio model, or both (`docs/scene-format.md`).
#[serde_with::skip_serializing_none]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// Loss per reflection, dB (>= 0). Default with a radio model: its loss at normal
    /// incidence at the scene's frequency.
    pub reflection_loss_db: Option<Real>,
    /// An ITU-R P.2040-3 material name (`concrete`, `itu_glass`, `very_dry_ground`, ...).
    pub itu: Option<String>,
    /// Custom relative permittivity εr' (with `conductivity`, instead of `itu`).
    pub relative_permittivity: Option<Real>,
    /// Custom conductivity σ, S/m (with `relative_permittivity`).
    pub conductivity: Option<Real>,
    /// Slab thickness, metres (absent: a half-space).
    pub thickness: Option<Real>,
    /// `true`: waves cross surfaces of this material (a slab only: it needs a `thickness`)
    /// even without `--transmission` (default `false`).
    pub transmission: Option<bool>,
}

/// One planar polygon.
#[serde_with::skip_serializing_none]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SurfaceDesc {
    /// Unique name.
    pub name: String,
    /// Material name (default `"default"`).
    pub material: Option<String>,
    /// `reflector` (default) or `blocker`.
    pub kind: Option<SurfaceKind>,
    /// Vertices `[[x, y, z], ...]` in order around the polygon (either winding), metres.
    pub vertices: Vec<[Real; 3]>,
    /// Dynamic scenes: the moving object this surface belongs to (a key of `objects`).
    pub object: Option<String>,
}

/// An axis-aligned box, expanded into up to six rectangular faces.
#[serde_with::skip_serializing_none]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct BoxDesc {
    /// Name prefix of the faces.
    pub name: String,
    /// Material name (default `"default"`).
    pub material: Option<String>,
    /// `reflector` (default) or `blocker`.
    pub kind: Option<SurfaceKind>,
    /// Minimum corner, metres.
    pub min: [Real; 3],
    /// Maximum corner, metres.
    pub max: [Real; 3],
    /// Faces to leave out, from `top`, `bottom`, `west`, `east`, `south`, `north`
    /// (e.g. the bottom of furniture standing on the floor).
    #[serde(default)]
    pub omit: Vec<String>,
    /// Dynamic scenes: the moving object this box belongs to (a key of `objects`).
    pub object: Option<String>,
}

/// Face names of a box in output order, with the axis and whether it is the max side.
pub(crate) const BOX_FACES: [(&str, usize, bool); 6] = [
    ("top", 2, true),
    ("bottom", 2, false),
    ("west", 0, false),
    ("east", 0, true),
    ("south", 1, false),
    ("north", 1, true),
];

/// A moving object as written in a scene file (an entry of `objects`).
///
/// Give either a constant per-step motion (`translate` and/or `rotate_deg`) or `keyframes`.
#[serde_with::skip_serializing_none]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// Names of surfaces or boxes that belong to the object, in addition to those whose
    /// `object` field names it (a box name covers all its faces).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub members: Vec<String>,
    /// Translation per step `[dx, dy, dz]`, metres.
    pub translate: Option<[Real; 3]>,
    /// Rotation per step about `axis` through `pivot`, degrees (right-hand rule).
    pub rotate_deg: Option<Real>,
    /// Point on the rotation axis (a door's hinge), metres. Required when the object rotates.
    pub pivot: Option<[Real; 3]>,
    /// Rotation axis direction (any length > 0; default `[0, 0, 1]`, z up).
    pub axis: Option<[Real; 3]>,
    /// Poses at given steps, linearly interpolated in between.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub keyframes: Vec<KeyframeDesc>,
}

/// The pose of an object at one step.
#[serde_with::skip_serializing_none]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct KeyframeDesc {
    /// Time step (0-based, below `steps`; keyframes strictly increasing).
    pub step: u32,
    /// Translation from the file's geometry `[dx, dy, dz]`, metres (default zero).
    pub offset: Option<[Real; 3]>,
    /// Rotation about the object's axis through its pivot, degrees (default 0).
    pub angle_deg: Option<Real>,
}

impl KeyframeDesc {
    /// The pose this keyframe gives (its offset and angle, without the step).
    pub fn pose(&self) -> PoseDesc {
        PoseDesc {
            offset: self.offset,
            angle_deg: self.angle_deg,
        }
    }
}

/// The pose of an object as a keyframe spells it, without the step: `{ "offset": [dx, dy,
/// dz], "angle_deg": a }` from the file's geometry, about the object's pivot and axis (what
/// `beamtrace serve` takes in a request's `objects`).
#[serde_with::skip_serializing_none]
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct PoseDesc {
    /// Translation from the file's geometry `[dx, dy, dz]`, metres (default zero).
    pub offset: Option<[Real; 3]>,
    /// Rotation about the object's axis through its pivot, degrees (default 0).
    pub angle_deg: Option<Real>,
}
