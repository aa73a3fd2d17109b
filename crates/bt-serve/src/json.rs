//! The path records of an answer written by hand, straight into the answer's buffer: the
//! bytes serde_json writes for [`PathReport`] (compact, its field order, `null` for a
//! non-finite number, numbers by serde_json's own formatter), without its per-key escaping
//! and small writes, which took 28 % of a serve stream's instructions, more than the trace
//! (docs/performance.md). Tested byte for byte against serde_json over drawn records (`tests`)
//! and real answers (`server`'s tests); a field added to [`PathReport`] (and so to
//! [`PathReport::example`], which every drawn record starts from) fails them until it is
//! written here too.

use bt_beams::{Direction, InteractionKind, PathReport};
use serde_json::ser::{CompactFormatter, Formatter};
use std::io;

/// `paths` as serde_json writes `Vec<PathReport>`: `[record, ...]`.
pub(crate) fn write_paths(out: &mut Vec<u8>, paths: &[PathReport]) -> io::Result<()> {
    out.push(b'[');
    for (k, path) in paths.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        write_path(out, path)?;
    }
    out.push(b']');
    Ok(())
}

/// One path record, as serde_json writes [`PathReport`].
pub(crate) fn write_path(out: &mut Vec<u8>, p: &PathReport) -> io::Result<()> {
    out.extend_from_slice(b"{\"rank\":");
    write_usize(out, p.rank)?;
    out.extend_from_slice(b",\"order\":");
    write_usize(out, p.order)?;
    out.extend_from_slice(b",\"interactions\":[");
    for (k, kind) in p.interactions.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        out.extend_from_slice(match kind {
            InteractionKind::Reflection => b"\"reflection\"",
            InteractionKind::Diffraction => b"\"diffraction\"",
            InteractionKind::Transmission => b"\"transmission\"",
        });
    }
    out.extend_from_slice(b"],\"surfaces\":[");
    for (k, name) in p.surfaces.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        write_str(out, name)?;
    }
    out.extend_from_slice(b"],\"points\":[");
    for (k, point) in p.points.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        write_reals(out, point)?;
    }
    out.extend_from_slice(b"],\"length_m\":");
    write_real(out, p.length_m)?;
    out.extend_from_slice(b",\"delay_s\":");
    write_real(out, p.delay_s)?;
    out.extend_from_slice(b",\"aod_deg\":");
    write_direction(out, &p.aod_deg)?;
    out.extend_from_slice(b",\"aoa_deg\":");
    write_direction(out, &p.aoa_deg)?;
    out.extend_from_slice(b",\"incidence_deg\":[");
    for (k, angle) in p.incidence_deg.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        write_option(out, *angle)?;
    }
    write_losses(out, p)
}

/// The record's fields from `free_space_loss_db` to its end, and its closing brace.
fn write_losses(out: &mut Vec<u8>, p: &PathReport) -> io::Result<()> {
    let reals = [
        (&b"],\"free_space_loss_db\":"[..], p.free_space_loss_db),
        (b",\"reflection_loss_db\":", p.reflection_loss_db),
        (b",\"diffraction_loss_db\":", p.diffraction_loss_db),
        (b",\"transmission_loss_db\":", p.transmission_loss_db),
        (b",\"loss_db\":", p.loss_db),
    ];
    for (key, value) in reals {
        out.extend_from_slice(key);
        write_real(out, value)?;
    }
    out.extend_from_slice(b",\"gain\":");
    write_reals(out, &[p.gain.re, p.gain.im])?;
    out.extend_from_slice(b",\"gain_db\":");
    write_option(out, p.gain_db)?;
    out.extend_from_slice(b",\"power_dbm\":");
    write_option(out, p.power_dbm)?;
    if let Some(n) = p.iterations {
        out.extend_from_slice(b",\"iterations\":");
        CompactFormatter.write_u32(out, n)?;
    }
    if let Some(r) = p.residual_m {
        out.extend_from_slice(b",\"residual_m\":");
        write_real(out, r)?;
    }
    out.push(b'}');
    Ok(())
}

/// `{"azimuth":..,"elevation":..}`.
fn write_direction(out: &mut Vec<u8>, d: &Direction) -> io::Result<()> {
    out.extend_from_slice(b"{\"azimuth\":");
    write_real(out, d.azimuth)?;
    out.extend_from_slice(b",\"elevation\":");
    write_real(out, d.elevation)?;
    out.push(b'}');
    Ok(())
}

/// `[a,b,...]` of reals.
pub(crate) fn write_reals(out: &mut Vec<u8>, values: &[f64]) -> io::Result<()> {
    out.push(b'[');
    for (k, v) in values.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        write_real(out, *v)?;
    }
    out.push(b']');
    Ok(())
}

