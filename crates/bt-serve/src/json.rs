//! The path records of an answer written by hand, straight into the answer's buffer: the
//! bytes serde_json writes for [`PathReport`] (compact, its field order, `null` for a
//! non-finite number, numbers by serde_json's own formatter), without its per-key escaping
//! and small writes, which took 28 % of a serve stream's instructions, more than the trace
//! (docs/performance.md). Room for a whole record is reserved once; +0.0 is written as `0.0`
//! and an integral point coordinate or loss below 10^15 (a wall's 6.0, a material's 4.0 dB)
//! as its digits and `.0`, the bytes serde_json's shortest form gives them, without its
//! search; a power equal to the gain (a transmitted power of 0 dBm) repeats the gain's bytes. Tested byte for byte against
//! serde_json over drawn records (`tests`) and real answers (`server`'s tests); a field added
//! to [`PathReport`] (and so to [`PathReport::example`], which every drawn record starts from)
//! fails them until it is written here too.

use bt_beams::{Direction, InteractionKind, PathReport};
use serde_json::ser::{CompactFormatter, Formatter};
use std::io;

/// `paths`' records separated by commas: inside brackets, the bytes serde_json writes for
/// `Vec<PathReport>`.
pub(crate) fn write_records(out: &mut Vec<u8>, paths: &[PathReport]) -> io::Result<()> {
    for (k, path) in paths.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        write_path(out, path)?;
    }
    Ok(())
}

/// Bytes a record's keys and punctuation take at most, besides its numbers and names
/// (about 430 with every optional field).
const RECORD_FRAME: usize = 512;

/// Bytes a real takes at most (serde_json's longest, `-2.2250738585072014e-308`, is 24).
const REAL: usize = 25;

/// Room for `p`'s record: its frame, every number at its longest, its names unescaped and
/// each interaction's kind (a name that needs escapes grows the buffer as it is written).
fn record_bound(p: &PathReport) -> usize {
    let names: usize = p.surfaces.iter().map(|s| s.len() + 3).sum();
    let reals = 17 + 3 * p.points.len() + p.incidence_deg.len();
    RECORD_FRAME + REAL * reals + names + 16 * p.interactions.len()
}

