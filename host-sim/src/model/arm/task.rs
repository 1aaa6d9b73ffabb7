//! The four tasks of sec. 2 as phase sequences with their goals.
//!
//! - snatch `g`: lift the object off a table (the arm's surface starts flush with it, at
//!   rest) and bring it to rest on the arm at a final joint angle;
//! - throw `gf`: carry it in a dynamic grasp, release it (the arm brakes), and let it fly
//!   to a goal pose;
//! - roll `grg`: roll it over a vertex from one edge to the next and bring the arm to
//!   rest with the object grasped on the new edge;
//! - rolling throw `grf`: release it while it rolls;
//! - throw and catch `gf` + `g`: a throw whose goal is the object lying on an edge of the
//!   arm at rest at the catching angle, which the time-optimal bang-bang move after the
//!   release (sec. 2.5) reaches before the object comes down; the catch is a one-sided
//!   plastic impact into a dynamic grasp ([`super::impact`]).

use serde::{Deserialize, Serialize};

/// One manipulation phase (sec. 2: g, r, f).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Dynamic grasp `g`.
    Grasp,
    /// Roll about a vertex `r`.
    Roll,
    /// Free flight `f`.
    Flight,
}

impl Phase {
    /// The paper's letter.
    pub fn letter(self) -> char {
        match self {
            Phase::Grasp => 'g',
            Phase::Roll => 'r',
            Phase::Flight => 'f',
        }
    }
}

/// Which task (`task.kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TaskKind {
    /// `"snatch"` (g).
    Snatch,
    /// `"throw"` (gf).
    Throw,
    /// `"roll"` (grg).
    Roll,
    /// `"rolling_throw"` (grf).
    RollingThrow,
    /// `"throw_catch"` (gf, then the catch into g).
    ThrowCatch,
}

impl TaskKind {
    /// The phase sequence.
    pub fn phases(self) -> &'static [Phase] {
        use Phase::*;
        match self {
            TaskKind::Snatch => &[Grasp],
            TaskKind::Throw => &[Grasp, Flight],
            TaskKind::Roll => &[Grasp, Roll, Grasp],
            TaskKind::RollingThrow => &[Grasp, Roll, Flight],
            TaskKind::ThrowCatch => &[Grasp, Flight],
        }
    }

    /// The phase letters a run executes: the planned phases, and for a catch the grasp
    /// after it (`"gfg"`).
    pub fn executed_letters(self) -> String {
        let mut l = self.letters();
        if self == TaskKind::ThrowCatch {
            l.push('g');
        }
        l
    }

    /// Whether the task catches the object it threw.
    pub fn catches(self) -> bool {
        self == TaskKind::ThrowCatch
    }

    /// The phase letters, e.g. `"grf"`.
    pub fn letters(self) -> String {
        self.phases().iter().map(|p| p.letter()).collect()
    }

    /// The name used in scenes and JSON.
    pub fn name(self) -> &'static str {
        match self {
            TaskKind::Snatch => "snatch",
            TaskKind::Throw => "throw",
            TaskKind::Roll => "roll",
            TaskKind::RollingThrow => "rolling_throw",
            TaskKind::ThrowCatch => "throw_catch",
        }
    }

    /// Whether the planned motion ends in flight (a throw, also one that is caught after).
    pub fn throws(self) -> bool {
        self.phases().last() == Some(&Phase::Flight)
    }

    /// Whether the task has a roll.
    pub fn rolls(self) -> bool {
        self.phases().contains(&Phase::Roll)
    }
}

/// The pose a thrown object must reach: its centre of mass crosses height `y_m` going
/// down at `x_m`, turned to `angle_rad`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Goal {
    /// Goal x of the centre of mass, m.
    pub x_m: f64,
    /// Goal height of the centre of mass, m (the landing event: crossing it downward).
    pub y_m: f64,
    /// Goal orientation of the object (body frame to world), rad.
    pub angle_rad: f64,
    /// Accepted distance from (x, y) at the landing event, m.
    pub tolerance_m: f64,
    /// Accepted angle error at the landing event, rad.
    pub angle_tolerance_rad: f64,
}

/// Where a thrown object is caught: the arm at rest at `angle_rad`, the object's edge
/// `place.edge` flat on the surface at `place` (the throw's goal is that pose).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Catch {
    /// The catching joint angle, rad (where the bang-bang move after the release rests).
    pub angle_rad: f64,
    /// The edge and where it lies on the surface.
    pub place: super::contact::Placement,
}

/// A validated task.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Task {
    /// Which task.
    pub kind: TaskKind,
    /// Joint angle at the start (at rest), rad.
    pub initial_angle_rad: f64,
    /// Roll direction: +1 counterclockwise, -1 clockwise (0 without a roll).
    pub roll_dir: f64,
    /// Joint angle where the arm comes to rest, if the task fixes it, rad.
    pub final_angle_rad: Option<f64>,
    /// Bounds on the final joint angle, rad (the paper's "limited the end angle").
    pub final_angle_range_rad: (f64, f64),
    /// The throw's goal.
    pub goal: Option<Goal>,
    /// The catch, for a throw and catch.
    pub catch: Option<Catch>,
    /// Weight of the squared roll-end impact speed in the objective, (m/s)^-2 (0 = mu only).
    pub impact_weight_s2pm2: f64,
    /// Time the verifier keeps the arm at rest after the trajectory, s.
    pub hold_s: f64,
    /// Throw-catch cycles in a row (1 but for a juggle).
    pub cycles: usize,
    /// The contact's friction coefficient a juggle is verified at (else each plan's mu).
    pub mu: Option<f64>,
}
