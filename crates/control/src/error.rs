//! Errors of controller files: what is wrong, in which field, and at which line and column.
//!
//! ron reports where it stopped reading but not in which field; our own checks (an unknown sensor, a
//! value outside its interval) know the field path but not the line. [`field_sites`] joins the two: a
//! small scanner that follows the brackets of a RON text and names every `field:` it meets.

use std::fmt;

/// What kind of problem a controller file has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControllerErrorKind {
    /// Not valid RON for the controller format (ron's own message).
    Syntax,
    /// Valid RON that describes no valid controller (unknown name, index out of range, value outside
    /// its interval, …).
    Invalid,
}

/// A controller that could not be read or built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct ControllerError {
    pub kind: ControllerErrorKind,
    /// Path of the offending field: struct fields joined by `.`, list items as `[index]`, e.g.
    /// `machines[0].transitions[2].when.params[0]`. Empty when the whole file is concerned.
    pub field: String,
    /// 1-based line, when the controller came from text.
    pub line: Option<usize>,
    /// 1-based column, when ron reported one.
    pub column: Option<usize>,
    pub message: String,
}

impl fmt::Display for ControllerError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.column) {
            (Some(l), Some(c)) => write!(f, "line {l}, column {c}: ")?,
            (Some(l), None) => write!(f, "line {l}: ")?,
            _ => {}
        }
        if self.field.is_empty() {
            write!(f, "controller: {}", self.message)
        } else {
            write!(f, "field `{}`: {}", self.field, self.message)
        }
    }
}

impl ControllerError {
    pub(crate) fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            kind: ControllerErrorKind::Invalid,
            field: field.into(),
            line: None,
            column: None,
            message: message.into(),
        }
    }

    /// A ron error, placed in `text`.
    pub(crate) fn syntax(text: &str, e: &ron::error::SpannedError) -> Self {
        let (line, column) = (e.span.start.line, e.span.start.col);
        Self {
            kind: ControllerErrorKind::Syntax,
            field: path_at(text, line, column),
            line: Some(line),
            column: Some(column),
            message: e.code.to_string(),
        }
    }

    /// Adds the line and column of the field to an error found by the checks.
    pub(crate) fn locate(mut self, text: &str) -> Self {
        if let Some(site) = site_of(text, &self.field) {
            self.line = Some(site.line);
            self.column = Some(site.column);
        }
        self
    }
}

/// One `field:` (or list item) in a RON text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct FieldSite {
    pub path: String,
    pub line: usize,
    pub column: usize,
}

#[derive(Debug, Clone)]
struct Frame {
    list: bool,
    field: Option<String>,
    index: usize,
}

fn path_of(stack: &[Frame]) -> String {
    let mut path = String::new();
    for fr in stack {
        if fr.list {
            path.push_str(&format!("[{}]", fr.index));
        } else if let Some(f) = &fr.field {
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(f);
        }
    }
    path
}

