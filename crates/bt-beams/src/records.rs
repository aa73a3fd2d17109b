//! Path records kept from report to report: a long-running tracer (`beamtrace serve`, Python's
//! `trace_many`) reports every answer into the records of the previous one, refilling their
//! vectors and names instead of allocating and freeing six vectors and a name per
//! interaction for every path (a third of a serve answer's allocations; docs/performance.md).

use crate::{PathReport, RadioOptions, ReportError, Scratch, describe_into, gain, unfolded_length};
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
    /// The ranking's first keys of each path and its index ([`RankKey`]), kept too.
    keys: Vec<RankKey>,
    /// The surfaces' responses of the last report and the key of its scene: the next report
    /// in a scene of the same surfaces, materials and frequency starts from them (a material
    /// looked up by name and its model evaluated at the frequency, about 14 surfaces a room's
    /// report; docs/performance.md).
    responses: Option<(bt_scene::RadioKey, gain::Known)>,
    /// The buffers each path is described with, kept too.
    scratch: Scratch,
}

/// A path's first keys in the ranking ([`rank_order`]) and its index among the paths: its
/// order, its length as [`f64::total_cmp`] orders it ([`total_order_bits`]), then the index,
/// so that sorting the keys (all distinct) is a stable sort of the paths by (order, length).
type RankKey = (usize, i64, usize);

impl Records {
    /// [`crate::report`] of `paths` (found in `scene`) into these records: the same records,
    /// in the same order, reusing the memory of the previous report's.
    ///
    /// The paths are ranked by their order and length (computed as their records compute
    /// them) before they are described, and each is described into its ranked place: no
    /// record is compared or moved, except among paths of the same order and length, which
    /// the rest of the ranking then orders (a stable sort of those records alone).
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
        let scratch = &mut self.scratch;
        self.len = 0;
        self.keys.clear();
        if !paths.is_empty() {
            let bt_scene::Endpoints { tx, rx } = scene.terminals()?;
            self.keys
                .extend(paths.iter().enumerate().map(|(index, path)| {
                    let length_m = unfolded_length(tx, &path.points, rx);
                    (path.points.len(), total_order_bits(length_m), index)
                }));
        }
        self.keys.sort_unstable();
        if self.records.len() < paths.len() {
            self.records.resize_with(paths.len(), PathReport::blank);
        }
        for (&(_, _, index), record) in self.keys.iter().zip(&mut self.records) {
            let described = describe_into(&mut responses, scratch, &paths[index], radio, record);
            if let Err(e) = described {
                // The error a report in the paths' order meets first.
                return Err(first_error(&mut responses, paths, radio).unwrap_or(e));
            }
        }
        self.responses = Some((scene.radio_key(), responses.into_known()));
        self.len = paths.len();
        self.records.truncate(self.len + SPARE_RECORDS);
        self.rank_ties();
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

    /// Finish the ranking of records placed by their order and length (`keys`, aligned with
    /// them): each run of records of the same order and length sorted by [`rank_order`]
    /// (stable, so equal records keep the paths' order), and the records numbered from 1.
    fn rank_ties(&mut self) {
        let records = &mut self.records[..self.len];
        let mut start = 0;
        while start < records.len() {
            let first = &self.keys[start];
            let run = self.keys[start..]
                .iter()
                .take_while(|k| (k.0, k.1) == (first.0, first.1))
                .count();
            if run > 1 {
                records[start..start + run].sort_by(rank_order);
            }
            start += run;
        }
        for (i, r) in records.iter_mut().enumerate() {
            r.rank = i + 1;
        }
    }
}

/// `x`'s bits as a signed integer whose order is [`f64::total_cmp`]'s (its own definition):
/// negative numbers' magnitude bits flipped.
fn total_order_bits(x: Real) -> i64 {
    let bits = x.to_bits() as i64;
    bits ^ ((((bits >> 63) as u64) >> 1) as i64)
}

