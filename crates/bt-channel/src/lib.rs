//! The radio channel of traced paths: ITU-R P.2040-3 materials and their reflection
//! coefficients, antennas (pattern and polarisation), polarised complex path gains (Jones
//! calculus) with first-order UTD edge diffraction, channel impulse and frequency responses,
//! and beam codebooks.
//!
//! Frames and units: world frame of `docs/conventions.md` (metres, z up), Hz, radians inside
//! the library. Every formula and sign convention: `docs/channel.md`.

#![warn(missing_docs)]

pub mod antenna;
pub mod codebook;
pub mod diffraction;
pub mod gain;
pub mod material;
pub mod response;
pub mod sionna;

pub use antenna::{Antenna, Orientation, Pattern, Polarization};
pub use codebook::{Array, Beam, MAX_BEAM_PAIRS, PathDirections, beam_pairs, check_beam_pairs};
pub use diffraction::{DiffractionCoefficient, Wedge, fresnel_integrals, transition};
pub use gain::{
    Bounce, FreeSpace, Interaction, PathGain, SurfaceResponse, free_space, path_gain,
    path_gain_detailed, path_gain_mixed,
};
pub use material::{
    ItuBand, ItuMaterial, RadioMaterial, RadioModel, Reflection, SPEED_OF_LIGHT, Transmission,
    VACUUM_PERMITTIVITY, slab_transmission,
};
pub use num_complex::Complex64;
pub use response::{
    MAX_CFR_PRODUCTS, MAX_SUBCARRIERS, ResponseBudget, Tap, frequency_response, subcarriers,
    total_power,
};
pub use sionna::{path_gain_sionna_rt22, sionna_rt22_diffracted_leg};

use bt_geom::Real;
use thiserror::Error;

/// Errors of the channel computations.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ChannelError {
    /// A material name not in ITU-R P.2040-3 Table 3.
    #[error(
        "unknown ITU material \"{name}\" (known: vacuum, concrete, brick, plasterboard, wood, glass, ceiling_board, chipboard, plywood, marble, floorboard, metal, very_dry_ground, medium_dry_ground, wet_ground)"
    )]
    UnknownMaterial {
        /// The name given.
        name: String,
    },
    /// The frequency lies outside the material's validity range.
    #[error(
        "ITU material \"{material}\" is defined for {valid}, not at {:.4} GHz",
        frequency_hz / 1e9
    )]
    OutOfRange {
        /// Material name.
        material: String,
        /// The frequency asked for, Hz.
        frequency_hz: Real,
        /// The validity bands, as text.
        valid: String,
    },
    /// Work or memory over its budget, estimated before the work.
    #[error(transparent)]
    Budget(#[from] bt_geom::OverBudget),
    /// A parameter out of its domain.
    #[error("{field}: {message}")]
    Invalid {
        /// Parameter name.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
}
