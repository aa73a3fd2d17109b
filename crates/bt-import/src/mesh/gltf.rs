//! glTF 2.0 scenes (`.gltf` JSON, `.glb` binary): the scene models of MATLAB's `raytrace`
//! (besides STL) and of most 3-D tools' exports.
//!
//! The `gltf` crate parses the document and the GLB container and checks its references; the
//! vertex data is read here, with every offset, stride and count checked against its buffer
//! (a hostile file is an error, never a read out of bounds or a huge allocation).
//!
//! - **What is read**: the default scene (else the first; else every root node), its nodes'
//!   meshes under their transforms (matrix, or translation · rotation · scale, composed down
//!   the hierarchy), and of each primitive in mode triangles, triangle strip or fan the
//!   `POSITION` accessor (float32 `VEC3`) and its indices (unsigned 8, 16 or 32 bit). Points
//!   and lines are skipped with a warning; morph targets and skins are ignored (the rest
//!   pose). A node's name (else its mesh's) names its surfaces, a primitive's material's
//!   name is their material (names of the ITU table such as `itu_concrete` or `concrete` get
//!   that radio model, as in OBJ).
//! - **Buffers**: a GLB's binary chunk, `data:` URIs (base64), or files next to the scene
//!   (relative URIs, percent-escapes decoded; absolute paths, `..` and other schemes are
//!   refused); each within the file-size budget.
//! - **Frame**: glTF is metres with +Y up; beamtrace has +Z up, so `(x, y, z)` becomes
//!   `(x, −z, y)` (a quarter turn about x, as Blender imports glTF).

use super::{MeshError, Position, intern};
use bt_geom::Vec3;
use bt_mesh::RawMesh;
use glam::{DMat4, DQuat, DVec3, DVec4};
use std::path::{Component, Path, PathBuf};

/// Deepest node hierarchy followed (a deeper one, or a cycle, is an error).
const MAX_DEPTH: usize = 64;

/// A parsed glTF document and the bytes of its buffers, in the document's order.
pub(crate) struct Document {
    gltf: gltf::Gltf,
    /// Per buffer, its bytes; `None`: the GLB's binary chunk (`gltf.blob`, not copied).
    buffers: Vec<Option<Vec<u8>>>,
    /// The external files read for buffers (in the scene's folder), in the document's order.
    pub(crate) files: Vec<PathBuf>,
    /// Their SHA-256s, with hashing on (else empty).
    pub(crate) digests: Vec<crate::source::Digest>,
}

impl Document {
    /// The bytes of buffer `index` (a GLB chunk's presence was checked by [`document`]).
    fn buffer(&self, index: usize) -> &[u8] {
        let own = self.buffers[index].as_deref();
        own.or(self.gltf.blob.as_deref()).unwrap_or_default()
    }
}

fn syntax(file: &str, position: Position, detail: String) -> MeshError {
    MeshError::Syntax {
        file: file.to_owned(),
        position,
        detail,
    }
}

fn unsupported(file: &str, detail: String) -> MeshError {
    MeshError::Unsupported {
        file: file.to_owned(),
        detail,
    }
}

/// Parse `bytes` (a `.gltf` or `.glb` file named `file`, in `folder`) and read its buffers,
/// each file within `max_file_bytes`, hashing the files read with `hashing` on. Without a
/// folder no file is read: a buffer must be a `data:` URI or the GLB binary chunk.
pub(crate) fn document(
    bytes: &[u8],
    (file, folder): (&str, Option<&Path>),
    max_file_bytes: u64,
    hashing: crate::source::Hashing,
) -> Result<Document, MeshError> {
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| match e {
        gltf::Error::Deserialize(json) => syntax(
            file,
            Position::Line(json.line()),
            format!("glTF JSON: {json}"),
        ),
        other => syntax(
            file,
            Position::Line(1),
            format!("not a valid glTF file: {other}"),
        ),
    })?;
    let (mut buffers, mut files, mut digests) = (Vec::new(), Vec::new(), Vec::new());
    for buffer in gltf.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => None,
            gltf::buffer::Source::Uri(uri) => {
                let (data, read) = uri_bytes(uri, file, folder, max_file_bytes)?;
                if let Some(path) = read {
                    digests.extend(hashing.of(&data));
                    files.push(path);
                }
                Some(data)
            }
        };
        let found = match &data {
            Some(data) => data.len(),
            None => (gltf.blob.as_ref()).map(Vec::len).ok_or_else(|| {
                let detail = format!("buffer {} has no GLB binary chunk", buffer.index());
                unsupported(file, detail)
            })?,
        };
        if found < buffer.length() {
            return Err(MeshError::Truncated {
                file: file.to_owned(),
                position: Position::Element {
                    element: "buffer".to_owned(),
                    index: buffer.index() as u64,
                    line: None,
                },
                detail: format!("{} bytes declared, {found} found", buffer.length()),
            });
        }
        buffers.push(data);
    }
    Ok(Document {
        gltf,
        buffers,
        files,
        digests,
    })
}

