//! The one rule for names from input (surfaces, materials, boxes, scenes): names are data.
//!
//! A name is 1 to [`MAX_CHARS`] characters, none of them a control character (line breaks,
//! escape sequences, NUL, DEL and the C1 range) or a character that breaks or reorders a line
//! (Unicode line/paragraph separators, bidirectional overrides and isolates). Loaders check it
//! ([`check`]) and refuse the scene with the name's location; every output that prints a name
//! still escapes it or derives an identifier (`bt_pe_<index>`), so a name never becomes code.

/// Longest name accepted, in characters.
pub const MAX_CHARS: usize = 200;

/// Longest name a message prints, in characters of its escaped form: a 1 KB name repeated in
/// 10,000 problems must not make megabytes of error text.
pub const MESSAGE_CHARS: usize = 64;

/// Whether `c` may appear in a name.
fn allowed(c: char) -> bool {
    !(c.is_control()
        || matches!(c, '\u{2028}' | '\u{2029}' | '\u{200e}' | '\u{200f}')
        || ('\u{202a}'..='\u{202e}').contains(&c)
        || ('\u{2066}'..='\u{2069}').contains(&c))
}

/// `Ok` when `name` follows the rule; otherwise what is wrong (lowercase, the name escaped).
pub fn check(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("name is empty".into());
    }
    // Printable ASCII (every imported surface's name, 17,803 in a city): one byte per
    // character, none refused; a byte scan says so without decoding characters.
    if name.len() <= MAX_CHARS && name.bytes().all(|b| (0x20..0x7f).contains(&b)) {
        return Ok(());
    }
    let count = name.chars().count();
    if count > MAX_CHARS {
        return Err(format!(
            "name \"{}\" has {count} characters (at most {MAX_CHARS})",
            shown(name)
        ));
    }
    if let Some((i, c)) = name.chars().enumerate().find(|(_, c)| !allowed(*c)) {
        return Err(format!(
            "name \"{}\" contains the control character U+{:04X} at character {} (names must be printable)",
            shown(name),
            c as u32,
            i + 1
        ));
    }
    Ok(())
}

/// `name` as it may be printed on a terminal or in a text file: quotes, backslashes and every
/// character [`check`] refuses written as Rust escapes (`\n`, `\u{1b}`).
pub fn escape(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        push_escaped(&mut out, c);
    }
    out
}

/// Whether the byte `b` is a printable ASCII character [`escape`] writes as itself.
fn plain_ascii(b: u8) -> bool {
    matches!(b, b' '..=b'~') && b != b'"' && b != b'\\'
}

/// Whether `c` is printed as itself by [`escape`].
fn plain(c: char) -> bool {
    c != '"' && c != '\\' && allowed(c)
}

/// Append `c` as [`escape`] writes it; the number of characters appended. One buffer for the
/// whole name: a `String` per character made `shown` 17 % of loading a city of 17,808 surfaces.
fn push_escaped(out: &mut String, c: char) -> usize {
    if plain(c) {
        out.push(c);
        1
    } else {
        let escaped = c.escape_default();
        let count = escaped.len();
        out.extend(escaped);
        count
    }
}

/// `name` as a message prints it: [`escape`]d, and cut after [`MESSAGE_CHARS`] characters
/// with its length (`wallwall…(1024 bytes)`). Every error and warning that repeats a name from
/// input prints it through here; outputs of valid names (tables, DOT) use [`escape`].
pub fn shown(name: &str) -> String {
    // Most names are short printable ASCII, shown as they are: one scan instead of a push per
    // character (validation shows every surface's name in its location: 17,803 in Munich).
    if name.len() <= MESSAGE_CHARS && name.bytes().all(plain_ascii) {
        return name.to_string();
    }
    let mut out = String::new();
    let mut count = 0;
    for c in name.chars() {
        let before = out.len();
        count += push_escaped(&mut out, c);
        if count > MESSAGE_CHARS {
            out.truncate(before);
            return format!("{out}…({} bytes)", name.len());
        }
    }
    out
}

/// What separates the surface names of a path in one line or CSV cell (` > `).
pub const PATH_SEPARATOR: &str = " > ";

