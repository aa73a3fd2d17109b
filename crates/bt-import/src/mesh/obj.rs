//! Wavefront OBJ reader.
//!
//! A small parser of our own rather than `tobj`: tobj drops `usemtl` names when the `.mtl`
//! library is absent (it maps names to loaded materials) and its errors carry no line numbers.
//! Supported: `v x y z [w|r g b]` (extra values ignored), `f` with `v`, `v/vt`, `v//vn`,
//! `v/vt/vn` references, 1-based and negative (relative) indices, polygons of any vertex count,
//! `o`/`g` names, `usemtl` names, `#` comments and `\` line continuation. Texture coordinates,
//! normals, smoothing groups and `mtllib` are ignored; `l`/`p` elements and unknown statements
//! are skipped with a warning.

use bt_geom::{Real, Vec3};
use std::collections::BTreeSet;

use super::{MeshError, Position, intern};
use bt_mesh::RawMesh;

/// Parses OBJ bytes into a validated polygon soup; stops at the first vertex or face beyond `max_elements` of its kind.
pub(crate) fn parse(bytes: &[u8], file: &str, max_elements: u64) -> Result<RawMesh, MeshError> {
    let mut mesh = RawMesh::new();
    // Line of each face, to report positive indices that turn out out of range at the end
    // (OBJ files may in principle reference vertices defined later).
    let mut face_line: Vec<usize> = Vec::new();
    let mut object: Option<u32> = None;
    let mut group: Option<u32> = None;
    let mut material: Option<u32> = None;
    let mut skipped_elements = 0usize;
    let mut unknown: BTreeSet<String> = BTreeSet::new();
    let mut face: Vec<u32> = Vec::new();

    for (line_no, text) in logical_lines(bytes) {
        let text = match text.find('#') {
            Some(i) => &text[..i],
            None => &text[..],
        };
        let mut tokens = text.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        let at = Line {
            file,
            line: line_no,
        };
        match keyword {
            "v" => {
                let position = at.vertex(tokens)?;
                if mesh.positions.len() == u32::MAX as usize {
                    return Err(MeshError::Unsupported {
                        file: file.to_owned(),
                        detail: format!("more than {} vertices", u32::MAX),
                    });
                }
                super::check_budget(
                    file,
                    "vertices",
                    mesh.positions.len(),
                    max_elements,
                    line_no,
                )?;
                mesh.positions.push(position);
            }
            "f" => {
                at.face(tokens, mesh.positions.len(), &mut face)?;
                super::check_budget(file, "faces", mesh.face_count(), max_elements, line_no)?;
                mesh.push_face(&face, group.or(object), material);
                face_line.push(line_no);
            }
            "o" => {
                object = rest_name(text, keyword).map(|n| intern(&mut mesh.names, n));
                group = None;
            }
            "g" => {
                group = rest_name(text, keyword).map(|n| intern(&mut mesh.names, n));
            }
            "usemtl" => {
                material = rest_name(text, keyword).map(|n| intern(&mut mesh.materials, n));
            }
            "vt" | "vn" | "vp" | "s" | "mtllib" => {}
            "l" | "p" => skipped_elements += 1,
            other => {
                unknown.insert(other.to_owned());
            }
        }
    }

    // Positive indices were only checked against u32; check them against the final count.
    let count = mesh.positions.len();
    for (f, &line) in face_line.iter().enumerate() {
        if let Some(&bad) = mesh.face(f).iter().find(|&&i| i as usize >= count) {
            return Err(MeshError::IndexOutOfRange {
                file: file.to_owned(),
                position: Position::Line(line),
                index: i64::from(bad) + 1,
                vertex_count: count,
            });
        }
    }

    if skipped_elements > 0 {
        mesh.warnings.push(format!(
            "{file}: {skipped_elements} line/point elements (l, p) ignored: only faces become surfaces"
        ));
    }
    if !unknown.is_empty() {
        let list: Vec<&str> = unknown.iter().map(String::as_str).collect();
        mesh.warnings.push(format!(
            "{file}: unsupported statements ignored: {}",
            list.join(", ")
        ));
    }
    Ok(mesh)
}

/// One statement's place, for its errors.
struct Line<'a> {
    file: &'a str,
    line: usize,
}

