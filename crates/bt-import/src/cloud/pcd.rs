//! PCD (Point Cloud Library) reader and writer: `DATA ascii` and `DATA binary`
//! (little-endian, as PCL writes on every platform it supports). `binary_compressed` is
//! reported as [`CloudError::Unsupported`].

use bt_geom::{Real, Vec3};
use std::io::{Read, Write};

use super::{CloudError, DataPos, Origin};
use super::{
    LoadedCloud, PointSink, ReadOptions, Scalar, io_err, next_line, parse_number, read_all,
};
use bt_pointcloud::PointCloud;

/// PCD data encodings this crate writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PcdData {
    /// `DATA ascii`: one point per line.
    Ascii,
    /// `DATA binary`: packed little-endian records.
    Binary,
}

struct Field {
    name: String,
    size: usize,
    count: usize,
    scalar: Scalar,
}

fn header_err(line: usize, reason: impl Into<String>) -> CloudError {
    CloudError::Header {
        origin: Origin(None),
        line,
        reason: reason.into(),
    }
}

/// The header lines up to `DATA`, as written.
struct Keywords {
    names: Option<Vec<String>>,
    sizes: Option<Vec<usize>>,
    types: Option<Vec<u8>>,
    counts: Option<Vec<usize>>,
    width: Option<u64>,
    height: Option<u64>,
    points: Option<u64>,
    binary: bool,
    /// Byte offset of the body.
    data_start: usize,
    /// Line number of the `DATA` line.
    data_line: usize,
}

/// A checked PCD header: the fields with their scalar types, the point count and the body's
/// place and encoding.
struct PcdHeader {
    fields: Vec<Field>,
    count: u64,
    binary: bool,
    data_start: usize,
    data_line: usize,
}

/// Where the values of one point are: per field its column (ASCII value index) and byte
/// offset (binary record), the values and bytes per point, and the fields read.
struct Layout {
    col: Vec<usize>,
    offset: Vec<usize>,
    values_per_point: usize,
    stride: usize,
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
}

/// Parse a PCD file held in memory. Reads `x y z` (any numeric type, count 1) and, when all
/// three are present, `normal_x normal_y normal_z`; other fields are skipped using their
/// SIZE, TYPE and COUNT.
pub fn parse_pcd(bytes: &[u8], opts: &ReadOptions) -> Result<LoadedCloud, CloudError> {
    let header = parse_header(bytes)?;
    let layout = layout(&header.fields, header.data_line)?;
    let count = header.count;
    let available = bytes.len() - header.data_start;
    let min_per_point = if header.binary {
        layout.stride as u128
    } else {
        2 * layout.values_per_point as u128
    };
    let min_bytes = count as u128 * min_per_point;
    if super::is_absurd(min_bytes, available) || (min_per_point == 0 && count > 0) {
        return Err(CloudError::CountExceedsData {
            origin: Origin(None),
            claimed: count,
            min_bytes,
            available,
        });
    }
    super::check_budget(count, opts)?;
    let capacity = count.min((available as u128 / min_per_point.max(1)) as u64) as usize;
    let mut sink = PointSink::new(capacity, layout.normal.is_some(), opts.non_finite);
    if header.binary {
        read_binary_body(bytes, &header, &layout, &mut sink)?;
    } else {
        read_ascii_body(bytes, &header, &layout, &mut sink)?;
    }
    sink.finish()
}

/// The header: keywords, then fields and point count checked against each other.
fn parse_header(bytes: &[u8]) -> Result<PcdHeader, CloudError> {
    let kw = read_keywords(bytes)?;
    let data_line = kw.data_line;
    let fields = fields(&kw)?;
    let count = point_count(&kw)?;
    Ok(PcdHeader {
        fields,
        count,
        binary: kw.binary,
        data_start: kw.data_start,
        data_line,
    })
}

