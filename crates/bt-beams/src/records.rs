//! Path records kept from report to report: a long-running tracer (`beamtrace serve`, Python's
//! `trace_many`) reports every answer into the records of the previous one, refilling their
//! vectors and names instead of allocating and freeing six vectors and a name per
//! interaction for every path (a third of a serve answer's allocations; docs/performance.md).

use crate::{PathReport, RadioOptions, ReportError, Scratch, describe_into, gain};
use bt_geom::Real;
use bt_scene::Scene;
use bt_solve::FoundPath;
use std::cmp::Ordering;

/// Records a report beyond the current one's keeps for the next (a few times a room's paths):
/// one unusually large report does not hold its memory for ever.
const SPARE_RECORDS: usize = 1024;

/// The records of the last report ([`Records::report`]), and their memory for the next.
#[derive(Debug, Default)]
pub struct Records {
    /// The records; the first `len` are the last report's, the rest spares.
    records: Vec<PathReport>,
    len: usize,
    /// The ranking's permutation and its marks, kept too.
    order: Vec<usize>,
    placed: Vec<bool>,
    /// The surfaces' responses of the last report and the key of its scene: the next report
    /// in a scene of the same surfaces, materials and frequency starts from them (a material
    /// looked up by name and its model evaluated at the frequency, about 14 surfaces a room's
    /// report; docs/performance.md).
    responses: Option<(bt_scene::RadioKey, gain::Known)>,
}

impl Records {
    /// [`crate::report`] of `paths` (found in `scene`) into these records: the same records,
    /// in the same order, reusing the memory of the previous report's.
    pub fn report(
        &mut self,
        scene: &Scene,
        paths: &[FoundPath],
        radio: &RadioOptions,
    ) -> Result<&[PathReport], ReportError> {
        let known = match self.responses.take() {
            Some((key, known)) if key.matches(scene) => known,
            _ => Vec::new(),
        };
        let mut responses = gain::Responses::with_known(scene, known);
        let mut scratch = Scratch::default();
        self.len = 0;
        if self.records.len() < paths.len() {
            self.records.resize_with(paths.len(), PathReport::blank);
        }
        for (path, record) in paths.iter().zip(&mut self.records) {
            describe_into(&mut responses, &mut scratch, path, radio, record)?;
        }
        self.responses = Some((scene.radio_key(), responses.into_known()));
        self.len = paths.len();
        self.records.truncate(self.len + SPARE_RECORDS);
        self.rank();
        Ok(self.paths())
    }

    /// The last report's records, ranked.
    pub fn paths(&self) -> &[PathReport] {
        &self.records[..self.len]
    }

    /// The last report's records as a vector (the spares dropped).
    pub fn into_paths(mut self) -> Vec<PathReport> {
        self.records.truncate(self.len);
        self.records
    }

    /// Rank the records: sort their indices by [`rank_order`], move each record once into its
    /// place (cycle by cycle), and number them from 1.
    fn rank(&mut self) {
        let records = &mut self.records[..self.len];
        self.order.clear();
        self.order.extend(0..records.len());
        self.order
            .sort_by(|&a, &b| rank_order(&records[a], &records[b]));
        // Place k takes the record at order[k].
        self.placed.clear();
        self.placed.resize(records.len(), false);
        for start in 0..records.len() {
            let mut k = start;
            while !self.placed[k] {
                self.placed[k] = true;
                let next = self.order[k];
                if next == start {
                    break;
                }
                records.swap(k, next);
                k = next;
            }
        }
        for (i, r) in records.iter_mut().enumerate() {
            r.rank = i + 1;
        }
    }
}

/// The ranking: by order, then length, then the largest incidence angle (closer to normal
/// first), then surface ids, then the diffractions' edges; each tie-break computed only when
/// the keys before it tie.
fn rank_order(a: &PathReport, b: &PathReport) -> Ordering {
    let key = |r: &PathReport| {
        r.incidence_deg
            .iter()
            .flatten()
            .copied()
            .fold(0.0, Real::max)
    };
    a.order
        .cmp(&b.order)
        .then_with(|| a.length_m.total_cmp(&b.length_m))
        .then_with(|| key(a).total_cmp(&key(b)))
        .then_with(|| a.surface_ids.cmp(&b.surface_ids))
        .then_with(|| {
            let edges = |r: &PathReport| -> Vec<(usize, bt_scene::EdgeId)> {
                r.diffractions.iter().map(|d| (d.index, d.edge)).collect()
            };
            edges(a).cmp(&edges(b))
        })
}
