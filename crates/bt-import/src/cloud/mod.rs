//! Reading and writing point clouds: PLY (ASCII, binary little- and big-endian) and PCD
//! (ASCII, binary). Only the thin `*_path` helpers touch the filesystem; the parsers work on
//! byte slices. [`scene`] extracts a cloud's planes (`bt-pointcloud`) into a scene.
//!
//! Robustness contract: malformed input never panics, and allocation is bounded by the
//! input length, never by a count claimed in the header. A claim that needs more than
//! twice the bytes present (plus 4 KiB) is rejected up front with
//! [`CloudError::CountExceedsData`] (a header claiming three billion points in a 1 KB
//! file); a smaller shortfall is read up to the point where data runs out and reported as
//! [`CloudError::Truncated`] with the point index, which is what a cut-off download
//! looks like.
//!
//! Non-finite points (NaN or infinite x, y or z; common in organised PCD files where a
//! pixel had no return) are skipped and counted by default ([`NonFinitePolicy::Skip`]),
//! because that is what downstream plane extraction wants; choose
//! [`NonFinitePolicy::Reject`] to get a [`CloudError::NonFinite`] error instead.
//! A non-finite *normal* on a finite point is replaced by the zero vector (normals are only
//! a hint for orienting extracted planes).

use bt_geom::{Real, Vec3};
mod error;
mod pcd;
mod ply;
pub mod scene;

use std::io::Read;
use std::path::Path;

pub use pcd::{PcdData, parse_pcd, read_pcd, write_pcd};
pub use ply::{PlyFormat, parse_ply, read_ply, write_ply};

use bt_pointcloud::PointCloud;
pub use error::{CloudError, DataPos, Origin};
pub use scene::{cloud_description, is_point_cloud};

/// What to do with points whose coordinates are NaN or infinite.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum NonFinitePolicy {
    /// Leave the point out and count it in [`LoadedCloud::skipped_non_finite`].
    #[default]
    Skip,
    /// Fail with [`CloudError::NonFinite`] at the first such point.
    Reject,
}

/// Options for the readers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadOptions {
    /// Policy for NaN / infinite coordinates.
    pub non_finite: NonFinitePolicy,
    /// Budget: the most points a file may declare (CLI `--max-cloud-points`), checked against
    /// the header before any point is stored; default [`DEFAULT_MAX_POINTS`].
    pub max_points: u64,
    /// Budget: the largest file read, bytes (CLI `--max-file-bytes`), checked against the
    /// file's size before reading; default [`crate::MAX_FILE_BYTES`].
    pub max_file_bytes: u64,
}

/// Default of [`ReadOptions::max_points`]: 20 million points, the budget `sample` writes
/// clouds under (plane extraction then holds every point with its normal and neighbours).
pub const DEFAULT_MAX_POINTS: u64 = 20_000_000;

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            non_finite: NonFinitePolicy::default(),
            max_points: DEFAULT_MAX_POINTS,
            max_file_bytes: crate::MAX_FILE_BYTES.limit,
        }
    }
}

/// Refuse a header declaring more points than the budget.
fn check_budget(claimed: u64, opts: &ReadOptions) -> Result<(), CloudError> {
    if claimed <= opts.max_points {
        return Ok(());
    }
    Err(CloudError::OverBudget {
        origin: Origin(None),
        claimed,
        budget: opts.max_points,
    })
}

/// A cloud read from a file together with what the reader had to leave out.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedCloud {
    /// The finite points (metres, the file's frame) and normals if the file has all of
    /// nx, ny, nz (PLY) or normal_x, normal_y, normal_z (PCD).
    pub cloud: PointCloud,
    /// Number of points left out because a coordinate was NaN or infinite.
    pub skipped_non_finite: u64,
}

/// File formats understood by [`read_path`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloudFormat {
    /// Stanford PLY.
    Ply,
    /// Point Cloud Library PCD.
    Pcd,
}

