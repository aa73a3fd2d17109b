//! PLY mesh reader (ASCII, binary little endian, binary big endian).
//!
//! The header is parsed by the one PLY grammar of [`crate::formats`] (shared with the cloud reader) and the body
//! here, rather than by `ply-rs`, so that every element count is checked against the body
//! length before anything is allocated: a header claiming billions of vertices
//! in a small file is an error, not an out-of-memory abort. Only `vertex` (`x`, `y`, `z` of any
//! scalar type; other properties skipped) and `face` (`vertex_indices` or `vertex_index` list
//! with integer count and index types; other properties skipped) are used; other elements are
//! read and skipped.

use super::{MeshError, Position};
use bt_geom::{Real, Vec3};
use bt_mesh::RawMesh;

use crate::formats::{
    PlyFormat as Format, PlyHeader as Header, PlyHeaderError, PlyHeaderErrorKind,
    PlyPropertyKind as Kind, Scalar,
};

/// Parses PLY bytes into a validated polygon soup; refuses a header declaring more than `max_elements` vertices or faces.
pub(crate) fn parse(bytes: &[u8], file: &str, max_elements: u64) -> Result<RawMesh, MeshError> {
    let header = parse_header(bytes, file)?;
    let body = &bytes[header.body_start..];
    check_counts(&header, body.len() as u64, file)?;
    check_budget(&header, file, max_elements)?;
    let layout = Layout::of(&header, file)?;

    let mut mesh = RawMesh::new();
    // Counts were checked against the body length above, so these reservations are bounded by
    // the file size.
    mesh.positions.reserve(layout.vertex_count as usize);
    let face_count = header.elements[layout.face_element].count as usize;
    mesh.face_start.reserve(face_count);
    mesh.indices.reserve(face_count.saturating_mul(3));
    mesh.face_name.reserve(face_count);
    mesh.face_material.reserve(face_count);

    let mut reader = Reader {
        bytes: body,
        pos: 0,
        format: header.format,
        line: header.lines + 1,
        file,
    };
    let mut values: Vec<Real> = Vec::new();
    let mut face: Vec<u32> = Vec::new();
    for (e, element) in header.elements.iter().enumerate() {
        let indices = (e == layout.face_element).then_some(layout.index_slot);
        for index in 0..element.count {
            reader.skip_space();
            // Where the entry starts, built only for an error (a `String` per vertex and face
            // was most of a city's small allocations).
            let line = (header.format == Format::Ascii).then_some(reader.line);
            let start = At {
                element: &element.name,
                index,
                line,
            };
            let entry = Entry {
                values: &mut values,
                face: &mut face,
                at: start,
            };
            reader.entry(element, indices, layout.vertex_count, entry)?;
            if e == layout.vertex_element {
                mesh.positions.push(layout.position(&values, file, start)?);
            } else if e == layout.face_element {
                if face.len() < 3 {
                    return Err(MeshError::FaceTooSmall {
                        file: file.to_owned(),
                        position: start.position(),
                        count: face.len(),
                    });
                }
                mesh.push_face(&face, None, None);
            }
        }
    }
    Ok(mesh)
}

/// Where the reader finds what it uses: the vertex and face elements, the slots of `x`, `y`,
/// `z` among the vertex properties and of the index list among the face properties.
struct Layout {
    vertex_element: usize,
    face_element: usize,
    xyz_slots: [usize; 3],
    index_slot: usize,
    vertex_count: u64,
}

