//! The methods that pick a beam pair, each from what it may know: the L1-RSRP it measures
//! ([`Measurement`]) and, for the twin methods, a twin's ranking of the pairs.

use super::metrics::Decision;
use bt_geom::Real;

/// What measuring a pair reports at one decision: the true power plus this decision's error of
/// that pair, then rounded to the reporting step (3GPP L1-RSRP: 1 dB), dBm.
#[derive(Debug, Clone)]
pub struct Measurement<'a> {
    /// True power of every narrow pair, dBm.
    pub truth: &'a [Real],
    /// This decision's measurement error of every narrow pair, dB.
    pub error_db: &'a [Real],
    /// True power of every wide pair, dBm.
    pub wide_truth: &'a [Real],
    /// This decision's measurement error of every wide pair, dB.
    pub wide_error_db: &'a [Real],
    /// Reporting step, dB; 0 reports unrounded values.
    pub step_db: Real,
}

impl Measurement<'_> {
    fn report(&self, truth: Real, error: Real) -> Real {
        let v = truth + error;
        if self.step_db > 0.0 && v.is_finite() {
            (v / self.step_db).round() * self.step_db
        } else {
            v
        }
    }

    /// Reported RSRP of narrow pair `pair`, dBm.
    pub fn narrow(&self, pair: usize) -> Real {
        self.report(self.truth[pair], self.error_db[pair])
    }

    /// Reported RSRP of wide pair `pair`, dBm.
    pub fn wide(&self, pair: usize) -> Real {
        self.report(self.wide_truth[pair], self.wide_error_db[pair])
    }

    /// Measure `pairs` (narrow) and return the strongest reported; ties go to the earlier
    /// pair in `pairs` (a twin's better-ranked one). `pairs` must not be empty.
    pub fn best_of(&self, pairs: &[usize]) -> usize {
        let mut best = pairs[0];
        let mut best_dbm = self.narrow(best);
        for &p in &pairs[1..] {
            let v = self.narrow(p);
            if v > best_dbm {
                (best, best_dbm) = (p, v);
            }
        }
        best
    }
}

/// Exhaustive sweep: every pair measured, the strongest reported kept.
pub fn exhaustive(m: &Measurement<'_>) -> Decision {
    let all: Vec<usize> = (0..m.truth.len()).collect();
    let chosen = m.best_of(&all);
    Decision {
        chosen,
        predicted: chosen,
        measured: all.len(),
        candidates: all,
    }
}

/// Two-stage sweep: every wide pair measured, then the narrow pairs under the strongest
/// reported wide pair (`groups[wide pair]`).
pub fn hierarchical(m: &Measurement<'_>, groups: &[Vec<usize>]) -> Decision {
    let wide = (1..m.wide_truth.len()).fold(0, |b, p| if m.wide(p) > m.wide(b) { p } else { b });
    let candidates = groups[wide].clone();
    let chosen = m.best_of(&candidates);
    Decision {
        chosen,
        predicted: chosen,
        measured: m.wide_truth.len() + candidates.len(),
        candidates,
    }
}

/// Twin top-K: the first `k` pairs of the twin's `ranking` measured, the strongest reported
/// kept.
pub fn twin_top_k(m: &Measurement<'_>, ranking: &[usize], k: usize) -> Decision {
    let candidates = ranking[..k.min(ranking.len())].to_vec();
    Decision {
        chosen: m.best_of(&candidates),
        predicted: ranking[0],
        measured: candidates.len(),
        candidates,
    }
}

/// Keep-previous-best tracking: the pair found by the last exhaustive sweep is kept and
/// measured once per decision; when its report falls more than `drop_db` below the report
/// it had when chosen (or at the first decision) the device sweeps every pair again.
#[derive(Debug, Clone, Default)]
pub struct KeepPrevious {
    kept: Option<(usize, Real)>,
}

impl KeepPrevious {
    /// The decision at this measurement.
    pub fn decide(&mut self, m: &Measurement<'_>, drop_db: Real) -> Decision {
        if let Some((pair, reference)) = self.kept
            && m.narrow(pair) >= reference - drop_db
        {
            return Decision {
                chosen: pair,
                predicted: pair,
                candidates: vec![pair],
                measured: 1,
            };
        }
        let mut d = exhaustive(m);
        // The faded pair's own measurement came first.
        d.measured += usize::from(self.kept.is_some());
        self.kept = Some((d.chosen, m.narrow(d.chosen)));
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn measurement<'a>(truth: &'a [Real], error: &'a [Real], step_db: Real) -> Measurement<'a> {
        Measurement {
            truth,
            error_db: error,
            wide_truth: &[-40.0, -45.0],
            wide_error_db: &[0.0, 0.0],
            step_db,
        }
    }

    #[test]
    fn reports_are_rounded_to_the_step_and_noise_can_swap_pairs() {
        let truth = [-50.2, -50.0, -60.0];
        let m = measurement(&truth, &[0.0; 3], 0.0);
        assert_eq!(exhaustive(&m).chosen, 1);
        // At 1 dB steps −50.2 and −50.0 both report −50: the tie goes to the first pair.
        let m = measurement(&truth, &[0.0; 3], 1.0);
        assert_eq!(m.narrow(0), -50.0);
        assert_eq!(exhaustive(&m).chosen, 0);
        // A 1 dB error on pair 0 wins.
        let m = measurement(&truth, &[1.0, 0.0, 0.0], 0.0);
        assert_eq!(exhaustive(&m).chosen, 0);
    }

    #[test]
    fn hierarchical_refines_under_the_best_wide_pair() {
        let truth = [-50.0, -55.0, -40.0, -70.0];
        let m = measurement(&truth, &[0.0; 4], 0.0);
        // Wide pair 0 (−40 dBm) covers {0, 1}: the true best (2) is under wide pair 1.
        let d = hierarchical(&m, &[vec![0, 1], vec![2, 3]]);
        assert_eq!(
            (d.chosen, d.measured, d.candidates.clone()),
            (0, 4, vec![0, 1])
        );
    }

    #[test]
    fn twin_top_k_measures_k_and_keeps_the_strongest() {
        let truth = [-50.0, -45.0, -60.0, -40.0];
        let m = measurement(&truth, &[0.0; 4], 1.0);
        let ranking = [2, 1, 3, 0];
        let d = twin_top_k(&m, &ranking, 2);
        assert_eq!((d.chosen, d.predicted, d.measured), (1, 2, 2));
        assert_eq!(twin_top_k(&m, &ranking, 8).chosen, 3);
    }

    #[test]
    fn keep_previous_sweeps_only_when_the_kept_pair_fades() {
        let mut keep = KeepPrevious::default();
        let truth = [-50.0, -45.0];
        let d = keep.decide(&measurement(&truth, &[0.0; 2], 0.0), 3.0);
        assert_eq!((d.chosen, d.measured), (1, 2));
        // Pair 1 fades by 2 dB: kept, one measurement.
        let faded = [-50.0, -47.0];
        let d = keep.decide(&measurement(&faded, &[0.0; 2], 0.0), 3.0);
        assert_eq!((d.chosen, d.measured), (1, 1));
        // By 6 dB: the kept pair's report, then a new sweep that finds pair 0.
        let gone = [-50.0, -51.0];
        let d = keep.decide(&measurement(&gone, &[0.0; 2], 0.0), 3.0);
        assert_eq!((d.chosen, d.measured), (0, 3));
    }
}
