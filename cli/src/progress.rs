//! The progress bar of long runs (`encode`, `bench`, `show build`): on
//! stderr, drawn only once a run has taken [`DELAY`] and only when stderr is
//! a terminal (indicatif hides itself otherwise), so scripts, tests and CI
//! logs stay clean. The library reports ([`mocap_encoder::encode::Progress`]);
//! this draws.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mocap_encoder::codec::CodecChoice;
use mocap_encoder::encode::Progress;

/// How long a run goes before its bar appears.
pub const DELAY: Duration = Duration::from_secs(2);

/// Positions per unit of the bar (a search round, a file): the work within
/// one moves the bar by fractions of it.
const SCALE: u64 = 1000;

/// A progress bar that appears after [`DELAY`].
pub struct Bar {
    bar: ProgressBar,
    start: Instant,
    shown: AtomicBool,
    /// Units before the current one, and units in all (rounds of a
    /// search, or jobs of a bench).
    base: AtomicUsize,
    units: AtomicUsize,
    /// What the current unit is (`pca-spline 3/15`).
    label: Mutex<String>,
}

impl Bar {
    /// A hidden bar of `units` units.
    pub fn new(units: usize) -> Bar {
        let bar =
            ProgressBar::with_draw_target(Some(units as u64 * SCALE), ProgressDrawTarget::hidden());
        if let Ok(style) =
            ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {percent:>3}% {msg}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        Bar {
            bar,
            start: Instant::now(),
            shown: AtomicBool::new(false),
            base: AtomicUsize::new(0),
            units: AtomicUsize::new(units),
            label: Mutex::new(String::new()),
        }
    }

    /// Unit `at` (from 0) of `units` begins: `label` says what it is.
    pub fn unit(&self, at: usize, units: usize, label: String) {
        self.base.store(at, Ordering::Relaxed);
        self.units.store(units.max(at + 1), Ordering::Relaxed);
        self.bar.set_length(units.max(at + 1) as u64 * SCALE);
        self.bar.set_position(at as u64 * SCALE);
        self.bar.set_message(label.clone());
        if let Ok(mut l) = self.label.lock() {
            *l = label;
        }
        self.show_if_slow();
    }

    /// `done` of `total` of the current unit are finished.
    pub fn within(&self, done: usize, total: usize) {
        let base = self.base.load(Ordering::Relaxed) as u64 * SCALE;
        let part = (done.min(total) as u64 * SCALE).checked_div(total as u64);
        self.bar.set_position(base + part.unwrap_or(0));
        self.show_if_slow();
    }

    /// A line above the bar (or on stderr while the bar is hidden).
    pub fn println(&self, line: &str) {
        if self.shown.load(Ordering::Relaxed) && !self.bar.is_hidden() {
            self.bar.println(line);
        } else {
            eprintln!("{line}");
        }
    }

    fn show_if_slow(&self) {
        if self.start.elapsed() >= DELAY && !self.shown.swap(true, Ordering::Relaxed) {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.bar.enable_steady_tick(Duration::from_millis(250));
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

/// An encode's bar: a unit per search round.
impl Progress for Bar {
    fn round(&self, codec: CodecChoice, round: usize, rounds: usize) {
        self.unit(
            round.saturating_sub(1),
            rounds,
            format!("{} round {round}/{rounds}", codec.name()),
        );
    }

    fn work(&self, done: usize, total: usize) {
        self.within(done, total);
    }
}

/// Inside a bench or show build: each encode is one unit of the outer bar,
/// its rounds fractions of it.
pub struct Nested<'a> {
    pub bar: &'a Bar,
    pub at: usize,
    pub units: usize,
    pub label: String,
}

impl Progress for Nested<'_> {
    fn round(&self, codec: CodecChoice, round: usize, rounds: usize) {
        self.bar.unit(
            self.at,
            self.units,
            format!("{} ({} round {round}/{rounds})", self.label, codec.name()),
        );
        self.bar.within(round.saturating_sub(1), rounds.max(1));
    }
}
