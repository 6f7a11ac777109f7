//! Generated reports stay true: a report whose content does not depend on the machine is regenerated
//! here and compared with the committed file, the way rust-analyzer checks its generated code.
//!
//! Only `docs/reproduction/flex3d-results.md`, the faithful-SIMBICON section of `nunes-simbicon.md`,
//! `nunes-walk-faithful.md` and `nunes-robustness.md` (a minute each) can be checked this way. The
//! others hold wall times (`oliveira-results.md`, `oliveira-implicit.md`, `oliveira-adaptive.md`,
//! `nunes-results.md`'s run time per iteration, `benchmarks.md`) or take minutes to an hour to
//! regenerate (`nunes-optimisers.md`, the SIMBICON-style section of `nunes-simbicon.md`, the adaptive
//! report): their commands rewrite them, and a partial run rewrites only its own sections.
//!
//! Prose that quotes a generated report is checked against it: the README's benchmark figures, the
//! measurements `docs/reproduction/flex3d.md`, `oliveira.md` and `nunes.md` state, and every crate doc
//! sentence that cites a generated report.

use anima_cloth::flex3d::FrictionMode;
use anima_lab::repo::Repo;

/// Compares a freshly generated report with the committed file at `path` (`UPDATE_REPORTS=1` writes it
/// instead); `what` names the report and `command` the command that regenerates it.
fn assert_fresh(path: &std::path::Path, fresh: &str, what: &str, command: &str) {
    if std::env::var_os("UPDATE_REPORTS").is_some() {
        std::fs::write(path, fresh).unwrap();
    }
    let committed = std::fs::read_to_string(path).unwrap();
    assert!(
        fresh == committed,
        "{what} is stale: run `{command}` (or `UPDATE_REPORTS=1 cargo test -p anima-tests --release reports`) \
         and review the diff"
    );
}

#[test]
fn the_committed_flex3d_results_are_what_reproduce_all_writes() {
    let (doc, failed) = anima_lab::flex3d::report::reproduce("all", FrictionMode::Literal).unwrap();
    assert!(failed.is_empty(), "criteria that do not hold: {failed:?}");
    let command = "cargo xtask reproduce all";
    let path = Repo::here().docs("reproduction/flex3d-results.md");
    assert_fresh(&path, &doc.render(), "docs/reproduction/flex3d-results.md", command);
    // The narrative report shows the E-5 and E-6 searches as the same run writes them.
    let path = Repo::here().docs(anima_lab::flex3d::report::NARRATIVE);
    let narrative = std::fs::read_to_string(&path).unwrap();
    let fresh = anima_lab::flex3d::report::narrative_with(&doc, &narrative).unwrap();
    assert_fresh(&path, &fresh, "docs/reproduction/flex3d.md's E-5/E-6 searches", command);
}

#[test]
fn the_committed_faithful_simbicon_section_is_what_its_command_writes() {
    use anima_lab::nunes::faithful;
    let section = faithful::section().unwrap();
    let path = Repo::here().docs(faithful::REPORT);
    let committed = std::fs::read_to_string(&path).unwrap();
    let fresh = faithful::document(&section).merged_into(Some(&committed));
    let what = "docs/reproduction/nunes-simbicon.md's faithful section";
    assert_fresh(&path, &fresh, what, "cargo xtask reproduce nunes-simbicon-faithful");
}

#[test]
fn the_committed_faithful_walker_scan_is_what_its_command_writes() {
    use anima_lab::nunes::faithful_walk;
    let fresh = faithful_walk::document(&Repo::here()).unwrap();
    let path = Repo::here().docs(faithful_walk::REPORT);
    let what = "docs/reproduction/nunes-walk-faithful.md";
    assert_fresh(&path, &fresh, what, "cargo xtask reproduce nunes-walk-faithful");
}

#[test]
fn the_committed_robustness_report_is_what_its_command_writes() {
    use anima_lab::nunes::robustness;
    let fresh = robustness::document().unwrap();
    let path = Repo::here().docs(robustness::REPORT);
    assert_fresh(
        &path,
        &fresh,
        "docs/reproduction/nunes-robustness.md",
        "cargo xtask reproduce nunes-robustness",
    );
}

