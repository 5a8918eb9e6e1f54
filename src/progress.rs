//! Progress bars for long stages: shown only on a terminal, only when not quiet, and only once
//! a stage has taken longer than half a second, so quick builds print nothing but summaries.

use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::build::Progress;

const DELAY: Duration = Duration::from_millis(500);

pub struct Bars {
    multi: MultiProgress,
    bars: Mutex<Vec<(String, ProgressBar)>>,
}

impl Bars {
    pub fn new() -> Bars {
        Bars {
            multi: MultiProgress::with_draw_target(ProgressDrawTarget::stderr()),
            bars: Mutex::new(Vec::new()),
        }
    }
}

impl Default for Bars {
    fn default() -> Self {
        Bars::new()
    }
}

impl Progress for Bars {
    fn start(&self, node: &str, steps: u64) -> Box<dyn Fn(usize) + Sync + '_> {
        let bar = ProgressBar::hidden();
        bar.set_length(steps);
        let style = ProgressStyle::with_template("{prefix:>14} [{bar:30}] {percent:>3}% {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(node.to_string());
        if let Ok(mut bars) = self.bars.lock() {
            bars.push((node.to_string(), bar.clone()));
        }
        let started = Instant::now();
        let shown = std::sync::atomic::AtomicBool::new(false);
        Box::new(move |n| {
            bar.inc(n as u64);
            if started.elapsed() > DELAY && !shown.swap(true, std::sync::atomic::Ordering::Relaxed)
            {
                let visible = self.multi.add(bar.clone());
                visible.tick();
            }
        })
    }

    fn finish(&self, node: &str) {
        if let Ok(mut bars) = self.bars.lock() {
            bars.retain(|(name, bar)| {
                if name == node {
                    bar.finish_and_clear();
                    self.multi.remove(bar);
                    false
                } else {
                    true
                }
            });
        }
    }
}
