//! Output files written all or nothing.
//!
//! A run that writes several files (an image, its EXR, its stats) promises that a failure
//! leaves every existing file as it was. So each output is first written to a temporary file
//! in its destination's directory ([`stage`]); only when all of them have been written are
//! they renamed into place ([`commit_all`]), and a rename within one directory is atomic.
//! Before any work, [`check_outputs`] refuses destinations that could not be written: a
//! missing directory, a directory given as a file, or one file named twice (which would leave
//! only the last writer's bytes, under the first writer's name).
//!
//! Temporaries are removed when dropped, and, once [`remove_temporaries_on_signal`] has been
//! called, when the process is interrupted or terminated (SIGINT, SIGTERM, SIGHUP), which would
//! otherwise skip every destructor and leave them behind.

use std::{
    path::{Path, PathBuf},
    sync::Mutex,
};

use anyhow::{Context, Result, bail};

/// The temporaries that exist now, for the signal handler.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A panic while the lock was held cannot leave the list inconsistent (pushes and
    // removals are single calls), so a poisoned lock is still usable.
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// Installs a handler that removes the live temporaries and exits with status 130 on SIGINT,
/// SIGTERM or SIGHUP. Call once, from the binary (a library must not own the process's
/// signals); a second call is an error.
pub fn remove_temporaries_on_signal() -> Result<()> {
    ctrlc::set_handler(|| {
        for p in live().iter() {
            let _ = std::fs::remove_file(p);
        }
        std::process::exit(130);
    })
    .context("cannot install the signal handler")
}

/// A finished output in a temporary file beside its destination, not yet in place. Dropped
/// without [`Staged::commit`], the temporary is removed.
pub struct Staged {
    tmp: Option<tempfile::TempPath>,
    dest: PathBuf,
}

impl Staged {
    /// The destination.
    pub fn path(&self) -> &Path {
        &self.dest
    }

    /// Renames the temporary over the destination.
    pub fn commit(mut self) -> Result<()> {
        let tmp = self.tmp.take().expect("a staged file is committed once");
        let tmp_path = tmp.to_path_buf();
        let res = tmp
            .persist(&self.dest)
            .map_err(|e| e.error)
            .with_context(|| format!("{}: cannot move the finished file into place", self.dest.display()));
        forget(&tmp_path);
        res
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(tmp) = self.tmp.take() {
            let p = tmp.to_path_buf();
            drop(tmp);
            forget(&p);
        }
    }
}

fn forget(p: &Path) {
    live().retain(|q| q != p);
}

/// The directory a destination's temporary goes to: the destination's own, so that the final
/// rename never crosses file systems.
fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Runs `write` on a new temporary file beside `path` and keeps it there (see [`Staged`]).
pub fn stage(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<Staged> {
    if path.file_name().is_none() {
        bail!("{}: not a file name", path.display());
    }
    let dir = dir_of(path);
    let mut builder = tempfile::Builder::new();
    // Temporary files are private (0600) by default; the finished file should get the usual
    // permissions (0666 less the umask), like any file the user creates.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let file = builder
        .prefix(".hyrt-")
        .suffix(&format!(".{}", path.extension().and_then(|e| e.to_str()).unwrap_or("tmp")))
        .tempfile_in(dir)
        .with_context(|| format!("{}: cannot create a file in {}", path.display(), dir.display()))?;
    let tmp = file.into_temp_path();
    live().push(tmp.to_path_buf());
    let staged = Staged { tmp: Some(tmp), dest: path.to_path_buf() };
    let tmp_path = staged.tmp.as_ref().map(|t| t.to_path_buf()).unwrap_or_default();
    write(&tmp_path).with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(staged)
}

/// Moves every staged file into place, in order.
///
/// Each rename is atomic; [`check_outputs`] has made the failure of one after another has
/// succeeded unlikely (same directories, checked beforehand), though not impossible (the disk
/// or the directory can change meanwhile).
pub fn commit_all(staged: Vec<Staged>) -> Result<()> {
    for s in staged {
        s.commit()?;
    }
    Ok(())
}

/// Writes one file atomically: [`stage`], then [`Staged::commit`].
pub fn atomic_write(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    stage(path, write)?.commit()
}

/// Refuses, before any work, outputs that cannot all be written: a destination whose
/// directory does not exist, one that is a directory, one without a file name, and the same
/// file named twice (compared after resolving the directories).
pub fn check_outputs(paths: &[&Path]) -> Result<()> {
    let mut seen: Vec<(PathBuf, &Path)> = Vec::with_capacity(paths.len());
    for &p in paths {
        let Some(name) = p.file_name() else {
            bail!("{}: not a file name", p.display());
        };
        let dir = dir_of(p);
        if !dir.is_dir() {
            bail!("{}: cannot write: directory {} does not exist", p.display(), dir.display());
        }
        if p.is_dir() {
            bail!("{}: cannot write: it is a directory", p.display());
        }
        let resolved = dir
            .canonicalize()
            .with_context(|| format!("{}: cannot resolve directory {}", p.display(), dir.display()))?
            .join(name);
        if let Some((_, first)) = seen.iter().find(|(r, _)| *r == resolved) {
            bail!(
                "{}: the same file is given for two outputs ({} and {})",
                p.display(),
                first.display(),
                p.display()
            );
        }
        seen.push((resolved, p));
    }
    Ok(())
}
