//! The PLY header grammar shared by the mesh and point-cloud readers: `ply`, one `format` line,
//! `element <name> <count>` each followed by its `property <type> <name>` or
//! `property list <count type> <item type> <name>` lines, `comment`/`obj_info` lines, and
//! `end_header`. The readers choose which elements and properties they use and wrap
//! [`PlyHeaderError`] into their own error types (file name, variant).

use super::{PlyFormat, Scalar};

/// The type of one PLY property.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyPropertyKind {
    /// One value.
    Scalar(Scalar),
    /// A count of type `count` followed by that many values of type `item`.
    List {
        /// The type of the length (always an integer type).
        count: Scalar,
        /// The type of each item.
        item: Scalar,
    },
}

/// One `property` line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlyProperty {
    /// The property name (unique within its element).
    pub name: String,
    /// Its type.
    pub kind: PlyPropertyKind,
}

/// One `element` line with its properties.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlyElement {
    /// The element name (`vertex`, `face`, ...).
    pub name: String,
    /// How many entries the body holds, as claimed (check it against the body length).
    pub count: u64,
    /// The properties of each entry, in file order.
    pub properties: Vec<PlyProperty>,
}

impl PlyElement {
    /// Fewest body bytes one entry can occupy: in binary, scalars at their size and list
    /// counts with zero items; in ASCII one character plus one separator per property.
    pub fn min_bytes(&self, format: PlyFormat) -> u64 {
        self.properties
            .iter()
            .map(|p| match (format, p.kind) {
                (PlyFormat::Ascii, _) => 2,
                (_, PlyPropertyKind::Scalar(s) | PlyPropertyKind::List { count: s, .. }) => {
                    s.size() as u64
                }
            })
            .sum()
    }

    /// The index of the property called `name`.
    pub fn position(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name)
    }
}

/// A parsed PLY header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlyHeader {
    /// The body encoding.
    pub format: PlyFormat,
    /// The elements in body order.
    pub elements: Vec<PlyElement>,
    /// Byte offset of the body (just after the `end_header` line).
    pub body_start: usize,
    /// Number of header lines (an ASCII body's first line is `lines + 1`).
    pub lines: usize,
}

/// What is wrong with a PLY header, and on which 1-based line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {kind}")]
pub struct PlyHeaderError {
    /// The header line (for a missing `end_header`, the line after the last one).
    pub line: usize,
    /// What is wrong.
    pub kind: PlyHeaderErrorKind,
}

/// The kinds of [`PlyHeaderError`]; the messages name the offending text.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PlyHeaderErrorKind {
    /// The first line is not `ply`.
    #[error("not a PLY file: first line must be \"ply\"")]
    NotPly,
    /// A header line is not UTF-8.
    #[error("header line is not text")]
    NotText,
    /// The bytes end before `end_header`.
    #[error("header has no end_header line")]
    NoEndHeader,
    /// `end_header` came without a `format` line.
    #[error("header has no format line")]
    NoFormat,
    /// A `format` line names an encoding other than the three of PLY (a valid-looking file
    /// this reader cannot read).
    #[error("unknown PLY format \"{}\"", bt_scene::name::shown(.0))]
    UnknownFormat(String),
    /// A `format` line names a version other than `1.0`.
    #[error("unsupported PLY format version \"{}\"", bt_scene::name::shown(.0))]
    UnsupportedVersion(String),
    /// An element count that is not a non-negative integer.
    #[error("element count \"{}\" is not a non-negative integer", bt_scene::name::shown(.0))]
    BadCount(String),
    /// A `property` line before the first `element` line.
    #[error("property declared before any element")]
    PropertyBeforeElement,
    /// A property type that PLY does not define.
    #[error("unknown property type \"{}\"", bt_scene::name::shown(.0))]
    UnknownType(String),
    /// A list whose count type is a floating-point type.
    #[error("list \"{}\" has a non-integer count type", bt_scene::name::shown(.0))]
    NonIntegerListCount(String),
    /// Two properties of one element with the same name.
    #[error("duplicate property \"{}\"", bt_scene::name::shown(.0))]
    DuplicateProperty(String),
    /// A line that does not fit the grammar (wrong number of words, unknown keyword).
    #[error("unexpected header line \"{}\"", bt_scene::name::shown(.0))]
    Malformed(String),
}

impl PlyHeaderErrorKind {
    /// Whether the header is well formed but uses an encoding or version no reader supports.
    pub fn is_unsupported(&self) -> bool {
        matches!(self, Self::UnknownFormat(_) | Self::UnsupportedVersion(_))
    }
}

