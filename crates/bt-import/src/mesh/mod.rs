//! Mesh files (Wavefront OBJ, PLY, STL, glTF 2.0) to bounded planar polygon surfaces: the
//! readers parse bytes into a [`bt_mesh::RawMesh`] (polygon soup) and `bt-mesh` welds and merges it
//! ([`bt_mesh::merge_mesh`]). [`read_mesh_path`] reads a file and picks the reader by
//! extension; [`scene`] turns the surfaces into a [`bt_scene::Scene`].
//!
//! Units and frame: coordinates are taken as metres in the file's own frame (beamtrace uses
//! z up; no axis swap is applied), except glTF's +Y up, turned to z up (`gltf` module).

mod error;
mod gltf;
mod obj;
mod ply;
pub mod scene;
mod stl;

use bt_geom::Vec3;
use bt_mesh::{MergeOptions, MeshImport, RawMesh};
use std::path::Path;

pub use error::{MeshError, Position};

/// The file name used in messages when none is given.
const UNNAMED: &str = "<input>";

/// Mesh file formats, for callers that choose the reader themselves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// PLY (ASCII, binary little or big endian).
    Ply,
    /// STL (binary or ASCII; `stl`'s module docs).
    Stl,
}

/// Reads a Wavefront OBJ mesh from bytes and merges its faces into planar surfaces.
/// `file` names the source in errors and warnings. `.mtl` libraries are not read; `usemtl`
/// names are kept as [`bt_mesh::MeshSurface::material`].
pub fn read_obj(
    bytes: &[u8],
    file: Option<&str>,
    opts: &MergeOptions,
) -> Result<MeshImport, MeshError> {
    read_transformed(bytes, MeshFormat::Obj, file, opts, &|p| p)
}

/// Reads a PLY mesh (ASCII, binary little or big endian) from bytes and merges its faces into
/// planar surfaces. `file` names the source in errors and warnings.
pub fn read_ply(
    bytes: &[u8],
    file: Option<&str>,
    opts: &MergeOptions,
) -> Result<MeshImport, MeshError> {
    read_transformed(bytes, MeshFormat::Ply, file, opts, &|p| p)
}

/// Reads an STL mesh (binary or ASCII) from bytes and merges its faces into planar surfaces.
/// `file` names the source in errors and warnings. STL has no materials: every surface gets
/// the default one.
pub fn read_stl(
    bytes: &[u8],
    file: Option<&str>,
    opts: &MergeOptions,
) -> Result<MeshImport, MeshError> {
    read_transformed(bytes, MeshFormat::Stl, file, opts, &|p| p)
}

/// Reads a glTF 2.0 scene from bytes (`.glb`, or `.gltf` JSON) and merges its triangles into
/// planar surfaces, as a `.gltf`/`.glb` scene file loads but reading no file: every buffer must be the
/// GLB binary chunk or a `data:` URI. `file` names the source in errors and warnings.
pub fn read_gltf(
    bytes: &[u8],
    file: Option<&str>,
    opts: &MergeOptions,
) -> Result<MeshImport, MeshError> {
    opts.validate()?;
    let hashing = crate::source::Hashing::Off;
    let (import, _) = merge_gltf(
        bytes,
        (file.unwrap_or(UNNAMED), None),
        (opts, u64::MAX),
        hashing,
    )?;
    Ok(import)
}

/// The glTF document of `bytes` (named `file`, its buffers read from `folder`, each within
/// `max_file_bytes`; none without a folder) merged into planar surfaces with `opts` (checked
/// by the caller), and the document (its buffer files and their SHA-256s with `hashing` on).
fn merge_gltf(
    bytes: &[u8],
    (file, folder): (&str, Option<&Path>),
    (opts, max_file_bytes): (&MergeOptions, u64),
    hashing: crate::source::Hashing,
) -> Result<(MeshImport, gltf::Document), MeshError> {
    let doc = gltf::document(bytes, (file, folder), max_file_bytes, hashing)?;
    let raw = gltf::parse(&doc, file, opts.max_elements)?;
    Ok((bt_mesh::merge_mesh(&raw, opts, file)?, doc))
}

/// Checks `opts` and parses `bytes` as `format` into the polygon soup the merge starts from.
fn parse(
    bytes: &[u8],
    format: MeshFormat,
    file: Option<&str>,
    opts: &MergeOptions,
) -> Result<RawMesh, MeshError> {
    let file = file.unwrap_or(UNNAMED);
    opts.validate()?;
    match format {
        MeshFormat::Obj => obj::parse(bytes, file, opts.max_elements),
        MeshFormat::Ply => ply::parse(bytes, file, opts.max_elements),
        MeshFormat::Stl => stl::parse(bytes, file, opts.max_elements),
    }
}

/// Reads a mesh from bytes like [`read_obj`] / [`read_ply`] / [`read_stl`], but first maps every vertex
/// through `to_world` (metres to metres), so that welding and the coplanar merge run in the
/// world frame with their tolerances in world metres: the `to_world` transform of a shape in
/// a Mitsuba scene. A vertex that the transform makes non-finite is an error.
pub fn read_transformed(
    bytes: &[u8],
    format: MeshFormat,
    file: Option<&str>,
    opts: &MergeOptions,
    to_world: &dyn Fn(Vec3) -> Vec3,
) -> Result<MeshImport, MeshError> {
    let raw = parse(bytes, format, file, opts)?;
    merge_transformed(raw, file.unwrap_or(UNNAMED), opts, to_world)
}

