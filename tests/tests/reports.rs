//! Generated reports stay true: a report whose content does not depend on the machine is regenerated
//! here and compared with the committed file, the way rust-analyzer checks its generated code.
//!
//! Only `docs/reproduction/flex3d-results.md` and the faithful-SIMBICON section of `nunes-simbicon.md`
//! can be checked this way. The others hold wall times (`oliveira-results.md`, `oliveira-implicit.md`,
//! `oliveira-adaptive.md`, `nunes-results.md`'s run time per iteration, `benchmarks.md`) or take minutes
//! to an hour to regenerate (`nunes-optimisers.md`, the SIMBICON-style section of `nunes-simbicon.md`, the
//! adaptive report): their commands rewrite them, and a partial run rewrites only its own sections.

use anima_cloth::flex3d::FrictionMode;
use anima_lab::repo::Repo;

#[test]
fn the_committed_flex3d_results_are_what_reproduce_all_writes() {
    let (doc, failed) = anima_lab::flex3d::report::reproduce("all", FrictionMode::Literal).unwrap();
    assert!(failed.is_empty(), "criteria that do not hold: {failed:?}");
    let path = Repo::here().docs("reproduction/flex3d-results.md");
    let fresh = doc.render();
    if std::env::var_os("UPDATE_REPORTS").is_some() {
        std::fs::write(&path, &fresh).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap();
    assert!(
        fresh == committed,
        "docs/reproduction/flex3d-results.md is stale: run `cargo xtask reproduce all` (or \
         `UPDATE_REPORTS=1 cargo test -p anima-tests --release reports`) and review the diff"
    );
}

#[test]
fn the_committed_faithful_simbicon_section_is_what_its_command_writes() {
    use anima_lab::nunes::faithful;
    let section = faithful::section().unwrap();
    let path = Repo::here().docs(faithful::REPORT);
    let committed = std::fs::read_to_string(&path).unwrap();
    let fresh = faithful::document(&section).merged_into(Some(&committed));
    if std::env::var_os("UPDATE_REPORTS").is_some() {
        std::fs::write(&path, &fresh).unwrap();
    }
    assert!(
        fresh == committed,
        "docs/reproduction/nunes-simbicon.md's faithful section is stale: run `cargo xtask reproduce \
         nunes-simbicon-faithful` (or `UPDATE_REPORTS=1 cargo test -p anima-tests --release reports`) and review \
         the diff"
    );
}
