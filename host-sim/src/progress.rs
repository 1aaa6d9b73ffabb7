//! Progress bars for long runs and sweeps: drawn on stderr, and only when stderr is a
//! terminal (never in pipes, files or tests).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// A bar over `len` items called `unit` (`impacts`, `points`), shown if `wanted` and stderr is
/// a terminal, else hidden (every call on it is then free).
pub fn bar(len: u64, unit: &str, wanted: bool) -> ProgressBar {
    if !(wanted && std::io::stderr().is_terminal()) {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    let template = format!("{{bar:40}} {{pos}}/{{len}} {unit} {{elapsed}}/{{eta}}");
    pb.set_style(
        ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}