/// A buffer's bytes from a `data:` URI, or read from the relative file it names (then also
/// that file's path).
fn uri_bytes(
    uri: &str,
    file: &str,
    folder: Option<&Path>,
    max_file_bytes: u64,
) -> Result<(Vec<u8>, Option<PathBuf>), MeshError> {
    if let Some(data) = uri.strip_prefix("data:") {
        let Some((_, encoded)) = data.split_once(";base64,") else {
            return Err(unsupported(
                file,
                "a data: URI that is not base64".to_owned(),
            ));
        };
        use base64::Engine as _;
        let decoded = base64::engine::general_purpose::STANDARD
            .decode(encoded)
            .map_err(|e| syntax(file, Position::Line(1), format!("data: URI: {e}")))?;
        return Ok((decoded, None));
    }
    let relative = PathBuf::from(percent_decoded(uri, file)?);
    let confined = relative
        .components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    if uri.contains(':') || !confined {
        return Err(unsupported(
            file,
            format!(
                "buffer URI \"{}\": only data: URIs and files in the scene's folder are read",
                bt_scene::name::shown(uri)
            ),
        ));
    }
    let Some(folder) = folder else {
        return Err(unsupported(
            file,
            format!(
                "buffer URI \"{}\": glTF read from bytes has no folder (only data: URIs and the GLB chunk)",
                bt_scene::name::shown(uri)
            ),
        ));
    };
    let path = folder.join(&relative);
    let bytes = super::read_bytes(&path, max_file_bytes)?;
    Ok((bytes, Some(path)))
}

/// `uri` with its `%XX` escapes decoded.
fn percent_decoded(uri: &str, file: &str) -> Result<String, MeshError> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3).unwrap_or_default());
            let byte = hex.ok().and_then(|h| u8::from_str_radix(h, 16).ok());
            let byte = byte.ok_or_else(|| {
                syntax(
                    file,
                    Position::Line(1),
                    format!("bad %-escape in URI \"{uri}\""),
                )
            })?;
            out.push(byte);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| {
        syntax(
            file,
            Position::Line(1),
            format!("URI \"{uri}\" is not UTF-8"),
        )
    })
}

/// The polygon soup of `doc`'s scene (module docs), in beamtrace's frame; refuses more than
/// `max_elements` faces.
pub(crate) fn parse(doc: &Document, file: &str, max_elements: u64) -> Result<RawMesh, MeshError> {
    let mut walk = Walk {
        doc,
        file,
        max_elements,
        mesh: RawMesh::new(),
        skipped: 0,
        visits: 0,
    };
    let gltf = &doc.gltf;
    let roots: Vec<gltf::Node<'_>> = match gltf.default_scene().or_else(|| gltf.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let children: std::collections::HashSet<usize> = (gltf.nodes())
                .flat_map(|n| n.children().map(|c| c.index()))
                .collect();
            (gltf.nodes())
                .filter(|n| !children.contains(&n.index()))
                .collect()
        }
    };
    // glTF's +Y up to beamtrace's +Z up: (x, y, z) to (x, −z, y), exactly (no rounded cosine).
    let up = DMat4::from_cols(DVec4::X, DVec4::Z, DVec4::NEG_Y, DVec4::W);
    for node in roots {
        walk.node(&node, up, 0)?;
    }
    if walk.skipped > 0 {
        walk.mesh.warnings.push(format!(
            "{file}: {} primitives of points or lines skipped (only triangles reflect)",
            walk.skipped
        ));
    }
    Ok(walk.mesh)
}

