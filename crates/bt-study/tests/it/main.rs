//! The integration tests of bt-study, one binary (one link) for all: early stopping never
//! loses a valid path, the room generator's invariants, the study runner.

mod beam_management;
mod early_stop;
mod generator;
mod study;
