//! Polygon soups to bounded planar polygon surfaces: vertex welding and coplanar merging.
//!
//! A room exported from a 3-D tool is a soup of triangles and polygons. The readers of
//! `bt-import` (OBJ, PLY) parse one into a [`RawMesh`]; [`merge_mesh`] welds duplicated
//! vertices, merges edge-connected coplanar faces into groups and outlines each group by
//! simple polygons: [`MeshSurface`]s. No file parsing and no I/O here.
//!
//! Units and frame: coordinates are taken as metres in the file's own frame (beamtrace uses
//! z up; no axis swap is applied). Areas are m², angles in the options are degrees.
//!
//! Decisions and limits:
//! - Faces merge only with faces of the same object/group name and the same material.
//! - Nothing is lost or filled: the surfaces' areas add up to the faces' (up to the removal of
//!   collinear vertices within `weld_tol_m`). A group whose boundary is one or more simple
//!   counter-clockwise loops (seen from the group normal) gives one surface per loop. A group
//!   with holes (a ground with building footprints), open or non-manifold boundaries, or
//!   faces overlapping in its plane is split into simple pieces made of its own faces, grown
//!   greedily so that there are few (`split`); seams between pieces are coplanar. Surfaces are
//!   named `<name>_<k>` in output order.
//! - Every surface is simple with a margin of the weld tolerance (no two non-adjacent edges
//!   closer, so rounding cannot make it touch itself in `bt_geom::Polygon`'s exact test) and
//!   has at most `bt_geom::polygon::MAX_VERTICES` vertices; it need not be convex.
//! - Coincident duplicate faces (the same welded vertices, either winding) are kept once and
//!   counted in a warning.
//! - Degenerate faces (fewer than three distinct welded vertices, or height under the weld
//!   tolerance) are dropped and counted in a warning. Polygon faces that are not planar within
//!   `dist_tol_m`, or touch themselves, are split into fan triangles with a warning.
//! - Output polygon vertices are projected onto the group's plane (moving them at most
//!   `dist_tol_m`), so every surface is exactly planar up to rounding.

#![warn(missing_docs)]

use bt_geom::{Real, Vec3};

mod edges;
mod merge;
mod outline;
mod raw;
mod split;
#[cfg(test)]
mod tests;
pub mod tol;
mod trace;

use serde::{Deserialize, Serialize};

pub use raw::RawMesh;

pub use tol::{DEFAULT_ANGLE_TOL_DEG, DEFAULT_DIST_TOL_M, DEFAULT_WELD_TOL_M};

/// The crate's one error: merge options out of range.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// The merge options are out of range (negative or non-finite tolerance, angle >= 90 deg).
    #[error("invalid merge options: {detail}")]
    InvalidOptions {
        /// What is wrong.
        detail: String,
    },
}

/// Tolerances of the coplanar merge.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MergeOptions {
    /// Maximum angle between a face normal and its group's normal, in degrees, in `[0, 90)`.
    pub angle_tol_deg: Real,
    /// Maximum distance of a face's vertices from its group's plane, in metres, `>= 0`. Also
    /// the planarity limit above which a polygon face is split into triangles.
    pub dist_tol_m: Real,
    /// Vertices closer than this, in metres, are welded into one, `>= 0` (0: exact duplicates
    /// only). Also the length under which boundary vertices count as collinear or repeated.
    pub weld_tol_m: Real,
    /// Budget: the most vertices, and the most faces, a file may hold (CLI
    /// `--max-mesh-elements`). Checked against a PLY header's counts before any allocation and
    /// while an OBJ file is read, so a huge mesh stops early instead of exhausting memory in
    /// the merge (about 0.2 kB per face and vertex: a 180,000-face OBJ peaks at 60 MB in
    /// `scene check`). Default [`DEFAULT_MAX_ELEMENTS`] (at most ~2 GB).
    #[serde(skip_serializing, default = "default_max_elements")]
    pub max_elements: u64,
}

/// Merge angles are below this, degrees: faces at right angles never merge.
pub const MAX_ANGLE_TOL_DEG: Real = 90.0;

