//! Surfaces: the validated [`Surface`] of a scene and the unvalidated [`RawSurface`] an
//! importer or a scene file hands to validation.

use bt_geom::{Polygon, Vec3};
use serde::{Deserialize, Serialize};

/// Index of a surface in [`crate::Scene::surfaces`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct SurfaceId(pub u32);

impl SurfaceId {
    /// The index as `usize`.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a surface does to a ray.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceKind {
    /// Reflects specularly from both sides, and occludes.
    Reflector,
    /// Only occludes (small objects, people).
    Blocker,
}

/// A named bounded planar surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Unique name (from the scene file, or generated for meshes).
    pub name: String,
    /// Material name, a key of [`crate::Scene::materials`].
    pub material: String,
    /// Reflector or blocker.
    pub kind: SurfaceKind,
    /// The validated polygon (metres, world frame).
    pub polygon: Polygon,
}

/// A surface as given, before validation (world frame, metres): what a scene file's
/// `surfaces`/`boxes` or an importer (mesh faces, extracted planes) hands to
/// [`crate::Scene::from_surfaces`].
#[derive(Debug, Clone, PartialEq)]
pub struct RawSurface {
    /// Where it came from, for messages (e.g. `surfaces[3] "sofa.top"`, `surface 2 "wall_0"`).
    pub location: String,
    /// Surface name (checked: printable, unique).
    pub name: String,
    /// Material name (`None`: `"default"`).
    pub material: Option<String>,
    /// Reflector or blocker.
    pub kind: SurfaceKind,
    /// Polygon vertices in order, metres, world frame.
    pub vertices: Vec<Vec3>,
}
