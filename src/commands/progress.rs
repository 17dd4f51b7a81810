//! What the pipeline commands tell the user on stderr while they work: log lines (shown unless
//! `--quiet`; the stages' detailed logs only with `-v`) and one indicatif progress bar per
//! frequency response curve (points traced, current excitation frequency in Hz, Newton
//! iterations of the last point). Bars are drawn only when stderr is a terminal and never with
//! `--quiet`; log lines are printed above the bars.

use std::collections::HashSet;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Bar length: the position is the fraction of the frequency range covered, in 1/1000.
const BAR_LENGTH: u64 = 1000;

/// Log lines and progress bars of one command (cheap to clone; clones share the bars).
#[derive(Clone, Debug)]
pub struct Reporter {
    quiet: bool,
    verbose: bool,
    prefix: String,
    multi: MultiProgress,
    /// Warnings already printed (shared by clones): sweep points solved in parallel raise the
    /// same warning once each, and the user needs it once.
    warned: Arc<Mutex<HashSet<String>>>,
}

impl Reporter {
    /// A reporter on stderr: `quiet` hides everything but warnings, `verbose` adds the stages'
    /// logs (model, reduction, contact).
    pub fn new(quiet: bool, verbose: bool) -> Reporter {
        let target = if quiet {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        };
        Reporter {
            quiet,
            verbose,
            prefix: String::new(),
            multi: MultiProgress::with_draw_target(target),
            warned: Arc::new(Mutex::new(HashSet::new())),
        }
    }

    /// A reporter that prints nothing (library use, tests).
    pub fn silent() -> Reporter {
        Reporter::new(true, false)
    }

    /// The same reporter with every line prefixed by `[label] ` (batch jobs).
    pub fn labelled(&self, label: &str) -> Reporter {
        Reporter {
            prefix: format!("[{label}] "),
            ..self.clone()
        }
    }

    /// Whether stage logs are shown (`-v`).
    pub fn verbose(&self) -> bool {
        self.verbose && !self.quiet
    }

    fn print(&self, line: &str) {
        self.multi
            .suspend(|| eprintln!("nlrom: {}{line}", self.prefix));
    }

    /// A line shown unless `--quiet` (what was read, reused, written).
    pub fn info(&self, line: &str) {
        if !self.quiet {
            self.print(line);
        }
    }

    /// A line shown only with `-v` (the stages' own logs).
    pub fn detail(&self, line: &str) {
        if self.verbose() {
            self.print(line);
        }
    }

    /// A warning, shown even with `--quiet`, once per reporter family (a repeated line, e.g. the
    /// same projection warning from every sweep point, is not printed again).
    pub fn warn(&self, line: &str) {
        if self.first_warning(line) {
            self.print(&format!("warning: {line}"));
        }
    }

    /// Whether `line` (with this reporter's prefix) is warned for the first time; records it.
    fn first_warning(&self, line: &str) -> bool {
        let text = format!("{}{line}", self.prefix);
        match self.warned.lock() {
            Ok(mut seen) => seen.insert(text),
            Err(_) => true,
        }
    }

    /// A progress bar for one frequency response from `start_hz` to `end_hz`.
    pub fn curve_bar(&self, label: &str, start_hz: f64, end_hz: f64) -> CurveBar {
        let bar = if self.quiet {
            ProgressBar::hidden()
        } else {
            let style = ProgressStyle::with_template(
                "{prefix} [{elapsed_precise}] {bar:30.cyan/blue} {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar());
            let bar = self.multi.add(ProgressBar::new(BAR_LENGTH));
            bar.set_style(style);
            bar.set_prefix(format!("{}{label}", self.prefix));
            bar.enable_steady_tick(Duration::from_millis(250));
            bar
        };
        CurveBar {
            bar,
            start_hz,
            end_hz,
            points: 0,
        }
    }
}

/// The progress bar of one curve.
pub struct CurveBar {
    bar: ProgressBar,
    start_hz: f64,
    end_hz: f64,
    points: usize,
}

impl CurveBar {
    /// A converged point at ω (rad/s) after `iterations` Newton iterations.
    pub fn point(&mut self, omega: f64, iterations: usize) {
        self.points += 1;
        let hz = omega / (2.0 * std::f64::consts::PI);
        let span = self.end_hz - self.start_hz;
        let fraction = if span != 0.0 {
            ((hz - self.start_hz) / span).clamp(0.0, 1.0)
        } else {
            1.0
        };
        self.bar.set_position((fraction * BAR_LENGTH as f64) as u64);
        self.bar.set_message(format!(
            "{} points, {hz:.3} Hz, {iterations} Newton iterations",
            self.points
        ));
    }

    /// Removes the bar.
    pub fn finish(self) {
        self.bar.finish_and_clear();
    }
}

impl crate::problem::Log for Reporter {
    fn info(&self, line: &str) {
        Reporter::info(self, line);
    }
    fn warn(&self, line: &str) {
        Reporter::warn(self, line);
    }
    fn detail(&self, line: &str) {
        Reporter::detail(self, line);
    }
}

#[cfg(test)]
mod tests {
    use super::Reporter;

    #[test]
    fn a_warning_is_given_once_per_label() {
        let rep = Reporter::silent();
        let clone = rep.clone();
        assert!(rep.first_warning("5 nodes unprojected"));
        assert!(!clone.first_warning("5 nodes unprojected"));
        assert!(rep.first_warning("another warning"));
        let job = rep.labelled("case 2");
        assert!(job.first_warning("5 nodes unprojected"));
        assert!(!job.labelled("case 2").first_warning("5 nodes unprojected"));
    }
}
