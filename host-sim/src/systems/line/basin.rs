//! `dexter basin` on a line scene: each run classified from its summary, and the region the
//! mirror law's Singer–Guckenheimer certificate covers ([`super::analyze`]): initial states
//! whose first impact speed v = √(b′² + 2 g b) (m/s) lies in (0, v0), the certificate's
//! invariant interval, for a scene whose verdict is essentially globally asymptotically
//! stable. For a `sil` scene the certificate is the ideal law's with the same gains.

use super::scene::Scene;
use super::{LineOutcome, LineSystem};
use crate::engine::unimodal::Verdict;
use crate::system::basin::{BasinClass, Basins};

impl Basins for LineSystem {
    fn classify(_: &Scene, out: &LineOutcome) -> BasinClass {
        let s = &out.summary;
        if s.control_steps > 0 && s.safe.mostly_safe() {
            BasinClass::Safe
        } else if s.converged_after_impacts.is_some() {
            BasinClass::Target
        } else if s.resting_contact {
            BasinClass::Rest
        } else if let Some(p) = s.period {
            BasinClass::OtherPeriod(p)
        } else {
            BasinClass::NotSettled
        }
    }

    fn certified(cfg: &Scene) -> Option<bool> {
        let a = super::analyze::analyze(cfg).ok()?;
        let cert = a.certificate()?;
        let (b, v) = (cfg.ball.height_m, cfg.ball.velocity_mps);
        let speed2 = v * v + 2.0 * cfg.physics.gravity_mps2 * b;
        let egas = matches!(cert.verdict, Verdict::Certified { .. });
        Some(egas && b >= 0.0 && speed2 > 0.0 && speed2.sqrt() < cert.interval.1)
    }

    fn cost(key: &str, value: f64) -> f64 {
        super::sweep::run_cost(key, value)
    }
}
