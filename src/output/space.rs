//! The free space of the file system that will hold a run's outputs, against the size of
//! the outputs `sgbem check` estimates ([`super::size`]).
//!
//! Place in the flow: after `model` and [`crate::estimate`], before anything is solved;
//! `sgbem run` (on its staging folder, beside the output folder) and `sgbem check` (on the
//! scene's `output.directory`, or its nearest folder that exists) ask the same question and
//! give the same answer. A run whose outputs cannot fit is refused as one whose memory
//! cannot (input error, exit 2): the scene's output requests decide the size, and the fix is
//! in the scene (or in `--out`). The staging folder holds the new run while the old one
//! still stands, so the whole estimate must fit in what is free now.
//!
//! With history "steps" or "final" the estimate is within 30 % of what the shipped scenes
//! write; a full history's number of states is only expected. So the refusal takes the
//! fewest states the run keeps (one per load step: the size with history "steps") less
//! those 30 % (`SURE`): outputs refused cannot fit. An estimate beyond the free space
//! short of that (a full history's, or one within its own error) is a note, not a refusal.
//! A file system that reports no size at all (`f_blocks` 0: /proc, some FUSE mounts) is
//! not judged.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::estimate::fmt_bytes;
use crate::output::size::OutputSize;

/// The bytes an unprivileged writer may still write (statvfs `f_bavail × f_frsize`, what
/// `df` shows as available) on the file system of `path`, or of its nearest ancestor that
/// exists, with that folder; None when it cannot be read.
pub(crate) fn free_bytes(path: &Path) -> Option<(f64, PathBuf)> {
    use std::os::unix::ffi::OsStrExt;
    let dir = path
        .ancestors()
        .map(|a| {
            if a.as_os_str().is_empty() {
                Path::new(".")
            } else {
                a
            }
        })
        .find(|a| a.exists())?
        .to_path_buf();
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut st = std::mem::MaybeUninit::<libc::statvfs>::zeroed();
    // SAFETY: `c` is a NUL-terminated path and `st` a buffer of the struct statvfs fills.
    let rc = unsafe { libc::statvfs(c.as_ptr(), st.as_mut_ptr()) };
    if rc != 0 {
        return None;
    }
    // SAFETY: statvfs returned 0, so it filled the struct.
    let st = unsafe { st.assume_init() };
    if st.f_blocks == 0 {
        return None;
    }
    Some((st.f_bavail as f64 * st.f_frsize as f64, dir))
}

/// What the run will write against what is free.
#[derive(Debug, Clone)]
pub(crate) struct Space<'a> {
    /// The estimate as asked for (a full history: its expected states).
    pub outputs: &'a OutputSize,
    /// The estimate with the fewest states the run keeps (one per load step); the same as
    /// `outputs` but for a full history.
    pub floor: &'a OutputSize,
    /// The output folder, as the user named it.
    pub folder: &'a Path,
    /// A folder on the file system the outputs go to (the staging folder, or the output
    /// folder's nearest existing ancestor).
    pub on: &'a Path,
}

/// The part of the estimate surely written: it is within 30 % of the outputs of the shipped
/// scenes (`tests/output_requests.rs`).
const SURE: f64 = 0.7;

/// What to ask for to write less, and where else to write.
const FIX: &str = "ask for less in [output] (history = \"steps\" keeps one state per load step, \
                   \"final\" the last only; every = N keeps every N-th iteration; vtk_fields = \
                   [...] fewer arrays; vtk = \"compressed\"; field = false; operators = false), \
                   free space there, or write elsewhere (--out DIR)";

impl Space<'_> {
    /// Err (input error, exit 2) when the fewest states the run keeps cannot fit in the free
    /// space (even at `SURE` of their estimate); Ok(Some(note)) when only the estimate
    /// exceeds it; Ok(None) when it fits or the free space cannot be read.
    pub fn check(&self, scene_file: &Path) -> Result<Option<String>> {
        let Some((free, _)) = free_bytes(self.on) else {
            return Ok(None);
        };
        let folder = self.folder.display();
        if SURE * self.floor.total() > free {
            let states = match self.floor.states {
                1 => "1 state".to_string(),
                n => format!("{n} states"),
            };
            let fewest = if self.floor == self.outputs {
                ""
            } else {
                " at least"
            };
            let more = if fewest.is_empty() {
                ""
            } else {
                ", one per load step; its full history writes more"
            };
            return Err(Error::input(
                scene_file,
                format!(
                    "this run writes{fewest} about {} of outputs into {folder} ({states}{more}: \
                     archive {}, vtk {}, csv {}; an estimate within 30 %), but its file system \
                     has {} free: {FIX}; `sgbem check` prints the estimate (`outputs:`)",
                    fmt_bytes(self.floor.total()),
                    fmt_bytes(self.floor.archive),
                    fmt_bytes(self.floor.vtk),
                    fmt_bytes(self.floor.csv),
                    fmt_bytes(free),
                ),
            ));
        }
        if self.outputs.total() > free {
            let why = if self.floor == self.outputs {
                "an estimate within 30 %".to_string()
            } else {
                format!(
                    "a full history of about {} states, a number only expected; one per load \
                     step would write about {}",
                    self.outputs.states,
                    fmt_bytes(self.floor.total())
                )
            };
            return Ok(Some(format!(
                "the outputs, about {} ({why}), may not fit in the {} free on the file system \
                 of {folder}: if the run ends for lack of space, {FIX}",
                fmt_bytes(self.outputs.total()),
                fmt_bytes(free),
            )));
        }
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_space_of_a_path_not_yet_made_is_its_nearest_folders() {
        let (free, dir) = free_bytes(Path::new("no/such/folder/here")).unwrap();
        assert_eq!(dir, Path::new("."));
        assert!(free >= 0.0);
        // /proc reports no size: not judged.
        assert!(free_bytes(Path::new("/proc/nothing/below")).is_none());
    }
}
