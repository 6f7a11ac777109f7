//! Whole-file output: every file is written under a temporary name in the same folder and renamed into
//! place, so a reader never sees half a file and an interrupted run never clobbers a good one. The
//! temporary files being written are known ([`remove_temporaries`]), so an interrupt can take them away.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result};

/// The temporary files being written now.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn temporaries() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARIES.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Removes every temporary file being written, for an interrupt handler: the program must end right
/// after. The list stays locked from then on, and a temporary file is only created under that lock,
/// so no writer can create a new one once these are gone (it waits for the end instead).
pub fn remove_temporaries() {
    let tmps = temporaries();
    for tmp in tmps.iter() {
        let _ = fs::remove_file(tmp);
    }
    std::mem::forget(tmps);
}

/// Creates `dir` if it is not there and checks that a file can be written in it, before a run spends
/// its time: a run that cannot save its results fails at once.
pub fn check_writable(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let probe = dir.join(format!(".anima-probe{}", std::process::id()));
    File::create(&probe).with_context(|| format!("{} is not writable", dir.display()))?;
    fs::remove_file(&probe).with_context(|| format!("removing {}", probe.display()))
}

/// Removes the files of `dir` that `ours` recognises by name (the frames an earlier run of the same
/// scene left there, which a shorter run would leave beside its own); returns how many.
pub fn remove_stale(dir: &Path, ours: impl Fn(&str) -> bool) -> Result<usize> {
    let Ok(entries) = fs::read_dir(dir) else { return Ok(0) };
    let mut removed = 0;
    for entry in entries {
        let entry = entry.with_context(|| format!("listing {}", dir.display()))?;
        let name = entry.file_name();
        if name.to_str().is_some_and(&ours) && entry.path().is_file() {
            fs::remove_file(entry.path()).with_context(|| format!("removing {}", entry.path().display()))?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// Whether `name` is `<prefix><digits><suffix>`: a frame file of a run.
pub fn is_frame_file(name: &str, prefix: &str, suffix: &str) -> bool {
    name.strip_prefix(prefix)
        .and_then(|r| r.strip_suffix(suffix))
        .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
}

/// Refuses to write `path` where something other than a regular file stands: a folder, a device, a
/// FIFO or a socket would be replaced by the rename of [`write_atomic`] (or, for a folder, the write
/// would fail after the run). A symbolic link is replaced, never written through, so it is allowed.
pub fn check_output_path(path: &Path) -> Result<()> {
    if path.file_name().is_none() {
        anyhow::bail!("{} names no file to write", path.display());
    }
    match fs::symlink_metadata(path) {
        Ok(meta) => {
            let kind = meta.file_type();
            if kind.is_file() || kind.is_symlink() {
                Ok(())
            } else {
                let what =
                    if kind.is_dir() { "a folder" } else { "not a regular file (a device, FIFO or socket)" };
                anyhow::bail!(
                    "{} is {what}; anima writes its output to a new or regular file only",
                    path.display()
                )
            }
        }
        Err(_) => Ok(()),
    }
}

/// Writes `path` through `fill`, atomically (temporary file, then rename), refusing a path where
/// something other than a regular file stands ([`check_output_path`]).
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    check_output_path(path)?;
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let name = path.file_name().with_context(|| format!("{} has no file name", path.display()))?;
    let tmp = dir.join(format!(".{}.tmp{}", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        // Created and listed under one lock: an interrupt sees either no file or a listed one.
        let file = {
            let mut tmps = temporaries();
            let file = File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
            tmps.push(tmp.clone());
            file
        };
        let mut w = BufWriter::new(file);
        fill(&mut w)?;
        let file = w
            .into_inner()
            .map_err(|e| e.into_error())
            .with_context(|| format!("writing {}", tmp.display()))?;
        file.sync_data().ok();
        fs::rename(&tmp, path).with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    let mut tmps = temporaries();
    if let Some(k) = tmps.iter().position(|t| *t == tmp) {
        tmps.swap_remove(k);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_files_are_told_by_name() {
        assert!(is_frame_file("toalha_12.OBT", "toalha_", ".OBT"));
        assert!(!is_frame_file("toalha_.OBT", "toalha_", ".OBT"));
        assert!(!is_frame_file("toalha_1x.OBT", "toalha_", ".OBT"));
        assert!(!is_frame_file("summary.json", "toalha_", ".OBT"));
    }

    #[test]
    fn only_new_or_regular_files_are_written() {
        let dir = std::env::temp_dir().join(format!("anima-output-kinds-{}", std::process::id()));
        fs::create_dir_all(dir.join("folder")).unwrap();
        let e = write_atomic(&dir.join("folder"), |w| Ok(w.write_all(b"x")?)).unwrap_err();
        assert!(e.to_string().contains("is a folder"), "{e}");
        assert!(dir.join("folder").is_dir(), "the folder is kept");
        #[cfg(unix)]
        {
            let e = write_atomic(Path::new("/dev/null"), |w| Ok(w.write_all(b"x")?)).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        assert!(check_output_path(Path::new("/")).is_err(), "the root names no file");
        write_atomic(&dir.join("new.txt"), |w| Ok(w.write_all(b"new")?)).unwrap();
        write_atomic(&dir.join("new.txt"), |w| Ok(w.write_all(b"again")?)).unwrap();
        assert_eq!(fs::read_to_string(dir.join("new.txt")).unwrap(), "again");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failed_write_keeps_the_old_file() {
        let dir = std::env::temp_dir().join(format!("anima-output-test-{}", std::process::id()));
        let path = dir.join("a.txt");
        write_atomic(&path, |w| Ok(w.write_all(b"good")?)).unwrap();
        let err = write_atomic(&path, |w| {
            w.write_all(b"half")?;
            anyhow::bail!("interrupted")
        });
        assert!(err.is_err());
        assert_eq!(fs::read_to_string(&path).unwrap(), "good");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1, "no temporary file is left behind");
        fs::remove_dir_all(&dir).unwrap();
    }
}
