//! OBJ/PLY mesh import (the readers here, the merge in bt-mesh): import and merging, robustness on random polygon soups, rotation invariance.

#[macro_use]
mod common;
mod gltf;
mod import;
mod robustness;
mod rotation;
mod stl;
