//! The run folder: always exactly one whole run, and never a file the tool did not write.
//!
//! A run writes into a staging folder beside the target (`.NAME.staging-PID`) and, when
//! every file is complete, marks it as the tool's (`.sgbem-run.json` lists every file
//! written: [`super::owned`]), syncs it once (all files at a time) and swaps it in place of
//! the target (the old folder is renamed aside, then loses the files its own marker lists),
//! so an interrupted run leaves the previous folder untouched and a re-run leaves no stale
//! file of an older one. An existing folder holding anything its marker does not list (or
//! anything at all, without a marker) is refused (input error, naming those files), never
//! replaced. A lock beside the target (`.NAME.lock`, locked with `flock`, so the kernel
//! releases it whenever the process ends) refuses a second run into the same folder while
//! the first is alive; the staging folders a killed run left are removed by the next one.
//! SIGINT and SIGTERM remove the staging folder and the lock file before the process ends
//! (exit 130). A symbolic link given as the folder is followed: the folder it points to is
//! the one replaced, and the link stays.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::error::{Error, Result};

/// Paths to remove if the process is interrupted.
static CLEANUP: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn cleanup_list() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    CLEANUP.lock().unwrap_or_else(|e| e.into_inner())
}

fn remove_path(p: &Path) {
    if p.is_dir() {
        // A writer thread may still add a file while the folder is removed: try again.
        for _ in 0..20 {
            if std::fs::remove_dir_all(p).is_ok() || !p.exists() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    } else {
        let _ = std::fs::remove_file(p);
    }
}

/// Removes the staging folder and the lock file of the run in progress (a process about
/// to end abruptly: a signal, a failed allocation); the folder itself stays as it was.
pub fn remove_unfinished() {
    for p in cleanup_list().iter() {
        remove_path(p);
    }
}

/// Installs the SIGINT/SIGTERM handler (once per process; later calls do nothing).
fn install_signal_cleanup() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            remove_unfinished();
            let _ = writeln!(
                std::io::stderr(),
                "sgbem: interrupted: the run folder was left as it was"
            );
            std::process::exit(130);
        });
    });
}

/// Removes the staging and set-aside folders that runs into `target` left (killed with
/// SIGKILL, or the machine stopped): the caller holds the lock, so no live run owns any.
/// A set-aside folder loses only what its marker lists.
fn remove_leftovers(target: &Path, parent: &Path) {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let kind = |k: &str| {
            file.strip_prefix(&format!(".{name}.{k}-"))
                .is_some_and(|p| p.parse::<u32>().is_ok())
        };
        if kind("staging") {
            remove_path(&entry.path());
        } else if kind("old") {
            let listed = match super::owned::owner(&entry.path()) {
                Ok(Some(o)) if o.prefix.is_empty() => o.entries,
                _ => continue,
            };
            super::owned::remove_listed(&entry.path(), &listed);
        }
    }
}

/// The longest name of an output folder: `.NAME.staging-PID` (PID up to 7 digits) must fit
/// in the 255 bytes of a file name.
const MAX_NAME: usize = 255 - ".".len() - ".staging-".len() - 7;

/// A run folder being written.
pub struct RunFolder {
    target: PathBuf,
    staging: PathBuf,
    lock: Lock,
    committed: bool,
}

/// `.NAME.SUFFIX` beside `target`.
pub(crate) fn beside(target: &Path, suffix: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    target.with_file_name(format!(".{name}.{suffix}"))
}

/// The lock of a folder: `.NAME.lock` beside it, locked with `flock` (the kernel releases
/// it when the process ends, however it ends). The file holds the process id, for the
/// message of a refused run only; the holder removes it before unlocking, so a run that
/// locked a file no longer at the path tries again. A symbolic link, folder or special file
/// at the path is refused, never written through.
pub(crate) struct Lock {
    path: PathBuf,
    file: Option<std::fs::File>,
}

