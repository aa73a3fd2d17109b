//! The documents of a trace, defined once: `beamtrace trace --json` ([`TraceDocument`]) and
//! `trace --steps --json` ([`StepsDocument`], one [`StepDocument`] a line with `--jsonl`),
//! their path record being [`PathReport`]. `Serialize + Deserialize`: the CLI prints them,
//! the viewer reads them back, Python's columns and coverage's rows come from the same record,
//! so a new path field is one edit. The layout is `docs/output-format.md`; the bytes are
//! pinned by the golden files (only the `time_s` fields vary between runs).

use crate::{PathReport, RadioOptions, ReportError};
use bt_channel::{Antenna, DiffractionCoefficient};
use bt_paths::CandidateStats;
use bt_paths::beamtree::TreeStats;
use bt_paths::wvrn::WvrnStats;
use bt_scene::Scene;
use bt_solve::pipeline::{CandidateMode, TraceOptions, Traced};
use bt_solve::{OutcomeCounts, Solver, StepTrace, UpdateStats};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Version of the documents' layout; bump on any incompatible change.
pub const FORMAT_VERSION: u32 = 4;

/// The document of one trace (`beamtrace trace --json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceDocument {
    /// [`FORMAT_VERSION`].
    pub format_version: u32,
    /// Scene name.
    pub scene: String,
    /// Transmitter, metres, world frame.
    pub tx: [f64; 3],
    /// Receiver, metres, world frame.
    pub rx: [f64; 3],
    /// Carrier frequency, Hz.
    pub frequency_hz: f64,
    /// Highest number of reflections traced.
    pub max_order: usize,
    /// The solver and its options.
    pub solver: Solver,
    /// Transmission switched on for every slab reflector (`--transmission`; a material's
    /// `"transmission": true` opens its surfaces either way). Read as `false` from a document
    /// written before the field existed.
    #[serde(default)]
    pub transmission: bool,
    /// Most diffractions per path the trace allowed: 0 without diffraction, 1 with
    /// `--diffraction`, 2 with `--max-diffractions 2`. Read as 0 from a document written before
    /// the field existed.
    #[serde(default)]
    pub max_diffractions: usize,
    /// Antennas and transmitted power of the gains.
    pub radio: Radio,
    /// The valid paths, ranked.
    pub paths: Vec<PathReport>,
    /// Counts and times.
    pub stats: Stats,
}

/// Antennas, transmitted power and diffraction coefficient of the gains.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Radio {
    /// Transmitting antenna.
    pub tx_antenna: Antenna,
    /// Receiving antenna.
    pub rx_antenna: Antenna,
    /// Transmitted power, dBm.
    pub tx_power_dbm: f64,
    /// The diffraction coefficient of diffracted paths' gains: `"utd"` or `"sionna-rt-2.2"`
    /// (a document written before it existed reads as `"utd"`, what it used).
    #[serde(default)]
    pub diffraction_coefficient: DiffractionCoefficient,
}

/// What a trace counted, and how long its stages took.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// How many candidates each stage produced.
    pub candidates: CandidateStats,
    /// Beam-tree node counts (beam-tree candidates only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tree: Option<TreeStats>,
    /// Every candidate's outcome, counted.
    pub outcomes: OutcomeCounts,
    /// Number of valid paths.
    pub valid_paths: usize,
    /// Total received power (power sum over the paths), dBm; null without any power.
    pub received_power_dbm: Option<f64>,
    /// Wall-clock seconds per stage (the only part of the document that varies between runs).
    pub time_s: StageTimes,
}

/// Wall-clock seconds per stage of a trace.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// Loading the scene.
    pub load: f64,
    /// Candidate generation.
    pub candidates: f64,
    /// Solving and validation.
    pub solve: f64,
    /// Describing and ranking the paths.
    pub report: f64,
}

impl TraceDocument {
    /// The one report of a trace: `traced` (a [`bt_solve::Tracer`] result for `scene`'s own
    /// terminals under `options`) described and ranked with `radio` ([`crate::report`]);
    /// `load` is the time the scene took to load.
    pub fn report(
        scene: &Scene,
        options: &TraceOptions,
        traced: &Traced,
        radio: &RadioOptions,
        load: Duration,
    ) -> Result<Self, ReportError> {
        let t0 = Instant::now();
        let paths = crate::report(scene, &traced.result.paths, radio)?;
        let [tx, rx] = terminals_world(scene)?;
        let report = t0.elapsed();
        Ok(Self {
            format_version: FORMAT_VERSION,
            scene: scene.name().to_string(),
            tx,
            rx,
            frequency_hz: scene.frequency_hz(),
            max_order: options.max_order,
            solver: options.solver,
            transmission: options.transmission,
            max_diffractions: options.diffraction.max_diffractions,
            radio: Radio {
                tx_antenna: radio.tx,
                rx_antenna: radio.rx,
                tx_power_dbm: radio.tx_power_dbm,
                diffraction_coefficient: radio.diffraction_coefficient,
            },
            stats: Stats::of(traced, &paths, radio, [load, report]),
            paths,
        })
    }
}

