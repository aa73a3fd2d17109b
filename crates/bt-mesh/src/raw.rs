//! The parsed, validated mesh that both readers produce and the merge consumes.

use bt_geom::Vec3;
/// A polygon soup as read from a file: finite positions, faces of at least three in-range
/// vertex indices, and per-face object and material names (interned).
#[derive(Debug, Default)]
pub(crate) struct RawMesh {
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
    pub fn new() -> Self {
        RawMesh {
            face_start: vec![0],
            ..Default::default()
        }
    }

    pub fn face_count(&self) -> usize {
        self.face_start.len() - 1
    }

    pub fn face(&self, f: usize) -> &[u32] {
        &self.indices[self.face_start[f]..self.face_start[f + 1]]
    }

    pub fn push_face(&mut self, vertices: &[u32], name: Option<u32>, material: Option<u32>) {
        self.indices.extend_from_slice(vertices);
        self.face_start.push(self.indices.len());
        self.face_name.push(name);
        self.face_material.push(material);
    }
}

/// Returns the index of `name` in `table`, appending it when new. Linear search: files have a
/// handful of objects and materials, and the reader caches the current one.
pub(crate) fn intern(table: &mut Vec<String>, name: &str) -> u32 {
    match table.iter().position(|n| n == name) {
        Some(i) => i as u32,
        None => {
            table.push(name.to_owned());
            (table.len() - 1) as u32
        }
    }
}