/// The README quotes the benchmark reports; each number it quotes is the one the report's table holds
/// (the reports are written by `cargo xtask bench` and `bench --peers`: when they are regenerated, this
/// fails until the README says what they say).
#[test]
fn the_readme_quotes_the_benchmark_reports_as_they_stand() {
    let read = |rel: &str| std::fs::read_to_string(Repo::here().root().join(rel)).unwrap();
    let (readme, peers, bench) =
        (read("README.md"), read("docs/benchmarks-peers.md"), read("docs/benchmarks.md"));
    // The first table row starting with `row` after the heading `heading`, split into its cells.
    let cells = |doc: &str, heading: &str, row: &str| -> Vec<String> {
        let from = doc.find(heading).unwrap_or_else(|| panic!("no section `{heading}`"));
        let line =
            doc[from..].lines().find(|l| l.starts_with(row)).unwrap_or_else(|| panic!("no row `{row}`"));
        line.split('|').map(|c| c.trim().to_owned()).filter(|c| !c.is_empty()).collect()
    };
    // A cell's leading number with its unit ("0.544 s (0.543–0.555)" gives "0.544 s").
    let lead = |cell: &str| cell.split(" (").next().unwrap().to_owned();
    let one = cells(&peers, "## Standard sheet, N = 64, 10⁻⁴ s, 1 s: anima on one thread", "| anima |");
    let every = cells(&peers, "## Standard sheet, N = 64, 10⁻⁴ s, 1 s: anima on every core", "| anima |");
    let alpha =
        cells(&bench, "### N = 64: anima at the common step", "| generalized-alpha | 1.67e-2 (large) |");
    let quoted = [
        format!("{} on one core, {} on two", lead(&one[1]), lead(&every[1])),
        format!("1/60 s in {}, {} from the converged centre of mass", lead(&alpha[2]), alpha[3]),
    ];
    // The README wraps its lines: compare with its whitespace made single spaces.
    let flat = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    for q in quoted {
        assert!(flat.contains(&q), "the README should say `{q}`, as the reports do");
    }
}

/// The README says how close the static drapes' step counts come to the thesis's ("to within 3 %"):
/// the smallest whole percentage that bounds every count `oliveira-results.md` compares with the
/// thesis's (`cargo xtask reproduce oliveira` writes it), so that a regenerated report that moves a
/// count past it fails here until the README says so.
#[test]
fn the_readme_quotes_the_static_drapes_step_counts_as_they_stand() {
    let read = |rel: &str| std::fs::read_to_string(Repo::here().root().join(rel)).unwrap();
    let (readme, results) = (read("README.md"), read("docs/reproduction/oliveira-results.md"));
    // "| coarse: step count within 5 % of the thesis's 2236 | 2262 | yes |"
    let deviations: Vec<f64> = results
        .lines()
        .filter_map(|l| {
            let (_, rest) = l.split_once("step count within 5 % of the thesis's ")?;
            let cells: Vec<&str> = rest.split('|').map(str::trim).collect();
            let (thesis, ours): (f64, f64) = (cells[0].parse().ok()?, cells[1].parse().ok()?);
            Some((ours - thesis).abs() / thesis)
        })
        .collect();
    assert!(deviations.len() >= 4, "the step-count criteria of Tests I and II: found {}", deviations.len());
    let largest = deviations.iter().copied().fold(0.0, f64::max);
    let bound = (100.0 * largest).ceil() as usize;
    let flat = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    let quote = format!("with the thesis's step counts to within {bound} %");
    assert!(
        flat.contains(&quote),
        "the README should say `{quote}` (the largest deviation is {:.2} %)",
        100.0 * largest
    );
}

