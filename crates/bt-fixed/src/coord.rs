use crate::FixedError;

/// Millimetres per metre: the decimal scale of [`Coord`].
pub const MM_PER_M: i64 = 1000;

fixed_word! {
    /// A coordinate or length word: 32-bit signed, value = metres × 1000 (1 LSB = 1 mm).
    ///
    /// Verilog twin: a `signed [31:0]` field of the 96-bit point word `{z, y, x}` in `bt_top`.
    Coord(i32)
}

/// A point in millimetre words, `[x, y, z]`.
pub type FixedPoint = [Coord; 3];

impl Coord {
    /// Quantises `metres` to the nearest millimetre, ties away from zero, computed on the exact
    /// binary value of the f64 (no rounding of an intermediate `metres * 1000.0`).
    ///
    /// Errors: [`FixedError::NonFinite`] for NaN/inf, [`FixedError::OutOfRange`] when the result
    /// does not fit 32 bits (|metres| ≳ 2147483.6 m). Never saturates.
    pub fn quantize(metres: f64) -> Result<Coord, FixedError> {
        let scaled = round_scaled(metres, MM_PER_M as i128, 0)?;
        i32::try_from(scaled)
            .map(Coord)
            .map_err(|_| FixedError::OutOfRange {
                value: metres,
                format: "32-bit millimetre coordinate",
            })
    }

    /// The value in metres (exact up to f64 rounding of `raw / 1000`).
    pub fn dequantize(self) -> f64 {
        f64::from(self.0) / MM_PER_M as f64
    }
}

/// Fraction bits below the millimetre of the iterated point state ([`FineCoord`]).
///
/// Why: with whole-millimetre state the Jacobi iteration stagnates once a round's true move
/// drops below 0.5 mm (error ≈ 0.5 mm / (1 − contraction)) and rounding noise sustains limit
/// cycles: on the seeded rooms of `tests/it/vs_f64.rs` that gave 73 mm / 0.58 degree worst case and
/// 6 % of paths never converging at a 1 mm threshold; 8 fraction bits bring it to ≈ 0.25 mm and
/// 0.003 degree. The bus keeps the paper's 32-bit millimetre words.
pub const POINT_FRAC: u32 = 8;

fixed_word! {
    /// The iterated coordinate word: 40-bit signed, value = millimetres × 2^[`POINT_FRAC`]
    /// (decimal millimetre scale with 8 binary fraction bits; range ±2^31 mm like [`Coord`]).
    ///
    /// Verilog twin: a `signed [39:0]` field of the 120-bit point word `{z, y, x}` in `bt_top`'s
    /// point memory and the PE ports.
    FineCoord(i64)
}

/// A point in [`FineCoord`] words, `[x, y, z]`.
pub type FinePoint = [FineCoord; 3];

impl FineCoord {
    /// Width of the word in bits.
    pub const BITS: u32 = 32 + POINT_FRAC;
    /// Smallest value.
    pub const MIN: FineCoord = FineCoord(-(1 << (Self::BITS - 1)));
    /// Largest value.
    pub const MAX: FineCoord = FineCoord((1 << (Self::BITS - 1)) - 1);

    /// Exact widening of a millimetre word (`raw << 8`).
    ///
    /// Verilog twin: `{tx_x, 8'b0}` in `bt_top`.
    pub fn from_coord(c: Coord) -> FineCoord {
        FineCoord(i64::from(c.0) << POINT_FRAC)
    }

    /// Quantises `metres` to the nearest 1/256 mm, ties away from zero on the exact f64;
    /// errors like [`Coord::quantize`] (same ±2147483.6 m range).
    pub fn quantize(metres: f64) -> Result<FineCoord, FixedError> {
        let scaled = round_scaled(metres, MM_PER_M as i128, POINT_FRAC as i32)?;
        if !(i128::from(Self::MIN.0)..=i128::from(Self::MAX.0)).contains(&scaled) {
            return Err(FixedError::OutOfRange {
                value: metres,
                format: "40-bit fine coordinate",
            });
        }
        Ok(FineCoord(scaled as i64))
    }

    /// The value in metres.
    pub fn dequantize(self) -> f64 {
        self.0 as f64 / f64::from(1u32 << POINT_FRAC) / MM_PER_M as f64
    }

    /// Whole millimetres, rounded down (the bus word; exact with [`FineCoord::frac`]).
    ///
    /// Verilog twin: `point[39:8]` on the Avalon read mux.
    pub fn floor_mm(self) -> Coord {
        Coord((self.0 >> POINT_FRAC) as i32)
    }

    /// The fraction bits (`raw mod 256`), so that `raw = floor_mm·256 + frac`.
    ///
    /// Verilog twin: `point[7:0]`, packed `{8'b0, z[7:0], y[7:0], x[7:0]}` in the 4th word.
    pub fn frac(self) -> u8 {
        (self.0 & ((1 << POINT_FRAC) - 1)) as u8
    }
}

/// Quantises the axes of `p` (metres) with `quantize`, x first; the first axis out of range
/// is the error.
fn quantize_axes<T>(
    p: [f64; 3],
    quantize: impl Fn(f64) -> Result<T, FixedError>,
) -> Result<[T; 3], FixedError> {
    let [x, y, z] = p;
    Ok([quantize(x)?, quantize(y)?, quantize(z)?])
}

