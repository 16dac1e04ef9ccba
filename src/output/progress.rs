//! Progress bars for the long stages of a run (assembly, interior field evaluation, contact
//! iterations), drawn on stderr with indicatif.
//!
//! README "Command line" (`sgbem run`): a progress bar on a terminal; none with `--quiet` or
//! when stderr is not a terminal (pipes, CI logs, tests). When hidden, every call is a cheap
//! no-op, so the pipeline calls the same methods either way.
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
use std::sync::{Arc, Mutex};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::estimate::fmt_seconds;
use crate::input::model::fmt_num;

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

    /// A bar for a stage of `total` steps, labelled `stage`, with the time left at the rate
    /// so far.
    pub fn bar(&self, stage: &str, total: u64) -> Stage {
        self.styled(
            stage,
            total,
            "{prefix:>12} [{bar:30}] {pos}/{len} {msg} ({elapsed}, eta {eta})",
        )
    }

    fn styled(&self, stage: &str, total: u64, template: &str) -> Stage {
        if !self.enabled {
            return Stage::hidden();
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        let style = ProgressStyle::with_template(template)
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(stage.to_string());
        bar.enable_steady_tick(Duration::from_millis(200));
        Stage::of(bar)
    }

    /// A bar for the contact stage: its length is the number of load steps (a collapse
    /// search first counts its trials: [`Stage::count_trials`]); the message shows the
    /// latest [`ContactTick`] (iteration, open pairs, detached length) and, once a step or
    /// trial is finished, the time left at the rate of those finished (the iterations a
    /// step needs are not known ahead: the message moves with each outer iteration).
    pub fn contact(&self, load_steps: usize) -> Stage {
        let stage = self.styled(
            "contact",
            load_steps as u64,
            "{prefix:>12} [{bar:30}] {pos}/{len} {msg} ({elapsed})",
        );
        stage.set_message("load step 1");
        stage
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
        Stage::of(bar)
    }
}

/// What the contact solver reports after an iteration, for [`Stage::contact_tick`].
#[derive(Debug, Clone, Copy, Default)]
pub struct ContactTick {
    /// Load step, counted from 0, and the number of steps.
    pub load_step: usize,
    pub load_steps: usize,
    /// Iteration within the load step, counted from 1.
    pub iteration: usize,
    pub max_iterations: usize,
    /// Open pairs and all pairs, over every interface.
    pub open_pairs: usize,
    pub pairs: usize,
    /// Detached length summed over the interfaces.
    pub detached_length: f64,
    /// Whether the load step is finished (converged or given up).
    pub step_done: bool,
}

/// The callback the contact solver calls after each iteration: `&dyn Fn(&ContactTick)`.
/// Make one with [`Stage::contact_callback`]; [`no_contact_progress`] ignores the ticks.
pub type ContactProgress<'a> = &'a (dyn Fn(&ContactTick) + Sync);

/// A contact callback that does nothing (tests, benches).
pub fn no_contact_progress(_: &ContactTick) {}

/// One stage's bar. Cloning shares the bar (for parallel loops); every method is a no-op
/// when progress is hidden.
#[derive(Debug, Clone)]
pub struct Stage {
    bar: ProgressBar,
    /// The contact bar in a collapse search: the trial being solved (from 1) and its
    /// multiplier t; `None` while it counts load steps.
    trial: Arc<Mutex<Option<(u64, f64)>>>,
}

impl Stage {
    fn of(bar: ProgressBar) -> Stage {
        Stage {
            bar,
            trial: Arc::default(),
        }
    }

    /// A bar that draws nothing.
    pub fn hidden() -> Stage {
        Stage::of(ProgressBar::hidden())
    }

