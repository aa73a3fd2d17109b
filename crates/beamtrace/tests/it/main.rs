//! Integration tests of the `beamtrace` binary, one test binary for the crate (one link): each
//! module runs the built binary on one part of the CLI; `common` holds what they share.

mod beam_management;
mod cache;
mod channel;
mod cli;
mod common;
mod hls;
mod hostile;
mod living_room;
mod pointcloud;
mod serve;
mod study;
mod sweep;
mod terminals;
mod transmission;
mod two_diffractions;
mod wvrn_steps;
