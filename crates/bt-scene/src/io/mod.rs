//! Scene input: the project's JSON/TOML scene files and OBJ/PLY meshes. The only module of the
//! library crates that touches the filesystem.

use crate::material::{DEFAULT_MATERIAL, Material, default_materials};
use crate::model::{Scene, SurfaceKind};
use crate::validate::{
    DEFAULT_FREQUENCY_HZ, RawSurface, SceneError, Terminals, build_surfaces, check_terminals,
};
use crate::{Problem, SceneDescription};
use bt_geom::Real;
use std::path::Path;

pub use crate::validate::Terminals as TerminalOverrides;

/// Options of scene loading.
#[derive(Debug, Clone)]
pub struct LoadOptions {
    /// TX/RX overriding the file's (required for meshes, which carry none).
    pub terminals: Terminals,
    /// Coplanar-merge tolerances for meshes.
    pub merge: bt_mesh::MergeOptions,
    /// Mesh surfaces smaller than this (m²) become blockers (default 0.25 m², as the paper).
    pub min_reflector_area_m2: Real,
    /// Carrier frequency for meshes, Hz (default 28 GHz).
    pub frequency_hz: Real,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            terminals: Terminals::default(),
            merge: bt_mesh::MergeOptions::default(),
            min_reflector_area_m2: 0.25,
            frequency_hz: DEFAULT_FREQUENCY_HZ,
        }
    }
}

/// A loaded scene and the non-fatal notes of the import (merged faces, holes dropped, ...).
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The validated scene.
    pub scene: Scene,
    /// Warnings for the user.
    pub warnings: Vec<String>,
}

/// Load a scene from `path`, choosing the format by extension (`.json`, `.toml`, `.obj`, `.ply`).
pub fn load(path: &Path, options: &LoadOptions) -> Result<Loaded, SceneError> {
    let display = path.display().to_string();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "json" | "toml" => {
            let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
                path: display.clone(),
                source,
            })?;
            let desc = if ext == "json" {
                parse_json(&text, &display)?
            } else {
                parse_toml(&text, &display)?
            };
            let scene = Scene::from_description(&desc, &display, options.terminals)?;
            Ok(Loaded {
                scene,
                warnings: Vec::new(),
            })
        }
        "obj" | "ply" => {
            let import = bt_mesh::read_mesh_path(path, &options.merge)?;
            let stem = path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("mesh")
                .to_string();
            from_mesh(import, &stem, &display, options)
        }
        _ => Err(SceneError::UnsupportedFormat { path: display }),
    }
}

/// Parse a JSON scene description; errors carry line and column.
pub fn parse_json(text: &str, path: &str) -> Result<SceneDescription, SceneError> {
    serde_json::from_str(text).map_err(|e| SceneError::Parse {
        path: path.to_string(),
        message: e.to_string(),
    })
}

/// Parse a TOML scene description; errors carry line and column.
pub fn parse_toml(text: &str, path: &str) -> Result<SceneDescription, SceneError> {
    toml::from_str(text).map_err(|e| SceneError::Parse {
        path: path.to_string(),
        message: e.to_string().trim_end().to_string(),
    })
}

/// Build a scene from imported mesh surfaces: surfaces below the area threshold become blockers,
/// unknown material names get the default loss (with a warning).
pub fn from_mesh(
    import: bt_mesh::MeshImport,
    name: &str,
    source: &str,
    options: &LoadOptions,
) -> Result<Loaded, SceneError> {
    let mut warnings = import.warnings;
    let mut materials = default_materials();
    let default_loss = materials[DEFAULT_MATERIAL].reflection_loss_db;
    let mut raw = Vec::with_capacity(import.surfaces.len());
    for (i, s) in import.surfaces.into_iter().enumerate() {
        let material = s.material.map(|m| {
            let lower = m.to_ascii_lowercase();
            if materials.contains_key(&lower) {
                lower
            } else {
                if !materials.contains_key(&m) {
                    warnings.push(format!(
                        "material \"{m}\" is not known: using {default_loss} dB per reflection"
                    ));
                    materials.insert(
                        m.clone(),
                        Material {
                            reflection_loss_db: default_loss,
                        },
                    );
                }
                m
            }
        });
        let kind = if s.area_m2 >= options.min_reflector_area_m2 {
            SurfaceKind::Reflector
        } else {
            SurfaceKind::Blocker
        };
        raw.push(RawSurface {
            location: format!("surface {i} \"{}\"", crate::name::escape(&s.name)),
            name: s.name,
            material,
            kind,
            vertices: s.vertices,
        });
    }
    let mut problems: Vec<Problem> = Vec::new();
    let surfaces = build_surfaces(raw, &materials, &mut problems);
    let (tx, rx) = match (options.terminals.tx, options.terminals.rx) {
        (Some(tx), Some(rx)) => (tx, rx),
        (tx, rx) => {
            for (field, v) in [("tx", tx), ("rx", rx)] {
                if v.is_none() {
                    problems.push(Problem {
                        location: field.into(),
                        message: format!("meshes carry no {field}: pass --{field} X,Y,Z"),
                    });
                }
            }
            return Err(SceneError::Invalid {
                source_name: source.to_string(),
                problems,
            });
        }
    };
    let extent = crate::model::scene_extent(&surfaces, tx, rx);
    if let Err(p) = check_terminals(&surfaces, tx, rx, extent) {
        problems.extend(p);
    }
    if !problems.is_empty() {
        return Err(SceneError::Invalid {
            source_name: source.to_string(),
            problems,
        });
    }
    Ok(Loaded {
        scene: Scene::assemble(
            name.to_string(),
            surfaces,
            tx,
            rx,
            options.frequency_hz,
            materials,
        ),
        warnings,
    })
}
