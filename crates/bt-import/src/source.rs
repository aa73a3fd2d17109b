//! The one loading entry: a source string (`builtin:NAME` or a file path) to a validated
//! [`Scene`] or [`DynamicScene`]. Every command of the CLI loads through here, so every
//! command accepts the same sources and gives the same errors.

use crate::builtin::{builtin_json, builtin_names};
use crate::mesh::scene::from_mesh;
use crate::{ImportError, parse_json, parse_toml};
use bt_geom::Real;
use bt_scene::dynamic::DynamicScene;
use bt_scene::{DEFAULT_FREQUENCY_HZ, Scene, SceneDescription, Terminals};
use std::path::{Path, PathBuf};

/// Options of scene loading.
#[derive(Debug, Clone)]
pub struct LoadOptions {
    /// TX/RX overriding the file's; formats that carry none (meshes, XML, point clouds)
    /// without them load as bare geometry.
    pub terminals: Terminals,
    /// Coplanar-merge tolerances for meshes.
    pub merge: bt_mesh::MergeOptions,
    /// Mesh surfaces smaller than this (m²) become blockers (default 0.25 m², as the paper); the
    /// pieces of a region split around holes count with the whole region's area.
    pub min_reflector_area_m2: Real,
    /// Carrier frequency for meshes and point clouds, Hz (default 28 GHz).
    pub frequency_hz: Real,
    /// Plane-extraction parameters for point clouds (PLY without faces, PCD).
    pub extract: bt_pointcloud::ExtractParams,
    /// Point-cloud reading: budget on the points a file declares (`max_points`, CLI
    /// `--max-cloud-points`) and the policy for non-finite points.
    pub cloud: crate::cloud::ReadOptions,
    /// A radio material for every surface (CLI `--material itu:NAME --thickness M`), replacing
    /// the radio model of every material of the loaded scene, whatever its format.
    pub radio: Option<bt_channel::RadioMaterial>,
    /// The slab thickness (m) of every material the scene leaves a half-space (CLI
    /// `--thickness`), so that `--transmission` crosses them too; ignored with `radio`
    /// (`--material`), whose own thickness it then is.
    pub thickness: Option<Real>,
    /// Budget: the largest input file read, bytes (CLI `--max-file-bytes`): scene files, meshes
    /// (also those of an XML scene), point clouds. Checked against the file's size before it
    /// is read ([`MAX_FILE_BYTES`]).
    pub max_file_bytes: u64,
    /// Budget: bytes an XML scene's `$parameter` substitutions may produce in all, checked
    /// before each substitution (CLI `--max-xml-substitution`, [`crate::xml::MAX_XML_SUBSTITUTION`]).
    pub max_xml_substitution: u64,
}

/// Budget on the size of one input file: the default of 256 MiB holds a binary cloud of the
/// point budget (20 M points × 12 B), a mesh of the element budget, and keeps a JSON or TOML
/// scene file's parse (a few times its size) under a 2 GB address space.
pub const MAX_FILE_BYTES: bt_geom::Budget =
    bt_geom::Budget::new("file bytes", "--max-file-bytes", 256 << 20);

impl LoadOptions {
    /// Refuse a value no load can use: a minimum reflector area that is not a finite number
    /// ≥ 0 (NaN would make every surface a blocker), merge options out of range (checked for
    /// every source, not only meshes: a value given and ignored is an error too).
    pub fn check(&self) -> Result<(), ImportError> {
        self.merge.validate()?;
        let area = self.min_reflector_area_m2;
        if !(area.is_finite() && area >= 0.0) {
            return Err(ImportError::Option {
                option: "--min-reflector-area",
                range: "a finite number of m² >= 0",
                value: area,
            });
        }
        Ok(())
    }
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            terminals: Terminals::default(),
            merge: bt_mesh::MergeOptions::default(),
            min_reflector_area_m2: 0.25,
            frequency_hz: DEFAULT_FREQUENCY_HZ,
            extract: bt_pointcloud::ExtractParams::default(),
            cloud: crate::cloud::ReadOptions::default(),
            radio: None,
            thickness: None,
            max_file_bytes: MAX_FILE_BYTES.limit,
            max_xml_substitution: crate::xml::MAX_XML_SUBSTITUTION.limit,
        }
    }
}

