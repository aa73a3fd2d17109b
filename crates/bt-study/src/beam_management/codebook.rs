//! The beams of the study: the narrow DFT codebooks of both arrays (`bt_channel`'s), a wide
//! codebook for the hierarchical sweep, and the received power of every beam pair from a
//! set of paths.
//!
//! A pair index is `tx_beam · rx_beams + rx_beam` over the narrow codebooks.

use bt_beams::PathReport;
use bt_channel::Complex64;
use bt_channel::codebook::{Array, Beam, PathDirections, beam_pairs};
use bt_geom::Real;
use std::f64::consts::PI;

/// The wide beams of one array and, for each, the narrow beams it covers.
#[derive(Debug, Clone)]
pub struct WideBook {
    /// Wide beams: a centred sub-array of the full array steered at the centre of its group.
    pub beams: Vec<Beam>,
    /// For each wide beam, the narrow beam indices it covers (a partition of the codebook).
    pub groups: Vec<Vec<usize>>,
}

/// Spatial frequencies k/n wrapped into [−1/2, 1/2), cycles per element (as
/// [`Array::dft_codebook`]).
fn frequency(k: usize, n: usize) -> Real {
    let u = k as Real / n as Real;
    if u >= 0.5 { u - 1.0 } else { u }
}

/// Split the `n` DFT frequencies of one axis into `wide` groups of neighbours (in increasing
/// frequency); returns for each group its member indices and its mean frequency.
fn axis_groups(n: usize, wide: usize) -> Vec<(Vec<usize>, Real)> {
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| frequency(a, n).total_cmp(&frequency(b, n)));
    let per = n.div_ceil(wide);
    order
        .chunks(per)
        .map(|members| {
            let mean =
                members.iter().map(|&k| frequency(k, n)).sum::<Real>() / members.len() as Real;
            (members.to_vec(), mean)
        })
        .collect()
}

/// The wide codebook of `array` with `factor` narrow beams per wide beam along each axis
/// (clamped to the axis length): a wide beam is the centred sub-array of
/// ⌈columns/factor⌉ × ⌈rows/factor⌉ elements (the others off), unit-norm, steered at the mean
/// spatial frequency of the narrow beams it covers. Hierarchical codebooks in NR are built the
/// same way (fewer active elements give a wider main lobe).
pub fn wide_book(array: &Array, factor: usize) -> WideBook {
    let factor = factor.max(1);
    let (cols_wide, rows_wide) = (
        array.columns.div_ceil(factor.min(array.columns)),
        array.rows.div_ceil(factor.min(array.rows)),
    );
    let col_groups = axis_groups(array.columns, cols_wide);
    let row_groups = axis_groups(array.rows, rows_wide);
    let sub = |n: usize, groups: usize| n.div_ceil(n.div_ceil(groups)).max(1);
    // Active sub-array: as many elements per axis as there are wide beams along it.
    let (sub_cols, sub_rows) = (
        sub(array.columns, col_groups.len()),
        sub(array.rows, row_groups.len()),
    );
    let active = |index: usize, n: usize, m: usize| {
        let first = (n - m) / 2;
        (first..first + m).contains(&index)
    };
    let norm = ((sub_cols * sub_rows) as Real).sqrt();
    let mut beams = Vec::new();
    let mut groups = Vec::new();
    for (rows, w) in &row_groups {
        for (cols, u) in &col_groups {
            let weights = (0..array.rows)
                .flat_map(|r| (0..array.columns).map(move |c| (r, c)))
                .map(|(r, c)| {
                    if !(active(r, array.rows, sub_rows) && active(c, array.columns, sub_cols)) {
                        return Complex64::new(0.0, 0.0);
                    }
                    let cc = c as Real - (array.columns as Real - 1.0) / 2.0;
                    let rc = r as Real - (array.rows as Real - 1.0) / 2.0;
                    Complex64::from_polar(1.0 / norm, 2.0 * PI * (cc * u + rc * w))
                })
                .collect();
            beams.push(Beam {
                index: beams.len(),
                weights,
                direction: None,
            });
            groups.push(
                rows.iter()
                    .flat_map(|&l| cols.iter().map(move |&k| l * array.columns + k))
                    .collect(),
            );
        }
    }
    WideBook { beams, groups }
}