/// The next line of `bytes` from `*pos` without its `\n` or `\r\n`; a last line without a
/// newline counts. `None` at the end.
fn next_line<'a>(bytes: &'a [u8], pos: &mut usize) -> Option<&'a [u8]> {
    let rest = bytes.get(*pos..).filter(|r| !r.is_empty())?;
    let (line, advance) = match rest.iter().position(|&b| b == b'\n') {
        Some(i) => (&rest[..i], i + 1),
        None => (rest, rest.len()),
    };
    *pos += advance;
    Some(line.strip_suffix(b"\r").unwrap_or(line))
}

/// Words of a header line looked at, in a list on the stack (a `Vec` per line was most of a
/// small mesh's allocations). The longest valid line other than a comment has five words
/// (`property list <count> <item> <name>`), and every line of six words or more other than a
/// comment is malformed whatever its further words, so the first six decide.
const MAX_WORDS: usize = 6;

impl PlyHeader {
    /// Parses the header at the start of `bytes` (the body is not looked at).
    pub fn parse(bytes: &[u8]) -> Result<PlyHeader, PlyHeaderError> {
        let mut pos = 0usize;
        let mut line = 0usize;
        let mut format = None;
        let mut elements: Vec<PlyElement> = Vec::new();
        loop {
            let fail = |kind| PlyHeaderError {
                line: line + 1,
                kind,
            };
            let raw =
                next_line(bytes, &mut pos).ok_or_else(|| fail(PlyHeaderErrorKind::NoEndHeader))?;
            let text = std::str::from_utf8(raw).map_err(|_| fail(PlyHeaderErrorKind::NotText))?;
            line += 1;
            let fail = |kind| PlyHeaderError { line, kind };
            if line == 1 {
                if text.trim() != "ply" {
                    return Err(fail(PlyHeaderErrorKind::NotPly));
                }
                continue;
            }
            let mut words = [""; MAX_WORDS];
            let mut count = 0;
            for word in text.split_ascii_whitespace().take(MAX_WORDS) {
                words[count] = word;
                count += 1;
            }
            match &words[..count] {
                [] | ["comment" | "obj_info", ..] => {}
                ["format", rest @ ..] => format = Some(parse_format(rest, text).map_err(fail)?),
                ["element", name, count] => elements.push(PlyElement {
                    name: (*name).to_owned(),
                    count: count
                        .parse()
                        .map_err(|_| fail(PlyHeaderErrorKind::BadCount((*count).to_owned())))?,
                    properties: Vec::new(),
                }),
                ["property", rest @ ..] => {
                    let element = elements
                        .last_mut()
                        .ok_or(fail(PlyHeaderErrorKind::PropertyBeforeElement))?;
                    let property = parse_property(rest, text).map_err(fail)?;
                    if element.position(&property.name).is_some() {
                        return Err(fail(PlyHeaderErrorKind::DuplicateProperty(property.name)));
                    }
                    element.properties.push(property);
                }
                ["end_header"] => break,
                _ => return Err(fail(PlyHeaderErrorKind::Malformed(text.to_owned()))),
            }
        }
        let format = format.ok_or(PlyHeaderError {
            line,
            kind: PlyHeaderErrorKind::NoFormat,
        })?;
        Ok(PlyHeader {
            format,
            elements,
            body_start: pos,
            lines: line,
        })
    }
}

/// The words after `format`: an encoding and the version `1.0`.
fn parse_format(words: &[&str], text: &str) -> Result<PlyFormat, PlyHeaderErrorKind> {
    let name = words.first().copied().unwrap_or("");
    let format =
        PlyFormat::from_name(name).ok_or_else(|| PlyHeaderErrorKind::UnknownFormat(name.into()))?;
    match words {
        [_, "1.0"] => Ok(format),
        [_, version] => Err(PlyHeaderErrorKind::UnsupportedVersion((*version).into())),
        _ => Err(PlyHeaderErrorKind::Malformed(text.into())),
    }
}

