//! The one parse error of both scene languages.

use std::fmt;

/// What [`ParseError::found`] holds when the input ended where a token was expected.
pub const END_OF_FILE: &str = "end of file";

/// A scene file that could not be read, pointing at the offending token.
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
}
