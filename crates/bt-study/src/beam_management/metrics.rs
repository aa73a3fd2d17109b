//! TR 38.843's beam-prediction metrics (§6.3.2.1 of its BM-Case1/2 evaluation): one
//! [`Outcome`] per decision from the true pair powers and what a method did, and their
//! aggregate, [`Metrics`].
//!
//! With b* the true best pair, s the pair the method serves with, C the K pairs it measured
//! in its final stage (its "predicted Top-K"), p its predicted best before that measurement,
//! and T_K the K truly strongest pairs:
//! - Top-1: s = b*; with a 1 dB margin: P(s) ≥ P(b*) − 1 dB;
//! - Top-K/1: b* ∈ C; with the margin: some c ∈ C has P(c) ≥ P(b*) − 1 dB;
//! - Top-1/K: p ∈ T_K; with the margin: P(p) ≥ P(K-th best) − 1 dB;
//! - SNR loss: P(b*) − P(s), dB (the noise does not depend on the beam, so the RSRP loss is the
//!   SNR loss).

use bt_geom::Real;
use serde::{Deserialize, Serialize};

/// The margin of the "with 1 dB margin" metrics, dB.
pub const MARGIN_DB: Real = 1.0;

/// A loss with no power on the served pair at all is counted as this many dB (never infinite
/// in an output; not reached in the built-in scenarios).
pub const MAX_LOSS_DB: Real = 200.0;

/// What a method did at one decision.
#[derive(Debug, Clone, PartialEq)]
pub struct Decision {
    /// The pair it serves with.
    pub chosen: usize,
    /// Its predicted best pair before the final measurement.
    pub predicted: usize,
    /// The pairs of its final stage (its predicted Top-K), K = its length.
    pub candidates: Vec<usize>,
    /// Beam pairs measured for this decision (every stage, wide beams included).
    pub measured: usize,
}

/// The metrics of one decision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Outcome {
    /// True best pair.
    pub best: usize,
    /// Its true power, dBm.
    pub best_dbm: Real,
    /// True power of the served pair, dBm.
    pub chosen_dbm: Real,
    /// Served pair = best pair.
    pub top1: bool,
    /// Served pair within the margin of the best.
    pub top1_1db: bool,
    /// Best pair among the final-stage candidates.
    pub topk1: bool,
    /// A candidate within the margin of the best.
    pub topk1_1db: bool,
    /// Predicted best among the true K best (K = candidates).
    pub top1k: bool,
    /// Predicted best within the margin of the true K-th best.
    pub top1k_1db: bool,
    /// P(best) − P(served), dB, at most [`MAX_LOSS_DB`].
    pub snr_loss_db: Real,
    /// Beam pairs measured.
    pub measured: usize,
}

/// The metrics of `decision` against the true pair powers `truth` (dBm, `−∞` for none);
/// `None` when no pair receives anything (an outage: no method can serve it).
pub fn outcome(truth: &[Real], decision: &Decision) -> Option<Outcome> {
    let order = super::codebook::ranking(truth);
    let best = *order.first()?;
    let best_dbm = truth[best];
    if !best_dbm.is_finite() {
        return None;
    }
    let k = decision.candidates.len().clamp(1, truth.len());
    let kth_dbm = truth[order[k - 1]];
    let chosen_dbm = truth[decision.chosen];
    let within = |p: Real, of: Real| p >= of - MARGIN_DB;
    let loss = (best_dbm - chosen_dbm).min(MAX_LOSS_DB);
    Some(Outcome {
        best,
        best_dbm,
        chosen_dbm: chosen_dbm.max(best_dbm - MAX_LOSS_DB),
        top1: decision.chosen == best,
        top1_1db: within(chosen_dbm, best_dbm),
        topk1: decision.candidates.contains(&best),
        topk1_1db: decision
            .candidates
            .iter()
            .any(|&c| within(truth[c], best_dbm)),
        top1k: order[..k].contains(&decision.predicted),
        top1k_1db: within(truth[decision.predicted], kth_dbm),
        snr_loss_db: loss,
        measured: decision.measured,
    })
}

/// A method's metrics over the decisions with signal: fractions in [0, 1], dB, beam pairs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Top-1 accuracy.
    pub top1: Real,
    /// Top-1 accuracy with the 1 dB margin.
    pub top1_1db: Real,
    /// Top-K/1.
    pub topk1: Real,
    /// Top-K/1 with the 1 dB margin.
    pub topk1_1db: Real,
    /// Top-1/K.
    pub top1k: Real,
    /// Top-1/K with the 1 dB margin.
    pub top1k_1db: Real,
    /// Mean SNR loss, dB.
    pub snr_loss_db_mean: Real,
    /// 95th percentile (nearest rank) of the SNR loss, dB.
    pub snr_loss_db_p95: Real,
    /// Mean beam pairs measured per decision.
    pub beams_measured: Real,
    /// Decisions counted (those with signal).
    pub decisions: usize,
}

