//! bt-import integration tests, one binary (one link): scene files and validation, the
//! inputs found by fuzzing, OBJ/PLY mesh import, PLY/PCD point-cloud round trips and bad input, Sionna RT's scenes loaded without loss.

mod cache;
mod cloud_bad_input;
mod cloud_roundtrip;
mod fuzz_regressions;
mod mesh;
mod scene_files;
mod sionna_scenes;
