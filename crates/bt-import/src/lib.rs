//! File formats into the scene model: the project's JSON/TOML scene files, OBJ/PLY/STL meshes,
//! glTF 2.0 scenes, PLY/PCD point clouds, Mitsuba/Sionna XML scenes and the built-in scenes,
//! all behind one entry ([`load`] / [`load_dynamic`]). The only crate below the binary that reads scene files.
//!
//! Importers sit above the model: `bt-scene` validates what this crate parses
//! ([`bt_scene::SceneDescription`], [`bt_scene::RawSurface`]); `bt-mesh` merges mesh faces and
//! `bt-pointcloud` extracts planes, both called from here. Units and frames: metres in the
//! file's own frame (z up, no axis swap; glTF alone, +Y up by its specification, is turned to
//! z up), Hz.
//!
//! Terminals: every format gives bare geometry; TX/RX come from the file when it has them,
//! else from [`LoadOptions::terminals`], else the scene has none (see [`bt_scene::Scene`]).
#![warn(missing_docs)]

mod builtin;
pub mod cache;
pub mod city;
pub mod cloud;
mod error;
pub mod formats;
pub mod mesh;
mod scene_file;
mod source;
pub mod xml;

pub use builtin::{
    builtin_dynamic_names, builtin_dynamic_scene, builtin_json, builtin_names, builtin_scene,
};
pub use error::ImportError;
pub use scene_file::{parse_json, parse_toml, write_description};
pub use source::{
    Digest, Format, LoadOptions, LoadProgress, Loaded, MAX_FILE_BYTES, Source, load, load_dynamic,
    load_with_progress, load_without_digests,
};
