//! The twins' rankings of the beam pairs at every decision, and the one trace loop the truth
//! and the twins share.

use super::codebook::ranking;
use super::radio::Radio;
use super::scenario::Scenario;
use super::{BeamManagementConfig, Found};
use crate::StudyError;
use bt_channel::codebook::PathDirections;
use bt_geom::{Real, Vec3};
use bt_scene::Scene;
use bt_solve::Tracer;
use bt_solve::pipeline::TraceError;
use bt_solve::pipeline::TraceOptions;
use std::time::Instant;

/// Where the scene of each trace comes from.
pub(crate) enum Source<'a> {
    /// One scene for every decision (one beam tree of the AP answers every receiver).
    Static(&'a Scene),
    /// The scene at each decision.
    Dynamic(&'a dyn Fn(usize) -> Result<Scene, StudyError>),
}

/// One trace per receiver: the scene with the AP and that receiver as terminals (`None` when
/// the receiver cannot be placed), and the paths or why there are none. A receiver that lies
/// on a surface is such a failure; a budget exceeded stops the study.
pub(crate) type Traced = (Option<Scene>, Result<Found, String>);

fn failure(e: TraceError) -> Result<String, StudyError> {
    match e {
        TraceError::Scene(e) => Ok(e.to_string()),
        other => Err(StudyError::Trace(other)),
    }
}

/// Trace from the AP to each of `receivers` in the scenes of `source`.
pub(crate) fn trace_along(
    ap: Vec3,
    options: TraceOptions,
    receivers: &[Vec3],
    source: Source<'_>,
    tick: &mut dyn FnMut(usize),
) -> Result<Vec<Traced>, StudyError> {
    let mut out = Vec::with_capacity(receivers.len());
    match source {
        Source::Static(scene) => {
            let mut tracer = Tracer::new(scene.clone(), options);
            // In chunks, for the progress bar; the AP's tree is kept between them.
            for (c, chunk) in receivers.chunks(64).enumerate() {
                let traced = tracer.trace_each(ap, chunk)?;
                for (j, result) in traced.into_iter().enumerate() {
                    let placed = scene.with_terminals(ap, receivers[c * 64 + j]).ok();
                    let result = match result {
                        Ok(t) => Ok(Found::of(t)),
                        Err(e) => Err(failure(e)?),
                    };
                    out.push((placed, result));
                }
                tick(chunk.len());
            }
        }
        Source::Dynamic(scene_at) => {
            let mut tracer: Option<Tracer> = None;
            for (i, &rx) in receivers.iter().enumerate() {
                let scene = scene_at(i)?;
                let tracer = match &mut tracer {
                    Some(t) => {
                        t.set_scene(scene.clone());
                        t
                    }
                    None => tracer.insert(Tracer::new(scene.clone(), options)),
                };
                let result = match tracer.trace(ap, rx) {
                    Ok(t) => Ok(Found::of(t)),
                    Err(e) => Err(failure(e)?),
                };
                out.push((scene.with_terminals(ap, rx).ok(), result));
                tick(1);
            }
        }
    }
    Ok(out)
}

/// One twin at one position error and latency: the first pairs of its ranking at every
/// decision.
pub(crate) struct TwinRankings {
    /// `twin-exact`, `twin-stale`, `twin-extracted` or `geometric-los`.
    pub family: String,
    /// Position error σ, metres.
    pub sigma_m: Real,
    /// Latency, seconds.
    pub latency_s: Real,
    /// The best-ranked pairs (as many as the largest K), strongest first, per decision.
    pub rankings: Vec<Vec<usize>>,
    /// Computing time of each ranking (trace, report, pair powers, sort), seconds.
    pub compute_s: Vec<Real>,
    /// Decisions that fell back to the line of sight.
    pub fallbacks: usize,
    /// Paths whose gain could not be computed, left out.
    pub dropped_paths: usize,
}

/// The twins of `scenario` under every σ and latency of `config`, from the standard normal
/// position offsets `offsets`.
pub(crate) fn rankings(
    scenario: &Scenario,
    config: &BeamManagementConfig,
    radio: &Radio,
    offsets: &[Vec3],
    tick: &mut dyn FnMut(usize),
) -> Result<Vec<TwinRankings>, StudyError> {
    let options = config.trace_options(config.twin_max_order, config.twin_diffraction);
    let static_truth = (scenario.truth.len() <= 1).then(|| scenario.truth.step(0));
    let mut models: Vec<(&str, Option<&Scene>)> = vec![("twin-exact", static_truth)];
    if let Some(s) = &scenario.stale {
        models.push(("twin-stale", Some(s)));
    }
    if let Some(s) = &scenario.extracted {
        models.push(("twin-extracted", Some(s)));
    }
    let keep = config.top_k.iter().copied().max().unwrap_or(1);
    let mut out = Vec::new();
    for &latency_s in &config.latencies_s {
        let lag = super::BeamManagementConfig::decisions(latency_s, scenario.decision_period_s);
        let past = |i: usize| i.saturating_sub(lag);
        for &sigma_m in &config.position_sigmas_m {
            let reported: Vec<Vec3> = (0..scenario.trajectory.len())
                .map(|i| scenario.inside(scenario.trajectory[past(i)] + offsets[i] * sigma_m))
                .collect();
            let headings: Vec<Real> = (0..reported.len())
                .map(|i| scenario.headings[past(i)])
                .collect();
            let view = View {
                radio,
                reported: &reported,
                headings: &headings,
                keep,
            };
            for (family, scene) in &models {
                let scene_at = |i: usize| scenario.truth_at(past(i));
                let source = match scene {
                    Some(s) => Source::Static(s),
                    None => Source::Dynamic(&scene_at),
                };
                let traced = trace_along(scenario.ap, options, &reported, source, tick)?;
                let mut twin = view.rank(traced.into_iter().map(Some))?;
                (twin.family, twin.sigma_m, twin.latency_s) =
                    (family.to_string(), sigma_m, latency_s);
                out.push(twin);
            }
            let mut los = view.rank(std::iter::repeat_with(|| None).take(reported.len()))?;
            (los.family, los.sigma_m, los.latency_s) = ("geometric-los".into(), sigma_m, latency_s);
            out.push(los);
        }
    }
    Ok(out)
}

/// What a twin is told at every decision.
struct View<'a> {
    radio: &'a Radio,
    reported: &'a [Vec3],
    headings: &'a [Real],
    keep: usize,
}

