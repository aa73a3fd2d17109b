//! Antenna arrays (ULA/UPA), their responses towards a direction, DFT codebooks and the
//! received power of every beam pair from the paths. `docs/channel.md`.

use crate::ChannelError;
use crate::antenna::Orientation;
use crate::response::Tap;
use bt_geom::{Real, Vec3};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Beam pairs × paths above which [`beam_pairs`] refuses to work (a stated budget).
pub const MAX_PAIR_PATH_PRODUCTS: u64 = 2_000_000_000;

/// Budget on the beam pairs of a sweep (TX beams × RX beams): each pair is a ranked record
/// (~100 B) and a JSON object (~300 B), so the default of 1,000,000 pairs (two 32 × 32 UPAs)
/// holds a sweep under ~0.5 GB; two 64 × 64 arrays (16.7 M pairs) are refused before the
/// codebooks are built.
pub const MAX_BEAM_PAIRS: bt_geom::Budget =
    bt_geom::Budget::new("beam pairs", "--max-beam-pairs", 1_000_000);

/// Refuse a sweep of `tx` × `rx` beams over `max_pairs` ([`MAX_BEAM_PAIRS`] with another
/// limit), before any codebook is built.
pub fn check_beam_pairs(tx: &Array, rx: &Array, max_pairs: u64) -> Result<(), ChannelError> {
    let pairs = (tx.len() as u64).saturating_mul(rx.len() as u64);
    Ok(MAX_BEAM_PAIRS.with_limit(max_pairs).check(pairs)?)
}

/// A uniform planar array in its local y-z plane (boresight local +x, as the element pattern):
/// `columns` elements along local y, `rows` along local z, `spacing_wavelengths` apart. A ULA
/// is one row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Array {
    /// Elements along local z (1 for a horizontal ULA).
    pub rows: usize,
    /// Elements along local y.
    pub columns: usize,
    /// Element spacing in wavelengths (0.5 is the usual choice).
    pub spacing_wavelengths: Real,
    /// Orientation in the world frame (shared with the element antenna).
    pub orientation: Orientation,
}

/// One beam of a codebook.
#[derive(Debug, Clone, PartialEq)]
pub struct Beam {
    /// Index in the codebook (column-major over the spatial frequencies).
    pub index: usize,
    /// Unit-norm weights v (the array gain towards u is v^H·a(u)).
    pub weights: Vec<Complex64>,
    /// World direction of the main lobe, or `None` when its spatial frequency lies outside the
    /// visible region (spacing above λ/2).
    pub direction: Option<Vec3>,
}

impl Array {
    /// Check the array's parameters.
    pub fn new(
        rows: usize,
        columns: usize,
        spacing_wavelengths: Real,
        orientation: Orientation,
    ) -> Result<Array, ChannelError> {
        if rows == 0 || columns == 0 || rows.saturating_mul(columns) > 4096 {
            return Err(ChannelError::Invalid {
                field: "array",
                message: format!(
                    "{rows} × {columns} elements: need at least 1 × 1 and at most 4096 elements"
                ),
            });
        }
        if !(spacing_wavelengths.is_finite() && spacing_wavelengths > 0.0) {
            return Err(ChannelError::Invalid {
                field: "spacing",
                message: format!(
                    "must be a positive number of wavelengths, got {spacing_wavelengths}"
                ),
            });
        }
        Ok(Array {
            rows,
            columns,
            spacing_wavelengths,
            orientation,
        })
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.rows * self.columns
    }

