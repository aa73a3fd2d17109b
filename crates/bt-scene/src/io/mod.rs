//! Scene input: the project's JSON/TOML scene files, OBJ/PLY meshes, PLY/PCD point clouds and
//! Mitsuba/Sionna XML scenes,
//! all behind one entry ([`load`] / [`load_dynamic`], in `source.rs`). The only module of this
//! crate that touches the filesystem.

mod cloud;
mod source;
pub mod xml;

pub use cloud::{cloud_description, is_point_cloud};
pub use source::{Format, LoadProgress, Source, load, load_dynamic, load_with_progress};

use crate::material::{DEFAULT_MATERIAL, Material, default_materials};
use crate::model::{Scene, SurfaceKind};
use crate::validate::{
    DEFAULT_FREQUENCY_HZ, RawSurface, SceneError, Terminals, build_surfaces, check_terminals,
    radio_problems,
};
use crate::{Problem, SceneDescription};
use bt_geom::Real;

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
    /// Carrier frequency for meshes and point clouds, Hz (default 28 GHz).
    pub frequency_hz: Real,
    /// Plane-extraction parameters for point clouds (PLY without faces, PCD).
    pub extract: bt_pointcloud::ExtractParams,
    /// Point-cloud reading: budget on the points a file declares (`max_points`, CLI
    /// `--max-cloud-points`) and the policy for non-finite points.
    pub cloud: bt_pointcloud::io::ReadOptions,
    /// A radio material for every surface (CLI `--material itu:NAME --thickness M`), replacing
    /// the radio model of every material of the loaded scene, whatever its format.
    pub radio: Option<bt_channel::RadioMaterial>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            terminals: Terminals::default(),
            merge: bt_mesh::MergeOptions::default(),
            min_reflector_area_m2: 0.25,
            frequency_hz: DEFAULT_FREQUENCY_HZ,
            extract: bt_pointcloud::ExtractParams::default(),
            cloud: bt_pointcloud::io::ReadOptions::default(),
            radio: None,
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
/// material names of the ITU table (`itu_concrete`, ...) get that material as a half-space,
/// other unknown names the default loss and radio model (with a warning).
pub fn from_mesh(
    import: bt_mesh::MeshImport,
    name: &str,
    source: &str,
    options: &LoadOptions,
) -> Result<Loaded, SceneError> {
    let mut warnings = import.warnings;
    let mut materials = default_materials();
    let default = materials[DEFAULT_MATERIAL].clone();
    let mut raw = Vec::with_capacity(import.surfaces.len());
    for (i, s) in import.surfaces.into_iter().enumerate() {
        let material = s.material.map(|m| {
            let lower = m.to_ascii_lowercase();
            if materials.contains_key(&lower) {
                lower
            } else {
                if !materials.contains_key(&m) {
                    let material = match bt_channel::RadioMaterial::itu(&m, None) {
                        Ok(radio) => Material {
                            reflection_loss_db: radio
                                .normal_loss_db(options.frequency_hz)
                                .unwrap_or(default.reflection_loss_db),
                            radio: Some(radio),
                        },
                        Err(_) => {
                            warnings.push(format!(
                                "material \"{m}\" is not known: using {} dB per reflection and the radio model of \"{DEFAULT_MATERIAL}\"",
                                default.reflection_loss_db
                            ));
                            default.clone()
                        }
                    };
                    materials.insert(m.clone(), material);
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
    let (tx, rx) = (options.terminals.tx, options.terminals.rx);
    let origin = crate::frame::recentre(&mut raw, [tx, rx], &mut problems);
    let surfaces = build_surfaces(raw, &materials, &mut problems);
    let (tx, rx) = match (tx, rx) {
        (Some(tx), Some(rx)) => (
            crate::frame::to_local(tx, origin),
            crate::frame::to_local(rx, origin),
        ),
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
    if let Err(p) = check_terminals(&surfaces, tx, rx, extent, origin) {
        problems.extend(p);
    }
    problems.extend(radio_problems(&surfaces, &materials, options.frequency_hz));
    if !problems.is_empty() {
        return Err(SceneError::Invalid {
            source_name: source.to_string(),
            problems,
        });
    }
    Ok(Loaded {
        scene: Scene::assemble(
            name.to_string(),
            origin,
            surfaces,
            tx,
            rx,
            options.frequency_hz,
            materials,
        ),
        warnings,
    })
}
