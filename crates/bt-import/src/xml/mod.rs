//! Mitsuba 3 / Sionna RT XML scenes (`docs/scene-format.md`, "Mitsuba / Sionna XML").
//!
//! Two stages: [`parse_xml`] turns the text into an [`XmlScene`] (bsdfs and shapes, every error
//! with its line; no file access, fuzzed), then [`load_xml`] reads each shape's PLY/OBJ mesh
//! relative to the XML's folder, maps it through its `to_world` before bt-mesh welds and merges
//! it (so surfaces never merge across shapes, hence never across materials), and validates the
//! result as a [`SceneDescription`] whose materials are the bsdfs, named by their ids.
//!
//! Mesh file names are resolved safely: only relative paths of plain components under the
//! XML's folder (no absolute path, no `..`), each file at most [`LoadOptions::max_file_bytes`]
//! and all of them at most [`MAX_MESH_TOTAL_BYTES`]; the vertices and the faces of all shapes
//! together are held to the mesh budget (`--max-mesh-elements`), which is per scene here, not
//! per file.

mod parse;
mod primitive;
mod transform;

pub use parse::{SIONNA_DEFAULT_THICKNESS_M, parse_xml, parse_xml_with};

use crate::mesh::MeshFormat;
use crate::source::{Digest, Hashing, file_stem};
use crate::{ImportError, LoadOptions, Loaded};
use bt_channel::{ItuMaterial, RadioModel};
use bt_geom::Real;
use bt_scene::{
    DEFAULT_MATERIAL, MaterialDesc, Scene, SceneDescription, SurfaceDesc, SurfaceKind,
    default_materials,
};
use glam::DMat4;
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};

/// Largest XML file read, bytes (16 MiB: Sionna's city scenes are well under 1 MiB of XML).
pub const MAX_XML_BYTES: u64 = 16 << 20;
/// Largest number of XML nodes (elements, attributes' text, comments) parsed.
pub const MAX_XML_NODES: u32 = 1_000_000;
/// Largest number of `<shape>` elements.
pub const MAX_XML_SHAPES: usize = 20_000;
/// Largest number of `<bsdf>` elements.
pub const MAX_XML_BSDFS: usize = 10_000;
/// Budget on the bytes all `$parameter` substitutions of one XML file produce: 16 MiB, the
/// size of the largest XML file read; Sionna's scenes substitute nothing.
pub const MAX_XML_SUBSTITUTION: bt_geom::Budget =
    bt_geom::Budget::new("substituted bytes", "--max-xml-substitution", 16 << 20);
/// Largest total size of all mesh files of one scene, bytes.
pub const MAX_MESH_TOTAL_BYTES: u64 = 2 << 30;

/// A position in the XML text, 1-based.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct XmlPos {
    /// Line.
    pub line: u32,
    /// Column (characters).
    pub column: u32,
}

/// A scene as written in the XML, before any mesh is read.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct XmlScene {
    /// The `<bsdf>` elements (top level and inline in shapes), ids unique.
    pub bsdfs: Vec<XmlBsdf>,
    /// The `<shape>` elements in document order.
    pub shapes: Vec<XmlShape>,
    /// Notes for the user (rendering-only elements skipped).
    pub warnings: Vec<String>,
}

/// One `<bsdf>`: its id (the scene material's name) and radio meaning.
#[derive(Debug, Clone, PartialEq)]
pub struct XmlBsdf {
    /// The `id` attribute (inline bsdfs without one: `<shape id>.bsdf`).
    pub id: String,
    /// What the bsdf says about radio propagation.
    pub radio: XmlRadio,
    /// Line of the element.
    pub line: u32,
}

/// The radio meaning of a bsdf.
#[derive(Debug, Clone, PartialEq)]
pub enum XmlRadio {
    /// `itu-radio-material`: an ITU-R P.2040-3 material by Sionna's name, as a slab.
    Itu {
        /// `concrete`, `itu_concrete`, `very_dry_ground`, ...
        name: String,
        /// Slab thickness, metres (Sionna's 0.1 m when not given).
        thickness_m: Real,
    },
    /// `radio-material`: constant εr' and σ, as a slab.
    Custom {
        /// Relative permittivity εr' (Sionna's default 1).
        relative_permittivity: Real,
        /// Conductivity σ, S/m (Sionna's default 0).
        conductivity: Real,
        /// Slab thickness, metres (Sionna's 0.1 m when not given).
        thickness_m: Real,
    },
    /// Any other (visual) Mitsuba bsdf: the radio material comes from the id as Sionna 0.x
    /// names them (`mat-itu_concrete`, `itu_glass`: an ITU half-space), else the default.
    Visual {
        /// The bsdf type (`diffuse`, `twosided`, `principled`, ...).
        kind: String,
    },
}

