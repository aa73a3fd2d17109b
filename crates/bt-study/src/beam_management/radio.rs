//! The radio side of a decision: the arrays, their codebooks, and the power of every beam pair
//! from a traced (or assumed) set of paths.

use super::codebook::{WideBook, directions, pair_power_dbm, wide_book};
use bt_beams::{Antenna, RadioOptions};
use bt_channel::codebook::{Array, Beam, PathDirections};
use bt_channel::response::Tap;
use bt_channel::{Complex64, Orientation, Pattern, Polarization, SPEED_OF_LIGHT};
use bt_geom::{Real, Vec3};
use bt_scene::Scene;
use bt_solve::FoundPath;
use std::f64::consts::PI;

/// Narrow beams per wide beam along each axis of the AP's array (8 × 8 → 2 × 2 wide beams).
pub const AP_WIDE_FACTOR: usize = 4;
/// Narrow beams per wide beam along each axis of the UE's array (2 × 4 → 1 × 2 wide beams).
pub const UE_WIDE_FACTOR: usize = 2;

/// The arrays and codebooks of a scenario.
#[derive(Debug, Clone)]
pub struct Radio {
    /// AP position, world frame, metres.
    pub ap: Vec3,
    /// The AP's array (its orientation is the AP's).
    pub ap_array: Array,
    /// The AP's narrow DFT codebook.
    pub ap_book: Vec<Beam>,
    /// The AP's wide codebook.
    pub ap_wide: WideBook,
    /// UE array rows × columns (its orientation follows the heading of each decision).
    pub ue_shape: (usize, usize),
    /// The UE's narrow codebook (weights do not depend on the orientation).
    pub ue_book: Vec<Beam>,
    /// The UE's wide codebook.
    pub ue_wide: WideBook,
    /// Carrier, Hz.
    pub carrier_hz: Real,
    /// Transmitted power per resource element, dBm.
    pub tx_power_dbm: Real,
    /// Highest order of the traces the reports describe (for the diffraction coefficient).
    pub max_order: usize,
}

impl Radio {
    /// The radio of an AP at `ap` with a `ap_shape` (rows, columns) array oriented
    /// `ap_orientation`, and a UE with a `ue_shape` array; half-wavelength spacing.
    pub fn new(
        ap: Vec3,
        ap_orientation: Orientation,
        ap_shape: (usize, usize),
        ue_shape: (usize, usize),
        carrier_hz: Real,
        tx_power_dbm: Real,
        max_order: usize,
    ) -> Result<Radio, bt_channel::ChannelError> {
        let ap_array = Array::new(ap_shape.0, ap_shape.1, 0.5, ap_orientation)?;
        let ue_array = Array::new(ue_shape.0, ue_shape.1, 0.5, Orientation::default())?;
        Ok(Radio {
            ap,
            ap_book: ap_array.dft_codebook(),
            ap_wide: wide_book(&ap_array, AP_WIDE_FACTOR),
            ap_array,
            ue_shape,
            ue_book: ue_array.dft_codebook(),
            ue_wide: wide_book(&ue_array, UE_WIDE_FACTOR),
            carrier_hz,
            tx_power_dbm,
            max_order,
        })
    }

    /// Narrow beam pairs (AP beams × UE beams).
    pub fn pairs(&self) -> usize {
        self.ap_book.len() * self.ue_book.len()
    }

    /// The narrow pair under each wide pair (row-major over AP wide × UE wide beams).
    pub fn wide_groups(&self) -> Vec<Vec<usize>> {
        let ue = self.ue_book.len();
        let mut groups = Vec::new();
        for a in &self.ap_wide.groups {
            for u in &self.ue_wide.groups {
                groups.push(
                    a.iter()
                        .flat_map(|&t| u.iter().map(move |&r| t * ue + r))
                        .collect(),
                );
            }
        }
        groups
    }

    fn ue_array(&self, heading: Real) -> Array {
        Array {
            rows: self.ue_shape.0,
            columns: self.ue_shape.1,
            spacing_wavelengths: 0.5,
            orientation: Orientation {
                yaw: heading,
                pitch: 0.0,
                roll: 0.0,
            },
        }
    }

    /// The antennas of the reports: a TR 38.901 element at the AP, isotropic elements at the
    /// UE (a handset's panels cover most directions), both vertically polarised.
    pub fn options(&self, heading: Real) -> RadioOptions {
        let element = |pattern, orientation| Antenna {
            pattern,
            polarization: Polarization::V,
            orientation,
        };
        RadioOptions {
            tx: element(Pattern::Tr38901, self.ap_array.orientation),
            rx: element(Pattern::Isotropic, self.ue_array(heading).orientation),
            ..RadioOptions::default()
        }
        .for_order(self.max_order)
    }

    /// The paths of `traced` (found in `scene`, whose terminals they run between) as the
    /// codebooks see them, with the UE heading `heading`, and the number of paths left out
    /// because their gain could not be computed (each is a [`bt_beams::describe`] error,
    /// such as a wedge angle a rounding error puts outside its range).
    pub fn directions(
        &self,
        scene: &Scene,
        traced: &[FoundPath],
        heading: Real,
    ) -> (Vec<PathDirections>, usize) {
        let options = self.options(heading);
        let reports: Vec<_> = traced
            .iter()
            .filter_map(|p| bt_beams::describe(scene, p, &options).ok())
            .collect();
        (directions(&reports), traced.len() - reports.len())
    }

    /// Power of every narrow pair, dBm (`−∞` where nothing arrives).
    pub fn narrow(
        &self,
        paths: &[PathDirections],
        heading: Real,
    ) -> Result<Vec<Real>, bt_channel::ChannelError> {
        let ue = self.ue_array(heading);
        pair_power_dbm(
            paths,
            (&self.ap_array, &self.ap_book),
            (&ue, &self.ue_book),
            self.carrier_hz,
            self.tx_power_dbm,
        )
    }

    /// Power of every wide pair, dBm.
    pub fn wide(
        &self,
        paths: &[PathDirections],
        heading: Real,
    ) -> Result<Vec<Real>, bt_channel::ChannelError> {
        let ue = self.ue_array(heading);
        pair_power_dbm(
            paths,
            (&self.ap_array, &self.ap_wide.beams),
            (&ue, &self.ue_wide.beams),
            self.carrier_hz,
            self.tx_power_dbm,
        )
    }

    /// The free-space line of sight from the AP to `ue` (what the geometric-LoS method
    /// assumes): departure towards the UE, arrival from the AP, Friis amplitude.
    pub fn line_of_sight(&self, ue: Vec3) -> Vec<PathDirections> {
        let d = ue - self.ap;
        let length = d.length();
        if length == 0.0 {
            return Vec::new();
        }
        let lambda = SPEED_OF_LIGHT / self.carrier_hz;
        vec![PathDirections {
            tap: Tap {
                gain: Complex64::new(lambda / (4.0 * PI * length), 0.0),
                delay_s: length / SPEED_OF_LIGHT,
            },
            departure: d / length,
            arrival: -d / length,
        }]
    }
}
