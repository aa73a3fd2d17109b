//! Path records kept from report to report: a long-running tracer (`beamtrace serve`, Python's
//! `trace_many`) reports every answer into the records of the previous one, refilling their
//! vectors and names instead of allocating and freeing six vectors and a name per
//! interaction for every path (a third of a serve answer's allocations; docs/performance.md).

use crate::{PathReport, RadioOptions, ReportError, Scratch, describe_into, gain, unfolded_length};
use bt_geom::Real;
use bt_scene::Scene;
use bt_solve::FoundPath;
use bt_solve::partner::{Partner, half_of_work};
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
    /// The partner's half of a split report ([`Records::report_halves`]): its surfaces'
    /// responses and buffers, kept as the caller's are.
    second: (Option<(bt_scene::RadioKey, gain::Known)>, Scratch),
}

/// Paths a report splits over a [`Partner`] from: below, the offer costs more than the half.
const SPLIT_FROM: usize = 8;

/// A path's first keys in the ranking ([`rank_order`]) and its index among the paths, packed
/// into one integer ([`rank_key`]) whose order is theirs: its order (the top 32 bits), its
/// length as [`f64::total_cmp`] orders it (the next 64, [`total_order_bits`]), then the index
/// (the low 32), so that sorting the keys (all distinct) is a stable sort of the paths by
/// (order, length). One integer compares in a few instructions where the triple took a
/// branch a field.
type RankKey = u128;

/// The [`RankKey`] of a path of `order` interactions, `length_m` long, at `index` among the
/// paths. An order or an index is far below 2^32 (a path or a report that large would not
/// fit in memory); both are clamped there all the same.
fn rank_key(order: usize, length_m: Real, index: usize) -> RankKey {
    let clamp = |n: usize| u128::from(u32::try_from(n).unwrap_or(u32::MAX));
    // `total_order_bits`' signed order as unsigned: the sign bit flipped.
    let length = (total_order_bits(length_m) as u64) ^ (1 << 63);
    (clamp(order) << 96) | (u128::from(length) << 32) | clamp(index)
}

/// The order of a [`RankKey`]'s path.
fn key_order(key: RankKey) -> usize {
    (key >> 96) as usize
}

/// The length (m) of a [`RankKey`]'s path, the same bits it was made of ([`total_order_bits`]
/// is its own inverse).
fn key_length(key: RankKey) -> Real {
    let length = ((key >> 32) as u64) ^ (1 << 63);
    Real::from_bits(total_order_bits(Real::from_bits(length)) as u64)
}

/// The index among the paths of a [`RankKey`]'s path.
fn key_index(key: RankKey) -> usize {
    (key as u32) as usize
}