/// One path record, as serde_json writes [`PathReport`].
pub(crate) fn write_path(out: &mut Vec<u8>, p: &PathReport) -> io::Result<()> {
    out.reserve(record_bound(p));
    out.extend_from_slice(b"{\"rank\":");
    write_u64(out, p.rank as u64)?;
    out.extend_from_slice(b",\"order\":");
    write_u64(out, p.order as u64)?;
    out.extend_from_slice(b",\"interactions\":[");
    for (k, kind) in p.interactions.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        // One constant copy per kind (a slice of the kind's length would be a `memcpy` call).
        match kind {
            InteractionKind::Reflection => out.extend_from_slice(b"\"reflection\""),
            InteractionKind::Diffraction => out.extend_from_slice(b"\"diffraction\""),
            InteractionKind::Transmission => out.extend_from_slice(b"\"transmission\""),
        }
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
        out.push(b'[');
        write_integral_or_real(out, point[0])?;
        out.push(b',');
        write_integral_or_real(out, point[1])?;
        out.push(b',');
        write_integral_or_real(out, point[2])?;
        out.push(b']');
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
    out.extend_from_slice(b"],\"free_space_loss_db\":");
    write_real(out, p.free_space_loss_db)?;
    out.extend_from_slice(b",\"reflection_loss_db\":");
    write_integral_or_real(out, p.reflection_loss_db)?;
    out.extend_from_slice(b",\"diffraction_loss_db\":");
    write_integral_or_real(out, p.diffraction_loss_db)?;
    out.extend_from_slice(b",\"transmission_loss_db\":");
    write_integral_or_real(out, p.transmission_loss_db)?;
    out.extend_from_slice(b",\"loss_db\":");
    write_real(out, p.loss_db)?;
    out.extend_from_slice(b",\"gain\":[");
    write_real(out, p.gain.re)?;
    out.push(b',');
    write_real(out, p.gain.im)?;
    out.extend_from_slice(b"],\"gain_db\":");
    let gain_db = out.len();
    write_option(out, p.gain_db)?;
    let gain_db = gain_db..out.len();
    out.extend_from_slice(b",\"power_dbm\":");
    // The same number (a transmitted power of 0 dBm), the same bytes.
    match (p.gain_db, p.power_dbm) {
        (Some(g), Some(p)) if g.to_bits() == p.to_bits() => out.extend_from_within(gain_db),
        (None, None) => out.extend_from_within(gain_db),
        (_, power_dbm) => write_option(out, power_dbm)?,
    }
    if let Some(n) = p.iterations {
        out.extend_from_slice(b",\"iterations\":");
        write_u64(out, n.into())?;
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

/// Integral reals below this magnitude are written as their digits and `.0`: serde_json's
/// formatter writes every integral value below 10^16 in that fixed form, and its shortest
/// digits of an integer below 2^53 are the integer's own.
const INTEGRAL_BELOW: u64 = 1_000_000_000_000_000;

/// A real as serde_json writes an `f64`: its formatter for a finite number, `null` otherwise
/// (+0.0, the most frequent value, as the `0.0` it writes).
#[inline]
fn write_real(out: &mut Vec<u8>, v: f64) -> io::Result<()> {
    if v.to_bits() == 0 {
        out.extend_from_slice(b"0.0");
        return Ok(());
    }
    match v.is_finite() {
        true => CompactFormatter.write_f64(out, v),
        false => CompactFormatter.write_null(out),
    }
}

/// [`write_real`] for a real often integral (a material's loss in dB, a wall's coordinate):
/// an integral value below [`INTEGRAL_BELOW`] as its digits and `.0`, the bytes serde_json's
/// formatter gives it, without its shortest-digits search.
#[inline]
fn write_integral_or_real(out: &mut Vec<u8>, v: f64) -> io::Result<()> {
    // +0.0 (a path's diffraction and transmission losses, most often) as `write_real` writes
    // it, without the integer's digits.
    if v.to_bits() == 0 {
        out.extend_from_slice(b"0.0");
        return Ok(());
    }
    // `as` saturates (and takes NaN to 0): only an integral, finite value comes back equal.
    let i = v as i64;
    if i as f64 != v || i.unsigned_abs() >= INTEGRAL_BELOW {
        return write_real(out, v);
    }
    if v.is_sign_negative() {
        out.push(b'-');
    }
    write_u64(out, i.unsigned_abs())?;
    out.extend_from_slice(b".0");
    Ok(())
}

/// An optional real: `null` when absent.
fn write_option(out: &mut Vec<u8>, v: Option<f64>) -> io::Result<()> {
    match v {
        Some(v) => write_real(out, v),
        None => CompactFormatter.write_null(out),
    }
}

/// An unsigned integer's decimal digits (one or two digits without serde_json's formatter).
#[inline]
fn write_u64(out: &mut Vec<u8>, n: u64) -> io::Result<()> {
    if n < 10 {
        out.push(b'0' + n as u8);
        return Ok(());
    }
    if n < 100 {
        out.extend_from_slice(&[b'0' + (n / 10) as u8, b'0' + (n % 10) as u8]);
        return Ok(());
    }
    CompactFormatter.write_u64(out, n)
}

/// A string as serde_json writes it: quoted as it is when nothing in it needs an escape
/// (a quote, a backslash, a control character), by serde_json itself otherwise.
fn write_str(out: &mut Vec<u8>, s: &str) -> io::Result<()> {
    if !needs_escape(s.as_bytes()) {
        out.push(b'"');
        out.extend_from_slice(s.as_bytes());
        out.push(b'"');
        return Ok(());
    }
    serde_json::to_writer(out, s).map_err(io::Error::other)
}

/// Whether `bytes` holds a byte serde_json escapes (below 0x20, a quote, a backslash), tested
/// eight at a time: a word has a byte below `n` (`n` ≤ 0x80) exactly when
/// `(x - n·0x01..01) & !x & 0x80..80` is not zero (a byte equal to `c` is a zero of `x ^ c·0x01..01`).
fn needs_escape(bytes: &[u8]) -> bool {
    const LOW: u64 = 0x0101_0101_0101_0101;
    const HIGH: u64 = 0x8080_8080_8080_8080;
    let below = |x: u64, n: u8| x.wrapping_sub(LOW * u64::from(n)) & !x & HIGH != 0;
    let mut words = bytes.chunks_exact(8);
    for word in &mut words {
        let mut x = [0u8; 8];
        x.copy_from_slice(word);
        let x = u64::from_le_bytes(x);
        let quote = x ^ (LOW * u64::from(b'"'));
        let backslash = x ^ (LOW * u64::from(b'\\'));
        if below(x, 0x20) || below(quote, 1) || below(backslash, 1) {
            return true;
        }
    }
    (words.remainder().iter()).any(|&b| b < 0x20 || b == b'"' || b == b'\\')
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_channel::Complex64;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn mine(paths: &[PathReport]) -> String {
        let mut out = vec![b'['];
        write_records(&mut out, paths).unwrap();
        out.push(b']');
        String::from_utf8(out).unwrap()
    }

    /// A real drawn to hit the formatter's cases: special values, integers, tiny, huge,
    /// subnormal, negative zero, and plain random ones.
    fn real(rng: &mut ChaCha8Rng) -> f64 {
        const SPECIAL: [f64; 22] = [
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
            // Integral values at the edges of the digits-and-`.0` shortcut.
            999_999_999_999_999.0,
            -999_999_999_999_999.0,
            1e15,
            1e16,
            9_007_199_254_740_992.0,
            i64::MAX as f64,
            i64::MIN as f64,
            -1.0,
        ];
        match rng.random_range(0..6) {
            0 => SPECIAL[rng.random_range(0..SPECIAL.len())],
            1 => f64::from_bits(rng.random()),
            2 => rng.random_range(-1e3..1e3),
            // Integral values of every size the shortcut takes, and beyond it.
            3 => (rng.random_range(-2e15..2e15_f64) / 10f64.powi(rng.random_range(0..16))).round(),
            4 => rng.random_range(-200.0..200.0_f64).round() / 2.0,
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
        // A transmitted power of 0 dBm: the power is the gain, whose bytes it repeats.
        p.power_dbm = match rng.random_bool(0.5) {
            true => p.gain_db,
            false => option(rng),
        };
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

    /// The escape test eight bytes at a time against the byte-by-byte rule, over drawn
    /// strings of every length to 40 (bytes near the limits, quotes, backslashes, UTF-8's
    /// high bytes), one byte to escape at every place or none.
    #[test]
    fn the_escape_test_is_the_byte_rule() {
        const BYTES: [u8; 12] = [
            0, 0x1f, 0x20, 0x21, b'"', b'\\', b'a', 0x7f, 0x80, 0xa0, 0xff, b'|',
        ];
        let rule = |s: &[u8]| s.iter().any(|&b| b < 0x20 || b == b'"' || b == b'\\');
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        let (mut escaped, mut plain) = (0, 0);
        for n in 0..4000 {
            let len = n % 41;
            let mut s: Vec<u8> = (0..len)
                .map(|_| match rng.random_bool(0.2) {
                    true => BYTES[rng.random_range(0..BYTES.len())],
                    false => rng.random_range(0x20..0x7f_u8),
                })
                .collect();
            // Half of them clean of escapes but for at most one drawn place.
            if n % 2 == 0 {
                s.retain(|&b| !(b < 0x20 || b == b'"' || b == b'\\'));
                if len > 0 && rng.random_bool(0.5) {
                    let at = rng.random_range(0..s.len().max(1)).min(s.len());
                    s.insert(at, [0x1f_u8, b'"', b'\\', 0][rng.random_range(0..4)]);
                }
            }
            assert_eq!(needs_escape(&s), rule(&s), "{s:?}");
            match rule(&s) {
                true => escaped += 1,
                false => plain += 1,
            }
        }
        assert!(escaped > 1000 && plain > 1000, "{escaped} {plain}");
    }

    /// Integers (ranks, orders, the digits of integral reals) against serde_json's
    /// formatter: every one to 10,000, the shortcuts' bounds and the largest.
    #[test]
    fn integers_are_written_as_serde_writes_them() {
        for n in (0..=10_000).chain([u64::from(u32::MAX), u64::MAX - 1, u64::MAX]) {
            let mut out = Vec::new();
            write_u64(&mut out, n).unwrap();
            assert_eq!(
                String::from_utf8(out).unwrap(),
                serde_json::to_string(&n).unwrap()
            );
        }
    }

    /// The digits-and-`.0` shortcut against serde_json's formatter: every integer to ±2000 and
    /// its halves, each power of ten and its neighbours up to 10^17, and the reals next to the
    /// shortcut's bound.
    #[test]
    fn integral_reals_are_written_as_serde_writes_them() {
        let mut values: Vec<f64> = (-4000..=4000).map(|k| f64::from(k) / 2.0).collect();
        for e in 0..=17 {
            let p = 10f64.powi(e);
            values.extend([
                p - 1.0,
                p,
                p + 1.0,
                -p,
                1.0 - p,
                3.0 * p,
                p.next_up(),
                p.next_down(),
            ]);
        }
        let bound = INTEGRAL_BELOW as f64;
        values.extend([
            0.0,
            -0.0,
            bound,
            bound.next_down(),
            -bound.next_down(),
            2f64.powi(53) - 1.0,
        ]);
        for v in values {
            let serde = serde_json::to_string(&v).unwrap();
            let (mut shortcut, mut real) = (Vec::new(), Vec::new());
            write_integral_or_real(&mut shortcut, v).unwrap();
            write_real(&mut real, v).unwrap();
            assert_eq!(String::from_utf8(shortcut).unwrap(), serde, "{v:e}");
            assert_eq!(String::from_utf8(real).unwrap(), serde, "{v:e}");
        }
    }
}
