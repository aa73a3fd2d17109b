//! The paper's 2-D validation study (Section III, Table I, Figs. 5-7): 100 generated rooms
//! (L, T, U and convex closed contours in a 10 m × 10 m square) whose one vertex moves over
//! time steps, traced by the image method (the reference), IPC and SBR up to third order, and
//! compared by angular error at TX and RX, missed and spurious paths, and elapsed time.
//!
//! - [`room`]: the seeded room generator and its contour invariants;
//! - [`embed`]: a 2-D room as a 3-D scene of vertical walls (the same solvers serve 2-D);
//! - [`mod@run`]: the study itself, one [`run::Row`] per room, step and solver;
//! - [`report`]: `results.csv`, `summary.md` and the aggregates behind the plots;
//! - [`plot`]: Figs. 5-7 on any plotters backend; [`io`] writes them as SVG and PNG.
//!
//! Units: metres, seconds; angles in degrees where the name says `_deg`.
//! `docs/study-2d.md` describes the method and the measured numbers.
#![warn(missing_docs)]

pub mod beam_management;
pub mod embed;
pub mod io;
pub mod living_room;
pub mod plot;
pub mod report;
pub mod room;
pub mod run;

pub use room::{Room, Shape};
pub use run::{MAX_ROOM_STEPS, Row, StudyConfig, StudyResults, StudySolver, run};

use thiserror::Error;

/// Errors of the study.
#[derive(Debug, Error)]
pub enum StudyError {
    /// The settings are unusable.
    #[error("invalid study settings: {0}")]
    Config(String),
    /// The generator could not make a room (not expected for any seed).
    #[error("room {room}: {message}")]
    Generation {
        /// Room index.
        room: usize,
        /// What failed.
        message: String,
    },
    /// A generated room did not validate as a scene (a generator bug).
    #[error("scene {name}: {message}")]
    Scene {
        /// Scene name (`room-R-step-S`).
        name: String,
        /// The validation message.
        message: String,
    },
    /// A time step of the living-room study failed (fixed-point model or scheduler).
    #[error("step {step}: {message}")]
    Step {
        /// Time step, from 0.
        step: usize,
        /// What failed.
        message: String,
    },
    /// A trace of the beam-management study exceeded its budget.
    #[error(transparent)]
    Trace(#[from] bt_solve::pipeline::TraceError),
    /// An output could not be written safely.
    #[error(transparent)]
    Output(#[from] bt_output::OutputError),
    /// A figure could not be drawn.
    #[error("{path}: plotting failed: {message}")]
    Plot {
        /// Figure file.
        path: String,
        /// The plotting library's message.
        message: String,
    },
}

impl StudyError {
    /// Refuses settings with any problem, naming every one (both studies' `problems()`).
    pub(crate) fn check_settings(problems: Vec<String>) -> Result<(), StudyError> {
        if problems.is_empty() {
            Ok(())
        } else {
            Err(StudyError::Config(problems.join("; ")))
        }
    }
}
