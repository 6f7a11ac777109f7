//! Generated reports: markdown documents made of named sections, so that a partial run replaces only
//! its own sections and keeps the rest of the committed file.
//!
//! A document is written as its header, then each section between two marker comments:
//!
//! ```text
//! <!-- section: test-1 -->
//! ## Test I — …
//! <!-- end: test-1 -->
//! ```
//!
//! The markers are invisible in rendered markdown. [`Document::merged_into`] keeps the sections of the
//! file on disk that the new document lacks, in the order the document's kind declares.

use std::fmt::Write as _;

/// A generated markdown document: a header and named sections.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Document {
    header: String,
    /// Every section name this kind of document can hold, in the order they are written.
    order: Vec<String>,
    sections: Vec<(String, String)>,
}

impl Document {
    /// An empty document whose sections, when present, appear in `order`.
    pub fn new(header: impl Into<String>, order: &[&str]) -> Self {
        Self {
            header: header.into(),
            order: order.iter().map(|s| s.to_string()).collect(),
            sections: Vec::new(),
        }
    }

    /// Adds (or replaces) section `name`.
    ///
    /// # Panics
    /// If `name` is not one of the document's declared sections: a report that writes a section it
    /// did not declare is a bug in its generator.
    pub fn section(&mut self, name: &str, text: impl Into<String>) -> &mut Self {
        assert!(self.order.iter().any(|o| o == name), "section `{name}` is not declared in {:?}", self.order);
        let text = text.into();
        match self.sections.iter_mut().find(|(n, _)| n == name) {
            Some((_, t)) => *t = text,
            None => self.sections.push((name.to_owned(), text)),
        }
        self
    }

    /// The text of section `name`, if the document has it.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.sections.iter().find(|(n, _)| n == name).map(|(_, t)| t.as_str())
    }

    /// The document as written on its own.
    pub fn render(&self) -> String {
        self.merged_into(None)
    }

    /// The document written over `existing` (a file written earlier, perhaps by hand-edited or older
    /// code): this document's header and sections, plus every section of `existing` this one lacks.
    /// Sections appear in the declared order; sections of `existing` the document no longer declares
    /// are dropped, since no command would write them now.
    pub fn merged_into(&self, existing: Option<&str>) -> String {
        let old = existing.map(parse_sections).unwrap_or_default();
        let mut out = self.header.trim_end().to_owned();
        out.push_str("\n\n");
        for name in &self.order {
            let text =
                self.get(name).or_else(|| old.iter().find(|(n, _)| n == name).map(|(_, t)| t.as_str()));
            if let Some(text) = text {
                let _ =
                    writeln!(out, "<!-- section: {name} -->\n{}\n<!-- end: {name} -->\n", text.trim_end());
            }
        }
        out
    }
}

/// The named sections of a document written by [`Document::render`].
pub fn parse_sections(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(start) = rest.find("<!-- section: ") {
        let after = &rest[start + "<!-- section: ".len()..];
        let Some(close) = after.find(" -->") else { break };
        let name = after[..close].to_owned();
        let body_start = &after[close + " -->".len()..];
        let end_marker = format!("<!-- end: {name} -->");
        let Some(end) = body_start.find(&end_marker) else { break };
        out.push((name, body_start[..end].trim_matches('\n').to_owned()));
        rest = &body_start[end + end_marker.len()..];
    }
    out
}

/// One markdown table row: `| a | b | c |`.
pub fn row<I, S>(cells: I) -> String
where
    I: IntoIterator<Item = S>,
    S: AsRef<str>,
{
    let mut s = String::from("|");
    for c in cells {
        let _ = write!(s, " {} |", c.as_ref());
    }
    s
}

/// A markdown table header with its separator line.
pub fn header(cells: &[&str]) -> String {
    format!("{}\n|{}", row(cells), "---|".repeat(cells.len()))
}

/// "yes" or a bold "**NO**", for criteria tables.
pub fn holds(ok: bool) -> &'static str {
    if ok { "yes" } else { "**NO**" }
}

/// Today's date (UTC) as YYYY-MM-DD, from the system clock (the reports' dates).
pub fn today() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400) as i64;
    civil_date(days)
}

/// The date `days` after 1970-01-01 (proleptic Gregorian), as YYYY-MM-DD.
fn civil_date(days: i64) -> String {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

#[cfg(test)]
mod tests {
    #[test]
    fn civil_dates() {
        assert_eq!(civil_date(0), "1970-01-01");
        assert_eq!(civil_date(59), "1970-03-01");
        assert_eq!(civil_date(11_016), "2000-02-29");
        assert_eq!(civil_date(20_415), "2025-11-23");
    }

    use super::*;

    #[test]
    fn a_partial_document_keeps_the_other_sections() {
        let order = ["one", "two", "three"];
        let mut full = Document::new("# Report\n\nheader v1", &order);
        full.section("one", "## One\n1").section("two", "## Two\n2").section("three", "## Three\n3");
        let written = full.render();
        assert_eq!(parse_sections(&written).len(), 3);

        let mut partial = Document::new("# Report\n\nheader v2", &order);
        partial.section("two", "## Two\n2, again");
        let merged = partial.merged_into(Some(&written));
        assert!(merged.starts_with("# Report\n\nheader v2\n"), "{merged}");
        let sections = parse_sections(&merged);
        let names: Vec<_> = sections.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, order, "{merged}");
        assert_eq!(sections[1].1, "## Two\n2, again");
        assert_eq!(sections[0].1, "## One\n1");
        // Writing the full document over the merge gives the full document back.
        assert_eq!(full.merged_into(Some(&merged)), written);
    }

    #[test]
    fn tables() {
        assert_eq!(header(&["a", "b"]), "| a | b |\n|---|---|");
        assert_eq!(row(["1", "2"]), "| 1 | 2 |");
    }

    #[test]
    #[should_panic(expected = "not declared")]
    fn undeclared_sections_are_refused() {
        Document::new("# R", &["a"]).section("b", "x");
    }
}
