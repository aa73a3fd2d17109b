//! PLY mesh reader (ASCII, binary little endian, binary big endian).
//!
//! The header is parsed here rather than by `ply-rs` so that every element count is checked
//! against the body length before anything is allocated: a header claiming billions of vertices
//! in a small file is an error, not an out-of-memory abort. Only `vertex` (`x`, `y`, `z` of any
//! scalar type; other properties skipped) and `face` (`vertex_indices` or `vertex_index` list
//! with integer count and index types; other properties skipped) are used; other elements are
//! read and skipped.

use crate::error::{MeshError, Position};
use crate::raw::RawMesh;
use bt_geom::{Real, Vec3};

use bt_formats::{PlyFormat as Format, Scalar};

#[derive(Debug, Clone, Copy)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

impl Element {
    /// Fewest body bytes one entry can occupy: binary scalars at their size and list counts
    /// with zero items; in ASCII one character plus one separator per property.
    fn min_bytes(&self, format: Format) -> u64 {
        self.properties
            .iter()
            .map(|p| match (format, p.kind) {
                (Format::Ascii, _) => 2,
                (_, Kind::Scalar(s)) | (_, Kind::List { count: s, .. }) => s.size() as u64,
            })
            .sum()
    }
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body_start: usize,
    /// Number of header lines (the body's first line is `lines + 1`).
    lines: usize,
}

