//! The integration tests of bt-pointcloud, one binary (one link) for all: plane extraction on
//! synthetic rooms and layered surfaces.

mod common;
mod extract_layers;
mod extract_room;
