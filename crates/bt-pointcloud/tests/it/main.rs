//! The integration tests of bt-pointcloud, one binary (one link) for all: plane extraction on
//! synthetic rooms and layered surfaces, PLY/PCD round trips and bad input.

mod common;
mod extract_layers;
mod extract_room;
mod io_bad_input;
mod io_roundtrip;