/// A real as serde_json writes an `f64`: its formatter for a finite number, `null` otherwise.
fn write_real(out: &mut Vec<u8>, v: f64) -> io::Result<()> {
    match v.is_finite() {
        true => CompactFormatter.write_f64(out, v),
        false => CompactFormatter.write_null(out),
    }
}

/// An optional real: `null` when absent.
fn write_option(out: &mut Vec<u8>, v: Option<f64>) -> io::Result<()> {
    match v {
        Some(v) => write_real(out, v),
        None => CompactFormatter.write_null(out),
    }
}

fn write_usize(out: &mut Vec<u8>, n: usize) -> io::Result<()> {
    CompactFormatter.write_u64(out, n as u64)
}

/// A string as serde_json writes it: quoted as it is when nothing in it needs an escape
/// (a quote, a backslash, a control character), by serde_json itself otherwise.
fn write_str(out: &mut Vec<u8>, s: &str) -> io::Result<()> {
    if s.bytes().all(|b| b >= 0x20 && b != b'"' && b != b'\\') {
        out.push(b'"');
        out.extend_from_slice(s.as_bytes());
        out.push(b'"');
        return Ok(());
    }
    serde_json::to_writer(out, s).map_err(io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_channel::Complex64;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn mine(paths: &[PathReport]) -> String {
        let mut out = Vec::new();
        write_paths(&mut out, paths).unwrap();
        String::from_utf8(out).unwrap()
    }

    /// A real drawn to hit the formatter's cases: special values, integers, tiny, huge,
    /// subnormal, negative zero, and plain random ones.
    fn real(rng: &mut ChaCha8Rng) -> f64 {
        const SPECIAL: [f64; 14] = [
            0.0,
            -0.0,
            1.0,
            -180.0,
            1e-12,
            1e21,
            1e-7,
            123456789012345680.0,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        match rng.random_range(0..4) {
            0 => SPECIAL[rng.random_range(0..SPECIAL.len())],
            1 => f64::from_bits(rng.random()),
            2 => rng.random_range(-1e3..1e3),
            _ => rng.random_range(-200.0..200.0_f64).round(),
        }
    }

    fn option(rng: &mut ChaCha8Rng) -> Option<f64> {
        rng.random_bool(0.8).then(|| real(rng))
    }

    /// A record with every field drawn, lists of 0 to 4 interactions.
    fn record(rng: &mut ChaCha8Rng) -> PathReport {
        const NAMES: [&str; 7] = [
            "floor",
            "wall-south",
            "sofa.back|floor",
            "quote\"d",
            "back\\slash\\|edge",
            "tab\there\u{1}",
            "näme ✓",
        ];
        const KINDS: [InteractionKind; 3] = [
            InteractionKind::Reflection,
            InteractionKind::Diffraction,
            InteractionKind::Transmission,
        ];
        let n = rng.random_range(0..5);
        let mut p = PathReport::example();
        p.rank = rng.random_range(0..usize::MAX);
        p.order = n;
        p.interactions = (0..n).map(|_| KINDS[rng.random_range(0..3)]).collect();
        p.surfaces = (0..n)
            .map(|_| NAMES[rng.random_range(0..NAMES.len())].to_string())
            .collect();
        p.points = (0..n).map(|_| [real(rng), real(rng), real(rng)]).collect();
        p.incidence_deg = (0..n).map(|_| option(rng)).collect();
        p.length_m = real(rng);
        p.delay_s = real(rng);
        p.aod_deg = Direction {
            azimuth: real(rng),
            elevation: real(rng),
        };
        p.aoa_deg = Direction {
            azimuth: real(rng),
            elevation: real(rng),
        };
        p.free_space_loss_db = real(rng);
        p.reflection_loss_db = real(rng);
        p.diffraction_loss_db = real(rng);
        p.transmission_loss_db = real(rng);
        p.loss_db = real(rng);
        p.gain = Complex64::new(real(rng), real(rng));
        p.gain_db = option(rng);
        p.power_dbm = option(rng);
        p.iterations = rng.random_bool(0.5).then(|| rng.random());
        p.residual_m = option(rng);
        p
    }

    #[test]
    fn drawn_records_are_written_as_serde_writes_them() {
        let mut rng = ChaCha8Rng::seed_from_u64(30);
        for n in 0..2000 {
            let paths: Vec<PathReport> = (0..n % 4).map(|_| record(&mut rng)).collect();
            assert_eq!(mine(&paths), serde_json::to_string(&paths).unwrap());
        }
        let example = [PathReport::example()];
        assert_eq!(mine(&example), serde_json::to_string(&example).unwrap());
    }
}
