//! The integration tests of bt-mesh, one binary (one link) for all: OBJ/PLY import and
//! merging, robustness on random polygon soups, rotation invariance.

#[macro_use]
mod common;
mod import;
mod robustness;
mod rotation;
