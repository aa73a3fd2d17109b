//! STL reader (binary and ASCII): the triangle soups that CAD tools and MATLAB's `raytrace`
//! (its `conferenceroom.stl`) use for scenes.
//!
//! A small parser of our own rather than `stl_io`: its errors carry no line or triangle
//! numbers, and it does not check a binary file's triangle count against the file's size
//! before allocating. STL has no units, materials or shared vertices: coordinates are taken as
//! metres, every face gets the default material, and `bt-mesh` welds the corners.
//!
//! - **Binary**: an 80-byte header, a little-endian `u32` triangle count, then 50 bytes per
//!   triangle (a normal, three corners as `f32`, two attribute bytes). A file is binary when
//!   its size is exactly `84 + 50 · count`, whatever its header says (many binary files start
//!   with `solid` too); normals and attribute bytes are ignored.
//! - **ASCII**: `solid [name]`, then facets `facet normal nx ny nz` / `outer loop` / `vertex x
//!   y z` (three or more) / `endloop` / `endfacet`, and `endsolid [name]`; several solids may
//!   follow each other. A solid's name becomes its faces' object name (the surfaces' names).
//!   Normals are ignored (the winding is not used either: surfaces reflect on both sides).

use super::{MeshError, Position, intern};
use bt_geom::{Real, Vec3};
use bt_mesh::RawMesh;

/// Bytes before a binary file's first triangle: the header and the count.
const BINARY_HEADER: usize = 84;
/// Bytes of one binary triangle.
const BINARY_TRIANGLE: usize = 50;

/// Parses STL bytes (binary or ASCII, module docs) into a validated polygon soup; refuses a
/// file of more than `max_elements` facets (binary: from its count, before reading them). Its
/// corners are not counted against the budget: STL repeats each corner in every facet (about
/// six times), and the positions are bounded by the file's size.
pub(crate) fn parse(bytes: &[u8], file: &str, max_elements: u64) -> Result<RawMesh, MeshError> {
    if let Some(count) = binary_count(bytes) {
        return parse_binary(bytes, count, file, max_elements);
    }
    if !starts_with_solid(bytes) {
        return Err(MeshError::Syntax {
            file: file.to_owned(),
            position: Position::Line(1),
            detail: format!(
                "not an STL file: it does not start with \"solid\" (ASCII STL), and {}",
                binary_mismatch(bytes)
            ),
        });
    }
    parse_ascii(bytes, file, max_elements)
}

/// The triangle count of a binary STL: `Some` when the size is exactly what the count needs.
fn binary_count(bytes: &[u8]) -> Option<u64> {
    let (count, needed) = claimed(bytes)?;
    (needed == bytes.len() as u64).then_some(count)
}

/// The triangle count the bytes at a binary STL's count field claim, and the file size (bytes)
/// it needs; `None` for a file shorter than the header.
fn claimed(bytes: &[u8]) -> Option<(u64, u64)> {
    let count = bytes.get(80..BINARY_HEADER)?;
    let count = u64::from(u32::from_le_bytes(count.try_into().ok()?));
    Some((count, BINARY_HEADER as u64 + BINARY_TRIANGLE as u64 * count))
}

/// Why `bytes` is not a binary STL, for messages: its size against what its count needs.
fn binary_mismatch(bytes: &[u8]) -> String {
    match claimed(bytes) {
        Some((count, needed)) => format!(
            "as a binary STL its count of {count} triangles needs {needed} bytes, but the file \
             has {}",
            bytes.len()
        ),
        None => format!(
            "it has {} bytes, fewer than a binary STL's header of {BINARY_HEADER}",
            bytes.len()
        ),
    }
}

/// Whether the text starts with the keyword `solid` (after blanks), as an ASCII STL does.
fn starts_with_solid(bytes: &[u8]) -> bool {
    let text = bytes.trim_ascii_start();
    text.starts_with(b"solid") && text.get(5).is_none_or(|b| b.is_ascii_whitespace())
}

/// The triangles of a binary STL of `count` triangles (its size checked by [`binary_count`]).
fn parse_binary(
    bytes: &[u8],
    count: u64,
    file: &str,
    max_elements: u64,
) -> Result<RawMesh, MeshError> {
    if count > max_elements {
        return Err(MeshError::Budget {
            file: file.to_owned(),
            element: "faces",
            count: count.to_string(),
            budget: max_elements,
        });
    }
    let mut mesh = RawMesh::new();
    // Bounded by the file's size: `count` triangles are exactly the file's body.
    let n = count as usize;
    mesh.positions.reserve(3 * n);
    mesh.indices.reserve(3 * n);
    mesh.face_start.reserve(n);
    mesh.face_name.reserve(n);
    mesh.face_material.reserve(n);
    let body = &bytes[BINARY_HEADER..];
    for (index, triangle) in body.chunks_exact(BINARY_TRIANGLE).enumerate() {
        let at = || Position::Element {
            element: "triangle".to_owned(),
            index: index as u64,
            line: None,
        };
        let first = mesh.positions.len() as u32;
        for corner in 0..3 {
            // The corners follow the 12-byte normal.
            let at_byte = 12 + 12 * corner;
            let mut p = [0.0; 3];
            for (axis, value) in p.iter_mut().enumerate() {
                let b = at_byte + 4 * axis;
                let word = [
                    triangle[b],
                    triangle[b + 1],
                    triangle[b + 2],
                    triangle[b + 3],
                ];
                *value = Real::from(f32::from_le_bytes(word));
            }
            mesh.positions.push(finite(p, file, at)?);
        }
        mesh.push_face(&[first, first + 1, first + 2], None, None);
    }
    Ok(mesh)
}

