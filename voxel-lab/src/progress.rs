//! Progress of long runs on stderr: an `indicatif` bar on a terminal, and one line per
//! tenth of the work elsewhere (CI logs), so that a long run is never silent.

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar over a known number of steps.
#[derive(Debug)]
pub struct Progress {
    bar: ProgressBar,
    tty: bool,
    last_tenth: u64,
}

impl Progress {
    /// A bar for `total` steps.
    pub fn new(total: usize) -> Self {
        use std::io::IsTerminal;
        let bar = ProgressBar::new(total.max(1) as u64);
        if let Ok(style) =
            ProgressStyle::with_template("[{bar:30}] {pos:>4}/{len} {elapsed_precise} {msg}")
        {
            bar.set_style(style.progress_chars("#>-"));
        }
        Self {
            bar,
            tty: std::io::stderr().is_terminal(),
            last_tenth: 0,
        }
    }

    /// One step done, doing `what` next. Never counts past the total: a step beyond it
    /// (a caller that miscounted) leaves the count at the total, and is logged.
    pub fn step(&mut self, what: &str) {
        if self.position() >= self.total() {
            log::debug!("progress: a step past the total {} ({what})", self.total());
        } else {
            self.bar.inc(1);
        }
        self.bar.set_message(what.to_owned());
        if !self.tty {
            let (pos, len) = (self.bar.position(), self.bar.length().unwrap_or(1));
            let tenth = pos * 10 / len;
            if tenth > self.last_tenth || pos == len {
                self.last_tenth = tenth;
                eprintln!(
                    "{pos:>4}/{len} {:>6.1}s {what}",
                    self.bar.elapsed().as_secs_f64()
                );
            }
        }
    }

    /// Steps done.
    pub fn position(&self) -> u64 {
        self.bar.position()
    }

    /// The steps it counts to.
    pub fn total(&self) -> u64 {
        self.bar.length().unwrap_or(1)
    }

    /// Clears the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn never_counts_past_its_total() {
        let mut p = Progress::new(2);
        for i in 1..=4 {
            p.step("a step");
            assert_eq!((p.position(), p.total()), (i.min(2), 2), "step {i}");
        }
        assert_eq!(Progress::new(0).total(), 1);
    }
}