/// Guess the format from the extension (`.ply` / `.pcd`, any case), else from the first
/// bytes (`ply` magic; PCD's `# .PCD` comment or `VERSION` line).
pub fn detect_format(path: Option<&Path>, head: &[u8]) -> Option<CloudFormat> {
    if let Some(ext) = path.and_then(|p| p.extension()).and_then(|e| e.to_str()) {
        if ext.eq_ignore_ascii_case("ply") {
            return Some(CloudFormat::Ply);
        }
        if ext.eq_ignore_ascii_case("pcd") {
            return Some(CloudFormat::Pcd);
        }
    }
    if head.starts_with(b"ply") {
        Some(CloudFormat::Ply)
    } else if head.starts_with(b"# .PCD")
        || head.starts_with(b"VERSION")
        || head.starts_with(b"FIELDS")
    {
        Some(CloudFormat::Pcd)
    } else {
        None
    }
}

/// Parse a PLY or PCD file held in memory, detecting the format from its first bytes.
pub fn parse_any(bytes: &[u8], opts: &ReadOptions) -> Result<LoadedCloud, CloudError> {
    match detect_format(None, bytes) {
        Some(CloudFormat::Ply) => parse_ply(bytes, opts),
        Some(CloudFormat::Pcd) => parse_pcd(bytes, opts),
        None => Err(CloudError::UnknownFormat {
            origin: Origin(None),
        }),
    }
}

/// Read a `.ply` or `.pcd` file. Errors carry the path.
pub fn read_path(path: &Path, opts: &ReadOptions) -> Result<LoadedCloud, CloudError> {
    let bytes =
        crate::source::read_file(path, opts.max_file_bytes).map_err(|source| CloudError::Io {
            origin: Origin(Some(path.to_path_buf())),
            source,
        })?;
    let result = match detect_format(Some(path), &bytes) {
        Some(CloudFormat::Ply) => parse_ply(&bytes, opts),
        Some(CloudFormat::Pcd) => parse_pcd(&bytes, opts),
        None => Err(CloudError::UnknownFormat {
            origin: Origin(None),
        }),
    };
    result.map_err(|e| e.with_path(path))
}

/// Write `cloud` to `path`, choosing the format from the extension: `.ply` as binary
/// little-endian PLY, `.pcd` as ASCII PCD. Atomic (`bt_output::write_atomic_with`): a failed
/// or killed write leaves the previous file, never a truncated one.
pub fn write_path(cloud: &PointCloud, path: &Path) -> Result<(), CloudError> {
    let format = detect_format(Some(path), b"").ok_or_else(|| CloudError::UnknownFormat {
        origin: Origin(Some(path.to_path_buf())),
    })?;
    bt_output::write_atomic_with(path, |w| {
        match format {
            CloudFormat::Ply => write_ply(cloud, w, PlyFormat::BinaryLittleEndian),
            CloudFormat::Pcd => write_pcd(cloud, w, PcdData::Ascii),
        }
        .map_err(|e| e.with_path(path))
    })
}

/// The columns of `x`, `y`, `z` (each required: a missing one is `MissingField`) and of the
/// three normal components `normal` (all three or none), looked up by `find`, which refuses a
/// column the reader cannot use (a list, a COUNT above 1).
pub(crate) fn point_columns(
    find: impl Fn(&str) -> Result<Option<usize>, CloudError>,
    normal: [&str; 3],
) -> Result<([usize; 3], Option<[usize; 3]>), CloudError> {
    let mut xyz = [0usize; 3];
    for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
        xyz[k] = find(name)?.ok_or_else(|| CloudError::MissingField {
            origin: Origin(None),
            field: name.to_string(),
        })?;
    }
    let normal = match (find(normal[0])?, find(normal[1])?, find(normal[2])?) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    Ok((xyz, normal))
}

/// How a writer encodes the values of a point record.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Encoding {
    /// One line per point, values in the shortest spelling that reads back to the same `Real`.
    Ascii,
    /// `f64` little endian.
    LittleEndian,
    /// `f64` big endian.
    BigEndian,
}