/// The decimal numbers of `text` (`61.4`, `−6.6`, `1.0·10⁻⁴`, `2.294 × 10⁻⁴`, `1.01e-4`, `19 237.7`), each
/// with its value and half the unit of its last printed digit (the rounding a quoted value may carry).
fn decimals(text: &str) -> Vec<(String, f64, f64)> {
    let superscript = |c: char| "⁰¹²³⁴⁵⁶⁷⁸⁹".chars().position(|s| s == c);
    let chars: Vec<char> = text.chars().collect();
    let digit = |k: usize| k < chars.len() && chars[k].is_ascii_digit();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let starts = chars[i].is_ascii_digit()
            && (i == 0 || !(chars[i - 1].is_ascii_alphanumeric() || chars[i - 1] == '.'));
        if !starts {
            i += 1;
            continue;
        }
        let negative = i > 0 && (chars[i - 1] == '-' || chars[i - 1] == '−');
        let begin = i;
        while digit(i) {
            i += 1;
        }
        // Thousands grouped by spaces ("19 237.7"): a lead of at most three digits, groups of three.
        if i - begin <= 3 {
            while i + 3 < chars.len()
                && matches!(chars[i], ' ' | '\u{a0}' | '\u{202f}')
                && (i + 1..i + 4).all(digit)
                && !digit(i + 4)
            {
                i += 4;
            }
        }
        // Only numbers with a fractional part: integers are counts and frame numbers.
        if !(chars.get(i) == Some(&'.') && digit(i + 1)) {
            continue;
        }
        i += 1;
        let fraction = i;
        while digit(i) {
            i += 1;
        }
        let digits = (i - fraction) as i32;
        let mantissa: f64 = chars[begin..i]
            .iter()
            .filter(|c| c.is_ascii_digit() || **c == '.')
            .collect::<String>()
            .parse()
            .unwrap();
        let mut exponent = 0i32;
        let rest: String = chars[i..chars.len().min(i + 10)].iter().collect();
        let power = ["·10", " × 10"].into_iter().find_map(|p| rest.strip_prefix(p).map(|t| (p, t)));
        if let Some((prefix, tail)) = power {
            let mut t = tail.chars().peekable();
            let sign = if t.peek() == Some(&'⁻') {
                t.next();
                -1
            } else {
                1
            };
            let mut e = 0i32;
            let mut n = 0;
            while let Some(d) = t.peek().and_then(|&c| superscript(c)) {
                e = e * 10 + d as i32;
                t.next();
                n += 1;
            }
            if n > 0 {
                exponent = sign * e;
                i += prefix.chars().count() + usize::from(sign < 0) + n;
            }
        } else if let Some(tail) = rest.strip_prefix('e') {
            let e: String = tail.chars().take_while(|c| c.is_ascii_digit() || *c == '-').collect();
            if let Ok(e) = e.parse::<i32>() {
                exponent = e;
                i += 1 + e.to_string().len();
            }
        }
        let sign = if negative { -1.0 } else { 1.0 };
        let value = sign * mantissa * 10f64.powi(exponent);
        let half = 0.5 * 10f64.powi(exponent - digits);
        out.push((chars[begin.saturating_sub(usize::from(negative))..i].iter().collect(), value, half));
    }
    out
}

/// The decimals of `quoted` that none of the `measured` values is, to the digits they are quoted with.
fn unheld(quoted: &str, measured: &[f64]) -> Vec<String> {
    decimals(quoted)
        .into_iter()
        .filter(|(_, value, half)| !measured.iter().any(|m| (m - value).abs() <= half * (1.0 + 1e-9)))
        .map(|(token, _, _)| token)
        .collect()
}

/// `text` without the numbers that name a figure, an equation, a table or a section of the thesis or
/// the spec (`Fig. 6.7`, `Eqs. 4.16–4.18`, `§8.1.2`), or give a scene's or a controller's parameter
/// (`β = 0.008`, the feedback gains `c_d = −0.91`, `c_v = −0.49`).
fn without_references(text: &str) -> String {
    let prefixes = ["Fig. ", "Figs. ", "Eq. ", "Eqs. ", "Table ", "§", "β = ", "c_d = ", "c_v = "];
    let (mut out, mut rest) = (String::new(), text);
    while let Some((at, prefix)) = prefixes.iter().filter_map(|p| rest.find(p).map(|a| (a, *p))).min() {
        out.push_str(&rest[..at + prefix.len()]);
        let after = &rest[at + prefix.len()..];
        // A parameter's sign goes with it.
        let after = after.strip_prefix(['−', '-']).filter(|_| prefix.ends_with("= ")).unwrap_or(after);
        rest = after.trim_start_matches(|c: char| c.is_ascii_digit() || c == '.' || c == '–');
    }
    out + rest
}

