//! PLY reader and writer (ASCII, binary little-endian, binary big-endian).
//!
//! The header is parsed by hand rather than with `ply-rs`, for three reasons: element counts
//! must be checked against the byte length before anything is allocated, errors must name the
//! line or point index, and the generic `ply-rs` element maps cost an allocation per point
//! (too slow for 10⁶-point clouds). `ply-rs` is used in the tests as an independent writer.

use bt_geom::{Real, Vec3};
use std::io::{Read, Write};

use super::{
    LoadedCloud, PointSink, ReadOptions, Scalar, io_err, next_line, parse_number, read_all,
};
use crate::cloud::PointCloud;
use crate::error::{DataPos, Origin, PointCloudError};

/// PLY encodings (the byte-level layer of `bt-formats`).
pub use bt_formats::PlyFormat;

#[derive(Debug, Clone, Copy)]
enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Prop {
    name: String,
    kind: PropKind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Prop>,
}

impl Element {
    /// Smallest number of bytes one element can occupy.
    fn min_bytes(&self, format: PlyFormat) -> u128 {
        match format {
            // Each value is at least one character plus a separator (or the newline).
            PlyFormat::Ascii => 2 * self.props.len() as u128,
            _ => self
                .props
                .iter()
                .map(|p| match p.kind {
                    PropKind::Scalar(s) => s.size() as u128,
                    PropKind::List { count, .. } => count.size() as u128,
                })
                .sum(),
        }
    }
}

struct Header {
    format: PlyFormat,
    elements: Vec<Element>,
    data_start: usize,
    /// Number of header lines, so ASCII data line numbers can be reported.
    lines: usize,
}

fn header_err(line: usize, reason: impl Into<String>) -> PointCloudError {
    PointCloudError::Header {
        origin: Origin(None),
        line,
        reason: reason.into(),
    }
}

fn parse_header(bytes: &[u8]) -> Result<Header, PointCloudError> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(raw) = next_line(bytes, &mut pos) else {
            return Err(header_err(
                line_no.max(1),
                "header has no 'end_header' line",
            ));
        };
        line_no += 1;
        let line =
            std::str::from_utf8(raw).map_err(|_| header_err(line_no, "header line is not text"))?;
        let mut tok = line.split_ascii_whitespace();
        let Some(key) = tok.next() else { continue };
        if line_no == 1 {
            if line.trim() != "ply" {
                return Err(header_err(1, "file does not start with 'ply'"));
            }
            continue;
        }
        match key {
            "format" => {
                let name = tok.next();
                let f = match name.and_then(PlyFormat::from_name) {
                    Some(f) => f,
                    None => {
                        let other = name;
                        return Err(header_err(
                            line_no,
                            format!("unknown format {:?}", other.unwrap_or("")),
                        ));
                    }
                };
                match tok.next() {
                    Some("1.0") => {}
                    v => {
                        return Err(header_err(
                            line_no,
                            format!("unsupported version {:?}", v.unwrap_or("")),
                        ));
                    }
                }
                format = Some(f);
            }
            "comment" | "obj_info" => {}
            "element" => {
                let (Some(name), Some(count), None) = (tok.next(), tok.next(), tok.next()) else {
                    return Err(header_err(line_no, "expected 'element <name> <count>'"));
                };
                let count = count.parse::<u64>().map_err(|_| {
                    header_err(
                        line_no,
                        format!("element count {count:?} is not a non-negative integer"),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(header_err(line_no, "property declared before any element"));
                };
                let words: Vec<&str> = tok.collect();
                let (kind, name) = match words.as_slice() {
                    ["list", c, i, name] => {
                        let (Some(count), Some(item)) =
                            (Scalar::from_ply_name(c), Scalar::from_ply_name(i))
                        else {
                            return Err(header_err(
                                line_no,
                                format!("unknown list types '{c} {i}'"),
                            ));
                        };
                        if matches!(count, Scalar::F32 | Scalar::F64) {
                            return Err(header_err(
                                line_no,
                                "list count type must be an integer type",
                            ));
                        }
                        (PropKind::List { count, item }, *name)
                    }
                    [t, name] => {
                        let s = Scalar::from_ply_name(t).ok_or_else(|| {
                            header_err(line_no, format!("unknown property type '{t}'"))
                        })?;
                        (PropKind::Scalar(s), *name)
                    }
                    _ => {
                        return Err(header_err(
                            line_no,
                            "expected 'property <type> <name>' or 'property list <t> <t> <name>'",
                        ));
                    }
                };
                if el.props.iter().any(|p| p.name == name) {
                    return Err(header_err(line_no, format!("duplicate property '{name}'")));
                }
                el.props.push(Prop {
                    name: name.to_string(),
                    kind,
                });
            }
            "end_header" => break,
            other => return Err(header_err(line_no, format!("unknown keyword '{other}'"))),
        }
    }
    let format = format.ok_or_else(|| header_err(line_no, "header has no 'format' line"))?;
    Ok(Header {
        format,
        elements,
        data_start: pos,
        lines: line_no,
    })
}

