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

/// Refuse the next element of kind `element` (`vertices` or `faces`) of an OBJ file when
/// `so_far` of them already fill the budget `max_elements`.
pub(crate) fn check_budget(
    file: &str,
    element: &'static str,
    so_far: usize,
    max_elements: u64,
    line: usize,
) -> Result<(), crate::MeshError> {
    if (so_far as u64) < max_elements {
        return Ok(());
    }
    Err(crate::MeshError::Budget {
        file: file.to_owned(),
        element,
        count: format!("at least {} (line {line})", max_elements.saturating_add(1)),
        budget: max_elements,
    })
}
