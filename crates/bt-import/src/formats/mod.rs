//! The byte-level layer shared by the PLY and PCD readers of [`crate::mesh`] and [`crate::cloud`]: the
//! numeric scalar types, their spellings in PLY headers (`float`, `uchar`, `int32`, ...) and in
//! PCD headers (`TYPE` letter + `SIZE`), their sizes, and exact decoding of one binary value.
//!
//! [`ply`] holds the one PLY header grammar both readers parse with ([`PlyHeader::parse`]); its
//! [`PlyHeaderError`] names the line and the offending text, and each reader wraps it into its
//! own error type (file name, variant). No I/O. Values decode to `f64` exactly (every PLY/PCD type up to 32 bits is exact in f64;
//! 64-bit integers round to the nearest f64).

pub mod ply;
pub use ply::{
    PlyElement, PlyHeader, PlyHeaderError, PlyHeaderErrorKind, PlyProperty, PlyPropertyKind,
};

/// A numeric scalar type of PLY or PCD.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    /// Signed 8-bit integer (PLY `char`/`int8`, PCD `I 1`).
    I8,
    /// Unsigned 8-bit integer (PLY `uchar`/`uint8`, PCD `U 1`).
    U8,
    /// Signed 16-bit integer (PLY `short`/`int16`, PCD `I 2`).
    I16,
    /// Unsigned 16-bit integer (PLY `ushort`/`uint16`, PCD `U 2`).
    U16,
    /// Signed 32-bit integer (PLY `int`/`int32`, PCD `I 4`).
    I32,
    /// Unsigned 32-bit integer (PLY `uint`/`uint32`, PCD `U 4`).
    U32,
    /// Signed 64-bit integer (PCD `I 8` only).
    I64,
    /// Unsigned 64-bit integer (PCD `U 8` only).
    U64,
    /// IEEE 754 single precision (PLY `float`/`float32`, PCD `F 4`).
    F32,
    /// IEEE 754 double precision (PLY `double`/`float64`, PCD `F 8`).
    F64,
}

impl Scalar {
    /// The type a PLY header names (`property <type> <name>`), both the classic and the
    /// sized spellings; `None` for anything else (PLY has no 64-bit integers).
    pub fn from_ply_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// The type of a PCD field from its `TYPE` letter (`b'F'`, `b'I'`, `b'U'`) and its `SIZE`
    /// in bytes; `None` for combinations PCD does not define (e.g. `F 2`).
    pub fn from_pcd(kind: u8, size: usize) -> Option<Scalar> {
        Some(match (kind, size) {
            (b'F', 4) => Scalar::F32,
            (b'F', 8) => Scalar::F64,
            (b'I', 1) => Scalar::I8,
            (b'I', 2) => Scalar::I16,
            (b'I', 4) => Scalar::I32,
            (b'I', 8) => Scalar::I64,
            (b'U', 1) => Scalar::U8,
            (b'U', 2) => Scalar::U16,
            (b'U', 4) => Scalar::U32,
            (b'U', 8) => Scalar::U64,
            _ => return None,
        })
    }

    /// Size of one value, bytes.
    pub fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// Whether the type is an integer type (list counts and vertex indices must be).
    pub fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Decodes one value from the first `self.size()` bytes of `b` (panics if `b` is shorter:
    /// callers slice the record after checking its length).
    #[inline(always)]
    pub fn decode(self, b: &[u8], big_endian: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big_endian {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(get!(i16, 2)),
            Scalar::U16 => f64::from(get!(u16, 2)),
            Scalar::I32 => f64::from(get!(i32, 4)),
            Scalar::U32 => f64::from(get!(u32, 4)),
            Scalar::I64 => get!(i64, 8) as f64,
            Scalar::U64 => get!(u64, 8) as f64,
            Scalar::F32 => f64::from(get!(f32, 4)),
            Scalar::F64 => get!(f64, 8),
        }
    }
}

/// The body encodings of PLY (`format <encoding> 1.0`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyFormat {
    /// `format ascii 1.0`.
    Ascii,
    /// `format binary_little_endian 1.0`.
    BinaryLittleEndian,
    /// `format binary_big_endian 1.0`.
    BinaryBigEndian,
}

impl PlyFormat {
    /// The encoding a PLY `format` line names; `None` for anything else.
    pub fn from_name(name: &str) -> Option<PlyFormat> {
        Some(match name {
            "ascii" => PlyFormat::Ascii,
            "binary_little_endian" => PlyFormat::BinaryLittleEndian,
            "binary_big_endian" => PlyFormat::BinaryBigEndian,
            _ => return None,
        })
    }

    /// The name written in a `format` line.
    pub fn name(self) -> &'static str {
        match self {
            PlyFormat::Ascii => "ascii",
            PlyFormat::BinaryLittleEndian => "binary_little_endian",
            PlyFormat::BinaryBigEndian => "binary_big_endian",
        }
    }

    /// Whether binary values are stored most significant byte first.
    pub fn is_big_endian(self) -> bool {
        self == PlyFormat::BinaryBigEndian
    }
}

/// Whether the PLY header at the start of `head` declares faces (an `element face N` line with
/// N other than `0`): how a loader tells a mesh from a point cloud without reading the body.
/// `None` when `head` holds no `end_header` (not PLY, or a header longer than `head`). Only
/// the header is looked at; its grammar is checked by the readers.
pub fn ply_declares_faces(head: &[u8]) -> Option<bool> {
    let text = String::from_utf8_lossy(head);
    let end = text.find("end_header")?;
    Some(text[..end].lines().any(|l| {
        let mut w = l.split_whitespace();
        w.next() == Some("element")
            && w.next() == Some("face")
            && w.next().is_some_and(|c| c != "0")
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_sizes_and_decoding() {
        assert_eq!(Scalar::from_ply_name("uchar"), Some(Scalar::U8));
        assert_eq!(Scalar::from_ply_name("float64"), Some(Scalar::F64));
        assert_eq!(Scalar::from_ply_name("int64"), None);
        assert_eq!(Scalar::from_pcd(b'U', 8), Some(Scalar::U64));
        assert_eq!(Scalar::from_pcd(b'F', 2), None);
        assert_eq!(Scalar::I16.size(), 2);
        assert!(Scalar::U32.is_integer() && !Scalar::F32.is_integer());
        assert_eq!(Scalar::I16.decode(&(-300i16).to_le_bytes(), false), -300.0);
        assert_eq!(Scalar::I16.decode(&(-300i16).to_be_bytes(), true), -300.0);
        assert_eq!(
            Scalar::F32.decode(&0.1f32.to_le_bytes(), false),
            f64::from(0.1f32)
        );
        assert_eq!(
            Scalar::U64.decode(&u64::MAX.to_be_bytes(), true),
            u64::MAX as f64
        );
        for f in [
            PlyFormat::Ascii,
            PlyFormat::BinaryLittleEndian,
            PlyFormat::BinaryBigEndian,
        ] {
            assert_eq!(PlyFormat::from_name(f.name()), Some(f));
        }
        assert_eq!(PlyFormat::from_name("binary"), None);
    }

    #[test]
    fn face_sniffing() {
        let mesh = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
        let cloud = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nelement face 0\nend_header\n";
        assert_eq!(ply_declares_faces(mesh), Some(true));
        assert_eq!(ply_declares_faces(cloud), Some(false));
        assert_eq!(ply_declares_faces(&mesh[..40]), None);
    }
}
