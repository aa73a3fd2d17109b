//! The one checked parser of every real-valued flag. Clap calls these as `value_parser`s, so a
//! NaN, an infinity or a value outside the option's documented range is refused while the
//! arguments are parsed — before anything is loaded, traced or written, whether or not the
//! run would use the option (`--merge-angle-deg` with a built-in scene, `--ipc-threshold` with
//! the image solver) — and clap's error names the flag:
//! `invalid value 'nan' for '--merge-angle-deg <MERGE_ANGLE_DEG>': must be a finite number in
//! [0, 90) degrees`. Integer flags need nothing here: clap's own parsers refuse `nan`, `-1`
//! and `1e300` for them, naming the flag. The ranges are listed in docs/reliability.md
//! (Numbers).

use std::ops::Bound::{self, Excluded, Included, Unbounded};

/// The longest length any flag takes, metres: no scene resolves coordinates beyond ~4.5e8 m
/// (docs/reliability.md), so a larger tolerance, threshold or noise means nothing.
pub const MAX_LENGTH_M: f64 = 1e9;

/// Transmitted power range, dBm: ±300 dBm (1e27 W / 1e-33 W) keeps every power in watts
/// and every received power finite.
const POWER_DBM: f64 = 300.0;

/// Array element spacings up to this many wavelengths (a codebook's grating lobes are
/// meaningless far beyond a few).
const MAX_SPACING_WAVELENGTHS: f64 = 1e3;

/// An allowed interval and the unit it is stated in.
struct Range {
    low: Bound<f64>,
    high: Bound<f64>,
    unit: &'static str,
}

impl Range {
    fn contains(&self, x: f64) -> bool {
        let above = match self.low {
            Included(l) => x >= l,
            Excluded(l) => x > l,
            Unbounded => true,
        };
        let below = match self.high {
            Included(h) => x <= h,
            Excluded(h) => x < h,
            Unbounded => true,
        };
        x.is_finite() && above && below
    }

    fn describe(&self) -> String {
        let low = match self.low {
            Included(l) => format!("[{}", compact(l)),
            Excluded(l) => format!("({}", compact(l)),
            Unbounded => "(-inf".into(),
        };
        let high = match self.high {
            Included(h) => format!("{}]", compact(h)),
            Excluded(h) => format!("{})", compact(h)),
            Unbounded => "inf)".into(),
        };
        format!("a finite number in {low}, {high} {}", self.unit)
            .trim_end()
            .to_string()
    }
}

/// `x` as people write it: plain when short, else in exponent form (`1e15`, never fifteen
/// zeros).
fn compact(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() <= 6 {
        plain
    } else {
        format!("{x:e}")
    }
}

/// `s` as a number inside `range`, or the message clap prints after the flag's name.
fn checked(s: &str, range: Range) -> Result<f64, String> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("not a number; must be {}", range.describe()))?;
    if range.contains(x) {
        Ok(x)
    } else {
        Err(format!("must be {}", range.describe()))
    }
}

/// A finite number ≥ 0, no upper bound (areas: a huge minimum only makes every surface block).
pub fn non_negative(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Included(0.0),
            high: Unbounded,
            unit: "",
        },
    )
}

/// A finite number > 0, no upper bound (densities: the point budget bounds the work).
pub fn positive(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Excluded(0.0),
            high: Unbounded,
            unit: "",
        },
    )
}

/// A length in metres, 0 to [`MAX_LENGTH_M`] (tolerances, noise, thicknesses).
pub fn length_m(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Included(0.0),
            high: Included(MAX_LENGTH_M),
            unit: "metres",
        },
    )
}

/// A length in metres above 0, at most [`MAX_LENGTH_M`] (thresholds that must let some
/// progress through).
pub fn positive_length_m(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Excluded(0.0),
            high: Included(MAX_LENGTH_M),
            unit: "metres",
        },
    )
}

/// An SBR grid step: above 0, at most [`bt_solve::sbr::MAX_STEP_DEG`] degrees.
pub fn sbr_step_deg(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Excluded(0.0),
            high: Included(bt_solve::sbr::MAX_STEP_DEG),
            unit: "degrees",
        },
    )
}

/// A mesh merge angle: 0 up to (not including) [`bt_mesh::MAX_ANGLE_TOL_DEG`] degrees.
pub fn merge_angle_deg(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Included(0.0),
            high: Excluded(bt_mesh::MAX_ANGLE_TOL_DEG),
            unit: "degrees",
        },
    )
}

