//! The scene: bounded planar reflectors, blockers, the transmitter (TX), the receiver (RX) and
//! the carrier frequency, validated once at the boundary.
//!
//! Units and frames: metres, z up, Hz; see `docs/conventions.md`. This crate reads no file and
//! parses no format: `bt-import` turns files (scene files, meshes, point clouds, XML) into the
//! [`SceneDescription`] or [`RawSurface`]s validated here.
//!
//! Module order (each uses only those before it): `name`, `material`, `problem`, `surface` →
//! `frame`, `enclosure` → `model` → `transmission`, `edges` → `description` → `validate` → `dynamic`.
#![warn(missing_docs)]

mod description;
pub mod dynamic;
pub mod edges;
mod enclosure;
mod frame;
mod material;
mod model;
pub mod name;
mod problem;
mod stored;
mod surface;
mod transmission;
mod validate;

pub use description::{
    BoxDesc, KeyframeDesc, MaterialDesc, ObjectDesc, PoseDesc, SceneDescription, SurfaceDesc,
};
pub use edges::{Edge, EdgeId, Edges};
pub use frame::RECENTRE_RATIO;
pub use material::{DEFAULT_MATERIAL, Material, default_materials};
pub use model::{Endpoints, GeometryKey, RadioKey, Scene};
pub use problem::{MAX_PRINTED_PROBLEMS, Problem, SceneError, Terminal};
pub use stored::{StoredScene, StoredSurface};
pub use surface::{RawSurface, Surface, SurfaceId, SurfaceKind};
pub use validate::{
    DEFAULT_FREQUENCY_HZ, MAX_FREQUENCY_HZ, MAX_TERMINAL_DISTANCE_RATIO, MIN_FREQUENCY_HZ,
    Terminals, frequency_problem,
};

/// Re-exported so users of the scene need not depend on the geometry crate for the basics.
pub use bt_geom::{Polygon, Real, Vec3};