    /// Whether the array is empty (never, once constructed).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Element offsets from the array centre in wavelengths, local frame, row-major
    /// (index = row·columns + column).
    fn local_offsets(&self) -> impl Iterator<Item = (Real, Real)> + '_ {
        let centre = |n: usize| (n as Real - 1.0) / 2.0;
        (0..self.rows).flat_map(move |r| {
            (0..self.columns).map(move |c| {
                (
                    (c as Real - centre(self.columns)) * self.spacing_wavelengths,
                    (r as Real - centre(self.rows)) * self.spacing_wavelengths,
                )
            })
        })
    }

    /// Array response a(u): a_n = e^{j2π·(p_n/λ)·u} for the world unit direction `u`
    /// (departure direction at a transmitter, the direction the wave comes from at a
    /// receiver); p_n are the element positions relative to the array centre.
    pub fn response(&self, direction: Vec3) -> Vec<Complex64> {
        let local = self.orientation.matrix().transpose() * direction;
        self.local_offsets()
            .map(|(y, z)| Complex64::from_polar(1.0, 2.0 * PI * (y * local.y + z * local.z)))
            .collect()
    }

    /// The DFT codebook: columns × rows beams with spatial frequencies k/N wrapped into
    /// [−1/2, 1/2) cycles per element along each axis; weights v[r, c] =
    /// e^{j2π(c'·u_k + r'·w_l)}/√(N·M) with c', r' the centred element indices.
    pub fn dft_codebook(&self) -> Vec<Beam> {
        let wrap = |k: usize, n: usize| {
            let u = k as Real / n as Real;
            if u >= 0.5 { u - 1.0 } else { u }
        };
        let norm = (self.len() as Real).sqrt();
        let mut beams = Vec::with_capacity(self.len());
        for l in 0..self.rows {
            for k in 0..self.columns {
                let (u, w) = (wrap(k, self.columns), wrap(l, self.rows));
                let d = self.spacing_wavelengths;
                let weights = self
                    .local_offsets()
                    .map(|(y, z)| Complex64::from_polar(1.0 / norm, 2.0 * PI * (y * u + z * w) / d))
                    .collect();
                let (sy, sz) = (u / d, w / d);
                let direction = (sy * sy + sz * sz <= 1.0).then(|| {
                    let local = Vec3::new((1.0 - sy * sy - sz * sz).max(0.0).sqrt(), sy, sz);
                    self.orientation.matrix() * local
                });
                beams.push(Beam {
                    index: beams.len(),
                    weights,
                    direction,
                });
            }
        }
        beams
    }
}

/// v^H·a.
fn inner(v: &[Complex64], a: &[Complex64]) -> Complex64 {
    v.iter()
        .zip(a)
        .map(|(v, a)| v.conj() * a)
        .fold(Complex64::new(0.0, 0.0), |x, y| x + y)
}

/// A path as the codebook sees it: its tap and its world unit departure and arrival directions
/// (arrival = where the wave comes from).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathDirections {
    /// Gain and delay.
    pub tap: Tap,
    /// Unit departure direction at TX.
    pub departure: Vec3,
    /// Unit arrival direction at RX (towards the last interaction or TX).
    pub arrival: Vec3,
}

/// Per-path beamforming gains of every beam of a codebook: `[path][beam]` = v_b^H·a(u_path).
pub fn beam_gains(
    array: &Array,
    beams: &[Beam],
    directions: impl Iterator<Item = Vec3>,
) -> Vec<Vec<Complex64>> {
    directions
        .map(|u| {
            let a = array.response(u);
            beams.iter().map(|b| inner(&b.weights, &a)).collect()
        })
        .collect()
}

