//! The scene → accelerator bridge, one home for what `beamtrace hls` and the living-room study
//! share: which planes the platform bakes in ([`static_reflectors`]), one time step's work
//! ([`step_input`], [`warm_start`], [`plan_step`]), the host's check of the results
//! ([`host_accepts`]) and the fixed-point vs f64 comparison ([`fixed_deviation`]).
//!
//! Dependency direction: `bt-scene`, `bt-paths`, `bt-solve` (candidates, image method,
//! validation) and `bt-hls` (model, schedule) → `bt-accel` → `bt-study`, `beamtrace`.
//! No file I/O.
#![warn(missing_docs)]

mod bridge;
mod deviation;
mod step;

pub use bridge::{
    HostRejection, REFLECTION_TOLERANCE_DEG, StepInput, hls_input, host_accepts,
    reflection_error_deg, static_reflectors, step_input, warm_start,
};
pub use deviation::{FixedDeviation, Reference, fixed_deviation};
pub use step::{AccelError, PlannedStep, StepOptions, plan_step};