/// Reads the header lines up to and including `DATA`.
fn read_keywords(bytes: &[u8]) -> Result<Keywords, CloudError> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut names: Option<Vec<String>> = None;
    let mut sizes: Option<Vec<usize>> = None;
    let mut types: Option<Vec<u8>> = None;
    let mut counts: Option<Vec<usize>> = None;
    let mut width: Option<u64> = None;
    let mut height: Option<u64> = None;
    let mut points: Option<u64> = None;
    loop {
        let Some(raw) = next_line(bytes, &mut pos) else {
            return Err(header_err(line_no.max(1), "header has no 'DATA' line"));
        };
        line_no += 1;
        let line =
            std::str::from_utf8(raw).map_err(|_| header_err(line_no, "header line is not text"))?;
        let line = line.split('#').next().unwrap_or("");
        let mut tok = line.split_ascii_whitespace();
        let Some(key) = tok.next() else { continue };
        let rest: Vec<&str> = tok.collect();
        let one = |what: &str| one_int(&rest, what, line_no);
        match key.to_ascii_uppercase().as_str() {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" => names = Some(rest.iter().map(|s| s.to_string()).collect()),
            "SIZE" => {
                let v = ints(&rest, "SIZE", line_no)?;
                sizes = Some(v.into_iter().map(|v| v as usize).collect());
            }
            "COUNT" => counts = Some(count_values(&rest, line_no)?),
            "TYPE" => types = Some(type_letters(&rest, line_no)?),
            "WIDTH" => width = Some(one("WIDTH")?),
            "HEIGHT" => height = Some(one("HEIGHT")?),
            "POINTS" => points = Some(one("POINTS")?),
            "DATA" => {
                return Ok(Keywords {
                    names,
                    sizes,
                    types,
                    counts,
                    width,
                    height,
                    points,
                    binary: data_is_binary(&rest, line_no)?,
                    data_start: pos,
                    data_line: line_no,
                });
            }
            other => {
                return Err(header_err(
                    line_no,
                    format!("unknown keyword '{}'", bt_scene::name::shown(other)),
                ));
            }
        }
    }
}

/// The values of a header line `what` on line `line`: non-negative integers.
fn ints(rest: &[&str], what: &str, line: usize) -> Result<Vec<u64>, CloudError> {
    rest.iter()
        .map(|t| {
            t.parse::<u64>().map_err(|_| {
                header_err(
                    line,
                    format!(
                        "{what}: '{}' is not a non-negative integer",
                        bt_scene::name::shown(t)
                    ),
                )
            })
        })
        .collect()
}

/// The one value of a header line `what` (WIDTH, HEIGHT, POINTS).
fn one_int(rest: &[&str], what: &str, line: usize) -> Result<u64, CloudError> {
    match ints(rest, what, line)?.as_slice() {
        [v] => Ok(*v),
        _ => Err(header_err(line, format!("{what} takes exactly one value"))),
    }
}

/// The values of `COUNT`, each between 1 and 2^20.
fn count_values(rest: &[&str], line: usize) -> Result<Vec<usize>, CloudError> {
    let c = ints(rest, "COUNT", line)?;
    if c.iter().any(|&v| v == 0 || v > 1 << 20) {
        return Err(header_err(line, "COUNT values must be between 1 and 2^20"));
    }
    Ok(c.into_iter().map(|v| v as usize).collect())
}

/// The letters of `TYPE` (`F`, `I` or `U`).
fn type_letters(rest: &[&str], line: usize) -> Result<Vec<u8>, CloudError> {
    rest.iter()
        .map(|s| match *s {
            "F" | "I" | "U" => Ok(s.as_bytes()[0]),
            _ => Err(header_err(
                line,
                format!("TYPE '{}' is not F, I or U", bt_scene::name::shown(s)),
            )),
        })
        .collect()
}

/// Whether the `DATA` line says `binary` (else `ascii`); `binary_compressed` is unsupported.
fn data_is_binary(rest: &[&str], line: usize) -> Result<bool, CloudError> {
    match rest {
        ["ascii"] => Ok(false),
        ["binary"] => Ok(true),
        ["binary_compressed"] => Err(CloudError::Unsupported {
            origin: Origin(None),
            line,
            what: "DATA binary_compressed (decompress with pcl_convert_pcd_ascii_binary)".into(),
        }),
        _ => Err(header_err(
            line,
            format!(
                "unknown DATA encoding '{}'",
                bt_scene::name::shown(&rest.join(" "))
            ),
        )),
    }
}