/// Default of [`MergeOptions::max_elements`]: 5 million vertices and 5 million faces.
pub const DEFAULT_MAX_ELEMENTS: u64 = 5_000_000;

fn default_max_elements() -> u64 {
    DEFAULT_MAX_ELEMENTS
}

impl Default for MergeOptions {
    fn default() -> Self {
        MergeOptions {
            angle_tol_deg: DEFAULT_ANGLE_TOL_DEG,
            dist_tol_m: DEFAULT_DIST_TOL_M,
            weld_tol_m: DEFAULT_WELD_TOL_M,
            max_elements: DEFAULT_MAX_ELEMENTS,
        }
    }
}

impl MergeOptions {
    /// Checks that every tolerance is finite and in range.
    pub fn validate(&self) -> Result<(), MergeError> {
        let bad = |detail: String| Err(MergeError::InvalidOptions { detail });
        if !(self.angle_tol_deg >= 0.0 && self.angle_tol_deg < MAX_ANGLE_TOL_DEG) {
            return bad(format!(
                "angle_tol_deg {} must be in [0, {MAX_ANGLE_TOL_DEG})",
                self.angle_tol_deg
            ));
        }
        if !(self.dist_tol_m >= 0.0 && self.dist_tol_m.is_finite()) {
            return bad(format!(
                "dist_tol_m {} must be finite and >= 0",
                self.dist_tol_m
            ));
        }
        if !(self.weld_tol_m >= 0.0 && self.weld_tol_m.is_finite()) {
            return bad(format!(
                "weld_tol_m {} must be finite and >= 0",
                self.weld_tol_m
            ));
        }
        Ok(())
    }
}

/// One bounded planar polygon made of coplanar, edge-connected mesh faces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshSurface {
    /// `<object>_<k>` with the OBJ object/group name (`face_<k>` when the face has none, as in
    /// every PLY file); `k` counts surfaces of that name from 0 in output order (a group split
    /// into pieces gives several).
    pub name: String,
    /// The OBJ `usemtl` material in effect for the faces, if any (no `.mtl` file is read).
    pub material: Option<String>,
    /// Boundary in metres, counter-clockwise seen from `normal` (right-hand rule gives
    /// `normal`), no repeated or collinear vertices, at least three, all on one plane; a
    /// simple polygon (no hole).
    pub vertices: Vec<Vec3>,
    /// Unit normal: the area-weighted average of the merged faces' normals, following the
    /// faces' winding (usually pointing into the room for exported interiors — whatever the
    /// file says).
    pub normal: Vec3,
    /// Area of the polygon `vertices` in m².
    pub area_m2: Real,
    /// Area in m² of the whole coplanar region this surface outlines a part of: the sum of
    /// `area_m2` over the surfaces of one group of merged faces (several when a region with
    /// holes was split into pieces, or touches itself at a vertex). Importers judge a surface's
    /// size by it, so that a piece of a large ground still reflects.
    pub region_area_m2: Real,
    /// Number of faces of the file merged into this surface.
    pub source_faces: usize,
}

/// What a mesh file yielded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshImport {
    /// Surfaces in the order of their first face in the file.
    pub surfaces: Vec<MeshSurface>,
    /// Human-readable notes about altered input (degenerate faces dropped, duplicates merged,
    /// faces split, ignored statements), each starting with the file name.
    pub warnings: Vec<String>,
    /// Number of faces in the file, before any was dropped or merged.
    pub faces_read: usize,
    /// Number of vertices in the file, before any was welded.
    pub vertices_read: usize,
}

/// Welds and merges the faces of `raw` into planar surfaces (checks `opts` first). `file`
/// names the source in warnings. The surfaces come in the order of their first face.
pub fn merge_mesh(
    raw: &RawMesh,
    opts: &MergeOptions,
    file: &str,
) -> Result<MeshImport, MergeError> {
    opts.validate()?;
    let merged = merge::merge(raw, opts, file);
    let mut warnings = raw.warnings.clone();
    warnings.extend(merged.warnings);
    Ok(MeshImport {
        surfaces: merged.surfaces,
        warnings,
        faces_read: raw.face_count(),
        vertices_read: raw.positions.len(),
    })
}
