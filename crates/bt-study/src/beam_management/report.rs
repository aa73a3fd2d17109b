//! The study's documents: `summary.json` (the exact shape), `details.json` (every
//! metric, the settings and notes; no timing, so byte-reproducible), and the per-decision
//! `decisions.csv` and `trajectory.csv`.

use super::metrics::Metrics;
use super::{BeamManagementConfig, BeamManagementResults, MethodResult};
use bt_geom::Real;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write;

/// Air time of one beam measurement, µs: one OFDM symbol with its cyclic prefix at 120 kHz
/// subcarrier spacing (FR2), the least a reference signal per beam pair can take.
pub const MEASUREMENT_AIR_TIME_US: Real = 8.93;

/// `summary.json`: `{"scenarios": {NAME: {"methods": {METHOD: {...}}}}}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Summary {
    /// By scenario name.
    pub scenarios: BTreeMap<String, ScenarioSummary>,
}

/// One scenario of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSummary {
    /// By method name.
    pub methods: BTreeMap<String, MethodSummary>,
}

/// One method of `summary.json` (fractions in [0, 1], dB, beam pairs, µs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodSummary {
    /// Top-1 accuracy.
    pub top1: Real,
    /// Top-1 accuracy with a 1 dB margin.
    pub top1_1db: Real,
    /// Top-K/1: the true best pair among the K the method measured last.
    pub topk1: Real,
    /// Top-1/K: the method's predicted best among the true K best.
    pub top1k: Real,
    /// Mean SNR loss against the true best pair, dB.
    pub snr_loss_db_mean: Real,
    /// 95th-percentile SNR loss, dB.
    pub snr_loss_db_p95: Real,
    /// Beam pairs measured per decision.
    pub beams_measured: Real,
    /// Mean computing time per decision, µs (the only field that varies between runs).
    pub latency_us: Real,
}

/// The summary document of `results`.
pub fn summary(results: &BeamManagementResults) -> Summary {
    let method = |m: &MethodResult| MethodSummary {
        top1: m.metrics.top1,
        top1_1db: m.metrics.top1_1db,
        topk1: m.metrics.topk1,
        top1k: m.metrics.top1k,
        snr_loss_db_mean: m.metrics.snr_loss_db_mean,
        snr_loss_db_p95: m.metrics.snr_loss_db_p95,
        beams_measured: m.metrics.beams_measured,
        latency_us: m.latency_us,
    };
    Summary {
        scenarios: (results.scenarios.iter())
            .map(|s| {
                let methods = s
                    .methods
                    .iter()
                    .map(|m| (m.name.clone(), method(m)))
                    .collect();
                (s.name.clone(), ScenarioSummary { methods })
            })
            .collect(),
    }
}

/// `details.json`: the settings and, per scenario and method, every metric without timing.
#[derive(Debug, Clone, Serialize)]
pub struct Details<'a> {
    /// The settings, seed included.
    pub config: &'a BeamManagementConfig,
    /// By scenario name.
    pub scenarios: BTreeMap<&'a str, ScenarioDetails<'a>>,
}

/// One scenario of `details.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioDetails<'a> {
    /// Decisions (UE positions).
    pub decisions: usize,
    /// Decisions without any signal, not scored.
    pub outages: usize,
    /// Narrow beam pairs.
    pub pairs: usize,
    /// Time between decisions, s.
    pub decision_period_s: Real,
    /// Twins absent and why; what the scan found.
    pub notes: &'a [String],
    /// By method name.
    pub methods: BTreeMap<&'a str, MethodDetails<'a>>,
}

/// One method of `details.json`.
#[derive(Debug, Clone, Serialize)]
pub struct MethodDetails<'a> {
    /// The method's family.
    pub family: &'a str,
    /// Twin methods: position error σ, metres.
    pub sigma_m: Option<Real>,
    /// Twin methods: reporting latency, s.
    pub latency_s: Option<Real>,
    /// Twin methods: K.
    pub k: Option<usize>,
    /// Every metric.
    #[serde(flatten)]
    pub metrics: Metrics,
    /// Air time of the measurements per decision at [`MEASUREMENT_AIR_TIME_US`], µs.
    pub air_time_us: Real,
    /// Decisions where the twin fell back to the line of sight.
    pub fallbacks: usize,
}

/// The details document of `results`.
pub fn details(results: &BeamManagementResults) -> Details<'_> {
    fn method(m: &MethodResult) -> MethodDetails<'_> {
        MethodDetails {
            family: &m.family,
            sigma_m: m.twin.map(|t| t.0),
            latency_s: m.twin.map(|t| t.1),
            k: m.twin.map(|t| t.2),
            metrics: m.metrics,
            air_time_us: m.metrics.beams_measured * MEASUREMENT_AIR_TIME_US,
            fallbacks: m.fallbacks,
        }
    }
    Details {
        config: &results.config,
        scenarios: (results.scenarios.iter())
            .map(|s| {
                let details = ScenarioDetails {
                    decisions: s.trajectory.len(),
                    outages: s.outages,
                    pairs: s.pairs,
                    decision_period_s: s.decision_period_s,
                    notes: &s.notes,
                    methods: s
                        .methods
                        .iter()
                        .map(|m| (m.name.as_str(), method(m)))
                        .collect(),
                };
                (s.name.as_str(), details)
            })
            .collect(),
    }
}

/// `decisions.csv`: one row per scenario, method and decision (outages have empty metrics).
pub fn decisions_csv(results: &BeamManagementResults) -> String {
    let mut out = String::from(
        "scenario,method,decision,chosen_pair,chosen_dbm,best_pair,best_dbm,snr_loss_db,top1,top1_1db,topk1,topk1_1db,top1k,top1k_1db,beams_measured\n",
    );
    let flag = |b: bool| u8::from(b);
    for s in &results.scenarios {
        for m in &s.methods {
            for (i, (chosen, o)) in m.outcomes.iter().enumerate() {
                let _ = write!(out, "{},{},{i},{chosen},", s.name, m.name);
                let _ = match o {
                    Some(o) => writeln!(
                        out,
                        "{:.3},{},{:.3},{:.3},{},{},{},{},{},{},{}",
                        o.chosen_dbm,
                        o.best,
                        o.best_dbm,
                        o.snr_loss_db,
                        flag(o.top1),
                        flag(o.top1_1db),
                        flag(o.topk1),
                        flag(o.topk1_1db),
                        flag(o.top1k),
                        flag(o.top1k_1db),
                        o.measured
                    ),
                    None => writeln!(out, ",,,,,,,,,,"),
                };
            }
        }
    }
    out
}

/// `trajectory.csv`: the UE position at every decision of every scenario.
pub fn trajectory_csv(results: &BeamManagementResults) -> String {
    let mut out = String::from("scenario,decision,time_s,x,y,z\n");
    for s in &results.scenarios {
        for (i, p) in s.trajectory.iter().enumerate() {
            let t = i as Real * s.decision_period_s;
            let _ = writeln!(
                out,
                "{},{i},{t:.3},{:.4},{:.4},{:.4}",
                s.name, p.x, p.y, p.z
            );
        }
    }
    out
}
