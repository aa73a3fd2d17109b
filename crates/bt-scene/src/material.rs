//! Materials: a constant reflection loss per bounce (the paper's ranking and `loss_db`) and an
//! optional radio model (ITU-R P.2040 or custom εr', σ; half-space or slab) for complex path
//! gains (`bt-channel`, `docs/channel.md`).

use bt_channel::{ItuMaterial, RadioMaterial, RadioModel};
use bt_geom::Real;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A material's name looked up once per run of surfaces that name it: neighbouring surfaces
/// mostly share one (an imported shape's), so validation, radio checks and the transmission
/// mask ask the material table once per run instead of once per surface.
pub(crate) struct MaterialRuns<'a, T> {
    /// The last name looked up and what it gave.
    last: Option<(&'a str, T)>,
}

impl<'a, T: Copy> MaterialRuns<'a, T> {
    pub(crate) fn new() -> Self {
        MaterialRuns { last: None }
    }

    /// What `look_up(name)` gives, calling it only when `name` differs from the last name.
    pub(crate) fn get(&mut self, name: &'a str, look_up: impl FnOnce(&'a str) -> T) -> T {
        match self.last {
            Some((last, found)) if last == name => found,
            _ => {
                let found = look_up(name);
                self.last = Some((name, found));
                found
            }
        }
    }
}

/// Name of the material used when a mesh names none.
pub const DEFAULT_MATERIAL: &str = "default";

/// A surface material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Power lost at each specular reflection, dB (>= 0).
    pub reflection_loss_db: Real,
    /// Electrical model for complex gains. `None`: the surface reflects both polarisations like
    /// a perfect conductor scaled by `reflection_loss_db` (R_TE = −a, R_TM = +a with
    /// a = 10^(−loss/20)); see `docs/channel.md`.
    // Every field is always written: the load cache encodes with postcard, which is not
    // self-describing (a skipped field would shift the bytes after it).
    #[serde(default)]
    pub radio: Option<RadioMaterial>,
    /// Waves cross surfaces of this material (thin-slab transmission, `docs/channel.md`) even
    /// when a trace does not switch transmission on everywhere: the scene file's key
    /// `"transmission": true`. Only a slab (a radio model with a thickness) lets waves through.
    #[serde(default)]
    pub transmission: bool,
}

/// Built-in materials with typical single-bounce losses at mmWave (dB), round numbers from
/// indoor measurement surveys: metal reflects almost fully, fabric absorbs most. Scene files
/// may override or add materials.
///
/// Their radio models (documented choices, `docs/channel.md`): `default` and `concrete` are ITU
/// concrete half-spaces, `plasterboard` a 12.5 mm ITU plasterboard slab, `wood` an 18 mm ITU
/// wood slab (furniture panels, floorboards), `glass` a 6 mm ITU glass pane, `metal` an ITU
/// metal half-space; `fabric` (upholstery, εr' = 2, σ = 0.1 S/m, 5 mm) and `human` (skin
/// at mmWave, εr' = 16.5, σ = 25 S/m, half-space) are custom: the ITU table has neither.
pub fn default_materials() -> BTreeMap<String, Material> {
    let itu = |m: ItuMaterial, thickness: Option<Real>| RadioMaterial {
        model: RadioModel::Itu(m),
        thickness,
    };
    let custom =
        |relative_permittivity: Real, conductivity: Real, thickness: Option<Real>| RadioMaterial {
            model: RadioModel::Custom {
                relative_permittivity,
                conductivity,
            },
            thickness,
        };
    [
        (DEFAULT_MATERIAL, 6.0, itu(ItuMaterial::Concrete, None)),
        ("concrete", 6.0, itu(ItuMaterial::Concrete, None)),
        (
            "plasterboard",
            8.0,
            itu(ItuMaterial::Plasterboard, Some(0.0125)),
        ),
        ("wood", 9.0, itu(ItuMaterial::Wood, Some(0.018))),
        ("glass", 4.0, itu(ItuMaterial::Glass, Some(0.006))),
        ("metal", 0.5, itu(ItuMaterial::Metal, None)),
        ("fabric", 12.0, custom(2.0, 0.1, Some(0.005))),
        ("human", 20.0, custom(16.5, 25.0, None)),
    ]
    .into_iter()
    .map(|(name, loss, radio)| {
        (
            name.to_string(),
            Material {
                reflection_loss_db: loss,
                radio: Some(radio),
                transmission: false,
            },
        )
    })
    .collect()
}