/// The traversal of a scene's node hierarchy into one soup.
struct Walk<'d> {
    doc: &'d Document,
    file: &'d str,
    max_elements: u64,
    mesh: RawMesh,
    /// Primitives that are not triangles.
    skipped: usize,
    /// Nodes visited: more than the document has means a node with two parents (or a cycle),
    /// which glTF forbids and which could multiply the work without bound.
    visits: usize,
}

impl Walk<'_> {
    /// Add `node`'s mesh under `parent · node's transform`, then its children's.
    fn node(
        &mut self,
        node: &gltf::Node<'_>,
        parent: DMat4,
        depth: usize,
    ) -> Result<(), MeshError> {
        self.visits += 1;
        if depth >= MAX_DEPTH || self.visits > self.doc.gltf.nodes().len() {
            return Err(unsupported(
                self.file,
                format!(
                    "node {}: a hierarchy deeper than {MAX_DEPTH}, a cycle or a node with two \
                     parents",
                    node.index()
                ),
            ));
        }
        let world = parent * local(node.transform());
        if let Some(mesh) = node.mesh() {
            let name = node.name().or(mesh.name());
            let name = name.map(|n| intern(&mut self.mesh.names, n));
            for primitive in mesh.primitives() {
                self.primitive(&primitive, world, name)?;
            }
        }
        for child in node.children() {
            self.node(&child, world, depth + 1)?;
        }
        Ok(())
    }

    /// Add `primitive`'s triangles, mapped by `world`, as faces named `name`.
    fn primitive(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        world: DMat4,
        name: Option<u32>,
    ) -> Result<(), MeshError> {
        use gltf::mesh::Mode;
        let mode = primitive.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.skipped += 1;
            return Ok(());
        }
        let Some(positions) = primitive.get(&gltf::Semantic::Positions) else {
            return Ok(());
        };
        let first = self.mesh.positions.len();
        if first.saturating_add(positions.count()) as u64 > self.max_elements {
            return Err(MeshError::Budget {
                file: self.file.to_owned(),
                element: "vertices",
                count: format!("more than {}", self.max_elements),
                budget: self.max_elements,
            });
        }
        for p in self.vec3s(&positions)? {
            let p = world.transform_point3(p);
            self.mesh.positions.push(Vec3::new(p.x, p.y, p.z));
        }
        let count = self.mesh.positions.len() - first;
        let indices = match primitive.indices() {
            Some(accessor) => self.indices(&accessor, count)?,
            None => (0..count as u32).collect(),
        };
        let material = primitive.material().name();
        let material = material.map(|m| intern(&mut self.mesh.materials, m));
        for t in triangles(mode, &indices) {
            if self.mesh.face_count() as u64 >= self.max_elements {
                return Err(MeshError::Budget {
                    file: self.file.to_owned(),
                    element: "faces",
                    count: format!("more than {}", self.max_elements),
                    budget: self.max_elements,
                });
            }
            let face = t.map(|i| first as u32 + i);
            self.mesh.push_face(&face, name, material);
        }
        Ok(())
    }
}

/// A node's local transform, in f64.
fn local(transform: gltf::scene::Transform) -> DMat4 {
    match transform {
        gltf::scene::Transform::Matrix { matrix } => {
            DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => DMat4::from_scale_rotation_translation(
            DVec3::from_array(scale.map(f64::from)),
            DQuat::from_array(rotation.map(f64::from)).normalize(),
            DVec3::from_array(translation.map(f64::from)),
        ),
    }
}

/// The corners of each triangle of a primitive in `mode` with these `indices`.
fn triangles(mode: gltf::mesh::Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    use gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .map(|k| match k % 2 {
                0 => [indices[k], indices[k + 1], indices[k + 2]],
                _ => [indices[k + 1], indices[k], indices[k + 2]],
            })
            .collect(),
        Mode::TriangleFan => (1..indices.len().saturating_sub(1))
            .map(|k| [indices[0], indices[k], indices[k + 1]])
            .collect(),
        _ => indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
    }
}