/// `p` as a point, or the error naming the first non-finite coordinate at `at`.
fn finite(p: [Real; 3], file: &str, at: impl Fn() -> Position) -> Result<Vec3, MeshError> {
    match p.iter().position(|v| !v.is_finite()) {
        None => Ok(Vec3::from_array(p)),
        Some(axis) => Err(MeshError::NonFiniteCoordinate {
            file: file.to_owned(),
            position: at(),
            axis: ['x', 'y', 'z'][axis],
            value: p[axis],
        }),
    }
}

/// Where the ASCII grammar stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Between solids: `solid` next.
    Outside,
    /// In a solid, between facets: `facet` or `endsolid` next.
    Solid,
    /// After `facet normal ..`: `outer loop` next.
    Facet,
    /// In a loop: `vertex` or `endloop` next.
    Loop,
    /// After `endloop`: `endfacet` next.
    EndLoop,
}

impl State {
    /// The keywords allowed next, for messages.
    fn expected(self) -> &'static str {
        match self {
            State::Outside => "\"solid\"",
            State::Solid => "\"facet\" or \"endsolid\"",
            State::Facet => "\"outer loop\"",
            State::Loop => "\"vertex\" or \"endloop\"",
            State::EndLoop => "\"endfacet\"",
        }
    }
}

/// The facets of an ASCII STL, one face per facet, named by their solid.
fn parse_ascii(bytes: &[u8], file: &str, max_elements: u64) -> Result<RawMesh, MeshError> {
    let text = std::str::from_utf8(bytes).map_err(|e| MeshError::Syntax {
        file: file.to_owned(),
        position: Position::Line(line_of(bytes, e.valid_up_to())),
        detail: format!(
            "not UTF-8 text, as an ASCII STL is; {}",
            binary_mismatch(bytes)
        ),
    })?;
    let mut mesh = RawMesh::new();
    let (mut state, mut name, mut face) = (State::Outside, None, Vec::new());
    let mut line = 0;
    for (i, text) in text.lines().enumerate() {
        line = i + 1;
        let syntax = |detail: String| MeshError::Syntax {
            file: file.to_owned(),
            position: Position::Line(line),
            detail,
        };
        let mut tokens = text.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        state = match (state, keyword) {
            (State::Outside, "solid") => {
                let rest = text.trim_start()["solid".len()..].trim();
                name = (!rest.is_empty()).then(|| intern(&mut mesh.names, rest));
                State::Solid
            }
            (State::Solid, "endsolid") => State::Outside,
            (State::Solid, "facet") => State::Facet,
            (State::Facet, "outer") if tokens.next() == Some("loop") => State::Loop,
            (State::Loop, "vertex") => {
                let p = vertex(tokens).map_err(syntax)?;
                face.push(mesh.positions.len() as u32);
                mesh.positions
                    .push(finite(p, file, || Position::Line(line))?);
                State::Loop
            }
            (State::Loop, "endloop") => {
                end_facet(&mut mesh, &mut face, (name, max_elements), (file, line))?;
                State::EndLoop
            }
            (State::EndLoop, "endfacet") => State::Solid,
            (state, other) => {
                return Err(syntax(format!(
                    "expected {}, found \"{}\"",
                    state.expected(),
                    bt_scene::name::shown(other)
                )));
            }
        };
    }
    match state {
        State::Outside | State::Solid => Ok(mesh),
        state => Err(MeshError::Truncated {
            file: file.to_owned(),
            position: Position::Line(line),
            detail: format!(
                "the file ends inside a facet: expected {}",
                state.expected()
            ),
        }),
    }
}

/// Close the facet whose corners are `face` (positions' indices) as a face of solid `name`,
/// refusing a facet of fewer than three corners or one beyond the budget.
fn end_facet(
    mesh: &mut RawMesh,
    face: &mut Vec<u32>,
    (name, max_elements): (Option<u32>, u64),
    (file, line): (&str, usize),
) -> Result<(), MeshError> {
    if face.len() < 3 {
        return Err(MeshError::FaceTooSmall {
            file: file.to_owned(),
            position: Position::Line(line),
            count: face.len(),
        });
    }
    super::check_budget(file, "faces", mesh.face_count(), max_elements, line)?;
    mesh.push_face(face, name, None);
    face.clear();
    Ok(())
}

/// The three coordinates after `vertex`, or what is wrong with them.
fn vertex<'a>(mut tokens: impl Iterator<Item = &'a str>) -> Result<[Real; 3], String> {
    let mut p = [0.0; 3];
    for (axis, value) in ['x', 'y', 'z'].into_iter().zip(&mut p) {
        let token = tokens
            .next()
            .ok_or_else(|| format!("vertex has no {axis} coordinate"))?;
        *value = token.parse().map_err(|_| {
            format!(
                "vertex coordinate {axis} \"{}\" is not a number",
                bt_scene::name::shown(token)
            )
        })?;
    }
    match tokens.next() {
        Some(extra) => Err(format!(
            "vertex has more than three coordinates (\"{}\")",
            bt_scene::name::shown(extra)
        )),
        None => Ok(p),
    }
}

/// The 1-based line of byte `offset`.
fn line_of(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset].iter().filter(|&&b| b == b'\n').count()
}