impl Stats {
    /// The stats of a trace: `traced`'s counts and stage times, the number and power of its
    /// reported `paths`, and `[load, report]`, the times the scene took to load and the paths
    /// to be reported.
    pub fn of(
        traced: &Traced,
        paths: &[PathReport],
        radio: &RadioOptions,
        [load, report]: [Duration; 2],
    ) -> Self {
        Stats {
            candidates: traced.candidates,
            tree: traced.tree.clone(),
            outcomes: traced.result.counts,
            valid_paths: paths.len(),
            received_power_dbm: crate::received_power_dbm(paths, radio.tx_power_dbm),
            time_s: StageTimes {
                load: load.as_secs_f64(),
                candidates: traced.time.candidates.as_secs_f64(),
                solve: traced.time.solve.as_secs_f64(),
                report: report.as_secs_f64(),
            },
        }
    }
}

/// The terminals of `scene` in the world frame, metres: `[tx, rx]` as a document writes them.
pub fn terminals_world(scene: &Scene) -> Result<[[f64; 3]; 2], ReportError> {
    let ends = scene.terminals()?;
    Ok([ends.tx, ends.rx].map(|p| scene.to_world(p).to_array()))
}

/// The document of every time step of a dynamic scene (`beamtrace trace --steps --json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepsDocument {
    /// [`FORMAT_VERSION`].
    pub format_version: u32,
    /// Scene name.
    pub scene: String,
    /// Carrier frequency, Hz.
    pub frequency_hz: f64,
    /// Highest number of reflections traced.
    pub max_order: usize,
    /// The solver and its options.
    pub solver: Solver,
    /// The candidate generator.
    pub candidates: CandidateMode,
    /// Whether the steps were traced incrementally (else each from scratch).
    pub incremental: bool,
    /// The steps, in order.
    pub steps: Vec<StepDocument>,
}

impl StepsDocument {
    /// The document of `steps`, traced under `options` in a dynamic scene whose first step is
    /// `scene0`.
    pub fn new(
        scene0: &Scene,
        options: &TraceOptions,
        incremental: bool,
        steps: Vec<StepDocument>,
    ) -> Self {
        StepsDocument {
            format_version: FORMAT_VERSION,
            scene: scene0.name().to_string(),
            frequency_hz: scene0.frequency_hz(),
            max_order: options.max_order,
            solver: options.solver,
            candidates: options.candidates,
            incremental,
            steps,
        }
    }
}

/// One time step (a line of `--jsonl`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepDocument {
    /// Time step, 0-based.
    pub step: usize,
    /// Transmitter, metres, world frame.
    pub tx: [f64; 3],
    /// Receiver, metres, world frame.
    pub rx: [f64; 3],
    /// The valid paths, ranked.
    pub paths: Vec<PathReport>,
    /// Counts and time.
    pub stats: StepStats,
}

/// What a step counted and recomputed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepStats {
    /// How many candidates each stage produced.
    pub candidates: CandidateStats,
    /// Every candidate's outcome, counted.
    pub outcomes: OutcomeCounts,
    /// Number of valid paths.
    pub valid_paths: usize,
    /// WVRN counts (WVRN candidates only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wvrn: Option<WvrnStats>,
    /// What the incremental update did.
    pub update: UpdateStats,
    /// Wall-clock seconds of the step (WVRN, candidates, solving; the only varying field).
    pub time_s: f64,
}

impl StepDocument {
    /// The one report of a time step: `traced` (step `traced.step` of a
    /// [`bt_solve::Tracer::update`], in `scene`) described and ranked with `radio`; `time`
    /// is the step's tracing time.
    pub fn report(
        scene: &Scene,
        traced: StepTrace,
        radio: &RadioOptions,
        time: Duration,
    ) -> Result<Self, ReportError> {
        let paths = crate::report(scene, &traced.trace.paths, radio)?;
        let [tx, rx] = terminals_world(scene)?;
        Ok(StepDocument {
            step: traced.step,
            tx,
            rx,
            stats: StepStats {
                candidates: traced.candidates,
                outcomes: traced.trace.counts,
                valid_paths: paths.len(),
                wvrn: traced.wvrn,
                update: traced.update,
                time_s: time.as_secs_f64(),
            },
            paths,
        })
    }
}
