//! Materials: for now a constant reflection loss per bounce (Fresnel comes later).

use bt_geom::Real;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Name of the material used when a mesh names none.
pub const DEFAULT_MATERIAL: &str = "default";

/// A surface material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Power lost at each specular reflection, dB (>= 0).
    pub reflection_loss_db: Real,
}

/// Built-in materials with typical single-bounce losses at mmWave (dB), round numbers from
/// indoor measurement surveys: metal reflects almost fully, fabric absorbs most. Scene files
/// may override or add materials.
pub fn default_materials() -> BTreeMap<String, Material> {
    [
        (DEFAULT_MATERIAL, 6.0),
        ("concrete", 6.0),
        ("plasterboard", 8.0),
        ("wood", 9.0),
        ("glass", 4.0),
        ("metal", 0.5),
        ("fabric", 12.0),
        ("human", 20.0),
    ]
    .into_iter()
    .map(|(name, loss)| {
        (
            name.to_string(),
            Material {
                reflection_loss_db: loss,
            },
        )
    })
    .collect()
}