/// What a `<shape>` is: a mesh file or one of Mitsuba's planar primitives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshKind {
    /// `<shape type="ply">`.
    Ply,
    /// `<shape type="obj">`.
    Obj,
    /// `<shape type="rectangle">` or `<shape type="cube">`: no file.
    Primitive(Primitive),
}

/// Mitsuba's planar primitive shapes, in their object frame (metres before `to_world`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Primitive {
    /// `<shape type="rectangle">`: the square `[-1, 1]²` in the plane `z = 0`, normal `+z`.
    Rectangle,
    /// `<shape type="cube">`: the cube `[-1, 1]³`, six faces with outward normals.
    Cube,
}

/// One `<shape type="ply|obj|rectangle|cube">`.
#[derive(Debug, Clone, PartialEq)]
pub struct XmlShape {
    /// The `id` attribute, or `shape-<k>`; prefixes its surfaces' names.
    pub name: String,
    /// Mesh format.
    pub kind: MeshKind,
    /// The `filename` property as written (relative to the XML's folder); `None` for the
    /// primitives (rectangle, cube), which have none.
    pub filename: Option<String>,
    /// The bsdf id it refers to (or defines inline) and where; `None`: material `default`.
    pub bsdf: Option<(String, XmlPos)>,
    /// `to_world`, metres to metres (identity when absent).
    pub to_world: DMat4,
    /// Where the element starts.
    pub at: XmlPos,
}

/// Load a Mitsuba/Sionna XML scene: parse, read every shape's mesh (bounded, relative to the
/// XML's folder; their paths are the returned [`Loaded::sources`]), and validate as a scene with `options.terminals` at `options.frequency_hz`.
/// The XML has no transmitter or receiver: without `options.terminals` the scene is bare
/// geometry, traced with terminals given per trace.
pub fn load_xml(path: &Path, options: &LoadOptions) -> Result<Loaded, ImportError> {
    Ok(load_xml_read(path, options, Hashing::On)?.0)
}

/// [`load_xml`], with the SHA-256 of the XML's bytes as parsed ([`Loaded::digests`] holds the
/// meshes'), with `hashing` on; with it off, no digest at all.
pub(crate) fn load_xml_read(
    path: &Path,
    options: &LoadOptions,
    hashing: Hashing,
) -> Result<(Loaded, Option<Digest>), ImportError> {
    let display = path.display().to_string();
    let limit = MAX_XML_BYTES.min(options.max_file_bytes);
    let text = read_bounded(path, None, limit, &display)?;
    let read = hashing.of(&text);
    let text = String::from_utf8(text).map_err(|e| ImportError::Parse {
        path: display.clone(),
        message: format!("not UTF-8 text: {e}"),
    })?;
    let xml = parse_xml_with(&text, &display, options.max_xml_substitution)?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut warnings = xml.warnings.clone();
    let mut desc = SceneDescription {
        name: Some(file_stem(path, "scene")),
        frequency_hz: Some(options.frequency_hz),
        materials: materials(&xml, &mut warnings),
        ..SceneDescription::default()
    };
    let mut reading = Reading {
        xml: &display,
        folder,
        options,
        hashing,
        bytes_left: MAX_MESH_TOTAL_BYTES,
        elements: SceneElements::default(),
        // Sized for one file per shape (as in Sionna's cities), not grown and rehashed.
        meshes: Vec::with_capacity(xml.shapes.len()),
        seen: std::collections::HashSet::with_capacity(xml.shapes.len()),
    };
    let (found, refused) = reading.find(&xml.shapes);
    for round in rounds(&found, ROUND_BYTES, file_bytes) {
        reading.round(round, &mut desc, &mut warnings)?;
    }
    if let Some(refused) = refused {
        return Err(refused);
    }
    let scene = Scene::from_owned_description(desc, &display, options.terminals)?;
    let (sources, digests): (Vec<_>, Vec<_>) = reading.meshes.into_iter().unzip();
    let loaded = Loaded {
        sources,
        // All or none: every mesh's with hashing on, else empty.
        digests: (digests.into_iter().collect::<Option<_>>()).unwrap_or_default(),
        ..Loaded::new(scene, warnings)
    };
    Ok((loaded, read))
}

