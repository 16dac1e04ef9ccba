//! Progress bars for the long stages of a run (assembly, interior field evaluation, contact
//! iterations), drawn on stderr with indicatif.
//!
//! SPEC.md: a progress bar on a terminal; none with `--quiet` or when stderr is not a
//! terminal (pipes, CI logs, tests). When hidden, every call is a cheap no-op, so the
//! pipeline calls the same methods either way.
//!
//! ```no_run
//! use sgbem::output::progress::Progress;
//! let progress = Progress::new(false);
//! let bar = progress.bar("assemble", 120);
//! for _ in 0..120 {
//!     bar.inc(1);
//! }
//! bar.finish();
//! ```

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Whether progress is shown; makes the bars of a run.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    enabled: bool,
}

impl Progress {
    /// Shown unless `quiet` or stderr is not a terminal.
    pub fn new(quiet: bool) -> Progress {
        Progress {
            enabled: !quiet && std::io::stderr().is_terminal(),
        }
    }

    /// Never shown.
    pub fn hidden() -> Progress {
        Progress { enabled: false }
    }

    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// A bar for a stage of `total` steps, labelled `stage`.
    pub fn bar(&self, stage: &str, total: u64) -> Stage {
        if !self.enabled {
            return Stage::hidden();
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        let style = ProgressStyle::with_template(
            "{prefix:>12} [{bar:30}] {pos}/{len} {msg} ({elapsed}, eta {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(stage.to_string());
        bar.enable_steady_tick(Duration::from_millis(200));
        Stage { bar }
    }

    /// A spinner for a stage of unknown length (contact iterations), labelled `stage`.
    pub fn spinner(&self, stage: &str) -> Stage {
        if !self.enabled {
            return Stage::hidden();
        }
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
        let style = ProgressStyle::with_template("{prefix:>12} {spinner} {pos} {msg} ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_spinner());
        bar.set_style(style);
        bar.set_prefix(stage.to_string());
        bar.enable_steady_tick(Duration::from_millis(120));
        Stage { bar }
    }
}

/// One stage's bar. Cloning shares the bar (for parallel loops); every method is a no-op
/// when progress is hidden.
#[derive(Debug, Clone)]
pub struct Stage {
    bar: ProgressBar,
}

impl Stage {
    /// A bar that draws nothing.
    pub fn hidden() -> Stage {
        Stage {
            bar: ProgressBar::hidden(),
        }
    }

    /// Advances by `n` steps.
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
    }

    pub fn set_position(&self, pos: u64) {
        self.bar.set_position(pos);
    }

    pub fn set_length(&self, len: u64) {
        self.bar.set_length(len);
    }

    /// Text after the bar (e.g. the body being assembled, or the open pairs).
    pub fn set_message(&self, msg: impl Into<String>) {
        self.bar.set_message(msg.into());
    }

    /// Steps done so far.
    pub fn position(&self) -> u64 {
        self.bar.position()
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }

    /// Prints a line above the bar without garbling it (plain eprintln when hidden).
    pub fn println(&self, line: &str) {
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }
}
