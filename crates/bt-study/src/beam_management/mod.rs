//! What the twin buys (issue 31): a beam-management study with the metrics of 3GPP TR 38.843
//! (top-K accuracy, SNR loss, beams measured, decision latency) for twin-driven beam
//! selection against the sweeps a device runs without one.
//!
//! A UE moves through a scenario ([`scenario`]); at each decision the truth (the full scene,
//! ITU materials, reflections and first-order diffraction) gives the power of every pair of
//! an 8 × 8 UPA at the AP and a 2 × 4 UPA at the UE with DFT codebooks ([`radio`]). Methods
//! ([`methods`]) see only noisy, 1 dB-quantised L1-RSRP of the pairs they measure, and twins
//! (exact, stale, extracted from a scan, or free space) that rank the pairs from a reported
//! UE position with an error of σ and a reporting latency. [`metrics`] scores each decision,
//! [`report`] writes `summary.json`, `details.json` and `decisions.csv`, [`plot`] the
//! figures. `docs/study-beam-management.md` has the method and the measured numbers.
//!
//! Units: metres, seconds, dBm and dB; positions in the world frame.

pub mod codebook;
pub mod methods;
pub mod metrics;
pub mod plot;
pub mod radio;
pub mod report;
pub mod scenario;
mod twins;

use crate::StudyError;
use bt_geom::{Real, Vec3};
use bt_solve::pipeline::{DiffractionOptions, TraceOptions};
use methods::{KeepPrevious, Measurement};
use metrics::{Decision, Metrics, Outcome};
use radio::Radio;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scenario::{ScanSettings, Scenario};
use serde::Serialize;
use std::time::Instant;

/// Largest number of UE positions per scenario (each keeps its pair powers, ~4 KB).
pub const MAX_POSITIONS: usize = 1_000_000;

/// Settings of the study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BeamManagementConfig {
    /// UE positions (decisions) per scenario.
    pub positions: usize,
    /// Seed of every random draw (measurement errors, position errors, the scan).
    pub seed: u64,
    /// Highest interaction order of the truth's traces.
    pub truth_max_order: usize,
    /// The truth includes first-order edge diffraction.
    pub truth_diffraction: bool,
    /// Highest order of the twins' traces.
    pub twin_max_order: usize,
    /// The twins' traces include diffraction.
    pub twin_diffraction: bool,
    /// Standard deviation of the L1-RSRP measurement error, dB.
    pub rsrp_noise_db: Real,
    /// L1-RSRP reporting step, dB (3GPP: 1); 0 reports exact values.
    pub rsrp_step_db: Real,
    /// Standard deviations of the reported UE position's horizontal error, metres.
    pub position_sigmas_m: Vec<Real>,
    /// Reporting latencies of the twins (position and scene as of this long ago), seconds.
    pub latencies_s: Vec<Real>,
    /// The K of the twin top-K methods.
    pub top_k: Vec<usize>,
    /// AP array rows × columns.
    pub ap_array: (usize, usize),
    /// UE array rows × columns.
    pub ue_array: (usize, usize),
    /// Transmitted power per resource element, dBm.
    pub tx_power_dbm: Real,
    /// Keep-previous-best sweeps again when the kept pair's report falls this far, dB.
    pub retrack_drop_db: Real,
    /// The scan behind the extracted twin.
    pub scan: ScanSettings,
    /// Candidate budget of every trace.
    pub max_candidates: u64,
}

