//! Progress bars for long runs and sweeps: drawn on stderr, and only when stderr is a
//! terminal (never in pipes, files or tests).
//!
//! - [`bar`]: a bar over a known number of items (sweep points).
//! - [`Progress`]: a run's progress towards whichever of its limits it reaches first
//!   (impacts, simulated seconds, cycles), revealed only once the run has taken
//!   [`REVEAL_AFTER`]: a short run draws nothing, a long one always shows where it is.
//!   `DEXTER_PROGRESS_REVEAL_MS` (milliseconds) sets that delay instead, so that a test of
//!   the bar does not depend on how fast the machine runs the scene.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// How long a run goes before its [`Progress`] bar appears.
pub const REVEAL_AFTER: Duration = Duration::from_millis(500);

/// [`REVEAL_AFTER`], or `DEXTER_PROGRESS_REVEAL_MS` if it is set to a whole number.
fn reveal_after() -> Duration {
    std::env::var("DEXTER_PROGRESS_REVEAL_MS")
        .ok()
        .and_then(|ms| ms.parse().ok())
        .map_or(REVEAL_AFTER, Duration::from_millis)
}

/// Steps of a [`Progress`] bar (per mille of the run).
const STEPS: u64 = 1000;

/// A bar over `len` items called `unit` (`impacts`, `points`), shown if `wanted` and stderr is
/// a terminal, else hidden (every call on it is then free).
pub fn bar(len: u64, unit: &str, wanted: bool) -> ProgressBar {
    if !(wanted && std::io::stderr().is_terminal()) {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    let template = format!("{{bar:40}} {{pos}}/{{len}} {unit} {{elapsed}}/{{eta}}");
    pb.set_style(style(&template));
    pb
}

fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar())
}

/// A run's progress towards the first of its limits (module docs).
pub struct Progress {
    limits: Vec<(f64, &'static str)>,
    bar: ProgressBar,
    start: Instant,
    /// How long before the bar appears.
    reveal_after: Duration,
    /// Shown on a terminal once the run takes a while.
    wanted: bool,
    shown: bool,
}

impl Progress {
    /// A run that ends at the first of `limits` (value, unit) it reaches; drawn on a
    /// terminal if `wanted`, after [`REVEAL_AFTER`].
    pub fn new<const N: usize>(limits: [(f64, &'static str); N], wanted: bool) -> Self {
        let bar = ProgressBar::with_draw_target(Some(STEPS), ProgressDrawTarget::hidden());
        bar.set_style(style("{bar:40} {percent:>3}% {msg} {elapsed}/{eta}"));
        Self {
            limits: limits.to_vec(),
            bar,
            start: Instant::now(),
            reveal_after: reveal_after(),
            wanted: wanted && std::io::stderr().is_terminal(),
            shown: false,
        }
    }

    /// The run's fraction done: the largest of `values[i] / limit[i]`, in [0, 1].
    pub fn fraction(&self, values: &[f64]) -> f64 {
        let f = self
            .limits
            .iter()
            .zip(values)
            .map(|((limit, _), v)| v / limit)
            .filter(|f| f.is_finite())
            .fold(0.0, f64::max);
        f.clamp(0.0, 1.0)
    }

    /// The run now stands at `values` (in the order of the limits).
    pub fn update<const N: usize>(&mut self, values: [f64; N]) {
        if !self.wanted {
            return;
        }
        if !self.shown && self.start.elapsed() >= self.reveal_after {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
        let words: Vec<String> = self
            .limits
            .iter()
            .zip(values)
            .map(|(&(limit, unit), v)| bound_words(v, limit, unit))
            .collect();
        self.bar.set_message(words.join(", "));
        self.bar
            .set_position((self.fraction(&values) * STEPS as f64) as u64);
    }

    /// The run ended: clear the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// `value` of a limit in words, with the bound that will stop the run: `120 of 600 s
/// simulated` (or `120 s simulated` for a limit too large to be one, e.g. `i64::MAX`).
fn bound_words(value: f64, limit: f64, unit: &str) -> String {
    if limit.is_finite() && limit < 1e15 {
        format!("{} of {} {unit}", value.round(), limit.round())
    } else {
        format!("{} {unit}", value.round())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_words_name_the_bound_that_stops_the_run() {
        assert_eq!(
            bound_words(119.6, 600.0, "s simulated"),
            "120 of 600 s simulated"
        );
        assert_eq!(bound_words(5.0, i64::MAX as f64, "impacts"), "5 impacts");
    }

    #[test]
    fn the_fraction_is_that_of_the_limit_nearest_to_its_end() {
        let p = Progress::new([(100.0, "impacts"), (60.0, "s")], false);
        assert_eq!(p.fraction(&[10.0, 30.0]), 0.5);
        assert_eq!(p.fraction(&[90.0, 30.0]), 0.9);
        assert_eq!(p.fraction(&[200.0, 0.0]), 1.0);
        // an unlimited count (i64::MAX impacts) leaves the time to measure progress
        let p = Progress::new([(i64::MAX as f64, "impacts"), (60.0, "s")], false);
        assert_eq!(p.fraction(&[1e6, 15.0]), 0.25);
    }
}
