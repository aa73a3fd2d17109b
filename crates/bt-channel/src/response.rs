//! Channel responses from path gains and delays: the impulse response (taps) and the
//! frequency response at subcarrier offsets from the carrier. `docs/channel.md`.

use bt_geom::Real;
use num_complex::Complex64;
use std::f64::consts::PI;

/// One tap of the channel impulse response h(t) = Σ a_i·δ(t − τ_i).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tap {
    /// Path gain a_i (no propagation phase), dimensionless.
    pub gain: Complex64,
    /// Delay τ_i, seconds.
    pub delay_s: Real,
}

impl Tap {
    /// The baseband-equivalent coefficient a_i·e^{−j2π·f_c·τ_i} (the propagation phase at the
    /// carrier `carrier_hz` applied).
    pub fn baseband(&self, carrier_hz: Real) -> Complex64 {
        self.gain * phase(carrier_hz * self.delay_s)
    }
}

/// e^{−j2π·x}, reducing x modulo 1 first so that long delays keep their phase accuracy.
fn phase(cycles: Real) -> Complex64 {
    let x = cycles - cycles.floor();
    Complex64::from_polar(1.0, -2.0 * PI * x)
}

/// Budget on the subcarriers of a frequency response: each is an offset, a complex value and
/// a CSV row (~100 B), so the default of 1,000,000 holds a response under ~150 MB.
pub const MAX_SUBCARRIERS: bt_geom::Budget =
    bt_geom::Budget::new("subcarriers", "--max-subcarriers", 1_000_000);

/// Budget on subcarriers × paths of a frequency response (one complex exponential each,
/// ~15 ns): the default of 100,000,000 is a few seconds of work.
pub const MAX_CFR_PRODUCTS: bt_geom::Budget = bt_geom::Budget::new(
    "subcarrier-path products",
    "--max-cfr-products",
    100_000_000,
);

/// The two budgets of a frequency response (limits of [`MAX_SUBCARRIERS`] and
/// [`MAX_CFR_PRODUCTS`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ResponseBudget {
    /// Subcarriers at most.
    pub max_subcarriers: u64,
    /// Subcarriers × taps at most.
    pub max_products: u64,
}

impl Default for ResponseBudget {
    fn default() -> Self {
        ResponseBudget {
            max_subcarriers: MAX_SUBCARRIERS.limit,
            max_products: MAX_CFR_PRODUCTS.limit,
        }
    }
}

impl ResponseBudget {
    /// Refuse a response of `subcarriers` over `taps` (at least one subcarrier) beyond either
    /// budget, before anything is allocated.
    pub fn check(&self, subcarriers: usize, taps: usize) -> Result<(), crate::ChannelError> {
        if subcarriers == 0 {
            return Err(crate::ChannelError::Invalid {
                field: "subcarriers",
                message: "need at least 1 subcarrier".into(),
            });
        }
        let n = subcarriers as u64;
        MAX_SUBCARRIERS.with_limit(self.max_subcarriers).check(n)?;
        let products = n.saturating_mul(taps.max(1) as u64);
        MAX_CFR_PRODUCTS
            .with_limit(self.max_products)
            .check(products)?;
        Ok(())
    }
}

/// `n` subcarrier offsets spaced `spacing_hz` apart and centred on the carrier:
/// (k − ⌊n/2⌋)·Δf for k = 0..n, Hz.
pub fn subcarriers(n: usize, spacing_hz: Real) -> Vec<Real> {
    let half = (n / 2) as Real;
    (0..n).map(|k| (k as Real - half) * spacing_hz).collect()
}

/// Channel frequency response H(f_c + Δf) = Σ a_i·e^{−j2π(f_c + Δf)·τ_i} at each offset Δf
/// (Hz) from the carrier `carrier_hz`; the path gains are taken as flat over the band.
pub fn frequency_response(taps: &[Tap], carrier_hz: Real, offsets_hz: &[Real]) -> Vec<Complex64> {
    offsets_hz
        .iter()
        .map(|df| {
            taps.iter()
                .map(|t| t.gain * phase((carrier_hz + df) * t.delay_s))
                .fold(Complex64::new(0.0, 0.0), |a, b| a + b)
        })
        .collect()
}

/// Total received power of the taps relative to the transmitted power, as a power sum
/// Σ|a_i|² (wideband: the paths do not interfere on average), linear.
pub fn total_power(taps: &[Tap]) -> Real {
    taps.iter()
        .map(|t| t.gain.norm_sqr())
        .fold(0.0, |a, b| a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn responses_beyond_either_budget_are_refused_before_allocating() {
        let b = ResponseBudget::default();
        assert!(b.check(64, 10).is_ok());
        assert!(b.check(0, 10).is_err());
        let e = b.check(usize::MAX, 1).unwrap_err().to_string();
        assert!(e.contains("--max-subcarriers"), "{e}");
        let e = b.check(1_000_000, 1_000).unwrap_err().to_string();
        assert!(e.contains("1000000000 subcarrier-path products"), "{e}");
        assert!(e.contains("--max-cfr-products"), "{e}");
    }

    #[test]
    fn one_tap_response_is_a_linear_phase() {
        let tap = Tap {
            gain: Complex64::new(0.5, 0.0),
            delay_s: 10e-9,
        };
        let offsets = subcarriers(4, 25e6);
        assert_eq!(offsets, vec![-50e6, -25e6, 0.0, 25e6]);
        let h = frequency_response(&[tap], 1e9, &offsets);
        for (df, v) in offsets.iter().zip(&h) {
            let expected = Complex64::from_polar(0.5, -2.0 * PI * (1e9 + df) * 10e-9);
            assert!((v - expected).norm() < 1e-12);
        }
        assert!((tap.baseband(1e9) - h[2]).norm() < 1e-15);
    }

    #[test]
    fn two_equal_taps_cancel_half_a_period_apart() {
        // τ2 − τ1 = 1/(2 f): the carrier sees opposite phases.
        let f = 1e9;
        let taps = [
            Tap {
                gain: Complex64::new(1.0, 0.0),
                delay_s: 3e-9,
            },
            Tap {
                gain: Complex64::new(1.0, 0.0),
                delay_s: 3e-9 + 0.5e-9,
            },
        ];
        let h = frequency_response(&taps, f, &[0.0]);
        assert!(h[0].norm() < 1e-9);
        assert_eq!(total_power(&taps), 2.0);
    }
}