impl Default for BeamManagementConfig {
    /// The documented study: 1,000 positions, truth order 2 with diffraction, twins order 2
    /// specular (the paper's real-time tracer), 1 dB noise and steps, σ of 0 / 5 cm / 30 cm /
    /// 1 m, latency 0 and 100 ms, K = 1, 2, 4, 8, 8 × 8 and 2 × 4 arrays, a 2,000 points/m²
    /// scan with 5 mm noise.
    fn default() -> Self {
        BeamManagementConfig {
            positions: 1000,
            seed: 1,
            truth_max_order: 2,
            truth_diffraction: true,
            twin_max_order: 2,
            twin_diffraction: false,
            rsrp_noise_db: 1.0,
            rsrp_step_db: 1.0,
            position_sigmas_m: vec![0.0, 0.05, 0.3, 1.0],
            latencies_s: vec![0.0, 0.1],
            top_k: vec![1, 2, 4, 8],
            ap_array: (8, 8),
            ue_array: (2, 4),
            tx_power_dbm: -6.0,
            retrack_drop_db: 3.0,
            scan: ScanSettings {
                density_per_m2: 2000.0,
                noise_m: 0.005,
                max_points: 5_000_000,
                seed: 1,
            },
            max_candidates: bt_solve::pipeline::DEFAULT_MAX_CANDIDATES,
        }
    }
}

impl BeamManagementConfig {
    /// Every problem with the settings, each naming its command-line option.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        if !(2..=MAX_POSITIONS).contains(&self.positions) {
            p.push(format!(
                "--positions must be 2 to {MAX_POSITIONS}, got {}",
                self.positions
            ));
        }
        for (name, order) in [
            ("--max-order", self.truth_max_order),
            ("--twin-max-order", self.twin_max_order),
        ] {
            if !(1..=crate::run::MAX_STUDY_ORDER).contains(&order) {
                p.push(format!(
                    "{name} must be 1 to {}, got {order}",
                    crate::run::MAX_STUDY_ORDER
                ));
            }
        }
        let finite_non_negative = |x: Real| x.is_finite() && x >= 0.0;
        for (name, v) in [
            ("--rsrp-noise-db", self.rsrp_noise_db),
            ("--rsrp-step-db", self.rsrp_step_db),
            ("--retrack-drop-db", self.retrack_drop_db),
            ("--scan-density", self.scan.density_per_m2),
            ("--scan-noise", self.scan.noise_m),
        ] {
            if !finite_non_negative(v) {
                p.push(format!("{name} must be a finite number >= 0, got {v}"));
            }
        }
        if !self.tx_power_dbm.is_finite() {
            p.push(format!(
                "--tx-power-dbm must be finite, got {}",
                self.tx_power_dbm
            ));
        }
        let lists: [(&str, &[Real]); 2] = [
            ("--position-sigmas", &self.position_sigmas_m),
            ("--latencies", &self.latencies_s),
        ];
        for (name, list) in lists {
            if list.is_empty() || !list.iter().all(|&x| finite_non_negative(x)) {
                p.push(format!(
                    "{name} must list finite numbers >= 0, got {list:?}"
                ));
            }
        }
        let pairs = self.ap_array.0 * self.ap_array.1 * self.ue_array.0 * self.ue_array.1;
        if self.top_k.is_empty() || self.top_k.iter().any(|&k| k == 0 || k > pairs) {
            p.push(format!(
                "--top-k must list numbers from 1 to the {pairs} beam pairs, got {:?}",
                self.top_k
            ));
        }
        p
    }

    /// The latency of `latency_s` in whole decisions of `period_s`.
    fn decisions(latency_s: Real, period_s: Real) -> usize {
        (latency_s / period_s).round() as usize
    }

    fn trace_options(&self, max_order: usize, diffraction: bool) -> TraceOptions {
        TraceOptions {
            max_candidates: self.max_candidates,
            diffraction: match diffraction {
                true => DiffractionOptions::first_order(),
                false => DiffractionOptions::default(),
            },
            ..TraceOptions::new(max_order)
        }
    }
}

/// One method's result in one scenario.
#[derive(Debug, Clone, Serialize)]
pub struct MethodResult {
    /// Its name in the outputs (`exhaustive`, `twin-exact-s0.05m-l0ms-top4`, ...).
    pub name: String,
    /// `exhaustive`, `hierarchical`, `keep-previous`, or the twin: `twin-exact`,
    /// `twin-stale`, `twin-extracted`, `geometric-los`.
    pub family: String,
    /// For twin methods: the reported position's error σ, metres, the latency, seconds, K.
    pub twin: Option<(Real, Real, usize)>,
    /// The aggregate over the decisions with signal.
    pub metrics: Metrics,
    /// Mean computing time per decision on this machine, µs (twin trace, ranking and the
    /// choice; not the air time of the measurements). Varies between runs.
    pub latency_us: Real,
    /// Decisions where the twin had no path or could not be traced and fell back to the
    /// geometric line of sight.
    pub fallbacks: usize,
    /// Per decision: the pair served and its metrics (`None`: an outage).
    pub outcomes: Vec<(usize, Option<Outcome>)>,
}

