use crate::coord::round_scaled;
use crate::{Csd, FineCoord, FixedError};

/// Fraction bits of a [`NormalComponent`] (Q2.30).
pub const NORMAL_FRAC: u32 = 30;

/// Accepted deviation of an input normal's Euclidean length from 1 (unitless). Loose enough
/// for normals written with ~7 significant digits, tight enough that the width analysis of
/// [`crate::width`] (which assumes ‖n‖ ≤ 1 + 1e-6 after quantisation) holds.
pub const UNIT_NORMAL_TOLERANCE: f64 = 1e-7;

fixed_word! {
    /// One component of a unit normal in Q2.30: value = raw / 2^30, raw ∈ [-2^30, 2^30].
    ///
    /// Verilog twin: not a wire but a constant baked into `bt_pe_<i>` as its [`Csd`] network.
    NormalComponent(i32)
}

impl NormalComponent {
    /// Quantises `value` (unitless, |value| ≤ 1) to Q2.30, ties away from zero on the exact f64.
    /// Errors on non-finite values and |value| > 1 (after rounding).
    pub fn quantize(value: f64) -> Result<NormalComponent, FixedError> {
        let raw = round_scaled(value, 1, NORMAL_FRAC as i32)?;
        if raw.abs() > 1 << NORMAL_FRAC {
            return Err(FixedError::OutOfRange {
                value,
                format: "Q2.30 unit-normal component",
            });
        }
        Ok(NormalComponent(raw as i32))
    }

    /// The value as f64 (exact).
    pub fn dequantize(self) -> f64 {
        f64::from(self.0) / f64::from(1u32 << NORMAL_FRAC)
    }

    /// The CSD decomposition of the raw word (what the hardware adds up).
    pub fn csd(self) -> Csd {
        Csd::of(i64::from(self.0))
    }
}

/// A reflection plane in fixed point: `n · x = offset`, with `n` a (quantised) unit normal.
///
/// Verilog twin: the constants of one `bt_pe_<i>` module.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct FixedPlane {
    /// Unit normal, Q2.30 per component.
    pub normal: [NormalComponent; 3],
    /// Plane offset along the normal, fine word (mm × 2^8).
    pub offset: FineCoord,
}

impl FixedPlane {
    /// Quantises a plane `normal · x = offset_m` (normal unit within
    /// [`UNIT_NORMAL_TOLERANCE`], offset in metres).
    pub fn quantize(normal: [f64; 3], offset_m: f64) -> Result<FixedPlane, FixedError> {
        let len = (normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]).sqrt();
        if !len.is_finite() {
            return Err(FixedError::NonFinite { value: len });
        }
        if (len - 1.0).abs() > UNIT_NORMAL_TOLERANCE {
            return Err(FixedError::InvalidInput {
                problems: vec![format!("normal {normal:?} has length {len}, expected 1")],
            });
        }
        Ok(FixedPlane {
            normal: [
                NormalComponent::quantize(normal[0])?,
                NormalComponent::quantize(normal[1])?,
                NormalComponent::quantize(normal[2])?,
            ],
            offset: FineCoord::quantize(offset_m)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_components_are_exact() {
        assert_eq!(
            NormalComponent::quantize(1.0).unwrap(),
            NormalComponent(1 << 30)
        );
        assert_eq!(
            NormalComponent::quantize(-1.0).unwrap(),
            NormalComponent(-(1 << 30))
        );
        assert_eq!(
            NormalComponent::quantize(1.0).unwrap().csd().digits.len(),
            1
        );
        assert!(NormalComponent::quantize(1.01).is_err());
        assert!(NormalComponent::quantize(f64::NAN).is_err());
    }

    #[test]
    fn plane_validation() {
        assert!(FixedPlane::quantize([0.0, 0.0, 1.0], 2.5).is_ok());
        assert!(FixedPlane::quantize([0.0, 0.6, 0.8], -1.0).is_ok());
        assert!(FixedPlane::quantize([0.0, 0.0, 2.0], 0.0).is_err());
        assert!(FixedPlane::quantize([0.0, f64::NAN, 1.0], 0.0).is_err());
    }
}