/// Writes one record per point of `cloud` after its header: `x y z`, then `nx ny nz` when the
/// cloud has normals.
pub(crate) fn write_records<W: std::io::Write>(
    cloud: &PointCloud,
    w: &mut W,
    encoding: Encoding,
) -> Result<(), CloudError> {
    let mut buf = Vec::with_capacity(64);
    for (i, p) in cloud.points().iter().enumerate() {
        buf.clear();
        let mut vals = vec![p.x, p.y, p.z];
        if let Some(ns) = cloud.normals() {
            vals.extend([ns[i].x, ns[i].y, ns[i].z]);
        }
        let all = vals.iter();
        match encoding {
            Encoding::Ascii => {
                let s: Vec<String> = all.map(|v| format!("{v:?}")).collect();
                buf.extend_from_slice(s.join(" ").as_bytes());
                buf.push(b'\n');
            }
            Encoding::LittleEndian => all.for_each(|v| buf.extend_from_slice(&v.to_le_bytes())),
            Encoding::BigEndian => all.for_each(|v| buf.extend_from_slice(&v.to_be_bytes())),
        }
        w.write_all(&buf).map_err(io_err)?;
    }
    Ok(())
}

/// Whether a header's claim of at least `min_bytes` of data is absurd given `available`
/// bytes (rather than a file cut short).
pub(crate) fn is_absurd(min_bytes: u128, available: usize) -> bool {
    min_bytes > 2 * available as u128 + 4096
}

pub(crate) fn io_err(source: std::io::Error) -> CloudError {
    CloudError::Io {
        origin: Origin(None),
        source,
    }
}

pub(crate) fn read_all<R: Read>(mut r: R) -> Result<Vec<u8>, CloudError> {
    let mut buf = Vec::new();
    r.read_to_end(&mut buf).map_err(io_err)?;
    Ok(buf)
}

/// Numeric scalar types shared by PLY and PCD: the byte-level layer of [`crate::formats`].
use crate::formats::Scalar;

/// Collects decoded points, applying the non-finite policy.
pub(crate) struct PointSink {
    points: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    skipped: u64,
    policy: NonFinitePolicy,
}

impl PointSink {
    /// `capacity` must already be bounded by the input length.
    pub(crate) fn new(capacity: usize, with_normals: bool, policy: NonFinitePolicy) -> Self {
        Self {
            points: Vec::with_capacity(capacity),
            normals: with_normals.then(|| Vec::with_capacity(capacity)),
            skipped: 0,
            policy,
        }
    }

    pub(crate) fn push(&mut self, p: Vec3, n: Vec3, at: DataPos) -> Result<(), CloudError> {
        if !p.is_finite() {
            return match self.policy {
                NonFinitePolicy::Skip => {
                    self.skipped += 1;
                    Ok(())
                }
                NonFinitePolicy::Reject => Err(CloudError::NonFinite {
                    origin: Origin(None),
                    at,
                }),
            };
        }
        self.points.push(p);
        if let Some(ns) = &mut self.normals {
            ns.push(if n.is_finite() { n } else { Vec3::ZERO });
        }
        Ok(())
    }

    /// The cloud (finite points and normals by construction: the checked constructors
    /// cannot refuse it).
    pub(crate) fn finish(self) -> Result<LoadedCloud, CloudError> {
        let cloud = match self.normals {
            Some(normals) => PointCloud::with_normals(self.points, normals)?,
            None => PointCloud::new(self.points)?,
        };
        Ok(LoadedCloud {
            cloud,
            skipped_non_finite: self.skipped,
        })
    }
}

/// Split off the next line (without `\n` / `\r\n`) starting at `*pos`; `None` at the end.
pub(crate) fn next_line<'a>(bytes: &'a [u8], pos: &mut usize) -> Option<&'a [u8]> {
    if *pos >= bytes.len() {
        return None;
    }
    let rest = &bytes[*pos..];
    let (line, adv) = match rest.iter().position(|&b| b == b'\n') {
        Some(i) => (&rest[..i], i + 1),
        None => (rest, rest.len()),
    };
    *pos += adv;
    Some(line.strip_suffix(b"\r").unwrap_or(line))
}

/// Parse a number token the way both formats spell them (`nan`, `inf` accepted). A value
/// declared as 32-bit float is rounded to `f32` first, so ASCII and binary files of the
/// same declared type give identical points.
pub(crate) fn parse_number(tok: &str, ty: Scalar) -> Option<Real> {
    match ty {
        Scalar::F32 => tok.parse::<f32>().ok().map(Real::from),
        _ => tok.parse::<Real>().ok(),
    }
}
