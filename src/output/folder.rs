//! The run folder: always exactly one whole run.
//!
//! A run writes into a staging folder beside the target (`.NAME.staging-PID`) and, when
//! every file is complete, syncs it once (all files at a time) and swaps it in place of the target (the old folder is renamed
//! aside, then removed), so an interrupted run leaves the previous folder untouched and a
//! re-run leaves no stale file of an older one. An existing folder holding anything a run
//! does not write is refused (input error), never replaced. A lock file beside the target
//! (`.NAME.lock`, holding the process id) refuses a second run into the same folder while
//! the first is alive; a lock whose process is gone is taken over, and the staging folders
//! such a process left (SIGKILL) are removed. SIGINT and SIGTERM
//! remove the staging folder and the lock before the process ends (exit 130).

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
        let _ = std::fs::remove_dir_all(p);
    } else {
        let _ = std::fs::remove_file(p);
    }
}

/// Installs the SIGINT/SIGTERM handler (once per process; later calls do nothing).
fn install_signal_cleanup() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            for p in cleanup_list().iter() {
                remove_path(p);
            }
            let _ = writeln!(
                std::io::stderr(),
                "sgbem: interrupted: the run folder was left as it was"
            );
            std::process::exit(130);
        });
    });
}

/// Names a run writes into its folder.
const RUN_ENTRIES: [&str; 7] = [
    "summary.json",
    "timings.json",
    "archive.h5",
    "vtk",
    "interfaces",
    "sections",
    "mesh",
];

/// The first entry of an existing `target` that a run does not write (so the folder is not
/// a run folder, and replacing it would lose data); None for a new, empty or run folder.
fn foreign_entry(target: &Path) -> Option<String> {
    let entries = std::fs::read_dir(target).ok()?;
    entries
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .find(|n| {
            !(RUN_ENTRIES.contains(&n.as_str()) || (n.starts_with('.') && n.ends_with(".tmp")))
        })
}

/// Removes the staging and set-aside folders of runs into `target` whose process is gone
/// (killed with SIGKILL, or the machine stopped); the caller holds the lock.
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
        let pid = [".staging-", ".old-"].iter().find_map(|kind| {
            file.strip_prefix(&format!(".{name}{kind}"))
                .and_then(|p| p.parse::<u32>().ok())
        });
        if let Some(pid) = pid {
            if pid == std::process::id() || !process_alive(pid) {
                remove_path(&entry.path());
            }
        }
    }
}

/// A run folder being written.
pub struct RunFolder {
    target: PathBuf,
    staging: PathBuf,
    lock: PathBuf,
    committed: bool,
}

/// `.NAME.SUFFIX` beside `target`.
fn beside(target: &Path, suffix: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    target.with_file_name(format!(".{name}.{suffix}"))
}

fn process_alive(pid: u32) -> bool {
    Path::new("/proc").join(pid.to_string()).exists()
}

impl RunFolder {
    /// Takes the lock of `target` and creates an empty staging folder beside it.
    pub fn acquire(target: &Path) -> Result<RunFolder> {
        let target = if target.file_name().is_none() {
            // "out/" or "." : name the folder itself.
            std::path::absolute(target).map_err(|e| Error::io(target, e))?
        } else {
            target.to_path_buf()
        };
        if target.exists() && !target.is_dir() {
            return Err(Error::io(
                &target,
                "the output path is a file, not a folder: remove it or choose another --out",
            ));
        }
        if let Some(stranger) = foreign_entry(&target) {
            return Err(Error::input(
                &target,
                format!(
                    "the output folder exists and holds `{stranger}`, which no sgbem run \
                     writes: a run replaces its whole folder, so give --out (or \
                     output.directory) a new or former run folder"
                ),
            ));
        }
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent)
            .map_err(|e| Error::io(&parent, format!("cannot create the folder: {e}")))?;
        install_signal_cleanup();
        let pid = std::process::id();
        let lock = beside(&target, "lock");
        let mut taken = false;
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&lock)
            {
                Ok(mut f) => {
                    let _ = writeln!(f, "{pid}");
                    taken = true;
                    break;
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = std::fs::read_to_string(&lock)
                        .ok()
                        .and_then(|t| t.trim().parse::<u32>().ok());
                    match holder {
                        Some(p) if p != pid && process_alive(p) => {
                            return Err(Error::io(
                                &target,
                                format!(
                                    "another sgbem run (process {p}) is writing this folder: \
                                     wait for it to finish, or give this run another --out \
                                     (lock file {})",
                                    lock.display()
                                ),
                            ));
                        }
                        // The process that held it is gone: the lock is stale.
                        _ => {
                            let _ = std::fs::remove_file(&lock);
                        }
                    }
                }
                Err(e) => {
                    return Err(Error::io(
                        &lock,
                        format!("cannot create the lock file: {e}"),
                    ))
                }
            }
        }
        if !taken {
            return Err(Error::io(
                &lock,
                "cannot take the lock file: remove it if no sgbem run is writing this folder",
            ));
        }
        cleanup_list().push(lock.clone());
        remove_leftovers(&target, &parent);
        let staging = beside(&target, &format!("staging-{pid}"));
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

    /// Syncs the complete staging folder (every file and folder, many at a time:
    /// [`super::sync_tree`]) and swaps it in place of the target, then syncs the parent
    /// folder so that the swap itself is durable.
    pub fn commit(mut self) -> Result<()> {
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
            remove_path(&old);
        }
        Ok(())
    }
}

impl Drop for RunFolder {
    fn drop(&mut self) {
        if !self.committed {
            remove_path(&self.staging);
        }
        remove_path(&self.lock);
        cleanup_list().retain(|p| *p != self.staging && *p != self.lock);
    }
}