impl Walk<'_> {
    /// The bytes of `accessor`'s elements: (data, start of element 0, stride), every element of
    /// `element_bytes` checked to lie inside its buffer view and buffer.
    fn elements(
        &self,
        accessor: &gltf::Accessor<'_>,
        element_bytes: usize,
    ) -> Result<(&[u8], usize, usize), MeshError> {
        let at = || Position::Element {
            element: "accessor".to_owned(),
            index: accessor.index() as u64,
            line: None,
        };
        let bad = |detail: &str| syntax(self.file, at(), detail.to_owned());
        if accessor.sparse().is_some() {
            return Err(unsupported(
                self.file,
                format!("sparse accessor {}", accessor.index()),
            ));
        }
        let view = accessor.view().ok_or_else(|| bad("no buffer view"))?;
        let buffer = self.doc.buffer(view.buffer().index());
        let stride = view.stride().unwrap_or(element_bytes);
        let view_end = view.offset().checked_add(view.length());
        let view_bytes = view_end
            .and_then(|end| buffer.get(view.offset()..end))
            .ok_or_else(|| bad("buffer view beyond its buffer"))?;
        let count = accessor.count();
        let last = (count.checked_sub(1))
            .and_then(|n| n.checked_mul(stride))
            .and_then(|n| n.checked_add(accessor.offset()))
            .and_then(|n| n.checked_add(element_bytes));
        if count > 0 && last.is_none_or(|end| end > view_bytes.len()) || stride < element_bytes {
            return Err(bad("elements beyond the buffer view"));
        }
        Ok((view_bytes, accessor.offset(), stride))
    }

    /// The points of a float32 `VEC3` accessor, in glTF's frame.
    fn vec3s(&self, accessor: &gltf::Accessor<'_>) -> Result<Vec<DVec3>, MeshError> {
        use gltf::accessor::{DataType, Dimensions};
        if accessor.data_type() != DataType::F32 || accessor.dimensions() != Dimensions::Vec3 {
            return Err(unsupported(
                self.file,
                format!("POSITION accessor {} is not float32 VEC3", accessor.index()),
            ));
        }
        let (bytes, start, stride) = self.elements(accessor, 12)?;
        let f = |at: usize| {
            f64::from(f32::from_le_bytes(
                bytes[at..at + 4].try_into().unwrap_or_default(),
            ))
        };
        let mut out = Vec::with_capacity(accessor.count());
        for k in 0..accessor.count() {
            let at = start + k * stride;
            let p = DVec3::new(f(at), f(at + 4), f(at + 8));
            if !p.is_finite() {
                return Err(MeshError::NonFiniteCoordinate {
                    file: self.file.to_owned(),
                    position: Position::Element {
                        element: "vertex".to_owned(),
                        index: k as u64,
                        line: None,
                    },
                    axis: ['x', 'y', 'z'][(0..3).find(|&a| !p[a].is_finite()).unwrap_or(0)],
                    value: p
                        .to_array()
                        .into_iter()
                        .find(|v| !v.is_finite())
                        .unwrap_or(0.0),
                });
            }
            out.push(p);
        }
        Ok(out)
    }

    /// The vertex indices of an index accessor, each checked below `count`.
    fn indices(&self, accessor: &gltf::Accessor<'_>, count: usize) -> Result<Vec<u32>, MeshError> {
        use gltf::accessor::DataType;
        let size = match accessor.data_type() {
            DataType::U8 => 1,
            DataType::U16 => 2,
            DataType::U32 => 4,
            other => {
                return Err(unsupported(self.file, format!("indices of type {other:?}")));
            }
        };
        let (bytes, start, stride) = self.elements(accessor, size)?;
        let mut out = Vec::with_capacity(accessor.count());
        for k in 0..accessor.count() {
            let at = start + k * stride;
            let mut word = [0u8; 4];
            word[..size].copy_from_slice(&bytes[at..at + size]);
            let index = u32::from_le_bytes(word);
            if index as usize >= count {
                return Err(MeshError::IndexOutOfRange {
                    file: self.file.to_owned(),
                    position: Position::Element {
                        element: "accessor".to_owned(),
                        index: accessor.index() as u64,
                        line: None,
                    },
                    index: i64::from(index),
                    vertex_count: count,
                });
            }
            out.push(index);
        }
        Ok(out)
    }
}
