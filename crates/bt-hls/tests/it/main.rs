//! bt-hls integration tests, one binary (one link): the small scene end to end (lint,
//! co-simulation, golden files), early stopping, a golden file per emitted module, per-step
//! loading, synthesis and the post-synthesis netlist, the products on embedded multipliers,
//! generic PEs.

mod common;
mod early_stop;
mod generic;
mod golden_rtl;
mod multipliers;
mod small_scene;
mod steps;
mod synth_and_golden;
