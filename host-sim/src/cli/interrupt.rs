//! SIGINT, SIGTERM and SIGHUP: the command is interrupted cleanly.
//!
//! A thread of its own waits for the signals ([`signal_hook::iterator::Signals`]); the
//! simulation loops are not involved. On a signal it removes every unfinished output's
//! temporary file ([`crate::output::remove_unfinished`], which also keeps any other from
//! being committed), kills every QEMU the command started ([`crate::hil::kill_all`]),
//! prints one line on stderr saying what was interrupted and exits with 128 + the signal's
//! number: 130 (SIGINT), 143 (SIGTERM), 129 (SIGHUP). Every previous output file is left as
//! it was; an output written directly (a device, a FIFO, stdout) keeps what was written.
//!
//! A trace streamed to a pipe whose reader has gone ends the command the same way, with
//! exit 141 ([`broken_pipe`]).

use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use signal_hook::iterator::Signals;

/// The signals handled, and their names.
const HANDLED: [(i32, &str); 3] = [(SIGINT, "SIGINT"), (SIGTERM, "SIGTERM"), (SIGHUP, "SIGHUP")];

/// Handle the signals from now on; `what` names the command for the message (`run
/// scenes/line-juggler.toml`). If the handler cannot be installed, the signals keep their
/// default action (the command is killed) and a warning says so.
pub fn install(what: String) {
    crate::output::on_broken_pipe(broken_pipe);
    let signals = match Signals::new(HANDLED.map(|(s, _)| s)) {
        Ok(s) => s,
        Err(e) => {
            crate::output::note(format_args!(
                "warning: cannot handle SIGINT/SIGTERM/SIGHUP ({e}): an interrupted run \
                 may leave a temporary .*.tmp file beside its output"
            ));
            return;
        }
    };
    let spawned = std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            let mut signals = signals;
            if let Some(signo) = signals.forever().next() {
                interrupted(signo, &what);
            }
        });
    if let Err(e) = spawned {
        crate::output::note(format_args!("warning: cannot handle signals ({e})"));
    }
}

/// A streamed output's reader has gone (EPIPE): clean up as for a signal and exit 141,
/// quietly if it was stdout ([`crate::output::on_broken_pipe`]).
pub fn broken_pipe(path: &std::path::Path) -> ! {
    crate::output::remove_unfinished();
    crate::hil::kill_all();
    if path != std::path::Path::new(crate::output::STDOUT) {
        crate::output::note(format_args!(
            "error: cannot write {}: the pipe's reader has gone",
            path.display()
        ));
    }
    std::process::exit(i32::from(crate::system::EXIT_BROKEN_PIPE))
}

/// Clean up after `signo` and exit with 128 + `signo`.
fn interrupted(signo: i32, what: &str) -> ! {
    let name = HANDLED
        .iter()
        .find(|(s, _)| *s == signo)
        .map_or("a signal", |(_, n)| n);
    let unwritten = crate::output::remove_unfinished();
    let qemus = crate::hil::kill_all();
    let mut line = format!("interrupted by {name}: dexter {what} stopped");
    if qemus > 0 {
        line.push_str(", QEMU stopped");
    }
    if !unwritten.is_empty() {
        let names: Vec<String> = unwritten.iter().map(|p| p.display().to_string()).collect();
        line.push_str(&format!(
            "; not written (any previous file left as it was): {}",
            names.join(", ")
        ));
    }
    crate::output::note(line);
    std::process::exit(128 + signo)
}