/// One scenario's result.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioResult {
    /// Scenario name.
    pub name: String,
    /// UE positions.
    pub trajectory: Vec<Vec3>,
    /// Time between decisions, s.
    pub decision_period_s: Real,
    /// Decisions where no pair receives anything (no method is scored on them).
    pub outages: usize,
    /// Narrow beam pairs.
    pub pairs: usize,
    /// Twins absent and why, and what the scan found.
    pub notes: Vec<String>,
    /// The methods, baselines first.
    pub methods: Vec<MethodResult>,
}

/// The whole study.
#[derive(Debug, Clone, Serialize)]
pub struct BeamManagementResults {
    /// The settings (seed echoed).
    pub config: BeamManagementConfig,
    /// One per scenario, in the order given.
    pub scenarios: Vec<ScenarioResult>,
}

/// The truth at every decision: narrow and wide pair powers, dBm.
struct Truth {
    narrow: Vec<Vec<Real>>,
    wide: Vec<Vec<Real>>,
}

/// The per-decision random draws, shared by all methods (common random numbers: a pair
/// measured by two methods at one decision reports the same value).
struct Draws {
    narrow_error_db: Vec<Vec<Real>>,
    wide_error_db: Vec<Vec<Real>>,
    /// Standard normal horizontal offsets of the reported position (scaled by each σ).
    position: Vec<Vec3>,
}

/// A standard normal draw (Box–Muller; 1 − x keeps the logarithm's argument in (0, 1]).
fn normal(rng: &mut ChaCha8Rng) -> Real {
    let (r1, r2): (Real, Real) = (rng.random(), rng.random());
    (-2.0 * (1.0 - r1).ln()).sqrt() * (std::f64::consts::TAU * r2).cos()
}

fn draws(config: &BeamManagementConfig, scenario: usize, radio: &Radio, n: usize) -> Draws {
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    rng.set_stream(2 * scenario as u64);
    let wide = radio.ap_wide.beams.len() * radio.ue_wide.beams.len();
    let errors = |count: usize, rng: &mut ChaCha8Rng| -> Vec<Vec<Real>> {
        (0..n)
            .map(|_| {
                (0..count)
                    .map(|_| config.rsrp_noise_db * normal(rng))
                    .collect()
            })
            .collect()
    };
    let narrow_error_db = errors(radio.pairs(), &mut rng);
    let wide_error_db = errors(wide, &mut rng);
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    rng.set_stream(2 * scenario as u64 + 1);
    let position = (0..n)
        .map(|_| Vec3::new(normal(&mut rng), normal(&mut rng), 0.0))
        .collect();
    Draws {
        narrow_error_db,
        wide_error_db,
        position,
    }
}

/// The traces [`run`] makes over `scenarios` (the length of its progress).
pub fn planned_traces(scenarios: &[Scenario], config: &BeamManagementConfig) -> usize {
    let variants = config.position_sigmas_m.len() * config.latencies_s.len();
    let per_scenario = |s: &Scenario| {
        let twins = 1 + usize::from(s.stale.is_some()) + usize::from(s.extracted.is_some());
        s.trajectory.len() * (1 + twins * variants)
    };
    scenarios.iter().map(per_scenario).sum()
}