/// A [`RankKey`]'s order and length, the part two paths tie on before the rest of the
/// ranking decides.
fn key_run(key: RankKey) -> u128 {
    key >> 32
}

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
        self.report_halves(scene, paths, radio, None, |_| (), |_| ())?;
        Ok(self.paths())
    }

    /// [`Records::report`] in two halves of the ranked records, the second on `partner`
    /// ([`Partner::join`]) when there is one and enough paths: each half is described and
    /// ranked, then handed to its own closure on the same thread (`mine` the first half's
    /// records, `theirs` the second's, empty without a partner), which may write them out
    /// while they are in that core's cache. The records are those of [`Records::report`]
    /// ([`Records::paths`] after the call): the halves split between runs of paths of the same
    /// order and length, the only records the ranking compares.
    pub fn report_halves<A, B, RA, RB>(
        &mut self,
        scene: &Scene,
        paths: &[FoundPath],
        radio: &RadioOptions,
        partner: Option<&Partner>,
        mine: A,
        theirs: B,
    ) -> Result<(RA, RB), ReportError>
    where
        A: FnOnce(&[PathReport]) -> RA,
        B: FnOnce(&[PathReport]) -> RB + Send,
        RB: Send,
    {
        let mut responses = gain::Responses::with_known(scene, known(&mut self.responses, scene));
        self.rank_keys(scene, paths)?;
        let n = paths.len();
        let partner = partner.filter(|_| n >= SPLIT_FROM);
        let k = partner.map_or(n, |_| halfway(&self.keys));
        let (keys, their_keys) = self.keys.split_at(k);
        let (records, their_records) = self.records[..n].split_at_mut(k);
        let (their_known, their_scratch) = &mut self.second;
        let scratch = &mut self.scratch;
        let first = |responses: &mut gain::Responses<'_>| {
            describe_ranked(responses, scratch, keys, records, paths, radio)?;
            rank_ties(keys, records, 0);
            Ok(mine(records))
        };
        let second = || {
            let known = known(their_known, scene);
            let mut responses = gain::Responses::with_known(scene, known);
            let keys = their_keys;
            describe_ranked(
                &mut responses,
                their_scratch,
                keys,
                their_records,
                paths,
                radio,
            )?;
            *their_known = Some((scene.radio_key(), responses.into_known()));
            rank_ties(keys, their_records, k);
            Ok(theirs(their_records))
        };
        let (a, b) = match partner {
            Some(partner) => partner.join(|| first(&mut responses), second),
            None => (first(&mut responses), second()),
        };
        let (a, b) = match (a, b) {
            (Ok(a), Ok(b)) => (a, b),
            // The error a report in the paths' order meets first.
            (Err(e), _) | (_, Err(e)) => {
                return Err(first_error(&mut responses, paths, radio).unwrap_or(e));
            }
        };
        self.responses = Some((scene.radio_key(), responses.into_known()));
        self.len = n;
        self.records.truncate(self.len + SPARE_RECORDS);
        Ok((a, b))
    }

    /// The ranking's keys of `paths` in `keys`, sorted, and records enough for them.
    fn rank_keys(&mut self, scene: &Scene, paths: &[FoundPath]) -> Result<(), ReportError> {
        self.len = 0;
        self.keys.clear();
        if !paths.is_empty() {
            let bt_scene::Endpoints { tx, rx } = scene.terminals()?;
            self.keys
                .extend(paths.iter().enumerate().map(|(index, path)| {
                    let length_m = unfolded_length(tx, &path.points, rx);
                    rank_key(path.points.len(), length_m, index)
                }));
        }
        self.keys.sort_unstable();
        if self.records.len() < paths.len() {
            self.records.resize_with(paths.len(), PathReport::blank);
        }
        Ok(())
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
}

/// Finish the ranking of records placed by their order and length (`keys`, aligned with
/// them): each run of records of the same order and length sorted by [`rank_order`] (stable,
/// so equal records keep the paths' order), and the records numbered from `before + 1` (the
/// records ranked before them: a second half's, [`Records::report_halves`]).
fn rank_ties(keys: &[RankKey], records: &mut [PathReport], before: usize) {
    let mut start = 0;
    while start < records.len() {
        let first = key_run(keys[start]);
        let run = keys[start..]
            .iter()
            .take_while(|&&k| key_run(k) == first)
            .count();
        if run > 1 {
            records[start..start + run].sort_by(rank_order);
        }
        start += run;
    }
    for (i, r) in records.iter_mut().enumerate() {
        r.rank = before + i + 1;
    }
}

/// The surfaces' responses kept in `kept` when they were looked up in a scene of `scene`'s
/// radio key (taken out of `kept`), else none.
fn known(kept: &mut Option<(bt_scene::RadioKey, gain::Known)>, scene: &Scene) -> gain::Known {
    match kept.take() {
        Some((key, known)) if key.matches(scene) => known,
        _ => Vec::new(),
    }
}

/// Where ranked `keys` split into the caller's and the partner's half
/// ([`Records::report_halves`]): half of the work ([`bt_solve::partner::half_of_work`]), a
/// path's description costing about one unit and one more for each interaction (its order,
/// [`key_order`]), moved on to fall between runs of the same order and length. The caller
/// once took 55 % of the work, to make up for a partner slowed by the allocator; timed per
/// half over 3,000 serve answers after that was mended, the caller's 55 % took 40-43 µs and
/// the partner's 45 % 32-34 µs, the same time per percent of the work (docs/performance.md,
/// session 9).
fn halfway(keys: &[RankKey]) -> usize {
    let mut k = half_of_work(keys.len(), |i| key_order(keys[i]) + 1);
    while k > 0 && k < keys.len() && key_run(keys[k]) == key_run(keys[k - 1]) {
        k += 1;
    }
    k
}