impl Layout {
    /// The layout of `header`, or why this reader cannot use it (`Unsupported`).
    fn of(header: &Header, file: &str) -> Result<Layout, MeshError> {
        let unsupported = |detail: String| MeshError::Unsupported {
            file: file.to_owned(),
            detail,
        };
        let element = |name: &str| header.elements.iter().position(|e| e.name == name);
        let vertex_element =
            element("vertex").ok_or_else(|| unsupported("no \"vertex\" element".into()))?;
        let face_element = element("face").ok_or_else(|| {
            unsupported("no \"face\" element: point clouds are not meshes".into())
        })?;
        let mut xyz_slots = [0; 3];
        for (slot, axis) in xyz_slots.iter_mut().zip(["x", "y", "z"]) {
            *slot = header.elements[vertex_element]
                .properties
                .iter()
                .position(|p| p.name == axis && matches!(p.kind, Kind::Scalar(_)))
                .ok_or_else(|| {
                    unsupported(format!("vertex element has no scalar property {axis:?}"))
                })?;
        }
        let index_slot = header.elements[face_element]
            .properties
            .iter()
            .position(|p| {
                (p.name == "vertex_indices" || p.name == "vertex_index")
                    && matches!(p.kind, Kind::List { .. })
            })
            .ok_or_else(|| {
                unsupported(
                    "face element has no \"vertex_indices\" or \"vertex_index\" list".into(),
                )
            })?;
        if let Kind::List { item, .. } = header.elements[face_element].properties[index_slot].kind
            && !item.is_integer()
        {
            return Err(unsupported(
                "face vertex list must use an integer index type".into(),
            ));
        }
        let vertex_count = header.elements[vertex_element].count;
        if vertex_count > u64::from(u32::MAX) {
            return Err(unsupported(format!("more than {} vertices", u32::MAX)));
        }
        Ok(Layout {
            vertex_element,
            face_element,
            xyz_slots,
            index_slot,
            vertex_count,
        })
    }

    /// The vertex position among one vertex entry's `values` (all finite).
    fn position(&self, values: &[Real], file: &str, at: At<'_>) -> Result<Vec3, MeshError> {
        let mut xyz = [0.0; 3];
        for (k, (&slot, axis)) in self.xyz_slots.iter().zip(['x', 'y', 'z']).enumerate() {
            let value = values[slot];
            if !value.is_finite() {
                return Err(MeshError::NonFiniteCoordinate {
                    file: file.to_owned(),
                    position: at.position(),
                    axis,
                    value,
                });
            }
            xyz[k] = value;
        }
        Ok(Vec3::from_array(xyz))
    }
}

/// What reading one entry fills: each property's value (a list's length for a list), the
/// face's vertex indices when the entry is a face, and the entry's position for errors.
struct Entry<'a> {
    values: &'a mut Vec<Real>,
    face: &'a mut Vec<u32>,
    at: At<'a>,
}

/// Where an entry starts, as [`Position::Element`] without its owned name.
#[derive(Clone, Copy)]
struct At<'a> {
    element: &'a str,
    index: u64,
    line: Option<usize>,
}

impl At<'_> {
    /// The position for an error message.
    fn position(self) -> Position {
        Position::Element {
            element: self.element.to_owned(),
            index: self.index,
            line: self.line,
        }
    }
}

/// Refuses a header declaring more than `max_elements` vertices or faces, before allocating.
fn check_budget(header: &Header, file: &str, max_elements: u64) -> Result<(), MeshError> {
    for (name, element) in [("vertex", "vertices"), ("face", "faces")] {
        let declared = header.elements.iter().filter(|e| e.name == name);
        if let Some(e) = declared.into_iter().find(|e| e.count > max_elements) {
            return Err(MeshError::Budget {
                file: file.to_owned(),
                element,
                count: e.count.to_string(),
                budget: max_elements,
            });
        }
    }
    Ok(())
}

/// The header through the one PLY grammar; its errors keep this reader's variants: an
/// encoding or version it cannot read is `Unsupported`, a missing `end_header` `Truncated`.
fn parse_header(bytes: &[u8], file: &str) -> Result<Header, MeshError> {
    Header::parse(bytes).map_err(|PlyHeaderError { line, kind }| {
        let file = file.to_owned();
        let detail = kind.to_string();
        match kind {
            k if k.is_unsupported() => MeshError::Unsupported { file, detail },
            PlyHeaderErrorKind::NoEndHeader => MeshError::Truncated {
                file,
                position: Position::Line(line),
                detail,
            },
            _ => MeshError::Syntax {
                file,
                position: Position::Line(line),
                detail,
            },
        }
    })
}

