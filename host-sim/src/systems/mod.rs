//! The simulated systems, all of one shape ([`crate::system::System`]); the registry the
//! CLI dispatches on lists them (`crate::cli::registry`).
//!
//! | system | scene table | what |
//! | --- | --- | --- |
//! | [`arm`] | `[arm]` or `[task]` | Akella, Huang, Lynch & Mason's one-joint arm: snatch, throw, roll, rolling throw, planned and tracked |
//! | [`feeder`] | `[feeder]` | Akella, Huang, Lynch & Mason's 1JOC parts feeder: plan, simulated feed, fraction fed |
//! | [`hopper::sampled`] | `[hopper]` with `[hopper.control]` | the hopper's thrust valve switched by the core's fixed-rate controller (SIL, `--hil`) |
//! | [`hopper`] | `[hopper]` | Koditschek & Bühler's vertical hopper: return maps, period doubling |
//! | [`planar_juggler`] | `[planar_juggler]` | Rizzi & Koditschek's planar juggler, mirror law eq. 12 or the modified law eq. 15 |
//! | [`spatial_juggler`] | `[spatial_juggler]` | Rizzi & Koditschek's spatial juggler, eq. 13 or the modified law |
//! | [`planar`] | `[planar]` | Zumel & Erdmann's bouncing body on the kappa-tilt table |
//! | [`line`](mod@line) | any other (`[physics]`, `[control]`, ...) | the line juggler and the passive bounce |
//!
//! How to add one: `docs/adding-a-system.md`.

pub mod arm;
pub mod feeder;
pub mod hopper;
pub mod line;
pub mod planar;
pub mod planar_juggler;
pub mod spatial_juggler;