/// A hand-written report's quotes of the generated reports it cites: in `doc` (under
/// `docs/reproduction/`), the text from each span's `from` marker to its `to` marker quotes the
/// span's generated reports, and every decimal number in it must be one they hold, to the digits it is
/// quoted with. Left out: the cells under a table header that starts with "thesis" (the thesis's own
/// figures) and references to figures, equations, tables and sections. At least `at_least` numbers
/// are checked, so that a moved marker cannot empty the check; `command` regenerates the reports.
fn assert_quotes_generated(doc: &str, spans: &[(&str, &str, &[&str])], at_least: usize, command: &str) {
    let read =
        |name: &str| std::fs::read_to_string(Repo::here().docs(format!("reproduction/{name}"))).unwrap();
    let prose = read(doc);
    let (mut checked, mut stale) = (0, Vec::new());
    for (from, to, generated) in spans {
        let measured: Vec<f64> =
            generated.iter().flat_map(|g| decimals(&read(g))).map(|(_, v, _)| v).collect();
        let start = prose.find(from).unwrap_or_else(|| panic!("{doc} has no `{from}`"));
        let end = prose[start..].find(to).map(|e| start + e).unwrap_or_else(|| panic!("{doc} has no `{to}`"));
        let (mut kept, mut thesis) = (Vec::new(), Vec::new());
        let mut in_table = false;
        for line in prose[start..end].lines() {
            if !line.starts_with('|') {
                in_table = false;
                kept.push(line.to_owned());
                continue;
            }
            let cells: Vec<&str> = line.split('|').collect();
            if !in_table {
                thesis = cells.iter().map(|c| c.trim().starts_with("thesis")).collect();
                in_table = true;
            }
            let ours = cells.iter().enumerate().filter(|(k, _)| !thesis.get(*k).copied().unwrap_or(false));
            kept.push(ours.map(|(_, c)| *c).collect::<Vec<_>>().join("|"));
        }
        let flat = without_references(&kept.join("\n").split_whitespace().collect::<Vec<_>>().join(" "));
        checked += decimals(&flat).len();
        for token in unheld(&flat, &measured) {
            stale.push(format!("{token} (after `{from}`, quoting {generated:?})"));
        }
    }
    assert!(checked >= at_least, "only {checked} numbers found in {doc}'s quotes of the generated reports");
    assert!(
        stale.is_empty(),
        "{doc} quotes numbers that the generated reports it cites do not hold (bring the prose to what \
         `{command}` writes, or point at the report instead of repeating the number):\n{}",
        stale.join("\n")
    );
}

