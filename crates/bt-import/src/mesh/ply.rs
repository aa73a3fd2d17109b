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
    parse_with(bytes, file, max_elements, true)
}

/// [`parse`], with the [`Fast`] readings of binary elements when `fast` (the same result and
/// errors either way).
fn parse_with(
    bytes: &[u8],
    file: &str,
    max_elements: u64,
    fast: bool,
) -> Result<RawMesh, MeshError> {
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
        let fast = fast.then(|| Fast::of(&header, &layout, e)).flatten();
        for index in 0..element.count {
            if let Some(fast) = &fast
                && reader.fast_entry(fast, layout.vertex_count, &mut mesh)
            {
                continue;
            }
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

/// A binary element read without the general per-property reader: a vertex element of
/// scalars only (fixed records, `x`, `y`, `z` at fixed offsets), or a face element holding
/// nothing but its index list (San Francisco's terrain: 96,641 vertices, 192,000 faces).
/// An entry that could end in an error (data too short, a coordinate not finite, a list
/// shorter than three or an index out of range) is left to the general reader, so the
/// errors are the same.
enum Fast {
    Vertex {
        /// Bytes of one entry.
        record: usize,
        /// Offset in the entry and type of `x`, `y`, `z`.
        xyz: [(usize, Scalar); 3],
    },
    Face {
        count: Scalar,
        item: Scalar,
    },
}

impl Fast {
    /// The fast reading of element `e`, if it has one.
    fn of(header: &Header, layout: &Layout, e: usize) -> Option<Fast> {
        let properties = &header.elements[e].properties;
        if header.format == Format::Ascii {
            return None;
        }
        if e == layout.vertex_element {
            let mut offsets = Vec::with_capacity(properties.len());
            let mut record = 0;
            for property in properties {
                let Kind::Scalar(s) = property.kind else {
                    return None;
                };
                offsets.push((record, s));
                record += s.size();
            }
            let xyz = layout.xyz_slots.map(|slot| offsets[slot]);
            return Some(Fast::Vertex { record, xyz });
        }
        match properties.as_slice() {
            [only] if e == layout.face_element => match only.kind {
                Kind::List { count, item } if count.is_integer() => {
                    Some(Fast::Face { count, item })
                }
                _ => None,
            },
            _ => None,
        }
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

    /// One entry read the [`Fast`] way into `mesh`, or `false` with nothing
    /// read when the general reader must take it.
    fn fast_entry(&mut self, fast: &Fast, vertex_count: u64, mesh: &mut RawMesh) -> bool {
        let big = self.format.is_big_endian();
        let rest = &self.bytes[self.pos..];
        match *fast {
            Fast::Vertex { record, xyz } => {
                let Some(raw) = rest.get(..record) else {
                    return false;
                };
                let p = xyz.map(|(at, s)| s.decode(&raw[at..], big));
                if !p.iter().all(|v| v.is_finite()) {
                    return false;
                }
                mesh.positions.push(Vec3::from_array(p));
                self.pos += record;
            }
            Fast::Face { count, item } => {
                let Some(raw) = rest.get(..count.size()) else {
                    return false;
                };
                let n = count.decode(raw, big);
                if n < 3.0 {
                    return false;
                }
                let (n, size) = (n as usize, item.size());
                let end = n
                    .checked_mul(size)
                    .and_then(|b| b.checked_add(count.size()));
                let Some(list) = end.and_then(|end| rest.get(count.size()..end)) else {
                    return false;
                };
                // Straight into the mesh's index list (taken back if an index is out of
                // range), as `push_face` would append them.
                let start = mesh.indices.len();
                for k in 0..n {
                    let v = item.decode(&list[k * size..], big);
                    if !(v >= 0.0 && v < vertex_count as Real) {
                        mesh.indices.truncate(start);
                        return false;
                    }
                    mesh.indices.push(v as u32);
                }
                mesh.face_start.push(mesh.indices.len());
                mesh.face_name.push(None);
                mesh.face_material.push(None);
                self.pos += count.size() + n * size;
            }
        }
        true
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A binary PLY of `vertices` (x, y, z among extra properties, in the given types) and
    /// `faces` (an index list of the given count and item types, maybe beside a flag), cut
    /// short by `cut` bytes.
    #[allow(clippy::too_many_arguments)]
    fn binary_ply(
        big: bool,
        xyz: Scalar,
        extra: bool,
        count: Scalar,
        item: Scalar,
        flag: bool,
        vertices: &[[f64; 3]],
        faces: &[Vec<u32>],
        cut: usize,
    ) -> Vec<u8> {
        let name = |s: Scalar| match s {
            Scalar::U8 => "uchar",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            _ => "double",
        };
        let encoding = if big { "big" } else { "little" };
        let mut head = format!("ply\nformat binary_{encoding}_endian 1.0\n");
        head += &format!("element vertex {}\n", vertices.len());
        if extra {
            head += "property uchar red\n";
        }
        for axis in ["z", "x", "y"] {
            head += &format!("property {} {axis}\n", name(xyz));
        }
        head += &format!("element face {}\n", faces.len());
        if flag {
            head += "property uchar flag\n";
        }
        head += &format!(
            "property list {} {} vertex_indices\n",
            name(count),
            name(item)
        );
        head += "end_header\n";
        let mut body = head.into_bytes();
        let put = |body: &mut Vec<u8>, s: Scalar, v: f64| {
            let bytes: Vec<u8> = match s {
                Scalar::U8 => vec![v as u8],
                Scalar::U16 if big => (v as u16).to_be_bytes().to_vec(),
                Scalar::U16 => (v as u16).to_le_bytes().to_vec(),
                Scalar::I32 if big => (v as i32).to_be_bytes().to_vec(),
                Scalar::I32 => (v as i32).to_le_bytes().to_vec(),
                Scalar::U32 if big => (v as u32).to_be_bytes().to_vec(),
                Scalar::U32 => (v as u32).to_le_bytes().to_vec(),
                Scalar::F32 if big => (v as f32).to_be_bytes().to_vec(),
                Scalar::F32 => (v as f32).to_le_bytes().to_vec(),
                _ if big => v.to_be_bytes().to_vec(),
                _ => v.to_le_bytes().to_vec(),
            };
            body.extend(bytes);
        };
        for v in vertices {
            if extra {
                put(&mut body, Scalar::U8, 7.0);
            }
            for k in [2, 0, 1] {
                put(&mut body, xyz, v[k]);
            }
        }
        for f in faces {
            if flag {
                put(&mut body, Scalar::U8, 1.0);
            }
            put(&mut body, count, f.len() as f64);
            for &i in f {
                put(&mut body, item, f64::from(i));
            }
        }
        body.truncate(body.len().saturating_sub(cut));
        body
    }

    fn scalar(options: &'static [Scalar]) -> impl Strategy<Value = Scalar> {
        proptest::sample::select(options)
    }

    proptest! {
        /// The fast readings give what the general reader gives: the same soup, or the same
        /// error (data cut short, coordinates not finite, short faces, indices out of range).
        #[test]
        fn fast_binary_reading_matches_the_general_reader(
            big in any::<bool>(),
            xyz in scalar(&[Scalar::F32, Scalar::F64, Scalar::I32]),
            extra in any::<bool>(),
            count in scalar(&[Scalar::U8, Scalar::U16, Scalar::I32, Scalar::U32]),
            item in scalar(&[Scalar::I32, Scalar::U32, Scalar::U16]),
            flag in any::<bool>(),
            vertices in proptest::collection::vec(
                proptest::array::uniform3(prop_oneof![
                    20 => -1e3f64..1e3,
                    1 => Just(f64::NAN),
                    1 => Just(f64::INFINITY),
                ]),
                1..8,
            ),
            faces in proptest::collection::vec(proptest::collection::vec(0u32..9, 0..6), 0..8),
            cut in prop_oneof![4 => Just(0usize), 1 => 0usize..12],
        ) {
            let bytes = binary_ply(big, xyz, extra, count, item, flag, &vertices, &faces, cut);
            let show = |r: Result<RawMesh, MeshError>| match r {
                Ok(mesh) => format!("{mesh:?}"),
                Err(e) => format!("error: {e}"),
            };
            let fast = show(parse_with(&bytes, "t.ply", 1000, true));
            let general = show(parse_with(&bytes, "t.ply", 1000, false));
            prop_assert_eq!(fast, general);
        }
    }
}
