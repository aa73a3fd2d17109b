//! The integration tests of bt-solve, one binary (one link) for all: analytic cases, IPC
//! against the image method on random scenes, Newton acceleration near corners, the beam tree
//! against exhaustive enumeration.

mod analytic;
mod beamtree;
mod common;
mod diffraction;
mod incremental;
mod ipc_vs_image;
mod newton;
mod sionna;
mod terminals;
mod translation;
mod transmission;
mod two_diffractions;
mod wvrn_completeness;