/// A carrier frequency: the scene's range (`bt_scene::frequency_problem`, whatever the
/// materials).
pub fn frequency_hz(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Included(bt_scene::MIN_FREQUENCY_HZ),
            high: Included(bt_scene::MAX_FREQUENCY_HZ),
            unit: "Hz",
        },
    )
}

/// A subcarrier spacing: above 0, at most the highest carrier frequency.
pub fn spacing_hz(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Excluded(0.0),
            high: Included(bt_scene::MAX_FREQUENCY_HZ),
            unit: "Hz",
        },
    )
}

/// A power in dBm, ±300.
pub fn power_dbm(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Included(-POWER_DBM),
            high: Included(POWER_DBM),
            unit: "dBm",
        },
    )
}

/// A measurement error, reporting step or margin: 0 to 100 dB (more means nothing to a
/// beam report).
pub fn decibels(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Included(0.0),
            high: Included(100.0),
            unit: "dB",
        },
    )
}

/// A latency: 0 to one hour, in milliseconds.
pub fn milliseconds(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Included(0.0),
            high: Included(3.6e6),
            unit: "ms",
        },
    )
}

/// A scan density: 0 (no scan) to 1e7 points/m² (a point every 0.3 mm).
pub fn scan_density(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Included(0.0),
            high: Included(1e7),
            unit: "points/m²",
        },
    )
}

/// An array element spacing: above 0, at most 1000 wavelengths.
pub fn spacing_wavelengths(s: &str) -> Result<f64, String> {
    checked(
        s,
        Range {
            low: Excluded(0.0),
            high: Included(MAX_SPACING_WAVELENGTHS),
            unit: "wavelengths",
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_values_are_refused_with_the_range() {
        for bad in ["nan", "NaN", "inf", "-inf", "1e309", "x", ""] {
            assert!(non_negative(bad).is_err(), "{bad}");
            assert!(positive(bad).is_err(), "{bad}");
            assert!(length_m(bad).is_err(), "{bad}");
        }
        assert_eq!(
            merge_angle_deg("90").unwrap_err(),
            "must be a finite number in [0, 90) degrees"
        );
        assert_eq!(
            frequency_hz("1e300").unwrap_err(),
            "must be a finite number in [1000, 1e15] Hz"
        );
        assert!(length_m("-1").is_err() && length_m("1e300").is_err());
        assert!(positive_length_m("0").is_err());
        assert!(power_dbm("1e300").is_err() && power_dbm("-1").is_ok());
        assert!(sbr_step_deg("90").is_ok() && sbr_step_deg("90.5").is_err());
    }

    /// A flag's value parser.
    type Parser = fn(&str) -> Result<f64, String>;

    /// Every parser of the flags, as the table-driven CLI test sees them.
    const PARSERS: [Parser; 10] = [
        non_negative,
        positive,
        length_m,
        positive_length_m,
        sbr_step_deg,
        merge_angle_deg,
        frequency_hz,
        spacing_hz,
        power_dbm,
        spacing_wavelengths,
    ];

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config {
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x0bad_f1a6),
            ..proptest::test_runner::Config::default()
        })]

        /// Fuzzing the numeric flags: any text, or any number however written, never panics
        /// and never yields a non-finite value; an accepted number is what was written.
        #[test]
        fn any_text_parses_to_a_finite_number_or_a_message(
            text in "\\PC{0,40}",
            x in proptest::num::f64::ANY,
            exponent in proptest::bool::ANY,
        ) {
            let written = if exponent { format!("{x:e}") } else { format!("{x}") };
            for parse in PARSERS {
                for input in [text.as_str(), written.as_str()] {
                    match parse(input) {
                        Ok(v) => proptest::prop_assert!(v.is_finite(), "{input:?} gave {v}"),
                        Err(message) => proptest::prop_assert!(message.contains("must be")),
                    }
                }
                if let Ok(v) = parse(&written) {
                    proptest::prop_assert_eq!(v.to_bits(), x.to_bits());
                }
            }
        }
    }

    #[test]
    fn ordinary_values_pass_unchanged() {
        assert_eq!(length_m("1e-3"), Ok(1e-3));
        assert_eq!(frequency_hz("28e9"), Ok(28e9));
        assert_eq!(non_negative("0"), Ok(0.0));
        assert_eq!(spacing_wavelengths(" 0.5 "), Ok(0.5));
    }
}