/// Parses PLY bytes into a validated polygon soup.
/// Parse a PLY mesh; refuses a header declaring more than `max_elements` vertices or faces.
pub(crate) fn parse(bytes: &[u8], file: &str, max_elements: u64) -> Result<RawMesh, MeshError> {
    let header = parse_header(bytes, file)?;
    let body = &bytes[header.body_start..];
    check_counts(&header, body.len() as u64, file)?;
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

    let unsupported = |detail: String| MeshError::Unsupported {
        file: file.to_owned(),
        detail,
    };
    let vertex_element = header
        .elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| unsupported("no \"vertex\" element".into()))?;
    let face_element = header
        .elements
        .iter()
        .position(|e| e.name == "face")
        .ok_or_else(|| unsupported("no \"face\" element: point clouds are not meshes".into()))?;
    let xyz_slots: Vec<usize> = ["x", "y", "z"]
        .iter()
        .map(|axis| {
            header.elements[vertex_element]
                .properties
                .iter()
                .position(|p| p.name == *axis && matches!(p.kind, Kind::Scalar(_)))
                .ok_or_else(|| {
                    unsupported(format!("vertex element has no scalar property {axis:?}"))
                })
        })
        .collect::<Result<_, _>>()?;
    let index_slot = header.elements[face_element]
        .properties
        .iter()
        .position(|p| {
            (p.name == "vertex_indices" || p.name == "vertex_index")
                && matches!(p.kind, Kind::List { .. })
        })
        .ok_or_else(|| {
            unsupported("face element has no \"vertex_indices\" or \"vertex_index\" list".into())
        })?;
    if let Kind::List { item, .. } = header.elements[face_element].properties[index_slot].kind {
        if !item.is_integer() {
            return Err(unsupported(
                "face vertex list must use an integer index type".into(),
            ));
        }
    }
    let vertex_count = header.elements[vertex_element].count;
    if vertex_count > u64::from(u32::MAX) {
        return Err(unsupported(format!("more than {} vertices", u32::MAX)));
    }

    let mut mesh = RawMesh::new();
    // Counts were checked against the body length above, so these reservations are bounded by
    // the file size.
    mesh.positions.reserve(vertex_count as usize);
    let face_count = header.elements[face_element].count as usize;
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
        for index in 0..element.count {
            reader.skip_space();
            let start = Position::Element {
                element: element.name.clone(),
                index,
                line: (header.format == Format::Ascii).then_some(reader.line),
            };
            values.clear();
            for (slot, property) in element.properties.iter().enumerate() {
                match property.kind {
                    Kind::Scalar(s) => values.push(reader.read(s, &property.name, &start)?),
                    Kind::List { count, item } => {
                        let n = reader.read(count, &property.name, &start)?;
                        if n < 0.0 {
                            return Err(MeshError::Syntax {
                                file: file.to_owned(),
                                position: start,
                                detail: format!("list {:?} has negative length {n}", property.name),
                            });
                        }
                        let collect = e == face_element && slot == index_slot;
                        if collect {
                            face.clear();
                        }
                        // No reservation by `n`: every read consumes input, so a huge count
                        // ends in a truncation error, not an allocation.
                        for _ in 0..n as u64 {
                            let v = reader.read(item, &property.name, &start)?;
                            if collect {
                                if v < 0.0 || v >= vertex_count as Real {
                                    return Err(MeshError::IndexOutOfRange {
                                        file: file.to_owned(),
                                        position: start,
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
            if e == vertex_element {
                let mut xyz = [0.0; 3];
                for (k, (&slot, axis)) in xyz_slots.iter().zip(['x', 'y', 'z']).enumerate() {
                    let value = values[slot];
                    if !value.is_finite() {
                        return Err(MeshError::NonFiniteCoordinate {
                            file: file.to_owned(),
                            position: start,
                            axis,
                            value,
                        });
                    }
                    xyz[k] = value;
                }
                mesh.positions.push(Vec3::from_array(xyz));
            } else if e == face_element {
                if face.len() < 3 {
                    return Err(MeshError::FaceTooSmall {
                        file: file.to_owned(),
                        position: start,
                        count: face.len(),
                    });
                }
                mesh.push_face(&face, None, None);
            }
        }
    }
    Ok(mesh)
}

fn parse_header(bytes: &[u8], file: &str) -> Result<Header, MeshError> {
    let syntax = |line: usize, detail: String| MeshError::Syntax {
        file: file.to_owned(),
        position: Position::Line(line),
        detail,
    };
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(MeshError::Truncated {
                file: file.to_owned(),
                position: Position::Line(line_no + 1),
                detail: "header has no end_header line".into(),
            });
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        line_no += 1;
        let text = std::str::from_utf8(raw)
            .map_err(|_| syntax(line_no, "header line is not text".into()))?
            .trim_end_matches('\r');
        let tokens: Vec<&str> = text.split_whitespace().collect();
        if line_no == 1 {
            if text.trim() != "ply" {
                return Err(syntax(
                    1,
                    "not a PLY file: first line must be \"ply\"".into(),
                ));
            }
            continue;
        }
        match tokens.as_slice() {
            [] => {}
            ["comment" | "obj_info", ..] => {}
            ["format", kind, version] => {
                if *version != "1.0" {
                    return Err(MeshError::Unsupported {
                        file: file.to_owned(),
                        detail: format!("PLY format version {version}"),
                    });
                }
                format = Some(
                    Format::from_name(kind).ok_or_else(|| MeshError::Unsupported {
                        file: file.to_owned(),
                        detail: format!("PLY format {kind:?}"),
                    })?,
                );
            }
            ["element", name, count] => {
                let count: u64 = count.parse().map_err(|_| {
                    syntax(line_no, format!("element count {count:?} is not a count"))
                })?;
                elements.push(Element {
                    name: (*name).to_owned(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", rest @ ..] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| syntax(line_no, "property before any element".into()))?;
                let scalar = |name: &str| {
                    Scalar::from_ply_name(name)
                        .ok_or_else(|| syntax(line_no, format!("unknown property type {name:?}")))
                };
                let property = match rest {
                    ["list", count, item, name] => Property {
                        name: (*name).to_owned(),
                        kind: Kind::List {
                            count: scalar(count)?,
                            item: scalar(item)?,
                        },
                    },
                    [ty, name] => Property {
                        name: (*name).to_owned(),
                        kind: Kind::Scalar(scalar(ty)?),
                    },
                    _ => return Err(syntax(line_no, format!("malformed property {text:?}"))),
                };
                if let Kind::List { count, .. } = property.kind {
                    if !count.is_integer() {
                        return Err(syntax(
                            line_no,
                            format!("list {:?} has a non-integer count type", property.name),
                        ));
                    }
                }
                element.properties.push(property);
            }
            ["end_header"] => break,
            _ => return Err(syntax(line_no, format!("unexpected header line {text:?}"))),
        }
    }
    let format = format.ok_or_else(|| syntax(line_no, "header has no format line".into()))?;
    Ok(Header {
        format,
        elements,
        body_start: pos,
        lines: line_no,
    })
}

/// Rejects headers whose element counts cannot fit in the body, before any allocation.
fn check_counts(header: &Header, body_bytes: u64, file: &str) -> Result<(), MeshError> {
    let mut needed = 0u64;
    for element in &header.elements {
        if element.properties.is_empty() && element.count > 0 {
            return Err(MeshError::Unsupported {
                file: file.to_owned(),
                detail: format!("element {:?} has no properties", element.name),
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

    /// One scalar of type `ty` as f64 (exact for every PLY integer type).
    fn read(&mut self, ty: Scalar, property: &str, at: &Position) -> Result<Real, MeshError> {
        let truncated = || MeshError::Truncated {
            file: self.file.to_owned(),
            position: at.clone(),
            detail: format!("data ends while reading property {property:?}"),
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
                    position: at.clone(),
                    detail: format!("property {property:?}: {token:?} is not a valid {ty:?} value"),
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
