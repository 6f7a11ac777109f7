//! Where in a RON text a field sits: a small scanner that follows the nesting of structs, tuples,
//! lists and maps and names every `field:` it meets by its path (`bodies[3].mass`) and line.
//!
//! ron reports a line and column but not which field of which list item it was reading, and our own
//! checks (an unknown body name, a negative mass) know the path but not the line. This scanner joins
//! the two without a second parser: it only tracks brackets, commas and `identifier:` pairs, skipping
//! strings, characters and comments.

/// One `field:` occurrence in the text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct FieldSite {
    /// `bodies[3].mass`: struct fields joined by `.`, list items by `[index]`.
    pub path: String,
    /// 1-based line and column of the field name.
    pub line: usize,
    pub column: usize,
    /// Byte offset of the field name.
    pub offset: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Open {
    Paren,
    Bracket,
    Brace,
}

#[derive(Debug, Clone)]
struct Frame {
    open: Open,
    field: Option<String>,
    index: usize,
}

fn path_of(stack: &[Frame]) -> String {
    let mut path = String::new();
    for frame in stack {
        match frame.open {
            Open::Bracket => path.push_str(&format!("[{}]", frame.index)),
            Open::Paren | Open::Brace => {
                if let Some(f) = &frame.field {
                    if !path.is_empty() {
                        path.push('.');
                    }
                    path.push_str(f);
                }
            }
        }
    }
    path
}

/// Scans `text` up to byte offset `stop` (or the end) and returns every field site met, plus the path
/// of the innermost context at `stop`.
fn scan(text: &str, stop: usize) -> (Vec<FieldSite>, String) {
    let bytes = text.as_bytes();
    let mut sites = Vec::new();
    let mut stack: Vec<Frame> = Vec::new();
    let (mut i, mut line, mut line_start) = (0usize, 1usize, 0usize);
    let stop = stop.min(bytes.len());
    while i < stop {
        let c = bytes[i];
        match c {
            b'\n' => {
                line += 1;
                line_start = i + 1;
                i += 1;
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i + 1 < bytes.len() && !(bytes[i] == b'*' && bytes[i + 1] == b'/') {
                    if bytes[i] == b'\n' {
                        line += 1;
                        line_start = i + 1;
                    }
                    i += 1;
                }
                i += 2;
            }
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    if bytes[i] == b'\\' {
                        i += 1;
                    } else if bytes[i] == b'\n' {
                        line += 1;
                        line_start = i + 1;
                    }
                    i += 1;
                }
                i += 1;
            }
            b'\'' => {
                // A character literal: 'x' or '\n'.
                i += if bytes.get(i + 1) == Some(&b'\\') { 4 } else { 3 };
            }
            b'(' | b'[' | b'{' => {
                let open = match c {
                    b'(' => Open::Paren,
                    b'[' => Open::Bracket,
                    _ => Open::Brace,
                };
                stack.push(Frame { open, field: None, index: 0 });
                i += 1;
            }
            b')' | b']' | b'}' => {
                stack.pop();
                i += 1;
            }
            b',' => {
                if let Some(top) = stack.last_mut() {
                    match top.open {
                        Open::Bracket => top.index += 1,
                        Open::Paren | Open::Brace => top.field = None,
                    }
                }
                i += 1;
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let start = i;
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                let mut j = i;
                while j < bytes.len() && (bytes[j] == b' ' || bytes[j] == b'\t') {
                    j += 1;
                }
                let is_field = bytes.get(j) == Some(&b':')
                    && matches!(stack.last().map(|f| f.open), Some(Open::Paren | Open::Brace));
                if is_field && start < stop {
                    let name = text[start..i].to_string();
                    if let Some(top) = stack.last_mut() {
                        top.field = Some(name);
                    }
                    sites.push(FieldSite {
                        path: path_of(&stack),
                        line,
                        column: start - line_start + 1,
                        offset: start,
                    });
                }
            }
            _ => i += 1,
        }
    }
    let here = path_of(&stack);
    (sites, here)
}