impl Line<'_> {
    fn syntax(&self, detail: String) -> MeshError {
        MeshError::Syntax {
            file: self.file.to_owned(),
            position: Position::Line(self.line),
            detail,
        }
    }

    /// The position of a `v` statement from the tokens after `v` (finite x, y, z).
    fn vertex<'t>(&self, mut tokens: impl Iterator<Item = &'t str>) -> Result<Vec3, MeshError> {
        let mut xyz = [0.0f64; 3];
        for (k, axis) in ['x', 'y', 'z'].into_iter().enumerate() {
            let token = tokens
                .next()
                .ok_or_else(|| self.syntax(format!("vertex has no {axis} coordinate")))?;
            let value: Real = token.parse().map_err(|_| {
                self.syntax(format!(
                    "vertex {axis} coordinate \"{}\" is not a number",
                    bt_scene::name::shown(token)
                ))
            })?;
            if !value.is_finite() {
                return Err(MeshError::NonFiniteCoordinate {
                    file: self.file.to_owned(),
                    position: Position::Line(self.line),
                    axis,
                    value,
                });
            }
            xyz[k] = value;
        }
        Ok(Vec3::from_array(xyz))
    }

    /// The 0-based vertex indices of an `f` statement into `face`, from the tokens after `f`;
    /// negative (relative) references resolve against the `count` vertices read so far.
    fn face<'t>(
        &self,
        tokens: impl Iterator<Item = &'t str>,
        count: usize,
        face: &mut Vec<u32>,
    ) -> Result<(), MeshError> {
        face.clear();
        for token in tokens {
            let index =
                parse_reference(token).map_err(|detail| self.syntax(format!("face {detail}")))?;
            let resolved = match index {
                0 => None,
                i if i > 0 => u32::try_from(i - 1).ok(),
                i => i64::try_from(count)
                    .ok()
                    .map(|c| c + i)
                    .filter(|&r| r >= 0)
                    .map(|r| r as u32),
            };
            let Some(resolved) = resolved else {
                return Err(MeshError::IndexOutOfRange {
                    file: self.file.to_owned(),
                    position: Position::Line(self.line),
                    index,
                    vertex_count: count,
                });
            };
            face.push(resolved);
        }
        if face.len() < 3 {
            return Err(MeshError::FaceTooSmall {
                file: self.file.to_owned(),
                position: Position::Line(self.line),
                count: face.len(),
            });
        }
        Ok(())
    }
}

/// The vertex index of one `f` token (`v`, `v/vt`, `v//vn`, `v/vt/vn`); the other parts must be
/// integers when present.
fn parse_reference(token: &str) -> Result<i64, String> {
    let mut parts = token.split('/');
    let vertex = parts.next().unwrap_or("");
    let index: i64 = vertex.parse().map_err(|_| {
        format!(
            "vertex reference \"{}\" does not start with an integer index",
            bt_scene::name::shown(token)
        )
    })?;
    let mut extra = 0;
    for part in parts {
        extra += 1;
        if extra > 2 || (!part.is_empty() && part.parse::<i64>().is_err()) {
            return Err(format!(
                "vertex reference \"{}\" is malformed",
                bt_scene::name::shown(token)
            ));
        }
    }
    Ok(index)
}

/// The name after a keyword (`o`, `g`, `usemtl`), trimmed; `None` when empty. Group statements
/// with several names keep them all, separated by single spaces.
fn rest_name<'a>(text: &'a str, keyword: &str) -> Option<&'a str> {
    let rest = text.trim_start()[keyword.len()..].trim();
    (!rest.is_empty()).then_some(rest)
}

/// Lines with `\`-continuations joined, each with the 1-based number of its first physical line.
/// Invalid UTF-8 is replaced (names in legacy encodings survive as readable text).
fn logical_lines(bytes: &[u8]) -> impl Iterator<Item = (usize, String)> + '_ {
    let mut physical = bytes.split(|&b| b == b'\n').enumerate().peekable();
    std::iter::from_fn(move || {
        let (first, raw) = physical.next()?;
        let mut line = String::from_utf8_lossy(raw)
            .trim_end_matches('\r')
            .to_owned();
        while line.ends_with('\\') {
            line.pop();
            line.push(' ');
            match physical.next() {
                Some((_, more)) => {
                    line.push_str(String::from_utf8_lossy(more).trim_end_matches('\r'))
                }
                None => break,
            }
        }
        Some((first + 1, line))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_in_all_forms() {
        assert_eq!(parse_reference("7"), Ok(7));
        assert_eq!(parse_reference("7/3"), Ok(7));
        assert_eq!(parse_reference("7//2"), Ok(7));
        assert_eq!(parse_reference("-2/1/1"), Ok(-2));
        assert!(parse_reference("a/1").is_err());
        assert!(parse_reference("1/x").is_err());
        assert!(parse_reference("1/2/3/4").is_err());
    }

    #[test]
    fn negative_indices_are_relative_to_vertices_so_far() {
        let text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf 1 2 -2\n";
        let mesh = parse(text, "t.obj", u64::MAX).unwrap();
        assert_eq!(mesh.face(0), &[0, 1, 2]);
        assert_eq!(mesh.face(1), &[0, 1, 2]);
    }

    #[test]
    fn names_and_materials_follow_statements() {
        let text = b"mtllib missing.mtl\no Room\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl concrete\nf 1 2 3\ng wall west\nusemtl\nf 1 2 3\n";
        let mesh = parse(text, "t.obj", u64::MAX).unwrap();
        assert_eq!(mesh.names, ["Room", "wall west"]);
        assert_eq!(mesh.materials, ["concrete"]);
        assert_eq!(mesh.face_name, [Some(0), Some(1)]);
        assert_eq!(mesh.face_material, [Some(0), None]);
    }

    #[test]
    fn continuation_lines_keep_first_line_number() {
        let text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 3\nf 1 2 \\\n 9\n";
        match parse(text, "t.obj", u64::MAX) {
            Err(MeshError::IndexOutOfRange {
                position: Position::Line(6),
                index: 9,
                ..
            }) => {}
            other => panic!("unexpected {other:?}"),
        }
    }
}
