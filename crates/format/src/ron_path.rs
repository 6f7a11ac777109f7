//! Where in a RON text a field sits: a small scanner that follows the nesting of structs, tuples, lists
//! and maps and names every `field:` and every list item it meets by its path (`bodies[3].mass`,
//! `machines[0].states[2]`), line and column.
//!
//! ron reports a line and column but not which field of which list item it was reading, and the checks
//! of a reader (an unknown body name, a negative mass) know the path but not the line. This scanner joins
//! the two without a second parser: it only tracks brackets, commas and `identifier:` pairs, skipping
//! strings, characters and comments.

/// One `field:` or list item in the text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldSite {
    /// `bodies[3].mass`: struct fields joined by `.`, list items by `[index]`.
    pub path: String,
    /// 1-based line and column of the field name, or of a list item's first token.
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
    for frame in stack {
        if frame.list {
            path.push_str(&format!("[{}]", frame.index));
        } else if let Some(f) = &frame.field {
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(f);
        }
    }
    path
}

/// Scans `text` up to byte `stop`: every site met, and the path of the innermost context at `stop`.
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
            sites.push(FieldSite { path: path_of(&stack), line, column: column(text, line_start, i) });
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
            // A character literal: 'x' or '\n'.
            b'\'' => i += if b.get(i + 1) == Some(&b'\\') { 4 } else { 3 },
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
                    sites.push(FieldSite {
                        path: path_of(&stack),
                        line,
                        column: column(text, line_start, start),
                    });
                }
            }
            _ => i += 1,
        }
    }
    (sites, path_of(&stack))
}

/// The 1-based column, in characters, of byte `at` on the line starting at byte `line_start`.
fn column(text: &str, line_start: usize, at: usize) -> usize {
    text.get(line_start..at).map_or(at - line_start, |s| s.chars().count()) + 1
}

/// Every site of `text`, in order.
pub fn field_sites(text: &str) -> Vec<FieldSite> {
    scan(text, usize::MAX).0
}

/// The path of the innermost field being read at 1-based (`line`, `column`), e.g. `bodies[3].mass`.
pub fn path_at(text: &str, line: usize, column: usize) -> String {
    let b = text.as_bytes();
    let mut offset = text.len();
    let mut acc = 0;
    for (k, l) in text.split_inclusive('\n').enumerate() {
        if k + 1 == line {
            // Columns count characters; walk them to the byte offset.
            let within = l.char_indices().nth(column.saturating_sub(1)).map_or(l.len(), |(o, _)| o);
            offset = acc + within;
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

/// The site of `path`, or of its longest prefix that has one: a field that is not written falls back to
/// the item that lacks it, `bodies[10]` to `bodies` when the list has fewer items.
pub fn site_of(text: &str, path: &str) -> Option<FieldSite> {
    let sites = field_sites(text);
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

    const CONTROLLER: &str = r#"// a comment (with: brackets)
Controller(
    name: "a(b)",
    machines: [
        Machine(name: "m", weight: 1.0,
            states: [State(name: "E1", pose: [("hip", Angle(0.1)), (3, NoTorque)])],
            transitions: [Transition(when: Sensory((kind: "x", params: [0.1, 0.2])))]),
    ],
)"#;

    const SKELETON: &str = r#"// a comment with (brackets) and: colons
Skeleton(
    name: "a(b)",
    bodies: [
        Body(name: "x", mass: 1.0, shape: Box(width: 0.1, height: 0.2), mark: 'c'),
        Body(name: "y",
             mass: 2.0),
    ],
    /* block: ( */ joints: [],
)"#;

    #[test]
    fn sites_follow_nesting_and_list_items() {
        let s = |p: &str| site_of(CONTROLLER, p).map(|s| (s.line, s.column));
        assert_eq!(s("name"), Some((3, 5)));
        assert_eq!(s("machines[0].weight"), Some((5, 28)));
        assert_eq!(s("machines[0].states[0].pose[1]"), Some((6, 68)));
        assert_eq!(s("machines[0].transitions[0].when.params[1]"), Some((7, 78)));
        // Not written: falls back to the enclosing item.
        assert_eq!(s("machines[0].enabled"), Some((5, 9)));
    }

    #[test]
    fn fields_skip_comments_strings_and_characters() {
        let paths: Vec<_> = field_sites(SKELETON)
            .into_iter()
            .filter(|s| !s.path.ends_with(']'))
            .map(|s| (s.path, s.line))
            .collect();
        let want = [
            ("name", 3),
            ("bodies", 4),
            ("bodies[0].name", 5),
            ("bodies[0].mass", 5),
            ("bodies[0].shape", 5),
            ("bodies[0].shape.width", 5),
            ("bodies[0].shape.height", 5),
            ("bodies[0].mark", 5),
            ("bodies[1].name", 6),
            ("bodies[1].mass", 7),
            ("joints", 9),
        ];
        assert_eq!(paths, want.map(|(p, l)| (p.to_owned(), l)));
        let line = |p: &str| site_of(SKELETON, p).map(|s| s.line);
        assert_eq!(line("bodies[1].side"), Some(6));
        assert_eq!(line("bodies[10]"), Some(4), "bodies[10] is not bodies[1]");
    }

    #[test]
    fn path_at_names_the_field_being_read() {
        assert_eq!(path_at(CONTROLLER, 7, 79), "machines[0].transitions[0].when.params[1]");
        assert_eq!(path_at(CONTROLLER, 5, 28), "machines[0].weight");
        // Line 7 of the skeleton is `mass: 2.0),`; column 20 is inside the number.
        assert_eq!(path_at(SKELETON, 7, 20), "bodies[1].mass");
    }

    #[test]
    fn columns_count_characters() {
        let text = "(\n    nome: \"ÇÃ\", massa: 1.0,\n)";
        let site = site_of(text, "massa").unwrap();
        assert_eq!((site.line, site.column), (2, 17));
        assert_eq!(path_at(text, 2, 26), "massa");
    }
}
