//! The polygon soup the readers of `bt-import` produce and the merge consumes.

use bt_geom::Vec3;

/// A polygon soup as read from a file: finite positions, faces of at least three in-range
/// vertex indices, and per-face object and material names (interned). Readers keep these
/// invariants; [`crate::merge_mesh`] relies on them.
#[derive(Debug, Clone, Default)]
pub struct RawMesh {
    /// Vertex positions in metres, all finite.
    pub positions: Vec<Vec3>,
    /// Concatenated face vertex indices into `positions`.
    pub indices: Vec<u32>,
    /// Face `f` uses `indices[face_start[f]..face_start[f + 1]]`; `len() == faces + 1`.
    pub face_start: Vec<usize>,
    /// Per face: index into `names`, if the face belongs to a named object or group.
    pub face_name: Vec<Option<u32>>,
    /// Per face: index into `materials`, if a material was in effect.
    pub face_material: Vec<Option<u32>>,
    /// Interned object/group names.
    pub names: Vec<String>,
    /// Interned material names.
    pub materials: Vec<String>,
    /// Reader warnings (already prefixed with the file name).
    pub warnings: Vec<String>,
}

impl RawMesh {
    /// An empty soup.
    pub fn new() -> Self {
        RawMesh {
            face_start: vec![0],
            ..Default::default()
        }
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.face_start.len() - 1
    }

    /// The vertex indices of face `f`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.indices[self.face_start[f]..self.face_start[f + 1]]
    }

    /// Appends a face (indices into `positions`) with its interned name and material.
    pub fn push_face(&mut self, vertices: &[u32], name: Option<u32>, material: Option<u32>) {
        self.indices.extend_from_slice(vertices);
        self.face_start.push(self.indices.len());
        self.face_name.push(name);
        self.face_material.push(material);
    }
}