/// The paths as the codebooks see them.
pub fn directions(paths: &[PathReport]) -> Vec<PathDirections> {
    bt_beams::taps(paths)
        .into_iter()
        .zip(paths)
        .map(|(tap, p)| PathDirections {
            tap,
            departure: p.departure,
            arrival: p.arrival,
        })
        .collect()
}

/// Received power of every pair of `tx_beams` × `rx_beams` (row-major, see the module), dBm:
/// `tx_power_dbm` + 20·log10|h| at the carrier; `−∞` where nothing arrives (no paths).
pub fn pair_power_dbm(
    paths: &[PathDirections],
    tx: (&Array, &[Beam]),
    rx: (&Array, &[Beam]),
    carrier_hz: Real,
    tx_power_dbm: Real,
) -> Result<Vec<Real>, bt_channel::ChannelError> {
    let h = beam_pairs(paths, tx, rx, carrier_hz)?;
    Ok(h.iter()
        .flatten()
        .map(|h| {
            let p = h.norm_sqr();
            if p > 0.0 {
                tx_power_dbm + 10.0 * p.log10()
            } else {
                Real::NEG_INFINITY
            }
        })
        .collect())
}

/// Pair indices by `power` (dBm), strongest first; ties by index (a total, stable order).
pub fn ranking(power: &[Real]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..power.len()).collect();
    order.sort_by(|&a, &b| power[b].total_cmp(&power[a]).then(a.cmp(&b)));
    order
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_channel::Orientation;

    #[test]
    fn wide_groups_partition_the_narrow_codebook() {
        for (rows, cols, factor) in [(8, 8, 4), (2, 4, 2), (1, 8, 2), (2, 4, 8), (3, 5, 2)] {
            let array = Array::new(rows, cols, 0.5, Orientation::default()).unwrap();
            let book = wide_book(&array, factor);
            let mut all: Vec<usize> = book.groups.iter().flatten().copied().collect();
            all.sort_unstable();
            assert_eq!(
                all,
                (0..rows * cols).collect::<Vec<_>>(),
                "{rows}x{cols}/{factor}"
            );
            for b in &book.beams {
                let norm: Real = b.weights.iter().map(|w| w.norm_sqr()).sum();
                assert!((norm - 1.0).abs() < 1e-12);
            }
        }
        let upa = Array::new(8, 8, 0.5, Orientation::default()).unwrap();
        let book = wide_book(&upa, 4);
        assert_eq!((book.beams.len(), book.groups[0].len()), (4, 16));
    }

    #[test]
    fn a_wide_beam_serves_its_narrow_beams_best() {
        // Towards each narrow beam's own direction, the wide beam covering it has the largest
        // gain of all wide beams (the hierarchy sends stage 2 to the right group).
        let array = Array::new(8, 8, 0.5, Orientation::from_degrees(30.0, 10.0, 0.0)).unwrap();
        let narrow = array.dft_codebook();
        let book = wide_book(&array, 4);
        let gain = |b: &Beam, a: &[Complex64]| {
            b.weights
                .iter()
                .zip(a)
                .map(|(w, x)| w.conj() * x)
                .sum::<Complex64>()
                .norm()
        };
        let mut checked = 0;
        for beam in &narrow {
            let Some(d) = beam.direction else { continue };
            let a = array.response(d);
            let best = (0..book.beams.len())
                .max_by(|&x, &y| gain(&book.beams[x], &a).total_cmp(&gain(&book.beams[y], &a)))
                .unwrap();
            assert!(
                book.groups[best].contains(&beam.index),
                "beam {}",
                beam.index
            );
            checked += 1;
        }
        assert!(checked > 40, "{checked}");
    }

    #[test]
    fn ranking_is_strongest_first_with_ties_by_index() {
        let p = [1.0, 3.0, Real::NEG_INFINITY, 3.0, 2.0];
        assert_eq!(ranking(&p), vec![1, 3, 4, 0, 2]);
    }
}