/// A loaded scene (a [`Scene`], or a [`DynamicScene`] from [`load_dynamic`]), the non-fatal
/// notes of the import (merged faces, holes dropped, ...) and the files it read.
#[derive(Debug, Clone)]
pub struct Loaded<S = Scene> {
    /// The validated scene.
    pub scene: S,
    /// Warnings for the user.
    pub warnings: Vec<String>,
    /// Every file the load read, as it opened them: the named file first, then each mesh an
    /// XML scene names (once each); empty for a built-in scene. The inputs an output of the
    /// same run must not replace (`bt_output::refuse_input`).
    pub sources: Vec<PathBuf>,
    /// The SHA-256 of each of [`Loaded::sources`] as the load read it (the bytes it parsed),
    /// in the same order; empty when the format does not record them (point clouds) or the
    /// load took none ([`load_without_digests`]). What the load cache ([`crate::cache`]) keys
    /// and checks its entries by.
    pub digests: Vec<Digest>,
}

/// A SHA-256 digest.
pub type Digest = [u8; 32];

/// The SHA-256 of `bytes`.
pub(crate) fn digest(bytes: &[u8]) -> Digest {
    use sha2::Digest as _;
    sha2::Sha256::digest(bytes).into()
}

/// Whether a load records [`Loaded::digests`]: they serve the load cache only, and hashing
/// every file read is a tenth of a city's load (San Francisco's 25 MB).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Hashing {
    /// Take the SHA-256 of every file read.
    On,
    /// Take none ([`Loaded::digests`] stays empty).
    Off,
}

impl Hashing {
    /// The SHA-256 of `bytes` when on.
    pub(crate) fn of(self, bytes: &[u8]) -> Option<Digest> {
        (self == Hashing::On).then(|| digest(bytes))
    }
}

impl<S> Loaded<S> {
    /// A load that read no file (yet): the scene and its warnings.
    pub(crate) fn new(scene: S, warnings: Vec<String>) -> Self {
        Loaded {
            scene,
            warnings,
            sources: Vec::new(),
            digests: Vec::new(),
        }
    }

    /// The same load holding `scene` instead (the files read and warnings kept).
    pub fn map<T>(self, f: impl FnOnce(S) -> T) -> Loaded<T> {
        Loaded {
            scene: f(self.scene),
            warnings: self.warnings,
            sources: self.sources,
            digests: self.digests,
        }
    }
}

/// Where a scene comes from, parsed from the command-line spelling by [`Source::parse`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A scene shipped inside the library (`builtin:NAME`), see [`crate::builtin_names`].
    Builtin(String),
    /// A file; its [`Format`] is chosen by extension (and, for `.ply`, by its header).
    File(PathBuf),
}

impl Source {
    /// `builtin:NAME` is a built-in scene, anything else a file path.
    pub fn parse(text: &str) -> Source {
        match text.strip_prefix("builtin:") {
            Some(name) => Source::Builtin(name.to_string()),
            None => Source::File(PathBuf::from(text)),
        }
    }
}

/// File formats [`load`] understands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// The project's scene file, JSON (`.json`).
    Json,
    /// The project's scene file, TOML (`.toml`).
    Toml,
    /// A Wavefront OBJ mesh (`.obj`).
    Obj,
    /// A PLY mesh (`.ply` declaring faces).
    PlyMesh,
    /// An STL mesh, binary or ASCII (`.stl`).
    Stl,
    /// A glTF 2.0 scene (`.gltf` with its buffers, or `.glb`): its triangles as a mesh.
    Gltf,
    /// A point cloud: `.pcd`, or `.ply` declaring no faces; planes are extracted.
    PointCloud,
    /// A Mitsuba 3 / Sionna RT scene (`.xml`) with PLY/OBJ shapes and radio bsdfs.
    Xml,
}

impl Format {
    /// The format of the file at `path`: by extension (any case); a `.ply` is a point cloud
    /// when its header declares no faces. A directory is an error of its own, not an
    /// "unsupported format".
    pub fn of(path: &Path) -> Result<Format, ImportError> {
        let display = path.display().to_string();
        if path.is_dir() {
            return Err(ImportError::IsDirectory { path: display });
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        Ok(match ext.as_str() {
            "json" => Format::Json,
            "toml" => Format::Toml,
            "obj" => Format::Obj,
            "xml" => Format::Xml,
            "pcd" => Format::PointCloud,
            "ply" if crate::cloud::is_point_cloud(path) => Format::PointCloud,
            "ply" => Format::PlyMesh,
            "stl" => Format::Stl,
            "gltf" | "glb" => Format::Gltf,
            _ => return Err(ImportError::UnsupportedFormat { path: display }),
        })
    }
}

/// Refuse anything but a regular file (or a symlink to one) before opening it: opening a
/// FIFO blocks until a writer comes, and a device can stream forever. The error is an I/O
/// error of kind `InvalidInput`, so every reader reports it with its file's path. The size in
/// bytes of the file found, from its `metadata` (one `stat` for both).
fn regular(metadata: &std::fs::Metadata) -> std::io::Result<u64> {
    let kind = metadata.file_type();
    if kind.is_file() {
        return Ok(metadata.len());
    }
    let what = if kind.is_dir() {
        "a directory"
    } else {
        "a FIFO, socket or device"
    };
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("not a regular file ({what}); give a scene file"),
    ))
}