/// `flex3d.md` tells what each experiment shows and quotes our measurements in its "Ours." paragraphs;
/// `flex3d-results.md` is what `cargo xtask reproduce all` measures. Every decimal number an "Ours."
/// paragraph quotes (outside the spec's own figures, which it names as the spec's) must be one the
/// results hold, to the digits it is quoted with: when a run changes what it measures, this fails
/// until the prose says what the results say.
#[test]
fn flex3d_md_quotes_the_generated_results() {
    let read = |rel: &str| std::fs::read_to_string(Repo::here().root().join(rel)).unwrap();
    let (prose, results) = (read("docs/reproduction/flex3d.md"), read("docs/reproduction/flex3d-results.md"));
    let measured: Vec<f64> = decimals(&results).into_iter().map(|(_, v, _)| v).collect();
    let (mut checked, mut stale) = (0, Vec::new());
    for paragraph in prose.split("\n\n").filter(|p| p.starts_with("**Ours.**")) {
        let flat = paragraph.split_whitespace().collect::<Vec<_>>().join(" ");
        // The spec's figures: a parenthesis that opens with "spec", or a sentence on "The spec's" numbers.
        let mut ours = String::new();
        let mut rest = flat.as_str();
        while let Some(open) = rest.find("(spec") {
            ours.push_str(&rest[..open]);
            let after = &rest[open..];
            let close = after.find(')').map_or(after.len(), |c| c + 1);
            rest = &after[close..];
        }
        ours.push_str(rest);
        let ours: String =
            ours.split(". ").filter(|s| !s.starts_with("The spec's")).collect::<Vec<_>>().join(". ");
        checked += decimals(&ours).len();
        for token in unheld(&ours, &measured) {
            stale.push(format!("{token} (in `{}…`)", flat.chars().take(60).collect::<String>()));
        }
    }
    assert!(checked >= 10, "only {checked} numbers found in flex3d.md's \"Ours.\" paragraphs");
    // The searches of E-5 and E-6 are shown as the results' tables: a row whose label the results
    // also give must be one of the results' rows with that label, cell for cell.
    let label = |row: &str| row.split('|').nth(1).map(str::trim).unwrap_or_default().to_owned();
    let mut rows = 0;
    for row in prose.lines().filter(|l| l.starts_with("| ") && !label(l).is_empty()) {
        let theirs: Vec<&str> =
            results.lines().filter(|l| l.starts_with("| ") && label(l) == label(row)).collect();
        if theirs.is_empty() {
            continue;
        }
        rows += 1;
        if !theirs.contains(&row) {
            stale.push(format!("the row `{row}`"));
        }
    }
    assert!(rows >= 10, "only {rows} rows of flex3d.md's tables found in flex3d-results.md");
    assert!(
        stale.is_empty(),
        "flex3d.md quotes numbers that flex3d-results.md does not hold (run `cargo xtask reproduce all` and \
         bring the prose to what it measures):\n{}",
        stale.join("\n")
    );
}

/// `oliveira.md` quotes the static drapes' measurements from `oliveira-results.md` (the choices the
/// thesis leaves open and the scenes, from the report's last section; its results table and the
/// paragraph after it; friction on the incline) and the adaptive runs' from `oliveira-adaptive.md`
/// (what the full-duration runs show). The wall times change with each run of `cargo xtask reproduce
/// oliveira`: this fails until the prose says what the regenerated report says.
#[test]
fn oliveira_md_quotes_the_generated_results() {
    assert_quotes_generated(
        "oliveira.md",
        &[
            ("## Choices the thesis leaves open", "## Results (static meshes)", &["oliveira-results.md"]),
            ("## Results (static meshes)", "What the runs show", &["oliveira-results.md"]),
            ("## Friction", "## Beyond the thesis", &["oliveira-results.md"]),
            ("What the full-duration runs show", "type-3 response", &["oliveira-adaptive.md"]),
        ],
        30,
        "cargo xtask reproduce oliveira [--adaptive]",
    );
}

/// `nunes.md` quotes, from its set-up to its figures, what the generated Nunes reports measure: the
/// set-up, the reconstructed poses, the results beside the thesis and their reading from
/// `nunes-results.md` and the reports that reading cites, the optimisers from `nunes-optimisers.md` (and `walk-robust.ron` from
/// `nunes-simbicon.md`), the SIMBICON sections from `nunes-simbicon.md`.
#[test]
fn nunes_md_quotes_the_generated_results() {
    let reading: &[&str] = &[
        "nunes-results.md",
        "nunes-walk-faithful.md",
        "nunes-optimisers.md",
        "nunes-robustness.md",
        "nunes-protocol.md",
        "nunes-slopes.md",
        "nunes-speeds.md",
    ];
    assert_quotes_generated(
        "nunes.md",
        &[
            ("## Set-up", "## Beyond the thesis: optimisers", reading),
            (
                "## Beyond the thesis: optimisers",
                "## SIMBICON-style",
                &["nunes-optimisers.md", "nunes-simbicon.md"],
            ),
            ("## SIMBICON-style", "## Figures", &["nunes-simbicon.md"]),
        ],
        60,
        "cargo xtask reproduce nunes-…",
    );
}

