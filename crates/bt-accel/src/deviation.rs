//! The fixed-point accelerator against the f64 reference: which exact paths it finds, loses
//! or invents, and how far its points and directions are from the exact ones.

use bt_geom::Vec3;
use bt_hls::PathResult;
use bt_paths::{AllVisible, CandidateSet};
use bt_scene::{Endpoints, Scene};
use serde::Serialize;

use crate::bridge::{HostRejection, StepInput, host_accepts};

/// The candidates the f64 reference of [`fixed_deviation`] traces with the image method.
#[derive(Debug, Clone, Copy, Serialize, Default, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Reference {
    /// Every sequence up to the order (blind enumeration): independent of the generator
    /// that gave the step its candidates.
    #[default]
    Exhaustive,
    /// The step's own candidates, when blind enumeration would exceed the candidate budget
    /// (a city holds ~10⁸ sequences at order 2, ~10¹² at order 3). The beam tree gives every
    /// path blind enumeration gives (property-tested), so the points and angles compare as
    /// before; `missed` then counts only the paths the host check rejects.
    StepCandidates,
}

/// Fixed-point model vs the f64 reference (image method over every candidate of the order).
#[derive(Debug, Clone, Serialize, Default, PartialEq)]
pub struct FixedDeviation {
    /// Which candidates the reference traced.
    pub reference: Reference,
    /// Exact paths the accelerator computed (found among its candidates).
    pub valid_paths_compared: usize,
    /// Largest distance between a fixed-point point and the exact one, millimetres.
    pub max_point_error_mm: f64,
    /// Mean of those distances, millimetres.
    pub mean_point_error_mm: f64,
    /// Largest angle between the fixed-point and the exact departure direction, degrees.
    pub max_angle_error_tx_deg: f64,
    /// Largest angle between the fixed-point and the exact arrival direction, degrees.
    pub max_angle_error_rx_deg: f64,
    /// Valid paths (in f64) the fixed-point model does not converge on.
    pub not_converged: usize,
    /// Exact paths lost: not among the accelerator's candidates (and not the host's), or
    /// rejected by the host check (`host_accepts`).
    pub missed: usize,
    /// Exact paths through a moving surface, solved by the host.
    pub host_solved: usize,
    /// Candidates frozen by early stopping.
    pub left_bounds: usize,
    /// Converged, f64-valid results rejected by the reflection-law check.
    pub reflection_rejected: usize,
    /// Results the host accepts that are no path of the image method (false convergences).
    pub spurious: usize,
}

/// Compare one step's accelerator results (`results[p]` of `step.sequences[p]`) with the
/// image method over every sequence up to `max_order` (exhaustive enumeration, validated):
/// the reference is independent of the candidate generator the step used. When those
/// sequences number more than `budget` (`--max-candidates`), the reference traces the step's
/// own candidates `own` instead ([`Reference::StepCandidates`]): enumerating a city's took
/// gigabytes. A scene without both terminals fails
/// ([`bt_scene::SceneError::MissingTerminal`]).
pub fn fixed_deviation(
    scene: &Scene,
    (step, own): (&StepInput, &CandidateSet),
    results: &[PathResult],
    (max_order, budget): (usize, u64),
) -> Result<FixedDeviation, bt_scene::SceneError> {
    let ends = scene.terminals()?;
    let within = bt_solve::pipeline::exhaustive_budget(scene, max_order, budget).is_ok();
    let enumerated;
    let (candidates, which) = match within {
        true => {
            enumerated = bt_paths::enumerate(scene, max_order, &AllVisible)?;
            (&enumerated, Reference::Exhaustive)
        }
        false => (own, Reference::StepCandidates),
    };
    let reference = bt_solve::trace(scene, candidates, &bt_solve::Solver::Image, true)?;
    let mut err = FixedDeviation {
        reference: which,
        left_bounds: results.iter().filter(|r| r.left_bounds).count(),
        ..FixedDeviation::default()
    };
    for (seq, r) in step.sequences.iter().zip(results) {
        match host_accepts(scene, ends, seq, r) {
            Ok(_) => {
                if !reference.paths.iter().any(|p| p.surfaces[..] == seq[..]) {
                    err.spurious += 1;
                }
            }
            Err(HostRejection::ReflectionLaw) => err.reflection_rejected += 1,
            Err(_) => {}
        }
    }
    let mut sum = 0.0;
    let mut count = 0usize;
    // Line of sight (no surface) needs no accelerator: the host adds it.
    for path in reference.paths.iter().filter(|p| !p.surfaces.is_empty()) {
        if step
            .host_sequences
            .iter()
            .any(|s| s[..] == path.surfaces[..])
        {
            err.host_solved += 1;
            continue;
        }
        let Some(k) = step
            .sequences
            .iter()
            .position(|s| s[..] == path.surfaces[..])
        else {
            err.missed += 1;
            continue;
        };
        let r = &results[k];
        if !r.converged {
            err.not_converged += 1;
        }
        if host_accepts(scene, ends, &step.sequences[k], r).is_err() {
            err.missed += 1;
        }
        err.valid_paths_compared += 1;
        for (q, p) in r.points_m.iter().zip(&path.points) {
            let d = (Vec3::from_array(*q) - *p).length() * 1e3;
            err.max_point_error_mm = err.max_point_error_mm.max(d);
            sum += d;
            count += 1;
        }
        let angle = |a: Vec3, b: Vec3| a.angle_between(b).to_degrees();
        let Endpoints { tx, rx } = ends;
        let first = Vec3::from_array(r.points_m[0]);
        let last = Vec3::from_array(*r.points_m.last().expect("order >= 1"));
        err.max_angle_error_tx_deg = err
            .max_angle_error_tx_deg
            .max(angle(first - tx, path.points[0] - tx));
        err.max_angle_error_rx_deg = err.max_angle_error_rx_deg.max(angle(
            last - rx,
            *path.points.last().expect("order >= 1") - rx,
        ));
    }
    err.mean_point_error_mm = if count > 0 { sum / count as f64 } else { 0.0 };
    Ok(err)
}