/// The bytes of the regular file `path` ([`regular`]), refused before reading when its
/// size exceeds `max_bytes` ([`MAX_FILE_BYTES`]); a file that grows while read is cut at
/// `max_bytes + 1` and refused too. The refusal is an I/O error of kind `InvalidData` whose
/// message names the size, the budget and `--max-file-bytes`.
pub(crate) fn read_file(path: &Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    read_stated(path, &std::fs::metadata(path)?, max_bytes)
}

/// [`read_file`] of a file whose `metadata` (followed through symlinks) was taken already, by
/// a caller that needed it before (an XML scene charges its meshes' sizes in document order,
/// from one `stat` each taken on all cores): the same checks and errors, one `stat` fewer.
pub(crate) fn read_stated(
    path: &Path,
    metadata: &std::fs::Metadata,
    max_bytes: u64,
) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let size = regular(metadata)?;
    let over = |size: u64| {
        let budget = MAX_FILE_BYTES.with_limit(max_bytes);
        budget
            .check(size)
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
    };
    over(size)?;
    // Room for the whole file and one byte more: one `read` fills it and the next sees its
    // end (growing from nothing took 3-5 reads for a 5 kB mesh; a city has 2,367 of them).
    let mut bytes = Vec::with_capacity(usize::try_from(size).map_or(0, |n| n.saturating_add(1)));
    std::fs::File::open(path)?
        .take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)?;
    over(bytes.len() as u64)?;
    Ok(bytes)
}

/// Progress of a long load (plane extraction from a point cloud), for a progress bar.
pub type LoadProgress = bt_pointcloud::Progress;

/// Load the scene named by `source` (`builtin:NAME` or a file path), see [`Source`] and
/// [`Format`]. A dynamic scene (JSON/TOML with `steps`, or `builtin:living-room-dynamic`)
/// loads as its step 0; use [`load_dynamic`] for every step.
pub fn load(source: &str, options: &LoadOptions) -> Result<Loaded, ImportError> {
    load_with_progress(source, options, &mut |_| {})
}

