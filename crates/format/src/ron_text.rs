//! RON text in and out: located errors, and which struct a file holds.

use ron::error::{Error, SpannedError};
use serde::de::DeserializeOwned;

use crate::{END_OF_FILE, ParseError};

/// Reads a `T` from RON text. Errors carry ron's position and its reason split into expected and found.
pub fn from_str<T: DeserializeOwned>(src: &str) -> Result<T, ParseError> {
    ron::Options::default().from_str(src).map_err(|e| parse_error(src, &e))
}

/// The struct name a RON text starts with after comments and `#![…]` attributes (`BodyScene` for
/// `BodyScene(…)`), which says what kind of file it is; `None` for an unnamed `(…)`.
pub fn struct_name(src: &str) -> Option<&str> {
    let mut rest = src;
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.split_once('\n').map_or("", |(_, after)| after);
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.split_once("*/").map_or("", |(_, after)| after);
        } else if let Some(r) = rest.strip_prefix("#![") {
            rest = r.split_once(']').map_or("", |(_, after)| after);
        } else {
            break;
        }
    }
    let end = rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(rest.len());
    (end > 0 && rest[end..].trim_start().starts_with('(')).then(|| &rest[..end])
}

fn backticked(names: &[&str]) -> String {
    names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
}

fn of(outer: &Option<String>) -> String {
    outer.as_ref().map(|o| format!(" of `{o}`")).unwrap_or_default()
}

/// Turns ron's error into expected and found at its start position.
pub fn parse_error(src: &str, e: &SpannedError) -> ParseError {
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

    #[test]
    fn struct_names_are_found_after_comments_and_attributes() {
        assert_eq!(struct_name("// x\n/* y */ #![enable(implicit_some)]\nBodyScene (\n)"), Some("BodyScene"));
        assert_eq!(struct_name("SheetScene(sheet: ())"), Some("SheetScene"));
        assert_eq!(struct_name("// unnamed\n(\n  a: 1,\n)"), None);
        assert_eq!(struct_name("Some"), None, "a name must open a struct");
        assert_eq!(struct_name(""), None);
    }

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code, reason = "only the errors are read")]
    struct Thing {
        speed_m_s: f64,
        kind: Kind,
    }

    #[derive(Debug, serde::Deserialize)]
    enum Kind {
        Fast,
        Slow,
    }

    #[test]
    fn ron_errors_become_expected_and_found() {
        let e = from_str::<Thing>("(\n  speed_m_s: 1.0,\n  knd: Fast,\n)").unwrap_err();
        assert_eq!((e.line, e.column, e.found.as_str()), (3, 3, "knd"));
        assert!(e.expected.contains("`speed_m_s`, `kind`"), "{e}");
        let e = from_str::<Thing>("(\n  speed_m_s: 1.0,\n  kind: Quick,\n)").unwrap_err();
        assert_eq!((e.line, e.found.as_str()), (3, "Quick"));
        assert!(e.expected.contains("`Fast`, `Slow`"), "{e}");
        let e = from_str::<Thing>("(\n  speed_m_s: 1.0,\n").unwrap_err();
        assert!(e.at_end_of_file() || e.found == ")", "{e}");
    }
}

#[cfg(test)]
mod column_tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[allow(dead_code, reason = "only the errors are read")]
    struct Named {
        nome: String,
        massa: f64,
    }

    #[test]
    fn ron_and_the_scanner_count_columns_alike() {
        let text = "(\n    nome: \"ÇÃ\", massa: pesada,\n)";
        let e = from_str::<Named>(text).unwrap_err();
        assert_eq!((e.line, e.column, e.found.as_str()), (2, 24, "pesada"), "{e}");
        assert_eq!(crate::ron_path::path_at(text, e.line, e.column), "massa");
    }
}
