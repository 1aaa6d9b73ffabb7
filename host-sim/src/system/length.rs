//! A system's run length: what `--impacts N` and `--duration S` set in its scene, declared
//! once per system ([`crate::system::System::LENGTH`]).

use super::Failure;
use crate::scene::apply_set;

/// How the command line sets the length of a system's runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunLength {
    /// Neither option applies: the scene fixes the run (e.g. a planned motion, settled and
    /// held); `--impacts` and `--duration` are refused (exit 2).
    Fixed,
    /// `--impacts N` sets the scene key `key` to N, in 1 ..= `max`; `--duration` is refused.
    Events {
        /// The scene key (e.g. `planar.impacts`, `hopper.cycles`).
        key: &'static str,
        /// The largest N the system runs.
        max: u64,
    },
    /// Either limit (the line juggler): `--impacts N` sets `events` to N and `time` to a
    /// cap of N x `cap_s` (N at least 1), for a run whose ball stops bouncing;
    /// `--duration S` sets `time` to S s and lifts `events`.
    EventsOrTime {
        /// The scene key of the impact limit.
        events: &'static str,
        /// The scene key of the time limit, s.
        time: &'static str,
        /// Simulated seconds allowed per impact under `--impacts`, s.
        cap_s: f64,
    },
}

impl RunLength {
    /// Apply `--impacts` / `--duration` (as given) to the scene `table` of the system
    /// called `system`, or refuse the option (exit 2, naming it).
    pub fn apply(
        &self,
        system: &str,
        table: &mut toml::Table,
        impacts: Option<u64>,
        duration: Option<f64>,
    ) -> Result<(), Failure> {
        let refuse = |what: &str| super::refusal(system, what);
        match *self {
            RunLength::Fixed => match (duration, impacts) {
                (Some(_), _) => Err(refuse("--duration")),
                (None, Some(_)) => Err(refuse("--impacts")),
                (None, None) => Ok(()),
            },
            RunLength::Events { key, max } => {
                if duration.is_some() {
                    return Err(refuse("--duration"));
                }
                if let Some(n) = impacts {
                    if n == 0 || n > max {
                        return Err(Failure::scene(format!(
                            "--impacts ({key}) must be in 1..={max}, got {n}"
                        )));
                    }
                    apply_set(table, key, toml::Value::Integer(n as i64))?;
                }
                Ok(())
            }
            RunLength::EventsOrTime {
                events,
                time,
                cap_s,
            } => {
                if let Some(n) = impacts {
                    let n = i64::try_from(n)
                        .map_err(|_| Failure::usage(format!("--impacts {n} is too large")))?;
                    apply_set(table, events, toml::Value::Integer(n))?;
                    let cap = (n.max(1) as f64) * cap_s;
                    apply_set(table, time, toml::Value::Float(cap))?;
                }
                if let Some(d) = duration {
                    apply_set(table, time, toml::Value::Float(d))?;
                    apply_set(table, events, toml::Value::Integer(i64::MAX))?;
                }
                Ok(())
            }
        }
    }
}