/// [`load`], reporting the progress of point-cloud plane extraction to `progress`.
/// `options.radio`, when set, replaces the radio model of every material, whatever the format;
/// otherwise `options.thickness` makes each half-space material a slab.
pub fn load_with_progress(
    source: &str,
    options: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Loaded, ImportError> {
    load_hashing(source, options, progress, Hashing::On)
}

/// [`load_with_progress`] without [`Loaded::digests`] (left empty; the scene, warnings and
/// files read are the same): the SHA-256 of every file read serves only the load cache
/// ([`crate::cache`]), so a load that will not be stored there need not take it.
pub fn load_without_digests(
    source: &str,
    options: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Loaded, ImportError> {
    load_hashing(source, options, progress, Hashing::Off)
}

fn load_hashing(
    source: &str,
    options: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
    hashing: Hashing,
) -> Result<Loaded, ImportError> {
    options.check()?;
    let mut loaded = load_any(source, options, progress, hashing)?;
    if let Some(radio) = options.radio {
        loaded.scene = loaded.scene.with_radio_material(radio)?;
    } else if let Some(thickness) = options.thickness {
        loaded.scene = loaded.scene.with_half_spaces_as_slabs(thickness)?;
    }
    Ok(loaded)
}

fn load_any(
    source: &str,
    options: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
    hashing: Hashing,
) -> Result<Loaded, ImportError> {
    let path = match Source::parse(source) {
        Source::Builtin(name) => {
            // Generated built-ins (the city) have no JSON: they build their own scene.
            if builtin_json(&name).is_none()
                && let Some(scene) = crate::builtin_scene(&name, options.terminals)
            {
                return Ok(Loaded::new(scene?, Vec::new()));
            }
            let desc = builtin_description(&name)?;
            let scene = Scene::from_description(&desc, source, options.terminals)?;
            return Ok(Loaded::new(scene, Vec::new()));
        }
        Source::File(path) => path,
    };
    let display = path.display().to_string();
    let (mut loaded, read) = match Format::of(&path)? {
        format @ (Format::Json | Format::Toml) => {
            let (desc, read) = read_description(&path, format, options.max_file_bytes, hashing)?;
            let scene = Scene::from_description(&desc, &display, options.terminals)?;
            let loaded = Loaded::new(scene.without_duplicates(&display)?, Vec::new());
            (loaded, read)
        }
        Format::Obj | Format::PlyMesh | Format::Stl => {
            let (import, read) = crate::mesh::read_mesh_file(
                &path,
                &options.merge,
                options.max_file_bytes,
                hashing,
            )?;
            let name = file_stem(&path, "mesh");
            (from_mesh(import, &name, &display, options)?, read)
        }
        Format::Gltf => {
            let limits = (&options.merge, options.max_file_bytes);
            let (import, read, buffers) = crate::mesh::read_gltf_file(&path, limits, hashing)?;
            let name = file_stem(&path, "gltf");
            let mut loaded = from_mesh(import, &name, &display, options)?;
            (loaded.sources, loaded.digests) = buffers;
            (loaded, read)
        }
        Format::PointCloud => (
            crate::cloud::scene::load_cloud(&path, options, progress)?,
            None,
        ),
        Format::Xml => crate::xml::load_xml_read(&path, options, hashing)?,
    };
    loaded.sources.insert(0, path);
    match read {
        Some(read) => loaded.digests.insert(0, read),
        None => loaded.digests.clear(),
    }
    Ok(loaded)
}

/// Load `source` as a scene over time steps: JSON/TOML files and built-ins with their
/// `steps` and moving objects; every other source (meshes, point clouds) as one step.
/// Warnings of the import and the files read come back beside the scene.
pub fn load_dynamic(
    source: &str,
    options: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Loaded<DynamicScene>, ImportError> {
    options.check()?;
    let (desc, sources) = match Source::parse(source) {
        // A generated built-in (no JSON) is static: one step, loaded below.
        Source::Builtin(name)
            if builtin_json(&name).is_none() && builtin_names().contains(&name.as_str()) =>
        {
            (None, Vec::new())
        }
        Source::Builtin(name) => (Some(builtin_description(&name)?), Vec::new()),
        Source::File(path) => match Format::of(&path)? {
            format @ (Format::Json | Format::Toml) => {
                let (desc, _) =
                    read_description(&path, format, options.max_file_bytes, Hashing::Off)?;
                (Some(desc), vec![path])
            }
            _ => (None, Vec::new()),
        },
    };
    match desc {
        Some(desc) => {
            let mut scene = DynamicScene::from_description(&desc, source, options.terminals)?;
            for step in 0..scene.len() {
                scene.step(step).check_duplicates(source)?;
            }
            if let Some(radio) = options.radio {
                scene = scene.with_radio_material(radio)?;
            } else if let Some(thickness) = options.thickness {
                scene = scene.with_half_spaces_as_slabs(thickness)?;
            }
            Ok(Loaded {
                sources,
                ..Loaded::new(scene, Vec::new())
            })
        }
        None => Ok(load_with_progress(source, options, progress)?.map(DynamicScene::from_static)),
    }
}

fn builtin_description(name: &str) -> Result<SceneDescription, ImportError> {
    let json = builtin_json(name).ok_or_else(|| ImportError::UnknownBuiltin {
        name: name.to_string(),
        known: builtin_names().join(", "),
    })?;
    parse_json(json, &format!("builtin:{name}"))
}

/// The description in the scene file `path` and the SHA-256 of the bytes it was parsed from
/// (with `hashing` on).
fn read_description(
    path: &Path,
    format: Format,
    max_bytes: u64,
    hashing: Hashing,
) -> Result<(SceneDescription, Option<Digest>), ImportError> {
    let display = path.display().to_string();
    let io = |source| ImportError::Io {
        path: display.clone(),
        source,
    };
    let bytes = read_file(path, max_bytes).map_err(io)?;
    let read = hashing.of(&bytes);
    let text = String::from_utf8(bytes).map_err(|_| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        ))
    })?;
    let desc = if format == Format::Toml {
        parse_toml(&text, &display)
    } else {
        parse_json(&text, &display)
    };
    Ok((desc?, read))
}

/// The file name without extension, the scene's name for formats that carry none.
pub(crate) fn file_stem(path: &Path, fallback: &str) -> String {
    path.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(fallback)
        .to_string()
}