/// Bytes of mesh files read and merged in parallel at a time (a round; at least one file).
/// The element budget is charged in document order after each round, so a refused scene
/// costs at most one round of extra work, and whatever the thread count the first problem in
/// document order is the one reported. Sionna's cities (7-10 MB of meshes) are one round, so
/// a large mesh (San Francisco's terrain: 192,000 triangles) is merged beside all the others
/// instead of alone at the end of its round.
const ROUND_BYTES: u64 = 64 << 20;

/// A shape with where its polygons come from.
type Found<'s> = (&'s XmlShape, Source);

/// Where a shape's polygons come from.
enum Source {
    /// Its mesh file in `format`, found within the byte budgets, and the file's metadata.
    File(PathBuf, std::fs::Metadata, MeshFormat),
    /// A primitive: no file.
    Primitive(Primitive),
}

/// `items` in rounds of consecutive items of at most `limit` bytes in all by `size` (a larger
/// item is a round alone).
fn rounds<T>(items: &[T], limit: u64, size: impl Fn(&T) -> u64) -> impl Iterator<Item = &[T]> {
    let mut rest = items;
    std::iter::from_fn(move || {
        let mut bytes = 0u64;
        let end = (0..rest.len())
            .find(|&n| {
                bytes = bytes.saturating_add(size(&rest[n]));
                n > 0 && bytes > limit
            })
            .unwrap_or(rest.len());
        let (round, tail) = rest.split_at(end);
        rest = tail;
        (!round.is_empty()).then_some(round)
    })
}

/// The bytes of a found shape's mesh file (none for a primitive).
fn file_bytes((_, source): &Found<'_>) -> u64 {
    match source {
        Source::File(_, metadata, _) => metadata.len(),
        Source::Primitive(_) => 0,
    }
}

/// The state of reading one XML scene's meshes: budgets left and the files read.
struct Reading<'a> {
    xml: &'a str,
    folder: &'a Path,
    options: &'a LoadOptions,
    /// Whether the meshes' SHA-256s are taken.
    hashing: Hashing,
    /// Of [`MAX_MESH_TOTAL_BYTES`].
    bytes_left: u64,
    elements: SceneElements,
    /// Every mesh file read, once each, in document order, with the SHA-256 of its bytes
    /// (with hashing on).
    meshes: Vec<(PathBuf, Option<Digest>)>,
    // A set beside `meshes`: comparing paths walks their components, and with one file per
    // shape (Sionna's cities: 2,367) `meshes.contains` was 40 % of the load.
    seen: std::collections::HashSet<PathBuf>,
}