/// Narrowband channel of every beam pair at the carrier:
/// h(t, r) = Σ_p a_p·e^{−j2π·f_c·τ_p}·(v_r^H·a_RX(arrival_p))·(v_t^H·a_TX(departure_p)),
/// returned as `[tx_beam][rx_beam]`. The element pattern is already in a_p.
pub fn beam_pairs(
    paths: &[PathDirections],
    tx: (&Array, &[Beam]),
    rx: (&Array, &[Beam]),
    carrier_hz: Real,
) -> Result<Vec<Vec<Complex64>>, ChannelError> {
    let work = (tx.1.len() as u64)
        .saturating_mul(rx.1.len() as u64)
        .saturating_mul(paths.len().max(1) as u64);
    if work > MAX_PAIR_PATH_PRODUCTS {
        return Err(ChannelError::Invalid {
            field: "codebook",
            message: format!(
                "{} × {} beam pairs × {} paths exceeds the budget of {MAX_PAIR_PATH_PRODUCTS}",
                tx.1.len(),
                rx.1.len(),
                paths.len()
            ),
        });
    }
    let gt = beam_gains(tx.0, tx.1, paths.iter().map(|p| p.departure));
    let gr = beam_gains(rx.0, rx.1, paths.iter().map(|p| p.arrival));
    let coefficients: Vec<Complex64> = paths.iter().map(|p| p.tap.baseband(carrier_hz)).collect();
    Ok((0..tx.1.len())
        .map(|t| {
            (0..rx.1.len())
                .map(|r| {
                    coefficients
                        .iter()
                        .enumerate()
                        .map(|(p, c)| c * gt[p][t] * gr[p][r])
                        .fold(Complex64::new(0.0, 0.0), |x, y| x + y)
                })
                .collect()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ula(n: usize) -> Array {
        Array::new(1, n, 0.5, Orientation::default()).unwrap()
    }

    #[test]
    fn two_64_by_64_arrays_are_over_the_pair_budget() {
        let upa = Array::new(64, 64, 0.5, Orientation::default()).unwrap();
        let e = check_beam_pairs(&upa, &upa, MAX_BEAM_PAIRS.limit)
            .unwrap_err()
            .to_string();
        assert!(e.contains("16777216 beam pairs"), "{e}");
        assert!(e.contains("--max-beam-pairs"), "{e}");
        assert!(check_beam_pairs(&ula(8), &upa, MAX_BEAM_PAIRS.limit).is_ok());
    }

    #[test]
    fn a_beam_towards_a_direction_has_full_array_gain() {
        for array in [
            ula(8),
            Array::new(4, 4, 0.5, Orientation::from_degrees(30.0, 10.0, 0.0)).unwrap(),
        ] {
            let beams = array.dft_codebook();
            assert_eq!(beams.len(), array.len());
            for b in &beams {
                let norm: Real = b.weights.iter().map(|w| w.norm_sqr()).sum();
                assert!((norm - 1.0).abs() < 1e-12);
                if let Some(d) = b.direction {
                    // |v^H a(u)|² = N towards the beam's own direction.
                    let g = inner(&b.weights, &array.response(d)).norm_sqr();
                    assert!(
                        (g - array.len() as Real).abs() < 1e-9,
                        "beam {}: {g}",
                        b.index
                    );
                }
            }
        }
    }

    #[test]
    fn dft_beams_are_orthogonal() {
        let beams = Array::new(2, 4, 0.5, Orientation::default())
            .unwrap()
            .dft_codebook();
        for a in &beams {
            for b in &beams {
                let x = inner(&a.weights, &b.weights).norm();
                let expected = if a.index == b.index { 1.0 } else { 0.0 };
                assert!((x - expected).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn ula_beam_directions_are_arcsin_of_k_over_n_d() {
        // 4 elements, λ/2: spatial frequencies 0, 1/4, −1/2, −1/4 → sin φ = 0, 0.5, −1, −0.5.
        let beams = ula(4).dft_codebook();
        let sines: Vec<Real> = beams.iter().map(|b| b.direction.unwrap().y).collect();
        for (s, e) in sines.iter().zip([0.0, 0.5, -1.0, -0.5]) {
            assert!((s - e).abs() < 1e-12, "{sines:?}");
        }
    }

    #[test]
    fn the_best_pair_points_at_the_only_path() {
        let tx = ula(8);
        let rx = ula(8);
        let (bt, br) = (tx.dft_codebook(), rx.dft_codebook());
        // Departure along beam 1's direction, arrival along beam 6's.
        let path = PathDirections {
            tap: Tap {
                gain: Complex64::new(1e-3, 0.0),
                delay_s: 1e-8,
            },
            departure: bt[1].direction.unwrap(),
            arrival: br[6].direction.unwrap(),
        };
        let h = beam_pairs(&[path], (&tx, &bt), (&rx, &br), 28e9).unwrap();
        let best = (0..8)
            .flat_map(|t| (0..8).map(move |r| (t, r)))
            .max_by(|a, b| h[a.0][a.1].norm().total_cmp(&h[b.0][b.1].norm()))
            .unwrap();
        assert_eq!(best, (1, 6));
        // Full array gain: power N = 8 at each end, amplitude √8·√8 = 8.
        assert!((h[1][6].norm() - 1e-3 * 8.0).abs() < 1e-12);
    }

    #[test]
    fn bad_arrays_are_rejected() {
        assert!(Array::new(0, 4, 0.5, Orientation::default()).is_err());
        assert!(Array::new(1, 4, -0.5, Orientation::default()).is_err());
        assert!(Array::new(100, 100, 0.5, Orientation::default()).is_err());
    }
}
