//! PLY reader and writer (ASCII, binary little-endian, binary big-endian).
//!
//! The header is parsed by the one PLY grammar of [`crate::formats`] (shared with the mesh reader) and the body here,
//! rather than with `ply-rs`, for three reasons: element counts must be checked against the
//! byte length before anything is allocated, errors must name the line or point index, and
//! the generic `ply-rs` element maps cost an allocation per point (too slow for 10⁶-point
//! clouds). `ply-rs` is used in the tests as an independent writer.

use bt_geom::{Real, Vec3};
use std::io::{Read, Write};

use super::{CloudError, DataPos, Origin};
use super::{LoadedCloud, PointSink, ReadOptions, io_err, next_line, parse_number, read_all};
use bt_pointcloud::PointCloud;

/// PLY encodings (the byte-level layer of [`crate::formats`]).
pub use crate::formats::PlyFormat;

use crate::formats::{PlyElement as Element, PlyHeader, PlyPropertyKind as PropKind};

fn header_err(line: usize, reason: impl Into<String>) -> CloudError {
    CloudError::Header {
        origin: Origin(None),
        line,
        reason: reason.into(),
    }
}

/// The header through the one PLY grammar; every error is a `Header` error.
fn parse_header(bytes: &[u8]) -> Result<PlyHeader, CloudError> {
    PlyHeader::parse(bytes).map_err(|e| header_err(e.line, e.kind.to_string()))
}

/// Parse a PLY file held in memory. Reads the `vertex` element's `x y z` (any numeric type)
/// and, when all three are present, `nx ny nz`; other properties and elements are skipped.
pub fn parse_ply(bytes: &[u8], opts: &ReadOptions) -> Result<LoadedCloud, CloudError> {
    let h = parse_header(bytes)?;
    let end_line = h.lines;
    let vi = h
        .elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| header_err(end_line, "no 'vertex' element"))?;
    let vertex = &h.elements[vi];
    let find = |n: &str| -> Result<Option<usize>, CloudError> {
        match vertex.properties.iter().position(|p| p.name == n) {
            Some(i) if matches!(vertex.properties[i].kind, PropKind::List { .. }) => {
                Err(header_err(
                    end_line,
                    format!("vertex property '{}' is a list", bt_scene::name::shown(n)),
                ))
            }
            other => Ok(other),
        }
    };
    let (xyz, normal_idx) = super::point_columns(find, ["nx", "ny", "nz"])?;

    // Check every claim up to the vertex element against the byte length before allocating.
    let available = bytes.len() - h.body_start;
    let mut min_total: u128 = 0;
    for e in &h.elements[..=vi] {
        if e.properties.is_empty() && e.count > 0 {
            return Err(header_err(
                end_line,
                format!(
                    "element '{}' has no properties",
                    bt_scene::name::shown(&e.name)
                ),
            ));
        }
        min_total += e.count as u128 * u128::from(e.min_bytes(h.format));
    }
    if super::is_absurd(min_total, available) {
        return Err(CloudError::CountExceedsData {
            origin: Origin(None),
            claimed: vertex.count,
            min_bytes: min_total,
            available,
        });
    }

    super::check_budget(vertex.count, opts)?;
    let per_vertex = u128::from(vertex.min_bytes(h.format).max(1));
    let capacity = vertex.count.min((available as u128 / per_vertex) as u64) as usize;
    let mut sink = PointSink::new(capacity, normal_idx.is_some(), opts.non_finite);
    let mut pos = h.body_start;
    let mut line = h.lines;
    let mut vals = vec![0.0f64; vertex.properties.len()];
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
                return Err(CloudError::Truncated {
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
    sink.finish()
}

/// Read one element; `Ok(false)` when the data ends first.
fn read_binary_element(
    bytes: &[u8],
    pos: &mut usize,
    e: &Element,
    big_endian: bool,
    vals: &mut [Real],
    k: u64,
) -> Result<bool, CloudError> {
    for (i, p) in e.properties.iter().enumerate() {
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
                    return Err(CloudError::BadValue {
                        origin: Origin(None),
                        at: DataPos {
                            element: k,
                            line: None,
                        },
                        reason: format!(
                            "negative list length {n} for '{}'",
                            bt_scene::name::shown(&p.name)
                        ),
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
) -> Result<bool, CloudError> {
    let text = loop {
        let Some(raw) = next_line(bytes, pos) else {
            return Ok(false);
        };
        *line += 1;
        if !raw.iter().all(u8::is_ascii_whitespace) {
            break raw;
        }
    };
    let bad = |reason: String| CloudError::BadValue {
        origin: Origin(None),
        at: DataPos {
            element: k,
            line: Some(*line),
        },
        reason,
    };
    let text = std::str::from_utf8(text).map_err(|_| bad("line is not text".into()))?;
    let mut tok = text.split_ascii_whitespace();
    for (i, p) in e.properties.iter().enumerate() {
        let t = tok.next().ok_or_else(|| {
            bad(format!(
                "missing value for '{}'",
                bt_scene::name::shown(&p.name)
            ))
        })?;
        match p.kind {
            PropKind::Scalar(ty) => {
                let v = parse_number(t, ty).ok_or_else(|| {
                    bad(format!(
                        "'{}' is not a number ('{}')",
                        bt_scene::name::shown(t),
                        bt_scene::name::shown(&p.name)
                    ))
                })?;
                if let Some(slot) = vals.get_mut(i) {
                    *slot = v;
                }
            }
            PropKind::List { .. } => {
                let n: usize = t.parse().map_err(|_| {
                    bad(format!(
                        "'{}' is not a list length ('{}')",
                        bt_scene::name::shown(t),
                        bt_scene::name::shown(&p.name)
                    ))
                })?;
                for _ in 0..n {
                    tok.next().ok_or_else(|| {
                        bad(format!(
                            "list '{}' shorter than its length {n}",
                            bt_scene::name::shown(&p.name)
                        ))
                    })?;
                }
            }
        }
    }
    Ok(true)
}

/// Read a PLY file from a stream (read to the end first, so counts can be checked against
/// the real length).
pub fn read_ply<R: Read>(reader: R, opts: &ReadOptions) -> Result<LoadedCloud, CloudError> {
    parse_ply(&read_all(reader)?, opts)
}

/// Write `cloud` as PLY with `double x y z` (and `double nx ny nz` when the cloud has
/// normals). ASCII output uses the shortest representation that reads back to the same
/// `Real`, so ASCII and binary round trips are both exact.
pub fn write_ply<W: Write>(
    cloud: &PointCloud,
    mut w: W,
    format: PlyFormat,
) -> Result<(), CloudError> {
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
    let encoding = match format {
        PlyFormat::Ascii => super::Encoding::Ascii,
        PlyFormat::BinaryLittleEndian => super::Encoding::LittleEndian,
        PlyFormat::BinaryBigEndian => super::Encoding::BigEndian,
    };
    super::write_records(cloud, &mut w, encoding)
}