/// The fields of the header with their scalar types (FIELDS, SIZE, TYPE, COUNT agree).
fn fields(kw: &Keywords) -> Result<Vec<Field>, CloudError> {
    let data_line = kw.data_line;
    let names = kw
        .names
        .clone()
        .ok_or_else(|| header_err(data_line, "no FIELDS line"))?;
    let n = names.len();
    let sizes = kw
        .sizes
        .clone()
        .ok_or_else(|| header_err(data_line, "no SIZE line"))?;
    let types = kw
        .types
        .clone()
        .ok_or_else(|| header_err(data_line, "no TYPE line"))?;
    let counts = kw.counts.clone().unwrap_or_else(|| vec![1; n]);
    if sizes.len() != n || types.len() != n || counts.len() != n {
        return Err(header_err(
            data_line,
            format!(
                "{n} FIELDS but {} SIZE, {} TYPE and {} COUNT values",
                sizes.len(),
                types.len(),
                counts.len()
            ),
        ));
    }
    let mut fields = Vec::with_capacity(n);
    for i in 0..n {
        let Some(scalar) = Scalar::from_pcd(types[i], sizes[i]) else {
            return Err(header_err(
                data_line,
                format!(
                    "field '{}': TYPE {} with SIZE {} is not valid",
                    bt_scene::name::shown(&names[i]),
                    types[i] as char,
                    sizes[i]
                ),
            ));
        };
        fields.push(Field {
            name: names[i].clone(),
            size: sizes[i],
            count: counts[i],
            scalar,
        });
    }
    Ok(fields)
}

/// The number of points: POINTS, or WIDTH x HEIGHT, which must agree when both are given.
fn point_count(kw: &Keywords) -> Result<u64, CloudError> {
    let data_line = kw.data_line;
    Ok(match (kw.points, kw.width, kw.height) {
        (Some(p), Some(w), Some(h)) if w.checked_mul(h) != Some(p) => {
            return Err(header_err(
                data_line,
                format!("POINTS {p} differs from WIDTH {w} x HEIGHT {h}"),
            ));
        }
        (Some(p), _, _) => p,
        (None, Some(w), Some(h)) => w
            .checked_mul(h)
            .ok_or_else(|| header_err(data_line, "WIDTH x HEIGHT overflows"))?,
        (None, Some(w), None) => w,
        _ => return Err(header_err(data_line, "neither POINTS nor WIDTH is given")),
    })
}

/// Columns and offsets of the fields and the indices of the fields read.
fn layout(fields: &[Field], data_line: usize) -> Result<Layout, CloudError> {
    let n = fields.len();
    // Column (value index) and byte offset of each wanted field.
    let mut col = Vec::with_capacity(n);
    let mut offset = Vec::with_capacity(n);
    let (mut c, mut o) = (0usize, 0usize);
    for f in fields {
        col.push(c);
        offset.push(o);
        c += f.count;
        o += f.size * f.count;
    }
    let find = |name: &str| -> Result<Option<usize>, CloudError> {
        match fields.iter().position(|f| f.name == name) {
            Some(i) if fields[i].count != 1 => Err(header_err(
                data_line,
                format!(
                    "field '{}' has COUNT {}, expected 1",
                    bt_scene::name::shown(name),
                    fields[i].count
                ),
            )),
            other => Ok(other),
        }
    };
    let (xyz, normal) = super::point_columns(find, ["normal_x", "normal_y", "normal_z"])?;

    Ok(Layout {
        col,
        offset,
        values_per_point: c,
        stride: o,
        xyz,
        normal,
    })
}

/// Reads `header.count` packed little-endian records.
fn read_binary_body(
    bytes: &[u8],
    header: &PcdHeader,
    layout: &Layout,
    sink: &mut PointSink,
) -> Result<(), CloudError> {
    let (fields, offset, stride, count) =
        (&header.fields, &layout.offset, layout.stride, header.count);
    let (xyz, normal) = (layout.xyz, layout.normal);
    let mut pos = header.data_start;
    let get = |rec: &[u8], i: usize| -> Real {
        let f = &fields[i];
        f.scalar.decode(&rec[offset[i]..offset[i] + f.size], false)
    };
    for k in 0..count {
        let at = DataPos {
            element: k,
            line: None,
        };
        let Some(rec) = bytes.get(pos..pos + stride) else {
            return Err(CloudError::Truncated {
                origin: Origin(None),
                at,
                expected: count,
            });
        };
        pos += stride;
        let p = Vec3::new(get(rec, xyz[0]), get(rec, xyz[1]), get(rec, xyz[2]));
        let nrm = normal.map_or(Vec3::ZERO, |[a, b, c]| {
            Vec3::new(get(rec, a), get(rec, b), get(rec, c))
        });
        sink.push(p, nrm, at)?;
    }
    Ok(())
}