/// The first error of describing `paths` in their order, if any.
fn first_error(
    responses: &mut gain::Responses<'_>,
    paths: &[FoundPath],
    radio: &RadioOptions,
) -> Option<ReportError> {
    let (mut scratch, mut record) = (Scratch::default(), PathReport::blank());
    paths
        .iter()
        .find_map(|path| describe_into(responses, &mut scratch, path, radio, &mut record).err())
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

#[cfg(test)]
mod tests {
    use super::*;
    use bt_geom::Vec3;
    use bt_scene::SurfaceId;
    use bt_solve::Tracer;
    use bt_solve::settings::SolveSettings;

    /// The ranking as it was: every path described in the paths' order, the records sorted
    /// by [`rank_order`] (stable) and numbered.
    fn reference(scene: &Scene, paths: &[FoundPath], radio: &RadioOptions) -> Vec<PathReport> {
        let mut records: Vec<PathReport> = (paths.iter())
            .map(|p| crate::describe(scene, p, radio).unwrap())
            .collect();
        records.sort_by(rank_order);
        for (i, r) in records.iter_mut().enumerate() {
            r.rank = i + 1;
        }
        records
    }

    /// Paths ranked before they are described are ranked as the records sort: the living
    /// room's paths at three receivers, and the same paths with ties made on purpose (each
    /// path again, tagged by its `iterations` to tell the copies apart, which the ranking
    /// ignores, so the paths' order must decide; and a reflection moved to another surface
    /// parallel to it, the same order, length and angles, so the surface ids must decide),
    /// in three orders.
    #[test]
    fn paths_ranked_before_they_are_described_rank_as_the_records() {
        let options = bt_import::LoadOptions::default();
        let dynamic = bt_import::load_dynamic("builtin:living-room", &options, &mut |_| {});
        let scene = dynamic.unwrap().scene.step(0).clone();
        let tx = scene.tx_world().unwrap();
        let settings = SolveSettings::default();
        let mut tracer = Tracer::new(scene.clone(), settings.trace_options(&scene).unwrap());
        let radio = RadioOptions::default();
        let mut records = Records::default();
        let mut ties = 0;
        for rx in [[1.0, 1.0, 1.0], [2.3, 2.1, 0.72], [4.1, 3.3, 1.9]].map(Vec3::from_array) {
            let found = tracer.trace(tx, rx).unwrap().result.paths;
            let moved = tracer.scene().with_terminals(tx, rx).unwrap();
            let mut paths = found.clone();
            for (k, path) in found.iter().enumerate() {
                let mut copy = path.clone();
                copy.iterations = Some(k as u32);
                paths.push(copy.clone());
                if let Some(other) = parallel_surface(&moved, &copy) {
                    copy.surfaces[0] = other;
                    paths.push(copy);
                    ties += 1;
                }
            }
            let reversed: Vec<FoundPath> = paths.iter().rev().cloned().collect();
            let mut interleaved = paths.clone();
            interleaved.sort_by_key(|p| p.surfaces.len() % 2);
            for paths in [found, paths, reversed, interleaved] {
                let ranked = records.report(&moved, &paths, &radio).unwrap();
                assert_eq!(
                    ranked,
                    reference(&moved, &paths, &radio).as_slice(),
                    "at {rx}"
                );
            }
        }
        assert!(ties > 10, "{ties} paths moved to a parallel surface");
    }

    /// Another surface of `scene` parallel to `path`'s first reflection's (the same normal,
    /// either sign), when the path's first interaction is that reflection.
    fn parallel_surface(scene: &Scene, path: &FoundPath) -> Option<SurfaceId> {
        let first = *path.surfaces.first()?;
        if !path.diffractions.is_empty() || !path.crossings.is_empty() {
            return None;
        }
        let normal = scene.surface(first).polygon.plane().normal;
        (0..scene.surfaces().len() as u32)
            .map(SurfaceId)
            .find(|&id| {
                let other = scene.surface(id).polygon.plane().normal;
                id != first && other.cross(normal).length() == 0.0
            })
    }
}