impl Reading<'_> {
    /// The shapes whose mesh files are found within the byte budgets, in document order, up
    /// to the first that is not (its error beside them): the files are looked up (`stat`) on
    /// all cores and their sizes charged in order, before any is read.
    fn find<'s>(&mut self, shapes: &'s [XmlShape]) -> (Vec<Found<'s>>, Option<ImportError>) {
        use rayon::prelude::*;
        let stated: Vec<Result<(Stated, MeshFormat), Primitive>> = (shapes.par_iter())
            .map(|shape| {
                let format = match shape.kind {
                    MeshKind::Ply => MeshFormat::Ply,
                    MeshKind::Obj => MeshFormat::Obj,
                    MeshKind::Primitive(primitive) => return Err(primitive),
                };
                let name = shape.filename.as_deref().unwrap_or_default();
                let stated = resolve(self.folder, name).map(|file| {
                    let metadata = std::fs::metadata(&file);
                    (file, metadata)
                });
                Ok((stated, format))
            })
            .collect();
        let mut found = Vec::with_capacity(shapes.len());
        for (shape, stated) in shapes.iter().zip(stated) {
            let (stated, format) = match stated {
                Ok(stated) => stated,
                Err(primitive) => {
                    found.push((shape, Source::Primitive(primitive)));
                    continue;
                }
            };
            match find_shape(shape, stated, self.xml, self.options, &mut self.bytes_left) {
                Ok((file, metadata)) => found.push((shape, Source::File(file, metadata, format))),
                Err(e) => return (found, Some(e)),
            }
        }
        (found, None)
    }

    /// Read and merge the meshes of `found` (one round) and append their surfaces to `desc`,
    /// as a shape-by-shape loop would: the meshes are read and merged on all cores, the
    /// largest files first (so that a large mesh is not merged alone at the end), then
    /// charged and appended in document order.
    fn round(
        &mut self,
        found: &[Found<'_>],
        desc: &mut SceneDescription,
        warnings: &mut Vec<String>,
    ) -> Result<(), ImportError> {
        use rayon::prelude::*;
        let mut largest_first: Vec<usize> = (0..found.len()).collect();
        largest_first.sort_by_key(|&k| std::cmp::Reverse(file_bytes(&found[k])));
        // Each mesh is read, merged and turned into scene surfaces on the worker threads.
        let mut merged: Vec<(usize, Result<_, ImportError>)> = (largest_first.par_iter())
            .map(|&k| {
                let (shape, source) = &found[k];
                let import = match source {
                    Source::File(file, metadata, format) => {
                        let options = (self.options, self.hashing);
                        read_shape(shape, (file, metadata, *format), options)
                    }
                    Source::Primitive(primitive) => {
                        merge_primitive(shape, *primitive, self.xml, self.options)
                            .map(|import| (import, None))
                    }
                };
                let surfaces =
                    |(import, read)| (shape_surfaces(shape, import, self.xml, self.options), read);
                (k, import.map(surfaces))
            })
            .collect();
        merged.sort_unstable_by_key(|&(k, _)| k);
        for ((shape, source), (_, import)) in found.iter().zip(merged) {
            let (added, read) = import?;
            (self.elements).charge(&added, shape, self.xml, self.options.merge.max_elements)?;
            if let Source::File(file, ..) = source
                && self.seen.insert(file.clone())
            {
                self.meshes.push((file.clone(), read));
            }
            desc.surfaces.extend(added.surfaces);
            warnings.extend(added.warnings);
        }
        Ok(())
    }
}

/// What one shape's mesh adds to the scene: its surfaces and warnings, and the vertices and
/// faces its file held (charged to the scene's budget).
struct ShapeSurfaces {
    surfaces: Vec<SurfaceDesc>,
    warnings: Vec<String>,
    vertices_read: usize,
    faces_read: usize,
}

/// The surfaces of `shape`'s merged mesh (named `<shape>.<surface>`, with the shape's bsdf,
/// blockers below the minimum reflector area) and its warnings, for the scene.
fn shape_surfaces(
    shape: &XmlShape,
    import: bt_mesh::MeshImport,
    xml: &str,
    options: &LoadOptions,
) -> ShapeSurfaces {
    let mut warnings = import.warnings;
    let material = shape.bsdf.as_ref().map(|(id, _)| id.clone());
    if material.is_none() {
        warnings.push(format!(
            "{xml}: line {}: <shape id=\"{}\"> has no bsdf: material \"{DEFAULT_MATERIAL}\"",
            shape.at.line,
            bt_scene::name::shown(&shape.name)
        ));
    }
    let surfaces = (import.surfaces.into_iter())
        .map(|s| SurfaceDesc {
            name: [shape.name.as_str(), ".", &s.name].concat(),
            material: material.clone(),
            kind: Some(if s.region_area_m2 >= options.min_reflector_area_m2 {
                SurfaceKind::Reflector
            } else {
                SurfaceKind::Blocker
            }),
            // In place: `Vec3` and `[Real; 3]` have one layout.
            vertices: s.vertices.into_iter().map(|v| v.to_array()).collect(),
            ..SurfaceDesc::default()
        })
        .collect();
    ShapeSurfaces {
        surfaces,
        warnings,
        vertices_read: import.vertices_read,
        faces_read: import.faces_read,
    }
}

/// The vertices and faces read so far from the meshes of one XML scene.
#[derive(Debug, Default)]
struct SceneElements {
    vertices: u64,
    faces: u64,
}