/// Every field site of `text`, in order.
pub(crate) fn field_sites(text: &str) -> Vec<FieldSite> {
    scan(text, usize::MAX).0
}

/// The path of the innermost field being read at 1-based (`line`, `column`), e.g. `bodies[3].mass`.
pub(crate) fn path_at(text: &str, line: usize, column: usize) -> String {
    // An error that points at a field name (an unknown field) belongs to that field: read through
    // the name and its colon.
    let bytes = text.as_bytes();
    let mut stop = offset_of(text, line, column);
    let start = stop;
    while stop < bytes.len() && (bytes[stop].is_ascii_alphanumeric() || bytes[stop] == b'_') {
        stop += 1;
    }
    let mut colon = stop;
    while colon < bytes.len() && (bytes[colon] == b' ' || bytes[colon] == b'\t') {
        colon += 1;
    }
    let stop = if stop > start && bytes.get(colon) == Some(&b':') { colon + 1 } else { start };
    scan(text, stop).1
}

/// The line of `path` in `text`: the site of exactly that path, else of its longest prefix that names
/// a site (`joints[2]` falls back to the first field of that item).
pub(crate) fn line_of(text: &str, path: &str) -> Option<usize> {
    let sites = field_sites(text);
    if let Some(s) = sites.iter().find(|s| s.path == path) {
        return Some(s.line);
    }
    // A list item has no name of its own: use its first field; a field that is not written (a
    // missing one) falls back to the item that lacks it.
    let mut p = path;
    loop {
        if let Some(s) = sites.iter().find(|s| is_within(&s.path, p)) {
            return Some(s.line);
        }
        p = &p[..p.rfind(['.', '['])?];
    }
}

/// `path` is `outer` or lies inside it (`bodies[1].mass` is within `bodies[1]`, `bodies[10]` is not).
fn is_within(path: &str, outer: &str) -> bool {
    path.strip_prefix(outer).is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
}

fn offset_of(text: &str, line: usize, column: usize) -> usize {
    let mut offset = 0;
    for (k, l) in text.split_inclusive('\n').enumerate() {
        if k + 1 == line {
            return offset + column.saturating_sub(1).min(l.len());
        }
        offset += l.len();
    }
    text.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"// a comment with (brackets) and: colons
Skeleton(
    name: "a(b)",
    bodies: [
        Body(name: "x", mass: 1.0, shape: Box(width: 0.1, height: 0.2)),
        Body(name: "y",
             mass: 2.0),
    ],
    /* block: ( */ joints: [],
)"#;

    #[test]
    fn paths_and_lines_follow_nesting() {
        let sites = field_sites(TEXT);
        let paths: Vec<_> = sites.iter().map(|s| (s.path.as_str(), s.line)).collect();
        assert_eq!(
            paths,
            vec![
                ("name", 3),
                ("bodies", 4),
                ("bodies[0].name", 5),
                ("bodies[0].mass", 5),
                ("bodies[0].shape", 5),
                ("bodies[0].shape.width", 5),
                ("bodies[0].shape.height", 5),
                ("bodies[1].name", 6),
                ("bodies[1].mass", 7),
                ("joints", 9),
            ]
        );
    }

    #[test]
    fn path_at_names_the_field_being_read() {
        // Line 7 is `mass: 2.0),`; column 20 is inside the number.
        assert_eq!(path_at(TEXT, 7, 20), "bodies[1].mass");
        assert_eq!(line_of(TEXT, "bodies[1].mass"), Some(7));
        assert_eq!(line_of(TEXT, "bodies[1]"), Some(6));
        assert_eq!(line_of(TEXT, "bodies[1].side"), Some(6));
        assert_eq!(line_of(TEXT, "bodies[10]"), Some(4), "bodies[10] is not bodies[1]");
    }
}