/// Scans `text` up to byte `stop`: every field and list-item site met, and the path at `stop`.
fn scan(text: &str, stop: usize) -> (Vec<FieldSite>, String) {
    let b = text.as_bytes();
    let stop = stop.min(b.len());
    let mut sites = Vec::new();
    let mut stack: Vec<Frame> = Vec::new();
    let (mut i, mut line, mut line_start) = (0, 1, 0);
    // A list item's site is where its first token starts.
    let mut item_pending = false;
    while i < stop {
        let c = b[i];
        if item_pending && !c.is_ascii_whitespace() && c != b']' && c != b'/' {
            item_pending = false;
            sites.push(FieldSite { path: path_of(&stack), line, column: i - line_start + 1 });
        }
        match c {
            b'\n' => {
                line += 1;
                line_start = i + 1;
                i += 1;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                    if b[i] == b'\n' {
                        line += 1;
                        line_start = i + 1;
                    }
                    i += 1;
                }
                i += 2;
            }
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    if b[i] == b'\\' {
                        i += 1;
                    } else if b[i] == b'\n' {
                        line += 1;
                        line_start = i + 1;
                    }
                    i += 1;
                }
                i += 1;
            }
            b'(' | b'[' | b'{' => {
                let list = c == b'[';
                stack.push(Frame { list, field: None, index: 0 });
                item_pending = list;
                i += 1;
            }
            b')' | b']' | b'}' => {
                stack.pop();
                item_pending = false;
                i += 1;
            }
            b',' => {
                if let Some(top) = stack.last_mut() {
                    if top.list {
                        top.index += 1;
                        item_pending = true;
                    } else {
                        top.field = None;
                    }
                }
                i += 1;
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let start = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                let mut j = i;
                while j < b.len() && (b[j] == b' ' || b[j] == b'\t') {
                    j += 1;
                }
                let in_struct = stack.last().is_some_and(|f| !f.list);
                if in_struct && b.get(j) == Some(&b':') && start < stop {
                    if let Some(top) = stack.last_mut() {
                        top.field = Some(text[start..i].to_string());
                    }
                    sites.push(FieldSite { path: path_of(&stack), line, column: start - line_start + 1 });
                }
            }
            _ => i += 1,
        }
    }
    (sites, path_of(&stack))
}

/// The path of the field being read at 1-based (`line`, `column`).
pub(crate) fn path_at(text: &str, line: usize, column: usize) -> String {
    let b = text.as_bytes();
    let mut offset = text.len();
    let mut acc = 0;
    for (k, l) in text.split_inclusive('\n').enumerate() {
        if k + 1 == line {
            offset = acc + column.saturating_sub(1).min(l.len());
            break;
        }
        acc += l.len();
    }
    // An error at a field's name (an unknown field) belongs to that field: read through the colon.
    let start = offset;
    let mut end = offset;
    while end < b.len() && (b[end].is_ascii_alphanumeric() || b[end] == b'_') {
        end += 1;
    }
    let mut colon = end;
    while colon < b.len() && (b[colon] == b' ' || b[colon] == b'\t') {
        colon += 1;
    }
    let stop = if end > start && b.get(colon) == Some(&b':') { colon + 1 } else { start };
    scan(text, stop).1
}

/// The site of `path`, or of its longest prefix that has one (a field that is not written falls back
/// to the item that lacks it).
pub(crate) fn site_of(text: &str, path: &str) -> Option<FieldSite> {
    let sites = scan(text, usize::MAX).0;
    let mut p = path;
    loop {
        if let Some(s) = sites.iter().find(|s| s.path == p) {
            return Some(s.clone());
        }
        p = &p[..p.rfind(['.', '['])?];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"// a comment (with: brackets)
Controller(
    name: "a(b)",
    machines: [
        Machine(name: "m", weight: 1.0,
            states: [State(name: "E1", pose: [("hip", Angle(0.1)), (3, NoTorque)])],
            transitions: [Transition(when: Sensory((kind: "x", params: [0.1, 0.2])))]),
    ],
)"#;

    #[test]
    fn sites_follow_nesting_and_list_items() {
        let s = |p: &str| site_of(TEXT, p).map(|s| (s.line, s.column));
        assert_eq!(s("name"), Some((3, 5)));
        assert_eq!(s("machines[0].weight"), Some((5, 28)));
        assert_eq!(s("machines[0].states[0].pose[1]"), Some((6, 68)));
        assert_eq!(s("machines[0].transitions[0].when.params[1]"), Some((7, 78)));
        // Not written: falls back to the enclosing item.
        assert_eq!(s("machines[0].enabled"), Some((5, 9)));
    }

    #[test]
    fn path_at_names_the_field_being_read() {
        assert_eq!(path_at(TEXT, 7, 79), "machines[0].transitions[0].when.params[1]");
        assert_eq!(path_at(TEXT, 5, 28), "machines[0].weight");
    }
}