/// The nearest-rank `q` quantile (0 < q ≤ 1) of `values`; 0 for none.
pub fn quantile(values: &[Real], q: Real) -> Real {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(Real::total_cmp);
    let rank = ((q * v.len() as Real).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// Aggregate `outcomes` (all zero when there are none).
pub fn aggregate(outcomes: &[Outcome]) -> Metrics {
    let n = outcomes.len().max(1) as Real;
    let frac = |f: fn(&Outcome) -> bool| outcomes.iter().filter(|o| f(o)).count() as Real / n;
    let losses: Vec<Real> = outcomes.iter().map(|o| o.snr_loss_db).collect();
    Metrics {
        top1: frac(|o| o.top1),
        top1_1db: frac(|o| o.top1_1db),
        topk1: frac(|o| o.topk1),
        topk1_1db: frac(|o| o.topk1_1db),
        top1k: frac(|o| o.top1k),
        top1k_1db: frac(|o| o.top1k_1db),
        snr_loss_db_mean: losses.iter().sum::<Real>() / n,
        snr_loss_db_p95: quantile(&losses, 0.95),
        beams_measured: outcomes.iter().map(|o| o.measured as Real).sum::<Real>() / n,
        decisions: outcomes.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Six pairs; true powers in dBm. Order: 2 (−50), 4 (−50.5), 0 (−52), 1 (−60), 5 (−70), 3.
    const TRUTH: [Real; 6] = [-52.0, -60.0, -50.0, Real::NEG_INFINITY, -50.5, -70.0];

    fn decide(chosen: usize, predicted: usize, candidates: &[usize]) -> Outcome {
        let d = Decision {
            chosen,
            predicted,
            candidates: candidates.to_vec(),
            measured: candidates.len(),
        };
        outcome(&TRUTH, &d).unwrap()
    }

    #[test]
    fn hand_built_decisions_score_as_tr_38_843_defines() {
        // Right pair, right prediction.
        let o = decide(2, 2, &[2]);
        assert!(o.top1 && o.top1_1db && o.topk1 && o.top1k);
        assert_eq!(o.snr_loss_db, 0.0);
        // Served the second best, 0.5 dB down: wrong, but within the margin.
        let o = decide(4, 4, &[4, 0]);
        assert!(!o.top1 && o.top1_1db && !o.topk1 && o.topk1_1db);
        // Predicted 4 is in the true top-2 {2, 4}.
        assert!(o.top1k && o.top1k_1db);
        assert!((o.snr_loss_db - 0.5).abs() < 1e-12);
        // Candidates {0, 1} miss the best by 2 dB; predicted 0 is not in the true top-2
        // {2, 4}, and is 1.5 dB under the 2nd best (outside the margin).
        let o = decide(0, 0, &[0, 1]);
        assert!(!o.top1 && !o.top1_1db && !o.topk1 && !o.topk1_1db);
        assert!(!o.top1k && !o.top1k_1db);
        assert!((o.snr_loss_db - 2.0).abs() < 1e-12);
        // A candidate set holding the best, served with another (measurement noise).
        let o = decide(4, 2, &[4, 2, 0]);
        assert!(!o.top1 && o.topk1 && o.top1k);
        // Served a pair that receives nothing: the loss is capped, never infinite.
        let o = decide(3, 3, &[3]);
        assert_eq!(o.snr_loss_db, MAX_LOSS_DB);
        assert!(o.chosen_dbm.is_finite());
    }

    #[test]
    fn no_signal_is_an_outage() {
        let d = Decision {
            chosen: 0,
            predicted: 0,
            candidates: vec![0],
            measured: 1,
        };
        assert!(outcome(&[Real::NEG_INFINITY; 3], &d).is_none());
    }

    #[test]
    fn aggregate_means_and_nearest_rank_p95() {
        let outcomes: Vec<Outcome> = (0..20).map(|i| decide(i % 3, 2, &[2, 4])).collect();
        let m = aggregate(&outcomes);
        // chosen cycles 0, 1, 2: losses 2, 10, 0 dB; pair 2 is chosen 6 times of 20.
        assert!((m.top1 - 6.0 / 20.0).abs() < 1e-12);
        assert_eq!(m.topk1, 1.0);
        assert_eq!(m.snr_loss_db_p95, 10.0);
        let mean = (7.0 * 2.0 + 7.0 * 10.0) / 20.0;
        assert!((m.snr_loss_db_mean - mean).abs() < 1e-12);
        assert_eq!(m.beams_measured, 2.0);
        assert_eq!(quantile(&[3.0, 1.0, 2.0, 4.0], 0.5), 2.0);
        assert_eq!(quantile(&[], 0.95), 0.0);
    }
}