/// Maps every vertex of `raw` through `to_world` (metres to metres) and merges it
/// ([`read_transformed`] after its parse); `file` names the source in warnings and errors.
pub(crate) fn merge_transformed(
    mut raw: bt_mesh::RawMesh,
    file: &str,
    opts: &MergeOptions,
    to_world: &dyn Fn(Vec3) -> Vec3,
) -> Result<MeshImport, MeshError> {
    for (vertex, p) in raw.positions.iter_mut().enumerate() {
        *p = to_world(*p);
        if !p.is_finite() {
            return Err(MeshError::NonFiniteTransformed {
                file: file.to_string(),
                vertex,
            });
        }
    }
    Ok(bt_mesh::merge_mesh(&raw, opts, file)?)
}

/// Reads the mesh file at `path` and merges its faces into planar surfaces, choosing the
/// reader by extension (`.obj`, `.ply` or `.stl`, case-insensitive). Coordinates are in metres. A file
/// larger than `max_file_bytes` ([`crate::MAX_FILE_BYTES`]) is refused before it is read.
pub fn read_mesh_path(
    path: &Path,
    opts: &MergeOptions,
    max_file_bytes: u64,
) -> Result<MeshImport, MeshError> {
    let hashing = crate::source::Hashing::Off;
    Ok(read_mesh_file(path, opts, max_file_bytes, hashing)?.0)
}

/// [`read_mesh_path`], with the SHA-256 of the bytes it parsed.
pub(crate) fn read_mesh_file(
    path: &Path,
    opts: &MergeOptions,
    max_file_bytes: u64,
    hashing: crate::source::Hashing,
) -> Result<(MeshImport, Option<crate::source::Digest>), MeshError> {
    let file = path.display().to_string();
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let format = match extension.as_str() {
        "obj" => MeshFormat::Obj,
        "ply" => MeshFormat::Ply,
        "stl" => MeshFormat::Stl,
        _ => return Err(MeshError::UnsupportedExtension { file, extension }),
    };
    opts.validate()?;
    let bytes = read_bytes(path, max_file_bytes)?;
    let import = read_transformed(&bytes, format, Some(&file), opts, &|p| p)?;
    Ok((import, hashing.of(&bytes)))
}

/// Reads the glTF 2.0 scene at `path` (`.gltf` with its buffers, or `.glb`; the `gltf`
/// module's docs say what is read, and the +Y-up to +Z-up turn) and merges its triangles into
/// planar surfaces, each file within `max_file_bytes`. Returns the import, the SHA-256 of the
/// scene file's bytes, and the external buffer files read with theirs (no digests with
/// `hashing` off).
pub(crate) fn read_gltf_file(
    path: &Path,
    (opts, max_file_bytes): (&MergeOptions, u64),
    hashing: crate::source::Hashing,
) -> Result<GltfRead, MeshError> {
    let file = path.display().to_string();
    opts.validate()?;
    let bytes = read_bytes(path, max_file_bytes)?;
    let (import, doc) = merge_gltf(
        &bytes,
        (&file, path.parent()),
        (opts, max_file_bytes),
        hashing,
    )?;
    Ok((import, hashing.of(&bytes), (doc.files, doc.digests)))
}

/// The bytes of the mesh file `path` ([`crate::source::read_file`]: a regular file within
/// `max_file_bytes`), an I/O error naming it otherwise.
fn read_bytes(path: &Path, max_file_bytes: u64) -> Result<Vec<u8>, MeshError> {
    crate::source::read_file(path, max_file_bytes).map_err(|source| MeshError::Io {
        file: path.display().to_string(),
        source,
    })
}

/// What [`read_gltf_file`] returns: the import, the scene file's SHA-256, the buffer files
/// read and their SHA-256s.
pub(crate) type GltfRead = (
    MeshImport,
    Option<crate::source::Digest>,
    (Vec<std::path::PathBuf>, Vec<crate::source::Digest>),
);

/// Returns the index of `name` in `table`, appending it when new. Linear search: files have a
/// handful of objects and materials, and the reader caches the current one.
fn intern(table: &mut Vec<String>, name: &str) -> u32 {
    match table.iter().position(|n| n == name) {
        Some(i) => i as u32,
        None => {
            table.push(name.to_owned());
            (table.len() - 1) as u32
        }
    }
}

/// Refuse the next element of kind `element` (`vertices` or `faces`) of an OBJ file when
/// `so_far` of them already fill the budget `max_elements`.
fn check_budget(
    file: &str,
    element: &'static str,
    so_far: usize,
    max_elements: u64,
    line: usize,
) -> Result<(), MeshError> {
    if (so_far as u64) < max_elements {
        return Ok(());
    }
    Err(MeshError::Budget {
        file: file.to_owned(),
        element,
        count: format!("at least {} (line {line})", max_elements.saturating_add(1)),
        budget: max_elements,
    })
}