/// Parse a PLY file held in memory. Reads the `vertex` element's `x y z` (any numeric type)
/// and, when all three are present, `nx ny nz`; other properties and elements are skipped.
pub fn parse_ply(bytes: &[u8], opts: &ReadOptions) -> Result<LoadedCloud, PointCloudError> {
    let h = parse_header(bytes)?;
    let end_line = h.lines;
    let vi = h
        .elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| header_err(end_line, "no 'vertex' element"))?;
    let vertex = &h.elements[vi];
    let find = |n: &str| -> Result<Option<usize>, PointCloudError> {
        match vertex.props.iter().position(|p| p.name == n) {
            Some(i) if matches!(vertex.props[i].kind, PropKind::List { .. }) => Err(header_err(
                end_line,
                format!("vertex property '{n}' is a list"),
            )),
            other => Ok(other),
        }
    };
    let mut xyz = [0usize; 3];
    for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
        xyz[k] = find(name)?.ok_or_else(|| PointCloudError::MissingField {
            origin: Origin(None),
            field: name.to_string(),
        })?;
    }
    let normal_idx = match (find("nx")?, find("ny")?, find("nz")?) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };

    // Check every claim up to the vertex element against the byte length before allocating.
    let available = bytes.len() - h.data_start;
    let mut min_total: u128 = 0;
    for e in &h.elements[..=vi] {
        if e.props.is_empty() && e.count > 0 {
            return Err(header_err(
                end_line,
                format!("element '{}' has no properties", e.name),
            ));
        }
        min_total += e.count as u128 * e.min_bytes(h.format);
    }
    if super::is_absurd(min_total, available) {
        return Err(PointCloudError::CountExceedsData {
            origin: Origin(None),
            claimed: vertex.count,
            min_bytes: min_total,
            available,
        });
    }

    super::check_budget(vertex.count, opts)?;
    let per_vertex = vertex.min_bytes(h.format).max(1);
    let capacity = vertex.count.min((available as u128 / per_vertex) as u64) as usize;
    let mut sink = PointSink::new(capacity, normal_idx.is_some(), opts.non_finite);
    let mut pos = h.data_start;
    let mut line = h.lines;
    let mut vals = vec![0.0f64; vertex.props.len()];
    for (ei, e) in h.elements[..=vi].iter().enumerate() {
        let is_vertex = ei == vi;
        for k in 0..e.count {
            let at = |line: usize| DataPos {
                element: k,
                line: (h.format == PlyFormat::Ascii).then_some(line),
            };
            let ok = match h.format {
                PlyFormat::Ascii => {
                    read_ascii_element(bytes, &mut pos, &mut line, e, &mut vals, k)?
                }
                PlyFormat::BinaryLittleEndian => {
                    read_binary_element(bytes, &mut pos, e, false, &mut vals, k)?
                }
                PlyFormat::BinaryBigEndian => {
                    read_binary_element(bytes, &mut pos, e, true, &mut vals, k)?
                }
            };
            if !ok {
                return Err(PointCloudError::Truncated {
                    origin: Origin(None),
                    at: at(line + 1),
                    expected: e.count,
                });
            }
            if is_vertex {
                let p = Vec3::new(vals[xyz[0]], vals[xyz[1]], vals[xyz[2]]);
                let n =
                    normal_idx.map_or(Vec3::ZERO, |[a, b, c]| Vec3::new(vals[a], vals[b], vals[c]));
                sink.push(p, n, at(line))?;
            }
        }
    }
    Ok(sink.finish())
}