/// Every `.rs` file under `dir`, recursively, in a fixed order.
fn rust_files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The sentences of the doc comments (`///` and `//!` paragraphs) of a source file, each with the line
/// its paragraph starts on.
fn doc_sentences(source: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut paragraph: Vec<(usize, &str)> = Vec::new();
    let mut flush = |paragraph: &mut Vec<(usize, &str)>| {
        if paragraph.is_empty() {
            return;
        }
        let first = paragraph[0].0;
        let text = paragraph.iter().map(|(_, l)| *l).collect::<Vec<_>>().join(" ");
        let chars: Vec<char> = text.chars().collect();
        let mut start = 0;
        for k in 0..chars.len() {
            // A full stop, then a space and a capital, a parenthesis or a backquote: a sentence ends.
            let ends = chars[k] == '.'
                && chars.get(k + 1) == Some(&' ')
                && chars.get(k + 2).is_some_and(|c| c.is_uppercase() || matches!(c, '(' | '`' | '['));
            if ends || k + 1 == chars.len() {
                out.push((first, chars[start..=k].iter().collect::<String>()));
                start = k + 1;
            }
        }
        paragraph.clear();
    };
    for (n, line) in source.lines().enumerate() {
        let t = line.trim_start();
        match t.strip_prefix("///").or_else(|| t.strip_prefix("//!")) {
            Some(text) if !text.trim().is_empty() => paragraph.push((n + 1, text.trim())),
            _ => flush(&mut paragraph),
        }
    }
    flush(&mut paragraph);
    out
}

/// A crate's documentation that cites a generated report for a measurement quotes only what that
/// report holds: every decimal number of a doc-comment sentence that names a generated report under
/// `docs/` (one whose head says it is generated or written by a command) must be one the report
/// holds, to the digits it is quoted with. A design measurement that no report holds is stated as
/// what it is (a probe's, with its command), not pinned on a report.
#[test]
fn crate_docs_quote_the_generated_reports_they_cite() {
    let repo = Repo::here();
    let root = repo.root();
    let mut files = Vec::new();
    for dir in ["crates", "python/src", "xtask/src"] {
        rust_files(&root.join(dir), &mut files);
    }
    files.retain(|f| f.components().all(|c| c.as_os_str() != "tests"));
    let mut reports: std::collections::BTreeMap<String, Option<Vec<f64>>> = Default::default();
    let (mut checked, mut cited, mut stale) = (0, 0, Vec::new());
    for file in &files {
        let source = std::fs::read_to_string(file).unwrap();
        for (line, sentence) in doc_sentences(&source) {
            let mut rest = sentence.as_str();
            let mut measured = Vec::new();
            let mut names = Vec::new();
            while let Some(at) = rest.find("docs/") {
                let name: String = rest[at + 5..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '/' | '.'))
                    .collect();
                rest = &rest[at + 5..];
                let name = name.trim_end_matches('.').to_owned();
                if !name.ends_with(".md") {
                    continue;
                }
                let held = reports.entry(name.clone()).or_insert_with(|| {
                    let text = std::fs::read_to_string(root.join("docs").join(&name)).ok()?;
                    let head: String = text.lines().take(4).collect::<Vec<_>>().join(" ");
                    (head.contains("Generated by") || head.contains("Written by"))
                        .then(|| decimals(&text).into_iter().map(|(_, v, _)| v).collect())
                });
                if let Some(values) = held {
                    measured.extend_from_slice(values);
                    names.push(name);
                }
            }
            if names.is_empty() {
                continue;
            }
            cited += 1;
            let flat = without_references(&sentence);
            checked += decimals(&flat).len();
            for token in unheld(&flat, &measured) {
                let at = file.strip_prefix(root).unwrap().display();
                stale.push(format!("{at}:{line}: {token} (citing {names:?})"));
            }
        }
    }
    assert!(
        cited >= 10 && checked >= 3,
        "only {cited} doc sentences cite a generated report ({checked} numbers)"
    );
    assert!(
        stale.is_empty(),
        "crate docs quote numbers that the generated reports they cite do not hold (quote the report as it \
         stands, or say the number is a probe's):\n{}",
        stale.join("\n")
    );
}
