//! The verifier's phase steps against hand cases: it must see a slip whichever way the
//! friction force points, a separation, a tip over the right vertex, a flight landing.

use dexter_sim::model::arm::contact::{Joint, Placement, Rig};
use dexter_sim::model::arm::geometry::{Polygon, Surface, V2};
use dexter_sim::model::arm::motion::ArmMotion;
use dexter_sim::model::arm::simulate::step::{grasp_step, roll_step, GraspEvent, RollEvent};

const G: f64 = 9.81;

/// The joint held still at one angle, or moving at a constant acceleration.
struct Still {
    angle: f64,
    accel: f64,
}

impl ArmMotion for Still {
    fn joint(&self, t: f64) -> Joint {
        Joint {
            angle_rad: self.angle + 0.5 * self.accel * t * t,
            velocity_radps: self.accel * t,
            accel_radps2: self.accel,
        }
    }
    fn settled_s(&self) -> f64 {
        0.0
    }
    fn release_s(&self) -> f64 {
        0.0
    }
    fn breaks_s(&self) -> Vec<f64> {
        Vec::new()
    }
}

fn rig(rho: Option<f64>) -> Rig {
    Rig {
        body: Polygon::square(0.1, rho).unwrap(),
        surface: Surface {
            origin: V2::new(0.0, 0.05),
            beta_rad: 0.0,
            length_m: 1.22,
        },
        gravity_mps2: G,
    }
}

const AT: Placement = Placement {
    edge: 0,
    sigma_m: 0.85,
};

#[test]
fn a_grasp_slips_either_way_just_past_tan_tilt() {
    let r = rig(None);
    for tilt in [0.4f64, -0.4] {
        let arm = Still {
            angle: tilt,
            accel: 0.0,
        };
        let mu = tilt.abs().tan();
        assert_eq!(
            grasp_step(&r, &AT, &arm, mu * 1.001, 0.0, 0.01),
            None,
            "tilt {tilt}"
        );
        let e = grasp_step(&r, &AT, &arm, mu * 0.999, 0.0, 0.01);
        assert_eq!(e.map(|e| e.1), Some(GraspEvent::Slips), "tilt {tilt}");
    }
}

#[test]
fn a_grasp_tips_over_the_downhill_vertex_past_45_degrees() {
    let r = rig(None);
    for (tilt, dir) in [(0.9f64, 1.0), (-0.9, -1.0)] {
        let arm = Still {
            angle: tilt,
            accel: 0.0,
        };
        let e = grasp_step(&r, &AT, &arm, 10.0, 0.0, 0.01).unwrap();
        assert_eq!(e.1, GraspEvent::Tips(dir), "tilt {tilt}");
    }
}

#[test]
fn a_grasp_separates_when_the_arm_drops_faster_than_gravity() {
    // surface 0.9 m out: theta'' = -12 rad/s^2 pulls it down at ~10.8 m/s^2 > g
    let r = rig(None);
    let arm = Still {
        angle: 0.0,
        accel: -12.0,
    };
    let e = grasp_step(&r, &AT, &arm, 10.0, 0.0, 0.01).unwrap();
    assert_eq!(e.1, GraspEvent::Separates);
    assert!(e.0 < 1e-9, "at once: {}", e.0);
}

#[test]
fn a_roll_slips_whichever_way_the_pivot_is_pushed() {
    // mirrored set-ups (tilt and roll direction flipped) flip the friction force's sign
    let r = rig(Some(0.0577));
    let mut signs = Vec::new();
    for (tilt, dir) in [(0.95f64, 1.0), (-0.95, -1.0)] {
        let arm = Still {
            angle: tilt,
            accel: 0.0,
        };
        let pv = r.pivot(&AT, dir);
        let s0 = (dir * 0.05, 0.0);
        let f = r.roll(&pv, s0.0, s0.1, &arm.joint(0.0)).force;
        signs.push(f.tangential.signum());
        let ratio = f.friction_ratio();
        let (_, _, ok) = roll_step(&r, &pv, &arm, ratio * 1.05, 0.0, 1e-4, s0);
        assert_eq!(ok, None, "tilt {tilt}");
        let (t, _, bad) = roll_step(&r, &pv, &arm, ratio * 0.99, 0.0, 1e-4, s0);
        assert_eq!(bad, Some(RollEvent::Slips), "tilt {tilt}");
        assert!(t < 1e-6);
    }
    assert_eq!(
        signs[0], -signs[1],
        "the two cases push the pivot opposite ways"
    );
}

#[test]
fn a_roll_lands_on_the_next_edge_and_the_event_is_located() {
    // level and still, the square let go just past its balance over the vertex (psi =
    // 0.8 > pi/4) falls onto its next edge; the landing time from a coarse step matches
    // a fine one
    let r = rig(None);
    let pv = r.pivot(&AT, 1.0);
    let arm = Still {
        angle: 0.0,
        accel: 0.0,
    };
    let run = |h: f64| {
        let (mut t, mut s) = (0.0, (0.8, 0.0));
        loop {
            let (te, s1, e) = roll_step(&r, &pv, &arm, f64::INFINITY, t, t + h, s);
            (t, s) = (te, s1);
            if let Some(e) = e {
                return (t, e, s);
            }
            assert!(t < 5.0);
        }
    };
    let (t1, e1, s1) = run(1e-3);
    let (t2, e2, _) = run(1e-4);
    assert_eq!((e1, e2), (RollEvent::Lands, RollEvent::Lands));
    assert!((t1 - t2).abs() < 1e-6, "{t1} vs {t2}");
    assert!((s1.0 - pv.gamma_rad).abs() < 1e-6);
}