/// Read one element; `Ok(false)` when the data ends first.
fn read_binary_element(
    bytes: &[u8],
    pos: &mut usize,
    e: &Element,
    big_endian: bool,
    vals: &mut [Real],
    k: u64,
) -> Result<bool, PointCloudError> {
    for (i, p) in e.props.iter().enumerate() {
        match p.kind {
            PropKind::Scalar(s) => {
                let Some(b) = bytes.get(*pos..*pos + s.size()) else {
                    return Ok(false);
                };
                if let Some(v) = vals.get_mut(i) {
                    *v = s.decode(b, big_endian);
                }
                *pos += s.size();
            }
            PropKind::List { count, item } => {
                let Some(b) = bytes.get(*pos..*pos + count.size()) else {
                    return Ok(false);
                };
                let n = count.decode(b, big_endian);
                *pos += count.size();
                if n < 0.0 {
                    return Err(PointCloudError::BadValue {
                        origin: Origin(None),
                        at: DataPos {
                            element: k,
                            line: None,
                        },
                        reason: format!("negative list length {n} for '{}'", p.name),
                    });
                }
                let skip = n as u128 * item.size() as u128;
                if skip > (bytes.len() - *pos) as u128 {
                    return Ok(false);
                }
                *pos += skip as usize;
            }
        }
    }
    Ok(true)
}

/// Read one element written on one line; `Ok(false)` when the data ends first.
fn read_ascii_element(
    bytes: &[u8],
    pos: &mut usize,
    line: &mut usize,
    e: &Element,
    vals: &mut [Real],
    k: u64,
) -> Result<bool, PointCloudError> {
    let text = loop {
        let Some(raw) = next_line(bytes, pos) else {
            return Ok(false);
        };
        *line += 1;
        if !raw.iter().all(u8::is_ascii_whitespace) {
            break raw;
        }
    };
    let bad = |reason: String| PointCloudError::BadValue {
        origin: Origin(None),
        at: DataPos {
            element: k,
            line: Some(*line),
        },
        reason,
    };
    let text = std::str::from_utf8(text).map_err(|_| bad("line is not text".into()))?;
    let mut tok = text.split_ascii_whitespace();
    for (i, p) in e.props.iter().enumerate() {
        let t = tok
            .next()
            .ok_or_else(|| bad(format!("missing value for '{}'", p.name)))?;
        match p.kind {
            PropKind::Scalar(ty) => {
                let v = parse_number(t, ty)
                    .ok_or_else(|| bad(format!("'{t}' is not a number ('{}')", p.name)))?;
                if let Some(slot) = vals.get_mut(i) {
                    *slot = v;
                }
            }
            PropKind::List { .. } => {
                let n: usize = t
                    .parse()
                    .map_err(|_| bad(format!("'{t}' is not a list length ('{}')", p.name)))?;
                for _ in 0..n {
                    tok.next().ok_or_else(|| {
                        bad(format!("list '{}' shorter than its length {n}", p.name))
                    })?;
                }
            }
        }
    }
    Ok(true)
}

/// Read a PLY file from a stream (read to the end first, so counts can be checked against
/// the real length).
pub fn read_ply<R: Read>(reader: R, opts: &ReadOptions) -> Result<LoadedCloud, PointCloudError> {
    parse_ply(&read_all(reader)?, opts)
}

/// Write `cloud` as PLY with `double x y z` (and `double nx ny nz` when the cloud has
/// normals). ASCII output uses the shortest representation that reads back to the same
/// `Real`, so ASCII and binary round trips are both exact.
pub fn write_ply<W: Write>(
    cloud: &PointCloud,
    mut w: W,
    format: PlyFormat,
) -> Result<(), PointCloudError> {
    let fmt = format.name();
    let mut head = format!(
        "ply\nformat {fmt} 1.0\ncomment written by beamtrace bt-pointcloud (metres, z up)\nelement vertex {}\n\
         property double x\nproperty double y\nproperty double z\n",
        cloud.len()
    );
    if cloud.normals().is_some() {
        head.push_str("property double nx\nproperty double ny\nproperty double nz\n");
    }
    head.push_str("end_header\n");
    w.write_all(head.as_bytes()).map_err(io_err)?;
    let mut buf = Vec::with_capacity(64);
    for (i, p) in cloud.points().iter().enumerate() {
        buf.clear();
        let mut vals = vec![p.x, p.y, p.z];
        if let Some(ns) = cloud.normals() {
            vals.extend([ns[i].x, ns[i].y, ns[i].z]);
        }
        let all = vals.iter();
        match format {
            PlyFormat::Ascii => {
                let s: Vec<String> = all.map(|v| format!("{v:?}")).collect();
                buf.extend_from_slice(s.join(" ").as_bytes());
                buf.push(b'\n');
            }
            PlyFormat::BinaryLittleEndian => {
                all.for_each(|v| buf.extend_from_slice(&v.to_le_bytes()))
            }
            PlyFormat::BinaryBigEndian => all.for_each(|v| buf.extend_from_slice(&v.to_be_bytes())),
        }
        w.write_all(&buf).map_err(io_err)?;
    }
    Ok(())
}