/// A path's surface names as one text (terminal tables, CSV cells): each name [`escape`]d, with
/// a `>` inside a name written `\>`, so [`PATH_SEPARATOR`] only ever separates names: the
/// names `a > b` and `c` give `a \> b > c`, never the path `a`, `b`, `c`.
pub fn path<S: AsRef<str>>(names: &[S]) -> String {
    route(names, |_| false)
}

/// [`path`], with the names `crossed(k)` marks written `through "NAME"`: surfaces a path
/// crosses (transmission) rather than reflects on. [`escape`] writes every `"` inside a name as
/// `\"`, so the marker's quotes never come from a name.
pub fn route<S: AsRef<str>>(names: &[S], crossed: impl Fn(usize) -> bool) -> String {
    let names: Vec<String> = (names.iter().enumerate())
        .map(|(k, n)| {
            let name = escape(n.as_ref()).replace('>', "\\>");
            match crossed(k) {
                true => format!("through \"{name}\""),
                false => name,
            }
        })
        .collect();
    names.join(PATH_SEPARATOR)
}

/// What separates an edge's two face names in a path record's `surfaces` (`"A|B"`).
pub const EDGE_SEPARATOR: char = '|';

/// An edge's name in a path record: its face's name for a free edge, `face0|face_n` for a
/// wedge, with `\` inside a name written `\\` and `|` written `\|`, so that [`split_edge`]
/// gives back the two names whatever they hold: the faces `a|b` and `c` give `a\|b|c`, never
/// the faces `a`, `b|c`. The one place an edge's name is made (reports, the viewer's matching).
pub fn edge(face0: &str, face_n: Option<&str>) -> String {
    let escaped = |name: &str| name.replace('\\', "\\\\").replace(EDGE_SEPARATOR, "\\|");
    match face_n {
        Some(face_n) => format!("{}{EDGE_SEPARATOR}{}", escaped(face0), escaped(face_n)),
        None => escaped(face0),
    }
}

