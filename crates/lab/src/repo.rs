//! The repository an experiment reads its assets from and writes its reports, figures and caches into.
//!
//! The experiments need the thesis's scenes, meshes and controllers (`assets/`), and their reports go to
//! `docs/`, their figures to `docs/figures/` and their slow references to a cache under `target/`. All
//! of these are found one way: from a [`Repo`], which is the repository this crate was built in unless
//! the caller names another folder (`ANIMA_REPO` for the command-line tools). Nothing is written
//! outside the repository's folder, and every file is written whole ([`write_atomic`]).

use std::path::{Path, PathBuf};

use anima_viz::Image;
use anyhow::{Context, Result};

use crate::output::write_atomic;
use crate::report::Document;

/// The folders of an anima repository.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Repo {
    root: PathBuf,
}

impl Repo {
    /// The repository at `root` (the folder holding `assets/` and `docs/`).
    pub fn at(root: impl Into<PathBuf>) -> Self {
        Self { root: root.into() }
    }

    /// `ANIMA_REPO` when set, else the repository this crate was built in.
    pub fn here() -> Self {
        match std::env::var_os("ANIMA_REPO") {
            Some(root) => Self::at(root),
            None => Self::at(Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")),
        }
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    /// A file or folder under `assets/`, e.g. `assets("flex3d/a2-8-toalha.par")`.
    pub fn assets(&self, rel: impl AsRef<Path>) -> PathBuf {
        self.root.join("assets").join(rel)
    }

    /// A file under `docs/`.
    pub fn docs(&self, rel: impl AsRef<Path>) -> PathBuf {
        self.root.join("docs").join(rel)
    }

    /// A file of the cache of slow references and logs, `target/anima-lab/`.
    pub fn cache(&self, rel: impl AsRef<Path>) -> PathBuf {
        self.root.join("target/anima-lab").join(rel)
    }

    /// A file under `out/`, where per-step logs of the reproductions go.
    pub fn out(&self, rel: impl AsRef<Path>) -> PathBuf {
        self.root.join("out").join(rel)
    }

    /// Writes `docs/figures/<name>` as PNG.
    pub fn write_figure(&self, name: &str, image: &Image) -> Result<()> {
        let path = self.docs("figures").join(name);
        write_atomic(&path, |w| Ok(image.write_png(w)?))?;
        eprintln!("anima-lab: wrote docs/figures/{name}");
        Ok(())
    }

    /// Writes a text file under the repository root (a report, a controller found by a search).
    pub fn write_text(&self, rel: impl AsRef<Path>, text: &str) -> Result<()> {
        let path = self.root.join(rel.as_ref());
        write_atomic(&path, |w| Ok(w.write_all(text.as_bytes())?))?;
        eprintln!("anima-lab: wrote {}", rel.as_ref().display());
        Ok(())
    }

    /// Writes the sections of `doc` into `docs/<rel>`, keeping every section of the file there that
    /// `doc` does not have: a partial run (one test, one experiment) updates only its own part.
    pub fn write_report(&self, rel: &str, doc: &Document) -> Result<()> {
        let path = self.docs(rel);
        let existing = match std::fs::read_to_string(&path) {
            Ok(text) => Some(text),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
        };
        let text = doc.merged_into(existing.as_deref());
        self.write_text(Path::new("docs").join(rel), &text)
    }
}
