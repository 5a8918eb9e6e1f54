//! How long stages report progress ([`Progress`], [`StageProgress`]), and the bars that show
//! it: shown only on a terminal, only when not quiet, and only once a stage has taken longer
//! than half a second, so quick builds print nothing but summaries. `build`, `watch`, `cell`
//! and `sdf` show them ([`on_stderr`]). The stages and the builder both depend on this
//! module, not on each other for it.
//!
//! Invariants:
//! - Every running stage has a display (a bar when it counts steps, else a spinner), and it
//!   appears [`DELAY`] after the stage started whether or not the stage reports anything
//!   since: a ticker thread of [`Bars`] reveals it (a 4 s write or mesh check is silent
//!   inside), and keeps shown spinners and elapsed times moving.
//! - A stage's display is gone when its [`StageProgress`] is dropped; [`Bars`] stops its
//!   ticker when dropped.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, Weak};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Shows the progress of long stages ([`Bars`] on a terminal, [`NoProgress`] elsewhere).
pub trait Progress: Sync {
    /// A display for `node` with `steps` steps in all (0: a spinner, for a stage that does
    /// not count its steps).
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

/// [`Bars`] on stderr when it is a terminal and the command is not quiet, else
/// [`NoProgress`]: piped or captured output holds nothing but what the command prints.
pub fn on_stderr(quiet: bool) -> Box<dyn Progress> {
    use std::io::IsTerminal;
    if !quiet && std::io::stderr().is_terminal() {
        Box::new(Bars::new())
    } else {
        Box::new(NoProgress)
    }
}

/// How long a stage runs before its display appears.
pub const DELAY: Duration = Duration::from_millis(500);
/// How often the ticker looks for stages to reveal and redraws spinners.
const TICK: Duration = Duration::from_millis(100);

/// Bars and spinners on stderr, drawn by indicatif.
pub struct Bars {
    shared: Arc<Shared>,
    /// Dropped to wake and stop the ticker.
    stop: Option<Sender<()>>,
    ticker: Option<JoinHandle<()>>,
}

struct Shared {
    multi: MultiProgress,
    /// The running stages' displays (a dropped stage's entry is gone).
    live: Mutex<Vec<Weak<Entry>>>,
}

/// One stage's display, added to the screen only after [`DELAY`].
struct Entry {
    bar: ProgressBar,
    started: Instant,
    shown: AtomicBool,
}

impl Bars {
    /// Bars on stderr.
    pub fn new() -> Bars {
        Bars::with_target(ProgressDrawTarget::stderr(), true)
    }

    /// Bars drawn on `target`; `ticker` false leaves revealing to [`Bars::reveal_due`]
    /// (for tests, with a clock of their own).
    fn with_target(target: ProgressDrawTarget, ticker: bool) -> Bars {
        let shared = Arc::new(Shared {
            multi: MultiProgress::with_draw_target(target),
            live: Mutex::new(Vec::new()),
        });
        let (stop, ticker) = if ticker {
            let (send, receive) = mpsc::channel::<()>();
            let shared = Arc::clone(&shared);
            let ticker = std::thread::Builder::new()
                .name("progress".into())
                .spawn(move || {
                    while let Err(RecvTimeoutError::Timeout) = receive.recv_timeout(TICK) {
                        shared.reveal_due(Instant::now());
                    }
                })
                .ok();
            (Some(send), ticker)
        } else {
            (None, None)
        };
        Bars {
            shared,
            stop,
            ticker,
        }
    }

    /// Shows every running stage started at least [`DELAY`] before `now` (and redraws the
    /// shown ones); returns how many appeared now.
    #[cfg(test)]
    fn reveal_due(&self, now: Instant) -> usize {
        self.shared.reveal_due(now)
    }
}

impl Shared {
    fn reveal_due(&self, now: Instant) -> usize {
        let Ok(mut live) = self.live.lock() else {
            return 0;
        };
        live.retain(|entry| entry.strong_count() > 0);
        let mut revealed = 0;
        for entry in live.iter().filter_map(Weak::upgrade) {
            if entry.shown.load(Ordering::Relaxed) {
                entry.bar.tick();
            } else if now.saturating_duration_since(entry.started) >= DELAY
                && !entry.shown.swap(true, Ordering::Relaxed)
            {
                self.multi.add(entry.bar.clone()).tick();
                revealed += 1;
            }
        }
        revealed
    }
}

impl Default for Bars {
    fn default() -> Self {
        Bars::new()
    }
}

impl Drop for Bars {
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(ticker) = self.ticker.take() {
            let _ = ticker.join();
        }
    }
}

impl Progress for Bars {
    fn start(&self, node: &str, steps: u64) -> Box<dyn StageProgress + '_> {
        let bar = ProgressBar::hidden();
        let style = if steps == 0 {
            ProgressStyle::with_template("{prefix:>16} {spinner} {elapsed:>4} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner())
        } else {
            bar.set_length(steps);
            ProgressStyle::with_template("{prefix:>16} [{bar:30}] {percent:>3}% {elapsed:>4} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ")
        };
        bar.set_style(style);
        bar.set_prefix(node.to_string());
        let entry = Arc::new(Entry {
            bar,
            started: Instant::now(),
            shown: AtomicBool::new(false),
        });
        if let Ok(mut live) = self.shared.live.lock() {
            live.push(Arc::downgrade(&entry));
        }
        Box::new(Bar {
            multi: &self.shared.multi,
            entry,
        })
    }
}

/// A running stage's handle on its [`Entry`].
struct Bar<'a> {
    multi: &'a MultiProgress,
    entry: Arc<Entry>,
}

impl StageProgress for Bar<'_> {
    fn advance(&self, n: usize) {
        self.entry.bar.inc(n as u64);
    }

    fn phase(&self, name: &str) {
        self.entry.bar.set_message(name.to_string());
    }
}

impl Drop for Bar<'_> {
    fn drop(&mut self) {
        self.entry.bar.finish_and_clear();
        if self.entry.shown.load(Ordering::Relaxed) {
            self.multi.remove(&self.entry.bar);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_display_appears_only_after_half_a_second_and_only_while_its_stage_runs() {
        let bars = Bars::with_target(ProgressDrawTarget::hidden(), false);
        let t0 = Instant::now();
        let quick = bars.start("contour:a", 10);
        let slow = bars.start("write:a", 0);
        slow.phase("writing");
        assert_eq!(bars.reveal_due(t0 + Duration::from_millis(300)), 0);
        drop(quick);
        // The write reported nothing since it began, and still appears.
        assert_eq!(bars.reveal_due(t0 + DELAY + Duration::from_millis(1)), 1);
        assert_eq!(bars.reveal_due(t0 + Duration::from_secs(4)), 0, "once");
        // A stage started later waits its own half second.
        let later = Instant::now();
        let next = bars.start("islands:a", 0);
        assert_eq!(bars.reveal_due(later + Duration::from_millis(400)), 0);
        assert_eq!(bars.reveal_due(later + Duration::from_millis(600)), 1);
        drop((slow, next));
        assert_eq!(bars.reveal_due(later + Duration::from_secs(9)), 0);
        assert!(bars.shared.live.lock().unwrap().is_empty());
    }
}
