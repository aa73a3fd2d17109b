//! bt-scene integration tests, one binary (one link): scene files and validation, and the
//! inputs found by fuzzing.

mod fuzz_regressions;
mod scene_files;