/// Run the study over `scenarios`, reporting `progress(done, total)` in traces.
pub fn run(
    scenarios: &[Scenario],
    config: &BeamManagementConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<BeamManagementResults, StudyError> {
    StudyError::check_settings(config.problems())?;
    let total = planned_traces(scenarios, config);
    let mut done = 0;
    let mut results = Vec::new();
    for (index, scenario) in scenarios.iter().enumerate() {
        let mut tick = |k: usize| {
            done += k;
            progress(done, total);
        };
        results.push(run_scenario(scenario, index, config, &mut tick)?);
    }
    Ok(BeamManagementResults {
        config: config.clone(),
        scenarios: results,
    })
}

fn run_scenario(
    scenario: &Scenario,
    index: usize,
    config: &BeamManagementConfig,
    tick: &mut dyn FnMut(usize),
) -> Result<ScenarioResult, StudyError> {
    let radio = Radio::new(
        scenario.ap,
        scenario.ap_orientation,
        config.ap_array,
        config.ue_array,
        scenario.truth.step(0).frequency_hz(),
        config.tx_power_dbm,
        config.truth_max_order,
    )
    .map_err(|e| StudyError::Config(e.to_string()))?;
    let n = scenario.trajectory.len();
    let (truth, mut notes) = truth(scenario, config, &radio, tick)?;
    let draws = draws(config, index, &radio, n);
    let measure = Measure {
        truth: &truth,
        draws: &draws,
        step_db: config.rsrp_step_db,
    };
    let mut methods = baselines(&measure, &radio, config);
    let twins = twins::rankings(scenario, config, &radio, &draws.position, tick)?;
    for twin in &twins {
        for &k in &config.top_k {
            let name = format!(
                "{}-s{}m-l{}ms-top{k}",
                twin.family,
                twin.sigma_m,
                (twin.latency_s * 1e3).round()
            );
            let mut timed = |i: usize| {
                let start = Instant::now();
                let d = methods::twin_top_k(&measure.at(i), &twin.rankings[i], k);
                (d, twin.compute_s[i] + start.elapsed().as_secs_f64())
            };
            let twin_of = Some((twin.sigma_m, twin.latency_s, k));
            let (family, fallbacks) = (&twin.family, twin.fallbacks);
            methods.push(score(
                &name,
                family,
                twin_of,
                &truth.narrow,
                fallbacks,
                &mut timed,
            ));
        }
    }
    notes.extend(scenario.notes.iter().cloned());
    let dropped: usize = twins.iter().map(|t| t.dropped_paths).sum();
    if dropped > 0 {
        notes.push(format!(
            "twins: {dropped} paths left out over all variants, their gain could not be computed"
        ));
    }
    Ok(ScenarioResult {
        name: scenario.name.clone(),
        trajectory: scenario.trajectory.clone(),
        decision_period_s: scenario.decision_period_s,
        outages: truth
            .narrow
            .iter()
            .filter(|p| p.iter().all(|x| !x.is_finite()))
            .count(),
        pairs: radio.pairs(),
        notes,
        methods,
    })
}

/// What the methods measure at each decision.
struct Measure<'a> {
    truth: &'a Truth,
    draws: &'a Draws,
    step_db: Real,
}

impl Measure<'_> {
    fn at(&self, i: usize) -> Measurement<'_> {
        Measurement {
            truth: &self.truth.narrow[i],
            error_db: &self.draws.narrow_error_db[i],
            wide_truth: &self.truth.wide[i],
            wide_error_db: &self.draws.wide_error_db[i],
            step_db: self.step_db,
        }
    }
}

