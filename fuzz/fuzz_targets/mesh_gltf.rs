//! glTF 2.0 (`.glb`, or `.gltf` JSON with `data:` buffers): `read_gltf` with the default merge,
//! then the mesh-to-scene step the CLI runs. No file is read from bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "mesh_common.rs"]
mod mesh_common;

fuzz_target!(|data: &[u8]| {
    mesh_common::check(bt_import::mesh::read_gltf(
        data,
        None,
        &bt_mesh::MergeOptions::default(),
    ));
});