/// Rejects headers whose element counts cannot fit in the body, before any allocation.
fn check_counts(header: &Header, body_bytes: u64, file: &str) -> Result<(), MeshError> {
    let mut needed = 0u64;
    for element in &header.elements {
        if element.properties.is_empty() && element.count > 0 {
            return Err(MeshError::Unsupported {
                file: file.to_owned(),
                detail: format!(
                    "element \"{}\" has no properties",
                    bt_scene::name::shown(&element.name)
                ),
            });
        }
        let min_bytes = element
            .count
            .saturating_mul(element.min_bytes(header.format));
        // An ASCII body may omit the final separator.
        let slack = u64::from(header.format == Format::Ascii && min_bytes > 0);
        needed = needed.saturating_add(min_bytes);
        if needed.saturating_sub(slack) > body_bytes {
            return Err(MeshError::CountTooLarge {
                file: file.to_owned(),
                element: element.name.clone(),
                count: element.count,
                min_bytes: needed,
                body_bytes,
            });
        }
    }
    Ok(())
}

/// Reads scalars from a PLY body, tracking the line number in ASCII bodies.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: Format,
    line: usize,
    file: &'a str,
}

impl Reader<'_> {
    fn skip_space(&mut self) {
        if self.format != Format::Ascii {
            return;
        }
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// Reads one entry of `element`; the list in slot `indices` (the face's vertex indices)
    /// is collected into `entry.face`, each index checked against `vertex_count`.
    fn entry(
        &mut self,
        element: &crate::formats::PlyElement,
        indices: Option<usize>,
        vertex_count: u64,
        entry: Entry<'_>,
    ) -> Result<(), MeshError> {
        let Entry { values, face, at } = entry;
        values.clear();
        for (slot, property) in element.properties.iter().enumerate() {
            match property.kind {
                Kind::Scalar(s) => values.push(self.read(s, &property.name, at)?),
                Kind::List { count, item } => {
                    let n = self.read(count, &property.name, at)?;
                    if n < 0.0 {
                        return Err(MeshError::Syntax {
                            file: self.file.to_owned(),
                            position: at.position(),
                            detail: format!(
                                "list \"{}\" has negative length {n}",
                                bt_scene::name::shown(&property.name)
                            ),
                        });
                    }
                    let collect = indices == Some(slot);
                    if collect {
                        face.clear();
                    }
                    // No reservation by `n`: every read consumes input, so a huge count
                    // ends in a truncation error, not an allocation.
                    for _ in 0..n as u64 {
                        let v = self.read(item, &property.name, at)?;
                        if collect {
                            if v < 0.0 || v >= vertex_count as Real {
                                return Err(MeshError::IndexOutOfRange {
                                    file: self.file.to_owned(),
                                    position: at.position(),
                                    index: v as i64,
                                    vertex_count: vertex_count as usize,
                                });
                            }
                            face.push(v as u32);
                        }
                    }
                    values.push(n);
                }
            }
        }
        Ok(())
    }

    /// One scalar of type `ty` as f64 (exact for every PLY integer type).
    fn read(&mut self, ty: Scalar, property: &str, at: At<'_>) -> Result<Real, MeshError> {
        let truncated = || MeshError::Truncated {
            file: self.file.to_owned(),
            position: at.position(),
            detail: format!(
                "data ends while reading property \"{}\"",
                bt_scene::name::shown(property)
            ),
        };
        match self.format {
            Format::Ascii => {
                self.skip_space();
                let start = self.pos;
                while self
                    .bytes
                    .get(self.pos)
                    .is_some_and(|b| !b.is_ascii_whitespace())
                {
                    self.pos += 1;
                }
                if start == self.pos {
                    return Err(truncated());
                }
                let token = String::from_utf8_lossy(&self.bytes[start..self.pos]);
                let value = if ty.is_integer() {
                    token.parse::<i64>().ok().map(|v| v as Real)
                } else {
                    token.parse::<Real>().ok()
                };
                value.ok_or_else(|| MeshError::Syntax {
                    file: self.file.to_owned(),
                    position: at.position(),
                    detail: format!(
                        "property \"{}\": \"{}\" is not a valid {ty:?} value",
                        bt_scene::name::shown(property),
                        bt_scene::name::shown(&token)
                    ),
                })
            }
            Format::BinaryLittleEndian | Format::BinaryBigEndian => {
                let size = ty.size();
                let raw = self
                    .bytes
                    .get(self.pos..self.pos + size)
                    .ok_or_else(truncated)?;
                self.pos += size;
                Ok(ty.decode(raw, self.format.is_big_endian()))
            }
        }
    }
}