    /// Advances by `n` steps.
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
    }

    pub(crate) fn set_position(&self, pos: u64) {
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

    /// Shows a contact iteration: position = finished load steps (in a collapse search,
    /// the finished trials), message = iteration, open pairs, detached length.
    pub fn contact_tick(&self, t: &ContactTick) {
        if self.current_trial().is_none() {
            self.set_position((t.load_step + usize::from(t.step_done)) as u64);
        }
        self.contact_detail(&contact_message(t));
    }

    /// Shows `text` about the contact solver's progress, after the trial of a collapse
    /// search and before the time left at the rate of the finished steps or trials.
    pub(crate) fn contact_detail(&self, text: &str) {
        let head = self.current_trial().map_or(String::new(), |(k, t)| {
            format!("trial {k} at t = {}: ", fmt_num(t))
        });
        self.set_message(format!("{head}{text}{}", self.left()));
    }

    /// Makes the contact bar count a collapse search's `trials`, none done.
    pub fn count_trials(&self, trials: u64) {
        self.restart(trials);
        self.bar.set_prefix("collapse");
    }

    /// Marks the start of trial `k` (from 1) at the multiplier `t`: `k - 1` are done.
    pub(crate) fn begin_trial(&self, k: u64, t: f64) {
        self.set_trial(Some((k, t)));
        self.set_position(k.saturating_sub(1));
        self.contact_detail("started");
    }

    /// Makes the contact bar count `steps` load steps, none done (after a collapse search).
    pub(crate) fn count_steps(&self, steps: u64) {
        self.set_trial(None);
        self.bar.set_prefix("contact");
        self.set_message("load step 1");
        self.restart(steps);
    }

    fn restart(&self, len: u64) {
        self.bar.set_position(0);
        self.bar.set_length(len);
        self.bar.reset_elapsed();
        self.bar.reset_eta();
    }

    fn set_trial(&self, trial: Option<(u64, f64)>) {
        if let Ok(mut g) = self.trial.lock() {
            *g = trial;
        }
    }

    fn current_trial(&self) -> Option<(u64, f64)> {
        self.trial.lock().ok().and_then(|g| *g)
    }

    /// ", about 40 s left" at the rate of the finished steps since the count began; empty
    /// before the first is finished and after the last.
    fn left(&self) -> String {
        let (done, len) = (self.bar.position(), self.bar.length().unwrap_or(0));
        if done == 0 || done >= len {
            return String::new();
        }
        let secs = self.bar.elapsed().as_secs_f64() * (len - done) as f64 / done as f64;
        format!(", about {} left", fmt_seconds(secs))
    }

    /// A closure for the contact solver that forwards each tick to this bar.
    pub fn contact_callback(&self) -> impl Fn(&ContactTick) + Sync + '_ {
        move |t| self.contact_tick(t)
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

/// The text of a contact tick: `step 1/2, iteration 7/100, open 12/105 pairs, detached 33.8`.
pub(crate) fn contact_message(t: &ContactTick) -> String {
    format!(
        "step {}/{}, iteration {}/{}, open {}/{} pairs, detached {:.4}",
        t.load_step + 1,
        t.load_steps,
        t.iteration,
        t.max_iterations,
        t.open_pairs,
        t.pairs,
        t.detached_length
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_ticks_move_a_hidden_bar_and_read_well() {
        let stage = Stage::hidden();
        let tick = ContactTick {
            load_step: 1,
            load_steps: 2,
            iteration: 7,
            max_iterations: 100,
            open_pairs: 12,
            pairs: 105,
            detached_length: 33.85,
            step_done: true,
        };
        let cb = stage.contact_callback();
        let f: ContactProgress = &cb;
        f(&tick);
        assert_eq!(stage.position(), 2);
        assert_eq!(
            contact_message(&tick),
            "step 2/2, iteration 7/100, open 12/105 pairs, detached 33.8500"
        );
        no_contact_progress(&tick);
    }

    #[test]
    fn a_collapse_search_names_its_trial_and_then_counts_load_steps() {
        let stage = Stage::hidden();
        stage.count_trials(10);
        stage.begin_trial(3, 0.5);
        assert_eq!(stage.position(), 2);
        assert_eq!(stage.current_trial(), Some((3, 0.5)));
        // A tick inside a trial leaves the count of finished trials alone.
        stage.contact_tick(&ContactTick {
            load_step: 0,
            load_steps: 1,
            step_done: true,
            ..ContactTick::default()
        });
        assert_eq!(stage.position(), 2);
        stage.count_steps(1);
        assert_eq!((stage.position(), stage.current_trial()), (0, None));
    }
}
