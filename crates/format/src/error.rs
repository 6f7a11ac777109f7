//! The two located errors: a text that breaks the grammar, and a valid text that describes nothing
//! valid.

use std::fmt;

/// What [`ParseError::found`] holds when the input ended where a token was expected.
pub const END_OF_FILE: &str = "end of file";

/// A file that could not be read, pointing at the offending token.
///
/// Displays as `file:line:column: expected <expected>, found "<found>"` (or `found end of file`), the form
/// editors and terminals turn into a link. Lines and columns are 1-based and count characters, not bytes,
/// so a column is right in a file full of `Ç` and `Ã`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// The file, as the caller named it; `None` when parsing a string.
    pub file: Option<String>,
    pub line: usize,
    pub column: usize,
    /// What the grammar wanted there, e.g. "`QUADROS_SEG`" or "a positive number for `DELTA_t`".
    pub expected: String,
    /// The offending text as written, or [`END_OF_FILE`].
    pub found: String,
}

impl ParseError {
    pub fn new(line: usize, column: usize, expected: impl Into<String>, found: impl Into<String>) -> Self {
        Self { file: None, line, column, expected: expected.into(), found: found.into() }
    }

    /// The same error, naming the file it came from.
    pub fn with_file(mut self, name: impl Into<String>) -> Self {
        self.file = Some(name.into());
        self
    }

    /// Whether the input ended where something else was expected.
    pub fn at_end_of_file(&self) -> bool {
        self.found == END_OF_FILE
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{file}:")?;
        }
        write!(f, "{}:{}: expected {}, found ", self.line, self.column, self.expected)?;
        if self.at_end_of_file() { f.write_str(END_OF_FILE) } else { write!(f, "\"{}\"", self.found) }
    }
}

impl std::error::Error for ParseError {}

/// Which kind of problem a [`FieldError`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldErrorKind {
    /// The text is not valid RON for the format (ron's own message).
    Syntax,
    /// The text parses but describes nothing valid (an unknown name, a negative mass, a cycle …).
    Invalid,
}

/// A description that could not be read or checked: the field at fault (`bodies[3].mass`), its line and
/// column when the description came from text, and what is wrong. Skeletons, body scenes and
/// controllers report their errors in this form.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct FieldError {
    pub kind: FieldErrorKind,
    /// Path of the offending field: struct fields joined by `.`, list items as `[index]`, e.g.
    /// `machines[0].transitions[2].when.params[0]`. Empty when the whole description is concerned.
    pub field: String,
    /// 1-based line, when the description came from text.
    pub line: Option<usize>,
    /// 1-based column, when known.
    pub column: Option<usize>,
    pub message: String,
}

impl fmt::Display for FieldError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.column) {
            (Some(l), Some(c)) => write!(f, "line {l}, column {c}: ")?,
            (Some(l), None) => write!(f, "line {l}: ")?,
            _ => {}
        }
        if self.field.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "field `{}`: {}", self.field, self.message)
        }
    }
}

impl FieldError {
    /// A check that failed on `field`; [`FieldError::locate`] adds its line and column.
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            kind: FieldErrorKind::Invalid,
            field: field.into(),
            line: None,
            column: None,
            message: message.into(),
        }
    }

    /// A ron error placed in `text`, with the path of the field being read. ron reports a missing
    /// field at the end of the struct that lacks it, so its path is that struct's plus the field's name.
    pub fn syntax(text: &str, e: &ron::error::SpannedError) -> Self {
        let (line, column) = (e.span.start.line, e.span.start.col);
        let mut field = crate::ron_path::path_at(text, line, column);
        if let ron::Error::MissingStructField { field: missing, .. } = &e.code {
            // At the closing bracket the innermost frame is still the struct, whose last field is set.
            let outer = match field.rfind(['.', '[']) {
                Some(cut) if !field[cut..].starts_with('[') => field[..cut].to_string(),
                _ => field.clone(),
            };
            field = if outer.is_empty() { missing.to_string() } else { format!("{outer}.{missing}") };
        }
        Self {
            kind: FieldErrorKind::Syntax,
            field,
            line: Some(line),
            column: Some(column),
            message: e.code.to_string(),
        }
    }

    /// Adds the line and column of the field (or of the nearest enclosing item that is written) in
    /// `text` to an error found by the checks.
    pub fn locate(mut self, text: &str) -> Self {
        if let Some(site) = crate::ron_path::site_of(text, &self.field) {
            self.line = Some(site.line);
            self.column = Some(site.column);
        }
        self
    }
}