/// The words after `property`: `<type> <name>` or `list <count type> <item type> <name>`.
fn parse_property(words: &[&str], text: &str) -> Result<PlyProperty, PlyHeaderErrorKind> {
    let scalar = |name: &str| {
        Scalar::from_ply_name(name).ok_or_else(|| PlyHeaderErrorKind::UnknownType(name.into()))
    };
    let (kind, name) = match words {
        ["list", count, item, name] => {
            let count = scalar(count)?;
            let item = scalar(item)?;
            if !count.is_integer() {
                return Err(PlyHeaderErrorKind::NonIntegerListCount((*name).into()));
            }
            (PlyPropertyKind::List { count, item }, name)
        }
        [ty, name] => (PlyPropertyKind::Scalar(scalar(ty)?), name),
        _ => return Err(PlyHeaderErrorKind::Malformed(text.into())),
    };
    Ok(PlyProperty {
        name: (*name).to_owned(),
        kind,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use PlyHeaderErrorKind as K;

    #[test]
    fn a_mesh_header() {
        let text =
            b"ply\r\nformat binary_big_endian 1.0\ncomment x\nelement vertex 2\nproperty float x\n\
                     element face 1\nproperty list uchar int vertex_indices\nend_header\nBODY";
        let h = PlyHeader::parse(text).unwrap();
        assert_eq!(h.format, PlyFormat::BinaryBigEndian);
        assert_eq!(h.lines, 8);
        assert_eq!(&text[h.body_start..], b"BODY");
        assert_eq!(h.elements[0].count, 2);
        assert_eq!(h.elements[0].min_bytes(h.format), 4);
        assert_eq!(h.elements[1].min_bytes(PlyFormat::Ascii), 2);
        assert_eq!(
            h.elements[1].properties[0].kind,
            PlyPropertyKind::List {
                count: Scalar::U8,
                item: Scalar::I32
            }
        );
        assert_eq!(h.elements[1].position("vertex_indices"), Some(0));
    }

    #[test]
    fn every_error_names_its_line() {
        // One case per line: (header, line the error names, error).
        #[rustfmt::skip]
        let cases: &[(&[u8], usize, K)] = &[
            (b"plx\n",                                                1, K::NotPly),
            (b"ply\nformat ascii 1.0\n",                              3, K::NoEndHeader),
            (b"ply\n\xff\n",                                          2, K::NotText),
            (b"ply\nend_header\n",                                    2, K::NoFormat),
            (b"ply\nformat middle 1.0\n",                             2, K::UnknownFormat("middle".into())),
            (b"ply\nformat ascii 2.0\n",                              2, K::UnsupportedVersion("2.0".into())),
            (b"ply\nformat ascii\n",                                  2, K::Malformed("format ascii".into())),
            (b"ply\nelement vertex -3\n",                             2, K::BadCount("-3".into())),
            (b"ply\nproperty float x\n",                              2, K::PropertyBeforeElement),
            (b"ply\nelement v 1\nproperty quad x\n",                  3, K::UnknownType("quad".into())),
            (b"ply\nelement v 1\nproperty list float int f\n",        3, K::NonIntegerListCount("f".into())),
            (b"ply\nelement v 1\nproperty float x\nproperty int x\n", 4, K::DuplicateProperty("x".into())),
            (b"ply\nelement v\n",                                     2, K::Malformed("element v".into())),
            (b"ply\nvertex 3\n",                                      2, K::Malformed("vertex 3".into())),
            // Lines longer than the words looked at: the whole line is named.
            (b"ply\nformat ascii 1.0 a b c d\n",                      2, K::Malformed("format ascii 1.0 a b c d".into())),
            (b"ply\nformat middle 1.0 a b c d\n",                     2, K::UnknownFormat("middle".into())),
            (b"ply\nelement v 1 a b c d\n",                           2, K::Malformed("element v 1 a b c d".into())),
            (b"ply\nelement v 1\nproperty list uchar int f g h\n",     3, K::Malformed("property list uchar int f g h".into())),
            (b"ply\nproperty list uchar int f g h\n",                  2, K::PropertyBeforeElement),
            (b"ply\nend_header a b c d e f\n",                        2, K::Malformed("end_header a b c d e f".into())),
        ];
        for (bytes, line, kind) in cases {
            let e = PlyHeader::parse(bytes).unwrap_err();
            assert_eq!(
                (e.line, &e.kind),
                (*line, kind),
                "{}",
                String::from_utf8_lossy(bytes)
            );
        }
        assert!(K::UnknownFormat(String::new()).is_unsupported() && !K::NoFormat.is_unsupported());
        // A comment of any length is skipped.
        let long = b"ply\ncomment a b c d e f g h\nformat ascii 1.0\nend_header\n";
        assert_eq!(PlyHeader::parse(long).expect("a comment").lines, 4);
    }
}
