//! anima's own scene files: a [`Flex3dScene`] written in RON.
//!
//! A `.PAR` script cannot say everything a run needs (gravity, the friction reading, the integrator,
//! the reconstruction switches of spec S7.2); a RON scene says all of it, field for field as
//! `anima_cloth::flex3d::Flex3dScene` declares it, so the struct is the schema. Unknown fields are
//! errors, not silently ignored: a misspelt option would otherwise fall back to its default unseen.

use anima_cloth::flex3d::Flex3dScene;
use ron::error::{Error, SpannedError};

use crate::ParseError;
use crate::error::END_OF_FILE;

/// The comment every written scene starts with.
const HEADER: &str = "// anima FLEX3D scene (Nedel 1993). Units are SI (s, m, kg, N); y is up.\n";

/// Reads a scene. Errors carry ron's position and its reason split into expected and found.
pub fn from_ron_str(src: &str) -> Result<Flex3dScene, ParseError> {
    ron::Options::default().from_str(src).map_err(|e| parse_error(src, e))
}

/// Writes a scene as pretty RON after a header comment. Reals are printed in their shortest form that
/// reads back to the same bits, so [`from_ron_str`] returns exactly the scene written.
pub fn to_ron_string(scene: &Flex3dScene) -> String {
    let config = ron::ser::PrettyConfig::new();
    // The scene is plain data (numbers, strings, enums), which RON can always represent.
    let body = ron::ser::to_string_pretty(scene, config).expect("a scene always serialises to RON");
    format!("{HEADER}{body}\n")
}

fn backticked(names: &[&str]) -> String {
    names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
}

fn of(outer: &Option<String>) -> String {
    outer.as_ref().map(|o| format!(" of `{o}`")).unwrap_or_default()
}

/// Turns ron's error into expected/found at its start position.
pub(crate) fn parse_error(src: &str, e: SpannedError) -> ParseError {
    // Some of ron's spans start at the whitespace before the offending token.
    let (line, column) = skip_whitespace(src, e.span.start.line, e.span.start.col);
    let here = || text_at(src, line, column);
    let (expected, found) = match &e.code {
        Error::NoSuchStructField { expected, found, outer } => {
            (format!("a field{}: {}", of(outer), backticked(expected)), found.clone())
        }
        Error::NoSuchEnumVariant { expected, found, outer } => {
            (format!("a variant{}: {}", of(outer), backticked(expected)), found.clone())
        }
        Error::MissingStructField { field, outer } => {
            (format!("field `{field}`{}", of(outer)), ")".to_owned())
        }
        Error::DuplicateStructField { field, outer } => {
            (format!("field `{field}`{} only once", of(outer)), field.to_string())
        }
        Error::InvalidValueForType { expected, found } => (expected.clone(), found.clone()),
        Error::ExpectedDifferentLength { expected, found } => (expected.clone(), format!("{found} elements")),
        Error::SuggestRawIdentifier(name) => (format!("the raw identifier `r#{name}`"), name.clone()),
        Error::Eof => ("more RON".to_owned(), END_OF_FILE.to_owned()),
        Error::Message(message) => (message.clone(), here()),
        other => {
            // ron's other messages read "Expected float", "Expected closing `)`", …
            let message = other.to_string();
            let expected = match message.strip_prefix("Expected ") {
                Some(rest) => rest.to_owned(),
                None => format!("valid RON ({message})"),
            };
            (expected, here())
        }
    };
    ParseError::new(line, column, expected, found)
}

/// The first non-whitespace position at or after 1-based (`line`, `column`); the position itself when
/// only whitespace follows.
fn skip_whitespace(src: &str, line: usize, column: usize) -> (usize, usize) {
    for (k, text) in src.lines().enumerate().skip(line.saturating_sub(1)) {
        let skip = if k + 1 == line { column.saturating_sub(1) } else { 0 };
        if let Some(offset) = text.chars().skip(skip).position(|ch| !ch.is_whitespace()) {
            return (k + 1, skip + offset + 1);
        }
    }
    (line, column)
}

/// The token starting at 1-based (`line`, `column`), in characters: a word, or a single punctuation
/// character, or the end of the file.
fn text_at(src: &str, line: usize, column: usize) -> String {
    let Some(rest) =
        src.lines().nth(line.saturating_sub(1)).map(|l| l.chars().skip(column.saturating_sub(1)))
    else {
        return END_OF_FILE.to_owned();
    };
    let rest: String = rest.collect();
    let is_punct = |c: char| matches!(c, ',' | '(' | ')' | '[' | ']' | '{' | '}' | ':');
    let word: String = rest.chars().take_while(|&c| !c.is_whitespace() && !is_punct(c)).collect();
    match (word.is_empty(), rest.chars().next()) {
        (false, _) => word,
        (true, Some(c)) => c.to_string(),
        (true, None) if src.lines().nth(line).is_some() => "end of line".to_owned(),
        (true, None) => END_OF_FILE.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_at_finds_words_punctuation_and_the_end() {
        let src = "(\n  dt_s: abc,\n)";
        assert_eq!(text_at(src, 2, 9), "abc");
        assert_eq!(text_at(src, 2, 3), "dt_s");
        assert_eq!(text_at(src, 3, 1), ")");
        assert_eq!(text_at(src, 3, 2), END_OF_FILE);
        assert_eq!(text_at(src, 9, 1), END_OF_FILE);
        assert_eq!(skip_whitespace(src, 2, 8), (2, 9));
        assert_eq!(skip_whitespace(src, 2, 14), (3, 1));
        assert_eq!(skip_whitespace(src, 3, 2), (3, 2));
    }
}
