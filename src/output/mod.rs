//! Writers: they serialise result records and nothing else; nothing imports them but the
//! pipeline. Every file is written under a temporary name and renamed when complete, so an
//! interrupted run never leaves a file that looks finished.
//!
//! **Syncing.** A file must reach the device before the rename that makes it visible, or a
//! crash of the machine can leave a complete-looking name on empty content. One `fsync`
//! costs a journal commit (about 3 ms here), but concurrent ones share a commit, so files
//! are synced many at a time ([`sync_paths`]): files outside a run folder by [`write_atomic`]
//! and [`write_files`] before their renames; the files of a run, written unsynced into its
//! staging folder ([`write_staged`]), all at once when the folder is committed
//! ([`folder::RunFolder::commit`]), before it is renamed into place.

pub mod archive;
pub mod csv;
pub mod folder;
pub mod owned;
pub mod progress;
pub mod record;
pub mod size;
pub mod space;
mod stamp;
pub mod summary;
pub mod vtk;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::error::{Error, Result};

/// Writes `bytes` to `path` atomically and durably (temporary file in the same folder, synced,
/// then renamed).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_files(&[path.to_path_buf()], true, |_| Ok(bytes.to_vec()))
}

/// Writes one file of a run's staging folder: under a temporary name, renamed when complete,
/// not synced (the commit of the folder syncs every file at once).
pub fn write_staged(path: &Path, bytes: &[u8]) -> Result<()> {
    write_files(&[path.to_path_buf()], false, |_| Ok(bytes.to_vec()))
}

/// The temporary name of `path` while it is written.
fn temporary(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes `make(i)` to `paths[i]` for every i, the files made and written in parallel
/// (rayon), each under a temporary name and renamed when complete. With `durable`, the
/// temporary files are synced ([`sync_paths`]) before the first rename and the folders after
/// the last; without, the caller syncs them (a staged run folder when committed).
pub fn write_files(
    paths: &[PathBuf],
    durable: bool,
    make: impl Fn(usize) -> Result<Vec<u8>> + Sync,
) -> Result<()> {
    use rayon::prelude::*;
    let mut dirs: Vec<PathBuf> = paths
        .iter()
        .filter_map(|p| p.parent().map(Path::to_path_buf))
        .collect();
    dirs.sort();
    dirs.dedup();
    for dir in &dirs {
        std::fs::create_dir_all(dir)
            .map_err(|e| Error::io(dir, format!("cannot create the folder: {e}")))?;
    }
    let temps: Vec<PathBuf> = paths.iter().map(|p| temporary(p)).collect();
    let clean = |e: Error| {
        for t in &temps {
            let _ = std::fs::remove_file(t);
        }
        e
    };
    let written: Result<()> = (0..paths.len()).into_par_iter().try_for_each(|i| {
        let bytes = make(i)?;
        std::fs::File::create(&temps[i])
            .and_then(|mut f| f.write_all(&bytes))
            .map_err(|e| Error::io(&paths[i], format!("cannot write: {e}")))
    });
    written.map_err(clean)?;
    if durable {
        sync_paths(&temps).map_err(|(p, e)| clean(Error::io(&p, format!("cannot write: {e}"))))?;
    }
    for (t, p) in temps.iter().zip(paths) {
        std::fs::rename(t, p).map_err(|e| clean(Error::io(p, format!("cannot write: {e}"))))?;
    }
    if durable {
        sync_paths(&dirs)
            .map_err(|(p, e)| Error::io(&p, format!("cannot sync the folder: {e}")))?;
    }
    Ok(())
}

/// Files and folders synced at the same time: concurrent `fsync`s share the file system's
/// journal commits, so many in flight cost about as much as one (measured here: 98 files one
/// by one 0.33–0.42 s, 16 at a time 0.035 s). The first failure, with its path.
pub fn sync_paths(paths: &[PathBuf]) -> std::result::Result<(), (PathBuf, std::io::Error)> {
    const IN_FLIGHT: usize = 16;
    let next = AtomicUsize::new(0);
    let failure = std::sync::Mutex::new(None);
    std::thread::scope(|s| {
        for _ in 0..IN_FLIGHT.min(paths.len()) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(p) = paths.get(i) else { break };
                if let Err(e) = std::fs::File::open(p).and_then(|f| f.sync_all()) {
                    let mut f = failure.lock().unwrap_or_else(|e| e.into_inner());
                    f.get_or_insert((p.clone(), e));
                    break;
                }
            });
        }
    });
    match failure.into_inner().unwrap_or_else(|e| e.into_inner()) {
        Some(f) => Err(f),
        None => Ok(()),
    }
}

/// Every file under `dir` synced, then every folder (`dir` included), [`sync_paths`].
pub fn sync_tree(dir: &Path) -> std::result::Result<(), (PathBuf, std::io::Error)> {
    let (mut files, mut dirs) = (Vec::new(), vec![dir.to_path_buf()]);
    let mut i = 0;
    while i < dirs.len() {
        let entries = std::fs::read_dir(&dirs[i]).map_err(|e| (dirs[i].clone(), e))?;
        for entry in entries {
            let entry = entry.map_err(|e| (dirs[i].clone(), e))?;
            let kind = entry.file_type().map_err(|e| (entry.path(), e))?;
            if kind.is_dir() {
                dirs.push(entry.path());
            } else if kind.is_file() {
                files.push(entry.path());
            }
        }
        i += 1;
    }
    sync_paths(&files)?;
    sync_paths(&dirs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_are_written_in_parallel_whole_and_without_temporaries() {
        let dir = std::env::temp_dir().join(format!("sgbem-write-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let paths: Vec<PathBuf> = (0..40)
            .map(|i| {
                dir.join(if i % 2 == 0 { "a" } else { "b" })
                    .join(format!("{i}.txt"))
            })
            .collect();
        let content = |i: usize| format!("file {i}\n").repeat(i + 1).into_bytes();
        for durable in [true, false] {
            write_files(&paths, durable, |i| Ok(content(i))).expect("write");
            for (i, p) in paths.iter().enumerate() {
                assert_eq!(std::fs::read(p).unwrap(), content(i));
            }
            sync_tree(&dir).expect("sync");
        }
        // A failing file: nothing of the batch is renamed into place, no temporary is left.
        let more: Vec<PathBuf> = (0..5).map(|i| dir.join("c").join(format!("{i}"))).collect();
        let e = write_files(&more, true, |i| {
            if i == 3 {
                Err(Error::io(&more[i], "refused"))
            } else {
                Ok(vec![1, 2, 3])
            }
        })
        .unwrap_err();
        assert!(e.to_string().contains("refused"), "{e}");
        assert_eq!(std::fs::read_dir(dir.join("c")).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