impl SceneElements {
    /// Add `import`'s vertices and faces (as read, before merging) and refuse the scene when
    /// either total exceeds `max_elements`: the budget holds for the whole scene, so twenty
    /// shapes of one large mesh do not pass where one file of all of them would not.
    fn charge(
        &mut self,
        import: &ShapeSurfaces,
        shape: &XmlShape,
        xml: &str,
        max_elements: u64,
    ) -> Result<(), ImportError> {
        self.vertices = self.vertices.saturating_add(import.vertices_read as u64);
        self.faces = self.faces.saturating_add(import.faces_read as u64);
        for (element, total) in [("vertices", self.vertices), ("faces", self.faces)] {
            if total > max_elements {
                return Err(ImportError::Xml {
                    path: xml.to_string(),
                    line: shape.at.line,
                    column: shape.at.column,
                    message: format!(
                        "the meshes up to <shape id=\"{}\"> hold {}, more than the budget of \
                         {max_elements} {element} for the whole scene; raise it with \
                         --max-mesh-elements (load options: merge.max_elements)",
                        bt_scene::name::shown(&shape.name),
                        bt_geom::AtLeast(total).to_string() + " " + element
                    ),
                });
            }
        }
        Ok(())
    }
}

/// The scene materials of the bsdfs, by id.
fn materials(xml: &XmlScene, warnings: &mut Vec<String>) -> BTreeMap<String, MaterialDesc> {
    xml.bsdfs
        .iter()
        .map(|b| {
            let desc = match &b.radio {
                XmlRadio::Itu { name, thickness_m } => MaterialDesc {
                    itu: Some(name.clone()),
                    thickness: Some(*thickness_m),
                    ..MaterialDesc::default()
                },
                XmlRadio::Custom {
                    relative_permittivity,
                    conductivity,
                    thickness_m,
                } => MaterialDesc {
                    relative_permittivity: Some(*relative_permittivity),
                    conductivity: Some(*conductivity),
                    thickness: Some(*thickness_m),
                    ..MaterialDesc::default()
                },
                XmlRadio::Visual { kind } => visual_material(b, kind, warnings),
            };
            (b.id.clone(), desc)
        })
        .collect()
}

/// A visual bsdf: an ITU half-space when its id names one the way Sionna 0.x does
/// (`mat-itu_concrete`, `itu_wood`), otherwise a copy of the `default` material.
fn visual_material(b: &XmlBsdf, kind: &str, warnings: &mut Vec<String>) -> MaterialDesc {
    let stem = b.id.strip_prefix("mat-").unwrap_or(&b.id);
    if stem.starts_with("itu") && ItuMaterial::parse(stem).is_ok() {
        return MaterialDesc {
            itu: Some(stem.to_string()),
            ..MaterialDesc::default()
        };
    }
    warnings.push(format!(
        "line {}: <bsdf type=\"{kind}\" id=\"{}\"> is not a radio material: using material \"{DEFAULT_MATERIAL}\"'s properties",
        b.line,
        bt_scene::name::shown(&b.id)
    ));
    let default = &default_materials()[DEFAULT_MATERIAL];
    let mut desc = MaterialDesc {
        reflection_loss_db: Some(default.reflection_loss_db),
        ..MaterialDesc::default()
    };
    if let Some(radio) = default.radio {
        desc.thickness = radio.thickness;
        match radio.model {
            RadioModel::Itu(m) => desc.itu = Some(m.name().to_string()),
            RadioModel::Custom {
                relative_permittivity,
                conductivity,
            } => {
                desc.relative_permittivity = Some(relative_permittivity);
                desc.conductivity = Some(conductivity);
            }
        }
    }
    desc
}

/// The file of `shape`'s filename (resolved under the XML's folder by [`resolve`]) and its
/// metadata, or why it has none.
type Stated = Result<(PathBuf, std::io::Result<std::fs::Metadata>), &'static str>;

