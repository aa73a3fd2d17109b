//! The scene: bounded planar reflectors, blockers, the transmitter (TX), the receiver (RX) and
//! the carrier frequency, validated once at the boundary.
//!
//! Units and frames: metres, z up, Hz; see `docs/conventions.md`. Only [`io`] reads files.
#![warn(missing_docs)]

mod builtin;
pub mod city;
mod description;
pub mod dynamic;
mod enclosure;
mod frame;
pub mod io;
mod material;
mod model;
pub mod name;
mod validate;

pub use builtin::{builtin_json, builtin_names, builtin_scene};
pub use description::{BoxDesc, MaterialDesc, SceneDescription, SurfaceDesc};
pub use frame::RECENTRE_RATIO;
pub use io::{LoadOptions, Loaded, Source, load, load_dynamic, load_with_progress};
pub use material::{DEFAULT_MATERIAL, Material, default_materials};
pub use model::{GeometryKey, Scene, Surface, SurfaceId, SurfaceKind};
pub use validate::{DEFAULT_FREQUENCY_HZ, Problem, SceneError, Terminals};

/// Re-exported so users of the scene need not depend on the geometry crate for the basics.
pub use bt_geom::{Polygon, Real, Vec3};
