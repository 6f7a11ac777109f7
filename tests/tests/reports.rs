//! Generated reports stay true: a report whose content does not depend on the machine is regenerated
//! here and compared with the committed file, the way rust-analyzer checks its generated code.
//!
//! Only `docs/reproduction/flex3d-results.md`, the faithful-SIMBICON section of `nunes-simbicon.md`,
//! `nunes-walk-faithful.md` and `nunes-robustness.md` (a minute each) can be checked this way. The
//! others hold wall times (`oliveira-results.md`, `oliveira-implicit.md`, `oliveira-adaptive.md`,
//! `nunes-results.md`'s run time per iteration, `benchmarks.md`) or take minutes to an hour to
//! regenerate (`nunes-optimisers.md`, the SIMBICON-style section of `nunes-simbicon.md`, the adaptive
//! report): their commands rewrite them, and a partial run rewrites only its own sections.

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
