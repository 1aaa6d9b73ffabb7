//! A failed command and its exit status: 2 for a bad scene or bad arguments
//! ([`Failure::scene`], [`Failure::usage`]), 1 for a run that failed (controller, I/O;
//! [`Failure::run`]).

use crate::output::OutputError;
use crate::plot::PlotError;
use crate::scene::SceneError;
use std::fmt;

/// Exit status for a bad scene or bad arguments.
pub const EXIT_SCENE: u8 = 2;
/// Exit status for a failed run (controller, I/O).
pub const EXIT_RUN: u8 = 1;
/// Exit status when an output pipe's reader has gone (EPIPE): 128 + SIGPIPE, the status a
/// shell reports for `ls | head`'s `ls`.
pub const EXIT_BROKEN_PIPE: u8 = 141;

/// A failed command: its exit status and what to tell the user.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// [`EXIT_SCENE`] or [`EXIT_RUN`].
    pub code: u8,
    /// The message (printed after `error: `).
    pub message: String,
}

impl Failure {
    /// A bad scene (exit 2): `bad scene: ...`.
    pub fn scene(e: impl fmt::Display) -> Self {
        Self {
            code: EXIT_SCENE,
            message: format!("bad scene: {e}"),
        }
    }

    /// Bad arguments (exit 2).
    pub fn usage(m: impl fmt::Display) -> Self {
        Self {
            code: EXIT_SCENE,
            message: m.to_string(),
        }
    }

    /// A failed run (exit 1).
    pub fn run(m: impl fmt::Display) -> Self {
        Self {
            code: EXIT_RUN,
            message: m.to_string(),
        }
    }

    /// The same failure with `context` after its message (e.g. the swept value).
    pub fn at(mut self, context: impl fmt::Display) -> Self {
        self.message = format!("{} ({context})", self.message);
        self
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl From<SceneError> for Failure {
    fn from(e: SceneError) -> Self {
        Failure::scene(e)
    }
}

impl From<OutputError> for Failure {
    /// A failed run (exit 1); a closed pipe exits [`EXIT_BROKEN_PIPE`], silently if it was
    /// standard output.
    fn from(e: OutputError) -> Self {
        match e.is_broken_pipe() {
            true if e.path == std::path::Path::new(crate::output::STDOUT) => Self {
                code: EXIT_BROKEN_PIPE,
                message: String::new(),
            },
            true => Self {
                code: EXIT_BROKEN_PIPE,
                message: e.to_string(),
            },
            false => Failure::run(e),
        }
    }
}

impl From<PlotError> for Failure {
    fn from(e: PlotError) -> Self {
        Failure::run(format!("plot: {e}"))
    }
}