impl View<'_> {
    /// Rank the pairs at every decision from its trace (`None`: the line of sight alone).
    fn rank(
        &self,
        traced: impl Iterator<Item = Option<Traced>>,
    ) -> Result<TwinRankings, StudyError> {
        let mut twin = TwinRankings {
            family: String::new(),
            sigma_m: 0.0,
            latency_s: 0.0,
            rankings: Vec::with_capacity(self.reported.len()),
            compute_s: Vec::with_capacity(self.reported.len()),
            fallbacks: 0,
            dropped_paths: 0,
        };
        let channel = |e: bt_channel::ChannelError| StudyError::Config(e.to_string());
        for (i, traced) in traced.enumerate() {
            let start = Instant::now();
            let heading = self.headings[i];
            let (mut paths, trace_s): (Vec<PathDirections>, Real) = match &traced {
                Some((Some(scene), Ok(found))) => {
                    let (paths, left_out) = self.radio.directions(scene, &found.paths, heading);
                    twin.dropped_paths += left_out;
                    (paths, found.time_s)
                }
                _ => (Vec::new(), 0.0),
            };
            if paths.is_empty() {
                twin.fallbacks += usize::from(traced.is_some());
                paths = self.radio.line_of_sight(self.reported[i]);
            }
            let power = self.radio.narrow(&paths, heading).map_err(channel)?;
            let mut order = ranking(&power);
            order.truncate(self.keep);
            twin.rankings.push(order);
            twin.compute_s.push(trace_s + start.elapsed().as_secs_f64());
        }
        Ok(twin)
    }
}