impl Lock {
    pub(crate) fn take(path: &Path, target: &Path) -> Result<Lock> {
        use std::os::unix::fs::MetadataExt;
        for _ in 0..100 {
            // The file is written (the process id): never through a link to another file.
            if let Ok(m) = std::fs::symlink_metadata(path) {
                if !m.is_file() {
                    return Err(Error::io(
                        path,
                        format!(
                            "the lock file is {}, not a file sgbem wrote: sgbem writes its \
                             process id there; remove it, or give this run another --out",
                            if m.file_type().is_symlink() {
                                "a symbolic link"
                            } else if m.is_dir() {
                                "a folder"
                            } else {
                                "a special file"
                            }
                        ),
                    ));
                }
            }
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(path)
                .map_err(|e| Error::io(path, format!("cannot create the lock file: {e}")))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    let holder = std::fs::read_to_string(path)
                        .map(|t| format!(" (process {})", t.trim()))
                        .unwrap_or_default();
                    return Err(Error::io(
                        target,
                        format!(
                            "another sgbem run{holder} is writing this folder: wait for it \
                             to finish, or give this run another --out (lock file {})",
                            path.display()
                        ),
                    ));
                }
                Err(std::fs::TryLockError::Error(e)) => {
                    return Err(Error::io(path, format!("cannot lock the folder: {e}")))
                }
            }
            // The file locked must still be the one at the path (a holder removes it).
            let same = match (file.metadata(), std::fs::symlink_metadata(path)) {
                (Ok(a), Ok(b)) => a.ino() == b.ino() && a.dev() == b.dev(),
                _ => false,
            };
            if same {
                let _ = file.set_len(0);
                let _ = (&file).write_all(format!("{}\n", std::process::id()).as_bytes());
                return Ok(Lock {
                    path: path.to_path_buf(),
                    file: Some(file),
                });
            }
        }
        Err(Error::io(
            path,
            "cannot take the lock file: it keeps being replaced; is another program \
             writing it?",
        ))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        if self.file.is_some() {
            let _ = std::fs::remove_file(&self.path);
        }
        // Closing the file releases the lock.
        self.file = None;
    }
}

impl RunFolder {
    /// Takes the lock of `target`, checks that the tool may replace it (new, empty, or
    /// holding only what its marker lists: [`super::owned`], and none of the command's
    /// `inputs`), and creates an empty staging folder beside it.
    pub(crate) fn acquire(target: &Path, inputs: &[&Path]) -> Result<RunFolder> {
        let target = if target.file_name().is_none() {
            // "out/" or "." : name the folder itself.
            std::path::absolute(target).map_err(|e| Error::io(target, e))?
        } else {
            target.to_path_buf()
        };
        let target = through_link(target)?;
        let name_len = target.file_name().map_or(0, |n| n.len());
        if name_len > MAX_NAME {
            return Err(Error::io(
                &target,
                format!(
                    "the output folder's name has {name_len} bytes: sgbem writes \
                     `.NAME.staging-PID` beside it, and a file name has at most 255 bytes; give \
                     --out a name of at most {MAX_NAME} bytes"
                ),
            ));
        }
        if target.exists() && !target.is_dir() {
            return Err(Error::io(
                &target,
                "the output path is a file, not a folder: remove it or choose another --out",
            ));
        }
        check_replaceable(&target)?;
        check_inputs(&target, inputs)?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(|e| {
            let why = if parent.ancestors().any(|a| a.is_file()) {
                ": a part of the path is a file, not a folder; give --out a path of folders"
            } else {
                ""
            };
            Error::io(&parent, format!("cannot create the folder: {e}{why}"))
        })?;
        install_signal_cleanup();
        let lock_path = beside(&target, "lock");
        let lock = Lock::take(&lock_path, &target)?;
        cleanup_list().push(lock_path);
        remove_leftovers(&target, &parent);
        let staging = beside(&target, &format!("staging-{}", std::process::id()));
        remove_path(&staging);
        cleanup_list().push(staging.clone());
        let folder = RunFolder {
            target,
            staging,
            lock,
            committed: false,
        };
        std::fs::create_dir_all(&folder.staging)
            .map_err(|e| Error::io(&folder.staging, format!("cannot create the folder: {e}")))?;
        Ok(folder)
    }

