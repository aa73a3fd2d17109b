//! Mesh surfaces into a scene: small surfaces block, ITU material names get their radio model.

use crate::{ImportError, LoadOptions, Loaded};
use bt_scene::{DEFAULT_MATERIAL, Material, RawSurface, Scene, SurfaceKind, default_materials};

/// Build a scene from imported mesh surfaces: surfaces whose coplanar region is below the area
/// threshold become blockers, material names of the ITU table (`itu_concrete`, ...) get that
/// material as a half-space, other unknown names the default loss and radio model (with a
/// warning).
pub fn from_mesh(
    import: bt_mesh::MeshImport,
    name: &str,
    source: &str,
    options: &LoadOptions,
) -> Result<Loaded, ImportError> {
    let mut warnings = import.warnings;
    let mut materials = default_materials();
    let default = materials[DEFAULT_MATERIAL].clone();
    let mut raw = Vec::with_capacity(import.surfaces.len());
    for s in &import.surfaces {
        // Material names (OBJ `usemtl`, PLY and XML material ids) follow the name rule of
        // every other name: no control characters reach messages or outputs.
        if let Some(m) = &s.material
            && let Err(e) = bt_scene::name::check(m)
        {
            return Err(ImportError::Parse {
                path: source.to_string(),
                message: format!("material {}: {e}", quoted(m)),
            });
        }
    }
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
                            transmission: false,
                        },
                        Err(_) => {
                            warnings.push(format!(
                                "material {} is not known: using {} dB per reflection and the radio model of \"{DEFAULT_MATERIAL}\"",
                                quoted(&m),
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
        let kind = if s.region_area_m2 >= options.min_reflector_area_m2 {
            SurfaceKind::Reflector
        } else {
            SurfaceKind::Blocker
        };
        raw.push(RawSurface {
            location: format!("surface {i} \"{}\"", bt_scene::name::shown(&s.name)),
            name: s.name,
            material,
            kind,
            vertices: s.vertices,
        });
    }
    let scene = Scene::from_surfaces(
        name,
        source,
        raw,
        materials,
        options.terminals,
        options.frequency_hz,
    )?;
    Ok(Loaded::new(scene, warnings))
}

/// `name` in quotes, as messages print it (`bt_scene::name::shown`).
fn quoted(name: &str) -> String {
    format!("\"{}\"", bt_scene::name::shown(name))
}