/// Quantises a point given in metres to [`FineCoord`] words.
pub fn quantize_fine_point(p: [f64; 3]) -> Result<FinePoint, FixedError> {
    quantize_axes(p, FineCoord::quantize)
}

/// Dequantises a [`FinePoint`] to metres.
pub fn dequantize_fine_point(p: FinePoint) -> [f64; 3] {
    p.map(FineCoord::dequantize)
}

/// Quantises a point given in metres; see [`Coord::quantize`].
pub fn quantize_point(p: [f64; 3]) -> Result<FixedPoint, FixedError> {
    quantize_axes(p, Coord::quantize)
}

/// Dequantises a point to metres; see [`Coord::dequantize`].
pub fn dequantize_point(p: FixedPoint) -> [f64; 3] {
    p.map(Coord::dequantize)
}

/// `round_half_away_from_zero(x * mul * 2^pow2)` on the exact value of `x`, as an `i128`.
///
/// Returns `OutOfRange` (with `format` = "i128") only if the magnitude exceeds 2^100, which is
/// far beyond any 32-bit target; callers narrow the result themselves.
pub(crate) fn round_scaled(x: f64, mul: i128, pow2: i32) -> Result<i128, FixedError> {
    if !x.is_finite() {
        return Err(FixedError::NonFinite { value: x });
    }
    if x == 0.0 {
        return Ok(0);
    }
    let bits = x.to_bits();
    let negative = bits >> 63 == 1;
    let biased_exp = ((bits >> 52) & 0x7ff) as i32;
    let fraction = (bits & ((1u64 << 52) - 1)) as i128;
    // x = mant * 2^exp exactly.
    let (mant, exp) = if biased_exp == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1i128 << 52), biased_exp - 1075)
    };
    let product = mant * mul; // < 2^53 * 2^10
    let k = exp + pow2;
    let magnitude = if k >= 0 {
        if k > 100 - 63 {
            return Err(FixedError::OutOfRange {
                value: x,
                format: "i128",
            });
        }
        product << k
    } else {
        let shift = (-k) as u32;
        if shift >= 100 {
            0
        } else {
            (product + (1i128 << (shift - 1))) >> shift
        }
    };
    Ok(if negative { -magnitude } else { magnitude })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ties_round_away_from_zero_on_exact_values() {
        // 0.0005 m is not exactly representable: its f64 is slightly above 0.0005.
        assert_eq!(Coord::quantize(0.0005).unwrap(), Coord(1));
        // 0.0045 as f64 is 0.00449999999999999966 m, below the tie, so 4 mm; the naive
        // `(0.0045 * 1000.0).round()` sees the float product 4.5 exactly and returns 5.
        assert_eq!((0.0045f64 * 1000.0).round(), 5.0);
        assert_eq!(Coord::quantize(0.0045).unwrap(), Coord(4));
        assert_eq!(Coord::quantize(-0.0045).unwrap(), Coord(-4));
        assert_eq!(Coord::quantize(1.0005).unwrap(), Coord(1000));
        assert_eq!(Coord::quantize(2.0015).unwrap(), Coord(2002));
        // Exactly representable values are exact.
        assert_eq!(Coord::quantize(0.125).unwrap(), Coord(125));
        assert_eq!(Coord::quantize(-2.0).unwrap(), Coord(-2000));
    }

    #[test]
    fn range_and_non_finite_are_errors() {
        assert_eq!(Coord::quantize(2_147_483.647).unwrap(), Coord(i32::MAX));
        assert_eq!(Coord::quantize(-2_147_483.648).unwrap(), Coord(i32::MIN));
        assert!(matches!(
            Coord::quantize(2_147_483.648),
            Err(FixedError::OutOfRange { .. })
        ));
        assert!(matches!(
            Coord::quantize(f64::NAN),
            Err(FixedError::NonFinite { .. })
        ));
        assert!(matches!(
            Coord::quantize(f64::INFINITY),
            Err(FixedError::NonFinite { .. })
        ));
        assert!(matches!(
            Coord::quantize(1e300),
            Err(FixedError::OutOfRange { .. })
        ));
        assert_eq!(Coord::quantize(1e-300).unwrap(), Coord(0));
        assert_eq!(Coord::quantize(f64::MIN_POSITIVE / 4.0).unwrap(), Coord(0));
    }

    #[test]
    fn fine_words() {
        let f = FineCoord::quantize(-0.0015).unwrap();
        assert_eq!(f, FineCoord(-384));
        assert_eq!((f.floor_mm(), f.frac()), (Coord(-2), 128));
        assert_eq!(FineCoord::from_coord(Coord(i32::MIN)), FineCoord::MIN);
        assert_eq!(FineCoord::from_coord(Coord(3)).dequantize(), 0.003);
        assert!(FineCoord::quantize(2_147_483.648).is_err());
    }

    #[test]
    fn exact_tie_in_binary() {
        // 0.5 mm is not a binary fraction of a metre, but 2^-k m scaled by 1000 can be: use
        // round_scaled directly with an exact binary tie: 2.5 * 1 -> 3, -2.5 -> -3.
        assert_eq!(round_scaled(2.5, 1, 0).unwrap(), 3);
        assert_eq!(round_scaled(-2.5, 1, 0).unwrap(), -3);
        assert_eq!(round_scaled(0.75, 1, 1).unwrap(), 2);
        assert_eq!(round_scaled(0.5, 1, 30).unwrap(), 1 << 29);
    }
}
