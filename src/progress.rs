//! How long stages report progress ([`Progress`], [`StageProgress`]), and the bars that show
//! it: shown only on a terminal, only when not quiet, and only once a stage has taken longer
//! than half a second, so quick builds print nothing but summaries. The stages and the
//! builder both depend on this module, not on each other for it.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Shows the progress of long stages ([`Bars`] on a terminal, [`NoProgress`] elsewhere).
pub trait Progress: Sync {
    /// A bar for `node` with `steps` steps in all.
    fn start(&self, node: &str, steps: u64) -> Box<dyn StageProgress + '_>;
}

/// The progress of one running stage. Dropping it clears its bar.
pub trait StageProgress: Sync {
    /// `n` more steps are done.
    fn advance(&self, n: usize);
    /// The stage moved on to another phase (shown beside the bar).
    fn phase(&self, name: &str);
}

/// A progress display that shows nothing.
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _: &str, _: u64) -> Box<dyn StageProgress + '_> {
        Box::new(NoProgress)
    }
}

impl StageProgress for NoProgress {
    fn advance(&self, _: usize) {}
    fn phase(&self, _: &str) {}
}

const DELAY: Duration = Duration::from_millis(500);

pub struct Bars {
    multi: MultiProgress,
}

impl Bars {
    pub fn new() -> Bars {
        Bars {
            multi: MultiProgress::with_draw_target(ProgressDrawTarget::stderr()),
        }
    }
}

impl Default for Bars {
    fn default() -> Self {
        Bars::new()
    }
}

impl Progress for Bars {
    fn start(&self, node: &str, steps: u64) -> Box<dyn StageProgress + '_> {
        let bar = ProgressBar::hidden();
        bar.set_length(steps);
        let style = ProgressStyle::with_template(
            "{prefix:>16} [{bar:30}] {percent:>3}% {elapsed:>4} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(node.to_string());
        Box::new(Bar {
            multi: &self.multi,
            bar,
            started: Instant::now(),
            shown: AtomicBool::new(false),
        })
    }
}

/// One stage's bar, added to the display only after [`DELAY`].
struct Bar<'a> {
    multi: &'a MultiProgress,
    bar: ProgressBar,
    started: Instant,
    shown: AtomicBool,
}

impl Bar<'_> {
    fn show_if_slow(&self) {
        if self.started.elapsed() > DELAY && !self.shown.swap(true, Ordering::Relaxed) {
            self.multi.add(self.bar.clone()).tick();
        }
    }
}

impl StageProgress for Bar<'_> {
    fn advance(&self, n: usize) {
        self.bar.inc(n as u64);
        self.show_if_slow();
    }

    fn phase(&self, name: &str) {
        self.bar.set_message(name.to_string());
        self.show_if_slow();
    }
}

impl Drop for Bar<'_> {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
        if self.shown.load(Ordering::Relaxed) {
            self.multi.remove(&self.bar);
        }
    }
}
