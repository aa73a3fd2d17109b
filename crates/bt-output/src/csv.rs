//! CSV cells of text that comes from inputs (surface names, reasons): quoted where the CSV
//! grammar needs it, and never read as a formula by a spreadsheet.

/// One CSV text field. A field that begins with `=`, `+`, `-`, `@`, a tab or a carriage return
/// would be evaluated as a formula by spreadsheets (OWASP's CSV injection rule): it is prefixed
/// with `'` and quoted. A field holding a comma, quote or line break is quoted, its quotes
/// doubled (RFC 4180). Numbers are not text fields: write them as they are.
pub fn text_field(s: &str) -> String {
    let formula = s.starts_with(['=', '+', '-', '@', '\t', '\r']);
    if formula {
        format!("\"'{}\"", s.replace('"', "\"\""))
    } else if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separators_are_quoted() {
        assert_eq!(text_field("wall"), "wall");
        assert_eq!(text_field("a,b"), "\"a,b\"");
        assert_eq!(text_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(text_field("two\nlines"), "\"two\nlines\"");
    }

    #[test]
    fn formulas_are_not_formulas() {
        assert_eq!(
            text_field("=HYPERLINK(\"http://x\")"),
            "\"'=HYPERLINK(\"\"http://x\"\")\""
        );
        for start in ["+1", "-1+2", "@SUM(A1)", "\tx", "\rx"] {
            let cell = text_field(start);
            assert!(cell.starts_with("\"'"), "{cell}");
        }
        assert_eq!(text_field("wall=1"), "wall=1");
    }
}