/// Describe the paths of `keys` (ranked, [`RankKey`]) into `records`, one each, in order.
fn describe_ranked(
    responses: &mut gain::Responses<'_>,
    scratch: &mut Scratch,
    keys: &[RankKey],
    records: &mut [PathReport],
    paths: &[FoundPath],
    radio: &RadioOptions,
) -> Result<(), ReportError> {
    for (&key, record) in keys.iter().zip(records) {
        let (path, length_m) = (&paths[key_index(key)], key_length(key));
        describe_into(responses, scratch, path, radio, record, Some(length_m))?;
    }
    Ok(())
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
    paths.iter().find_map(|path| {
        describe_into(responses, &mut scratch, path, radio, &mut record, None).err()
    })
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
        let partner = Partner::new(std::time::Duration::from_millis(5)).unwrap();
        let (mut ties, mut split_ties) = (0, 0);
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
                let expected = reference(&moved, &paths, &radio);
                let ranked = records.report(&moved, &paths, &radio).unwrap();
                assert_eq!(ranked, expected.as_slice(), "at {rx}");
                // In halves, the second on a partner: the same records, and each closure
                // is handed its half of them, in order.
                let (first, second) = records
                    .report_halves(
                        &moved,
                        &paths,
                        &radio,
                        Some(&partner),
                        |a| a.to_vec(),
                        |b| b.to_vec(),
                    )
                    .unwrap();
                assert_eq!(records.paths(), expected.as_slice(), "halves at {rx}");
                assert_eq!([first.as_slice(), &second].concat(), expected, "at {rx}");
                assert!(
                    !first.is_empty() && !second.is_empty(),
                    "{} paths",
                    paths.len()
                );
                split_ties += usize::from(
                    first.last().map(|r| (r.order, r.length_m))
                        == second.first().map(|r| (r.order, r.length_m)),
                );
            }
        }
        assert!(ties > 10, "{ties} paths moved to a parallel surface");
        assert_eq!(split_ties, 0, "a run of ties split between the halves");
    }

    /// The packed keys give back their order, length (the same bits) and index, and sort as
    /// the triples (order, length by [`f64::total_cmp`], index) do: lengths of every kind
    /// (zeros of both signs, subnormal, infinite, NaN, negative, drawn bits) at orders 0 to 4.
    #[test]
    fn packed_keys_sort_as_their_triples() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut draw = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let special = [
            0.0,
            -0.0,
            5e-324,
            1.5,
            -1.5,
            Real::INFINITY,
            -Real::INFINITY,
        ];
        let mut triples: Vec<(usize, Real, usize)> = Vec::new();
        for index in 0..3000 {
            let length = match index % 3 {
                0 => special[(draw() % special.len() as u64) as usize],
                1 => Real::from_bits(draw()),
                _ => (draw() % 1000) as Real / 8.0,
            };
            let length = if index % 97 == 0 { Real::NAN } else { length };
            triples.push(((draw() % 5) as usize, length, index));
        }
        let mut keys: Vec<RankKey> = (triples.iter())
            .map(|&(order, length, index)| rank_key(order, length, index))
            .collect();
        for (&key, &(order, length, index)) in keys.iter().zip(&triples) {
            assert_eq!(key_order(key), order);
            assert_eq!(key_length(key).to_bits(), length.to_bits());
            assert_eq!(key_index(key), index);
        }
        keys.sort_unstable();
        triples.sort_by(|a, b| {
            (a.0.cmp(&b.0))
                .then(a.1.total_cmp(&b.1))
                .then(a.2.cmp(&b.2))
        });
        let sorted: Vec<usize> = keys.iter().map(|&k| key_index(k)).collect();
        let expected: Vec<usize> = triples.iter().map(|t| t.2).collect();
        assert_eq!(sorted, expected);
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