/// The text of a file that must be UTF-8 (RON is UTF-8 by definition, so unlike `.PAR` there is no
/// Latin-1 fallback), without a leading byte-order mark; the error points at the first bad byte.
pub fn utf8(bytes: &[u8]) -> Result<&str, ParseError> {
    let bytes = bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let good = std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or_default();
        let line = 1 + good.matches('\n').count();
        let column = 1 + good.rsplit('\n').next().unwrap_or_default().chars().count();
        ParseError::new(line, column, "UTF-8 text", format!("byte 0x{:02X}", bytes[e.valid_up_to()]))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_file_line_column_expected_and_found() {
        let e = ParseError::new(3, 9, "a number for `DELTA_t`", "abc");
        assert_eq!(e.to_string(), "3:9: expected a number for `DELTA_t`, found \"abc\"");
        let e = ParseError::new(27, 1, "`FIM_SUPERFÍCIE`", END_OF_FILE).with_file("cena.par");
        assert_eq!(e.to_string(), "cena.par:27:1: expected `FIM_SUPERFÍCIE`, found end of file");
    }

    #[test]
    fn utf8_errors_point_at_the_first_bad_byte() {
        let e = utf8(b"(\n  a: \xFF)").unwrap_err();
        assert_eq!((e.line, e.column, e.found.as_str()), (2, 6, "byte 0xFF"));
        assert_eq!(utf8("ÇÃ".as_bytes()).unwrap(), "ÇÃ");
        assert_eq!(utf8("\u{feff}(a: 1)".as_bytes()).unwrap(), "(a: 1)", "a byte-order mark is dropped");
    }

    #[test]
    fn field_errors_are_located_in_their_text() {
        let text = "Skeleton(\n    bodies: [\n        (mass: 1.0),\n        (mass: -2.0),\n    ],\n)";
        let e = FieldError::invalid("bodies[1].mass", "expected a positive number, found -2").locate(text);
        assert_eq!((e.line, e.column), (Some(4), Some(10)));
        assert_eq!(
            e.to_string(),
            "line 4, column 10: field `bodies[1].mass`: expected a positive number, found -2"
        );
        // A field that is not written is placed at the item that lacks it.
        let e = FieldError::invalid("bodies[0].side", "missing").locate(text);
        assert_eq!((e.line, e.column), (Some(3), Some(9)));
    }
}

/// Why `name` cannot be part of a file name, or `None` when it can: a name from a scene file (a FLEX3D
/// surface's, say) becomes a file name only when it is a plain one — letters, digits, `_`, `-` and `.`,
/// not starting with `.`, at most 64 characters — so that it can never name a path outside the output
/// folder or a hidden file.
pub fn not_a_plain_name(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("a name that is not empty")
    } else if name.chars().count() > 64 {
        Some("a name of at most 64 characters")
    } else if name.starts_with('.') {
        Some("a name that does not start with `.`")
    } else if !name.chars().all(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | '.')) {
        Some("a name of letters, digits, `_`, `-` and `.` (it names output files)")
    } else {
        None
    }
}

#[cfg(test)]
mod name_tests {
    use super::not_a_plain_name;

    #[test]
    fn only_plain_names_become_file_names() {
        for ok in ["toalha", "CORTINA_2", "pano-1.a", "CORTIÇA"] {
            assert_eq!(not_a_plain_name(ok), None, "{ok}");
        }
        for bad in ["", "../../x", "/etc/passwd", "a/b", "a\\b", ".hidden", "..", "a b", &"x".repeat(65)] {
            assert!(not_a_plain_name(bad).is_some(), "{bad:?}");
        }
    }
}
