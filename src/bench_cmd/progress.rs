//! The bench's progress: a bar over its cells on a terminal; on a log (CI,
//! a file) one line per cell with the time so far, which a bar would hide.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::Instant;

pub struct Progress {
    bar: Option<ProgressBar>,
    t0: Instant,
}

impl Progress {
    /// Progress over `cells` cells (backends × rows × scenes).
    pub fn new(cells: u64) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::new(cells);
            if let Ok(style) = ProgressStyle::with_template(
                "{elapsed_precise} [{bar:30}] {pos}/{len} cells, {eta} left  {msg}",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        });
        Self {
            bar,
            t0: Instant::now(),
        }
    }

    /// A cell starts.
    pub fn cell(&self, label: &str) {
        match &self.bar {
            Some(bar) => bar.set_message(label.to_string()),
            None => eprintln!("[{:>5.0} s] {label}", self.t0.elapsed().as_secs_f64()),
        }
    }

    /// A cell ended (measured or skipped).
    pub fn done(&self) {
        if let Some(bar) = &self.bar {
            bar.inc(1);
        }
    }

    /// A message above the bar (or on the log).
    pub fn note(&self, text: &str) {
        match &self.bar {
            Some(bar) => bar.println(text),
            None => eprintln!("{text}"),
        }
    }

    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