    /// Where the run writes its files.
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// The folder the run ends up in.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Marks the staging folder as the tool's, syncs it (every file and folder, many at a
    /// time: [`super::sync_tree`]) and swaps it in place of the target (checked again: the
    /// user may have added a file meanwhile), then syncs the parent folder so that the swap
    /// itself is durable. Of the previous folder only the entries its marker lists are
    /// removed.
    pub fn commit(mut self) -> Result<()> {
        use super::owned;
        let written = owned::listing(&self.staging);
        let previous = check_replaceable(&self.target)?;
        // A folder owned through its parent's marker (an export into a run's vtk/) is
        // listed there; any other gets a marker of its own.
        let in_parent = previous.as_ref().filter(|o| !o.prefix.is_empty());
        if in_parent.is_none() {
            super::write_staged(
                &self.staging.join(owned::MARKER),
                owned::marker_text(&written).as_bytes(),
            )?;
        }
        super::sync_tree(&self.staging).map_err(|(p, e)| {
            Error::io(
                &p,
                format!("cannot write the run to the device: {e}; check the disk"),
            )
        })?;
        let old = beside(&self.target, &format!("old-{}", std::process::id()));
        let had_old = self.target.exists();
        if had_old {
            remove_path(&old);
            std::fs::rename(&self.target, &old).map_err(|e| {
                Error::io(
                    &self.target,
                    format!("cannot move the previous run aside to replace it: {e}"),
                )
            })?;
        }
        if let Err(e) = std::fs::rename(&self.staging, &self.target) {
            if had_old {
                let _ = std::fs::rename(&old, &self.target);
            }
            return Err(Error::io(
                &self.target,
                format!("cannot move the finished run into place: {e}"),
            ));
        }
        self.committed = true;
        if let Some(o) = in_parent {
            let mut entries: std::collections::BTreeSet<String> = o
                .entries
                .iter()
                .filter(|e| !e.starts_with(&o.prefix) || **e == o.prefix)
                .cloned()
                .collect();
            entries.extend(written.iter().map(|w| format!("{}{w}", o.prefix)));
            super::write_atomic(&o.marker, owned::marker_text(&entries).as_bytes())?;
        }
        // The new folder is in place; syncing its parent makes the rename durable. A failure
        // here leaves a complete run whose swap a crash might undo: not worth an error.
        if let Some(parent) = self.target.parent() {
            let parent = if parent.as_os_str().is_empty() {
                Path::new(".")
            } else {
                parent
            };
            let _ = super::sync_paths(&[parent.to_path_buf()]);
        }
        if had_old {
            let listed = previous.map(|o| o.inside()).unwrap_or_default();
            owned::remove_listed(&old, &listed);
        }
        Ok(())
    }
}

/// The folder a symbolic link given as the output folder points to (the run is staged
/// beside that folder and swapped in there, the link kept); a link that leads nowhere is
/// refused, since the run would replace the link itself.
fn through_link(target: PathBuf) -> Result<PathBuf> {
    let is_link = std::fs::symlink_metadata(&target).is_ok_and(|m| m.file_type().is_symlink());
    if !is_link {
        return Ok(target);
    }
    match std::fs::canonicalize(&target) {
        Ok(real) if real.is_dir() => Ok(real),
        Ok(real) => Err(Error::io(
            &target,
            format!(
                "the output path is a symbolic link to {}, which is not a folder: give --out \
                 a folder",
                real.display()
            ),
        )),
        Err(e) => Err(Error::io(
            &target,
            format!(
                "the output path is a symbolic link that leads nowhere ({e}): create the \
                 folder it points to, or give --out another folder"
            ),
        )),
    }
}

/// Refuses (input error) a `target` that holds one of the command's own input files: the
/// archive an export reads (`--vtk` given the run folder itself), a mesh an earlier run
/// wrote into its `mesh/`. Replacing the folder would delete the input with the results.
fn check_inputs(target: &Path, inputs: &[&Path]) -> Result<()> {
    let Ok(real) = std::fs::canonicalize(target) else {
        return Ok(());
    };
    for input in inputs {
        if std::fs::canonicalize(input).is_ok_and(|f| f.starts_with(&real)) {
            return Err(Error::input(
                input,
                format!(
                    "this input of the command lies in the output folder {}, which the \
                     command replaces whole: give --out (or --vtk) another folder, or copy the \
                     file out of it first",
                    target.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses (input error, naming them) a `target` holding entries its marker does not
/// list; returns that marker's owner (None for a new or empty folder).
fn check_replaceable(target: &Path) -> Result<Option<super::owned::Owner>> {
    use super::owned;
    let owner = owned::owner(target)?;
    if !target.is_dir() {
        return Ok(owner);
    }
    let strangers = owned::foreign(target, owner.as_ref());
    if strangers.is_empty() {
        Ok(owner)
    } else {
        Err(owned::refusal(target, &strangers, owner.is_some()))
    }
}

impl Drop for RunFolder {
    fn drop(&mut self) {
        if !self.committed {
            remove_path(&self.staging);
        }
        cleanup_list().retain(|p| *p != self.staging && *p != self.lock.path);
    }
}