/// The sweeps without a twin: exhaustive, hierarchical, keep-previous.
fn baselines(
    measure: &Measure<'_>,
    radio: &Radio,
    config: &BeamManagementConfig,
) -> Vec<MethodResult> {
    let groups = radio.wide_groups();
    let mut keep = KeepPrevious::default();
    type Decide<'a> = Box<dyn FnMut(usize) -> Decision + 'a>;
    let baselines: [(&str, Decide<'_>); 3] = [
        (
            "exhaustive",
            Box::new(|i| methods::exhaustive(&measure.at(i))),
        ),
        (
            "hierarchical",
            Box::new(|i| methods::hierarchical(&measure.at(i), &groups)),
        ),
        (
            "keep-previous",
            Box::new(|i| keep.decide(&measure.at(i), config.retrack_drop_db)),
        ),
    ];
    let mut methods = Vec::new();
    for (name, mut decide) in baselines {
        let mut timed = |i: usize| {
            let start = Instant::now();
            let d = decide(i);
            (d, start.elapsed().as_secs_f64())
        };
        methods.push(score(
            name,
            name,
            None,
            &measure.truth.narrow,
            0,
            &mut timed,
        ));
    }
    methods
}

/// Decide at every decision with `decide` (the decision and its computing time, s) and score
/// it against `truth`.
fn score(
    name: &str,
    family: &str,
    twin: Option<(Real, Real, usize)>,
    truth: &[Vec<Real>],
    fallbacks: usize,
    decide: &mut dyn FnMut(usize) -> (Decision, Real),
) -> MethodResult {
    let mut outcomes = Vec::with_capacity(truth.len());
    let mut time_s = 0.0;
    for (i, powers) in truth.iter().enumerate() {
        let (d, t) = decide(i);
        time_s += t;
        outcomes.push((d.chosen, metrics::outcome(powers, &d)));
    }
    let scored: Vec<Outcome> = outcomes.iter().filter_map(|o| o.1).collect();
    MethodResult {
        name: name.to_string(),
        family: family.to_string(),
        twin,
        metrics: metrics::aggregate(&scored),
        latency_us: time_s * 1e6 / truth.len().max(1) as Real,
        fallbacks,
        outcomes,
    }
}

/// The truth's pair powers at every decision (a failed trace is an outage, noted).
fn truth(
    scenario: &Scenario,
    config: &BeamManagementConfig,
    radio: &Radio,
    tick: &mut dyn FnMut(usize),
) -> Result<(Truth, Vec<String>), StudyError> {
    let options = config.trace_options(config.truth_max_order, config.truth_diffraction);
    let scene_at = |i: usize| scenario.truth_at(i);
    let source = match scenario.truth.len() {
        1 => twins::Source::Static(scenario.truth.step(0)),
        _ => twins::Source::Dynamic(&scene_at),
    };
    let traced = twins::trace_along(scenario.ap, options, &scenario.trajectory, source, tick)?;
    let mut notes = Vec::new();
    let mut t = Truth {
        narrow: Vec::with_capacity(traced.len()),
        wide: Vec::with_capacity(traced.len()),
    };
    let none = vec![Real::NEG_INFINITY; radio.pairs()];
    let (mut dropped, mut paths_in_all) = (0, 0);
    for (i, (scene, result)) in traced.into_iter().enumerate() {
        let heading = scenario.headings[i];
        let paths = match (scene, result) {
            (Some(scene), Ok(found)) => {
                let (paths, left_out) = radio.directions(&scene, &found.paths, heading);
                (dropped, paths_in_all) = (dropped + left_out, paths_in_all + found.paths.len());
                paths
            }
            (_, Err(e)) => {
                notes.push(format!("truth at decision {i}: {e}; counted as an outage"));
                Vec::new()
            }
            (None, Ok(_)) => Vec::new(),
        };
        let channel = |e: bt_channel::ChannelError| StudyError::Config(e.to_string());
        match paths.is_empty() {
            true => {
                t.narrow.push(none.clone());
                t.wide
                    .push(vec![Real::NEG_INFINITY; radio.wide_groups().len()]);
            }
            false => {
                t.narrow
                    .push(radio.narrow(&paths, heading).map_err(channel)?);
                t.wide.push(radio.wide(&paths, heading).map_err(channel)?);
            }
        }
    }
    if dropped > 0 {
        notes.push(format!(
            "truth: {dropped} of {paths_in_all} paths left out, their gain could not be computed (bt_beams::describe refused them)"
        ));
    }
    Ok((t, notes))
}

/// A trace's outcome as the study keeps it: the paths, and the computing time, s.
pub(crate) struct Found {
    paths: Vec<bt_solve::FoundPath>,
    time_s: Real,
}

impl Found {
    fn of(traced: bt_solve::pipeline::Traced) -> Found {
        Found {
            time_s: (traced.time.candidates + traced.time.solve).as_secs_f64(),
            paths: traced.result.paths,
        }
    }
}