/// The face names of an edge's name made by [`edge`]: `(face0, None)` for a free edge,
/// `(face0, Some(face_n))` for a wedge; `None` for text [`edge`] never makes (a `\` before
/// anything but `\` or `|`, a trailing `\`, more than one unescaped `|`).
pub fn split_edge(text: &str) -> Option<(String, Option<String>)> {
    let mut names = vec![String::new()];
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        match c {
            '\\' => match chars.next() {
                Some(e @ ('\\' | EDGE_SEPARATOR)) => names.last_mut()?.push(e),
                _ => return None,
            },
            EDGE_SEPARATOR if names.len() == 1 => names.push(String::new()),
            EDGE_SEPARATOR => return None,
            c => names.last_mut()?.push(c),
        }
    }
    let mut names = names.into_iter();
    Some((names.next()?, names.next()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The byte scan for printable ASCII decides as the character rule does: every ASCII
    /// byte inside a name and alone, and names at and over the length limit.
    #[test]
    fn the_ascii_scan_agrees_with_the_character_rule() {
        let by_chars = |name: &str| {
            !name.is_empty() && name.chars().count() <= MAX_CHARS && name.chars().all(allowed)
        };
        for b in 0u8..0x80 {
            let c = char::from(b);
            for name in [format!("a{c}z"), c.to_string(), format!("{c}{c}")] {
                assert_eq!(check(&name).is_ok(), by_chars(&name), "{name:?}");
            }
        }
        for n in [MAX_CHARS, MAX_CHARS + 1] {
            let name = "x".repeat(n);
            assert_eq!(check(&name).is_ok(), by_chars(&name), "{n} characters");
        }
    }

    #[test]
    fn printable_names_pass() {
        for n in ["wall", "sofa.top", "Fenster Süd", "壁-1", "a b (2)"] {
            assert_eq!(check(n), Ok(()), "{n}");
        }
    }

    #[test]
    fn control_characters_and_long_names_fail() {
        let injection = "wall\nmodule pwn; initial $display(1); endmodule\n//";
        let e = check(injection).unwrap_err();
        assert!(e.contains("U+000A at character 5"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        for n in [
            "a\u{1b}[31m",
            "nul\0",
            "del\u{7f}",
            "bidi\u{202e}",
            "ls\u{2028}",
            "",
        ] {
            assert!(check(n).is_err(), "{n:?}");
        }
        assert!(check(&"x".repeat(MAX_CHARS)).is_ok());
        assert!(check(&"x".repeat(MAX_CHARS + 1)).is_err());
    }

    #[test]
    fn messages_cut_long_names() {
        let long = "n".repeat(1024);
        let s = shown(&long);
        assert_eq!(s, format!("{}…(1024 bytes)", "n".repeat(MESSAGE_CHARS)));
        assert_eq!(shown("wall\n"), "wall\\n");
        // An escape is never cut in half.
        let s = shown(&format!("{}\u{1b}", "x".repeat(MESSAGE_CHARS - 2)));
        assert!(s.ends_with("x…(63 bytes)"), "{s}");
        assert!(check(&long).unwrap_err().len() < 200);
    }

    #[test]
    fn a_separator_inside_a_name_is_escaped_in_paths() {
        assert_eq!(path(&["a > b", "c"]), "a \\> b > c");
        assert_eq!(path(&["wall", "floor"]), "wall > floor");
        assert_eq!(path::<&str>(&[]), "");
        assert_eq!(path(&["x\\>"]), "x\\\\\\>");
    }

    #[test]
    fn escape_leaves_no_control_character() {
        let e = escape("a\"b\\c\n\u{1b}\0");
        assert_eq!(e, "a\\\"b\\\\c\\n\\u{1b}\\u{0}");
        assert_eq!(escape("sofa.top"), "sofa.top");
    }

    #[test]
    fn edge_names_split_back_into_their_faces() {
        let cases: [(&str, Option<&str>, &str); 6] = [
            ("wall", Some("floor"), "wall|floor"),
            ("screen", None, "screen"),
            ("a|b", Some("c"), "a\\|b|c"),
            ("a", Some("b|c"), "a|b\\|c"),
            ("x\\", Some("|"), "x\\\\|\\|"),
            ("free|edge\\", None, "free\\|edge\\\\"),
        ];
        for (face0, face_n, text) in cases {
            assert_eq!(edge(face0, face_n), text);
            let split = split_edge(text).unwrap();
            assert_eq!(
                (split.0.as_str(), split.1.as_deref()),
                (face0, face_n),
                "{text}"
            );
        }
        for bad in ["a|b|c", "a\\", "a\\b", "\\"] {
            assert_eq!(split_edge(bad), None, "{bad}");
        }
    }

    /// The one-buffer `escape` and `shown` write what the former per-character form wrote
    /// (kept here as the reference), for every kind of character and around the cut.
    #[test]
    fn one_buffer_forms_match_the_per_character_reference() {
        fn reference_escape(name: &str) -> String {
            (name.chars())
                .map(|c| match c == '"' || c == '\\' || !allowed(c) {
                    true => c.escape_default().to_string(),
                    false => c.to_string(),
                })
                .collect()
        }
        fn reference_shown(name: &str) -> String {
            let mut out = String::new();
            let mut count = 0;
            for c in name.chars() {
                let piece = reference_escape(c.encode_utf8(&mut [0; 4]));
                count += piece.chars().count();
                if count > MESSAGE_CHARS {
                    return format!("{out}…({} bytes)", name.len());
                }
                out.push_str(&piece);
            }
            out
        }
        let pieces = [
            "a", "\"", "\\", "\n", "\u{1b}", "é", "壁", "\u{202e}", "\u{2028}", "\0",
        ];
        for len in [0, 1, 2, 30, 60, 63, 64, 65, 70, 200] {
            for (k, piece) in pieces.iter().enumerate() {
                let name: String = (0..len)
                    .map(|i| if i % (k + 2) == 1 { *piece } else { "x" })
                    .collect();
                assert_eq!(escape(&name), reference_escape(&name), "{name:?}");
                assert_eq!(shown(&name), reference_shown(&name), "{name:?}");
            }
        }
    }
}
