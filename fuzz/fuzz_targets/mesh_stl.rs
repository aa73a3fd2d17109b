//! STL meshes (binary and ASCII): `read_stl` with the default merge, then the mesh-to-scene
//! step the CLI runs.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "mesh_common.rs"]
mod mesh_common;

fuzz_target!(|data: &[u8]| {
    mesh_common::check(bt_import::mesh::read_stl(
        data,
        None,
        &bt_mesh::MergeOptions::default(),
    ));
});