/// The mesh file of `shape`, checked before it is read: a plain relative path (`stated`: the
/// file [`resolve`]d and its `stat`), its size within `--max-file-bytes` and within what is
/// left of `bytes_left` (charged). The file with its metadata, for [`read_shape`].
fn find_shape(
    shape: &XmlShape,
    stated: Stated,
    xml: &str,
    options: &LoadOptions,
    bytes_left: &mut u64,
) -> Result<(PathBuf, std::fs::Metadata), ImportError> {
    let at = |message: String| ImportError::Xml {
        path: xml.to_string(),
        line: shape.at.line,
        column: shape.at.column,
        message,
    };
    let (file, metadata) = stated.map_err(|why| {
        at(format!(
            "<shape id=\"{}\"> filename \"{}\": {why}",
            bt_scene::name::shown(&shape.name),
            bt_scene::name::shown(shape.filename.as_deref().unwrap_or_default())
        ))
    })?;
    // Only a refusal shows the file: a path's `Display` walks its bytes as UTF-8 chunks, and
    // in this loop over every shape (San Francisco: 4,735) that was 9 M instructions a load.
    let shown = || file.display().to_string();
    let metadata = metadata.map_err(|e| {
        at(format!(
            "<shape id=\"{}\"> mesh file {}: {e}",
            bt_scene::name::shown(&shape.name),
            shown()
        ))
    })?;
    let size = metadata.len();
    if let Err(e) = crate::MAX_FILE_BYTES
        .with_limit(options.max_file_bytes)
        .check(size)
    {
        return Err(at(format!(
            "<shape id=\"{}\"> mesh file {}: {e}",
            bt_scene::name::shown(&shape.name),
            shown()
        )));
    }
    if size > *bytes_left {
        return Err(at(format!(
            "<shape id=\"{}\"> mesh file {} is {size} bytes: over the limit ({MAX_MESH_TOTAL_BYTES} bytes for all meshes of a scene)",
            bt_scene::name::shown(&shape.name),
            shown()
        )));
    }
    *bytes_left -= size;
    Ok((file, metadata))
}

/// Read `shape`'s mesh `file` (found by [`find_shape`], with its `metadata`, in `format`) and
/// merge it through its transform; the mesh and the SHA-256 of the bytes read (with `hashing`
/// on).
fn read_shape(
    shape: &XmlShape,
    (file, metadata, format): (&Path, &std::fs::Metadata, MeshFormat),
    (options, hashing): (&LoadOptions, Hashing),
) -> Result<(bt_mesh::MeshImport, Option<Digest>), ImportError> {
    let shown = shown_path(file);
    let bytes = read_bounded(file, Some(metadata), options.max_file_bytes, &shown)?;
    let to_world = shape.to_world;
    let import =
        crate::mesh::read_transformed(&bytes, format, Some(&shown), &options.merge, &|p| {
            to_world.transform_point3(p)
        })?;
    Ok((import, hashing.of(&bytes)))
}

/// `file` as `Display` shows it, taken as is when it is UTF-8 (the same text, without
/// walking it chunk by chunk through the formatter).
fn shown_path(file: &Path) -> String {
    file.to_str()
        .map_or_else(|| file.display().to_string(), str::to_owned)
}

/// The primitive `shape` (rectangle, cube) mapped through its transform and merged, named in
/// warnings by the XML file `xml` and the shape's line.
fn merge_primitive(
    shape: &XmlShape,
    primitive: Primitive,
    xml: &str,
    options: &LoadOptions,
) -> Result<bt_mesh::MeshImport, ImportError> {
    let raw = primitive::mesh(primitive);
    let label = format!(
        "{xml}: line {}: <shape id=\"{}\">",
        shape.at.line,
        bt_scene::name::shown(&shape.name)
    );
    let to_world = shape.to_world;
    let import = crate::mesh::merge_transformed(raw, &label, &options.merge, &|p| {
        to_world.transform_point3(p)
    })?;
    Ok(import)
}

/// `name` under `folder`: relative, plain components only (no `..`, no root, no drive).
fn resolve(folder: &Path, name: &str) -> Result<PathBuf, &'static str> {
    let relative = Path::new(name);
    if name.is_empty() {
        return Err("is empty");
    }
    for c in relative.components() {
        match c {
            Component::Normal(_) | Component::CurDir => {}
            Component::ParentDir => {
                return Err("must stay under the XML's folder (no \"..\")");
            }
            Component::RootDir | Component::Prefix(_) => {
                return Err("must be relative to the XML's folder (no absolute path)");
            }
        }
    }
    Ok(folder.join(relative))
}

/// The bytes of `path`, at most `limit`: [`crate::source::read_stated`] with its `metadata`
/// when the caller took it already, else [`crate::source::read_file`]. An I/O failure is an
/// [`ImportError::Io`] naming the file as `display`.
fn read_bounded(
    path: &Path,
    metadata: Option<&std::fs::Metadata>,
    limit: u64,
    display: &str,
) -> Result<Vec<u8>, ImportError> {
    let read = match metadata {
        Some(metadata) => crate::source::read_stated(path, metadata, limit),
        None => crate::source::read_file(path, limit),
    };
    read.map_err(|source| ImportError::Io {
        path: display.to_string(),
        source,
    })
}

#[cfg(test)]
mod tests;