/// Reads `header.count` points, one a line (blank lines skipped).
fn read_ascii_body(
    bytes: &[u8],
    header: &PcdHeader,
    layout: &Layout,
    sink: &mut PointSink,
) -> Result<(), CloudError> {
    let (fields, col, values_per_point, count) = (
        &header.fields,
        &layout.col,
        layout.values_per_point,
        header.count,
    );
    let (xyz, normal) = (layout.xyz, layout.normal);
    let (mut pos, data_line) = (header.data_start, header.data_line);
    let mut line = data_line;
    let mut wanted: Vec<(usize, usize)> = xyz.iter().map(|&i| (col[i], i)).collect();
    if let Some(nr) = normal {
        wanted.extend(nr.iter().map(|&i| (col[i], i)));
    }
    let mut vals = [0.0f64; 6];
    for k in 0..count {
        let text = loop {
            let Some(raw) = next_line(bytes, &mut pos) else {
                return Err(CloudError::Truncated {
                    origin: Origin(None),
                    at: DataPos {
                        element: k,
                        line: Some(line + 1),
                    },
                    expected: count,
                });
            };
            line += 1;
            if !raw.iter().all(u8::is_ascii_whitespace) {
                break raw;
            }
        };
        let at = DataPos {
            element: k,
            line: Some(line),
        };
        let bad = |reason: String| CloudError::BadValue {
            origin: Origin(None),
            at,
            reason,
        };
        let text = std::str::from_utf8(text).map_err(|_| bad("line is not text".into()))?;
        let toks: Vec<&str> = text.split_ascii_whitespace().collect();
        if toks.len() != values_per_point {
            return Err(bad(format!(
                "expected {values_per_point} values, found {}",
                toks.len()
            )));
        }
        for (slot, &(c, fi)) in wanted.iter().enumerate() {
            vals[slot] = parse_number(toks[c], fields[fi].scalar).ok_or_else(|| {
                bad(format!(
                    "'{}' is not a number ('{}')",
                    bt_scene::name::shown(toks[c]),
                    bt_scene::name::shown(&fields[fi].name)
                ))
            })?;
        }
        let p = Vec3::new(vals[0], vals[1], vals[2]);
        let nrm = if normal.is_some() {
            Vec3::new(vals[3], vals[4], vals[5])
        } else {
            Vec3::ZERO
        };
        sink.push(p, nrm, at)?;
    }
    Ok(())
}

/// Read a PCD file from a stream (read to the end first, so counts can be checked against
/// the real length).
pub fn read_pcd<R: Read>(reader: R, opts: &ReadOptions) -> Result<LoadedCloud, CloudError> {
    parse_pcd(&read_all(reader)?, opts)
}

/// Write `cloud` as PCD v0.7 with `F 8` fields `x y z` (and `normal_x normal_y normal_z`
/// when present), as an unorganised cloud (`HEIGHT 1`). ASCII values use the shortest
/// round-trip representation.
pub fn write_pcd<W: Write>(cloud: &PointCloud, mut w: W, data: PcdData) -> Result<(), CloudError> {
    let has_n = cloud.normals().is_some();
    let k = if has_n { 6 } else { 3 };
    let head = format!(
        "# .PCD v0.7 - Point Cloud Data file format (written by beamtrace, metres, z up)\nVERSION 0.7\n\
         FIELDS x y z{}\nSIZE{}\nTYPE{}\nCOUNT{}\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {}\n",
        if has_n {
            " normal_x normal_y normal_z"
        } else {
            ""
        },
        " 8".repeat(k),
        " F".repeat(k),
        " 1".repeat(k),
        match data {
            PcdData::Ascii => "ascii",
            PcdData::Binary => "binary",
        },
        n = cloud.len(),
    );
    w.write_all(head.as_bytes()).map_err(io_err)?;
    let encoding = match data {
        PcdData::Ascii => super::Encoding::Ascii,
        PcdData::Binary => super::Encoding::LittleEndian,
    };
    super::write_records(cloud, &mut w, encoding)
}
