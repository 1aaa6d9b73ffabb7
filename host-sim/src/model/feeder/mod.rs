//! The 1JOC parts feeder of Akella, Huang, Lynch & Mason, "From Robotic Juggling to
//! Robotic Parts Feeding", sec. 3 (a condensed revision of their ISRR 1995 paper): a
//! straight fence turning on one revolute joint above a conveyor belt that moves at
//! constant speed in -y brings a polygonal part from its arrival pose to one goal edge and
//! contact radius by alternating stable pushes with drift.
//!
//! | module | holds |
//! | --- | --- |
//! | [`geometry`] | vectors, poses, area integrals, convex hull |
//! | [`part`] | the part: hull edges, stable edges, turn angles |
//! | [`support`] | the belt's support friction: ellipsoidal limit surface and the exact integral |
//! | [`quasistatic`] | the contact-mode solver: stable push, slide, pivot, drift |
//! | [`sim`] | time-stepping the part under a fence schedule; failures (off the belt or fence) |
//! | [`stability`] | stable-push condition and the minimum contact radius |
//! | [`primitives`] | stable push, turn, jog, convergent turn as fence schedules |
//! | [`pushes`] | rate-scheduled stable pushes: the window of stable fence rates, profiles |
//! | [`planner`] | goal edge, edge sequences, parameter optimization (COBYLA) |
//! | [`execute`] | simulated execution with noise, the JSON summary, the arrival sweep |
//!
//! Conventions: world origin at the fence pivot, belt velocity `(0, -v_b)`, fence angle
//! theta from +x, the part on the fence's `(-sin theta, cos theta)` side, only the right
//! half of the belt (x > 0) used. The **contact radius** r is the fence coordinate of the
//! foot of the perpendicular from the part's center of mass onto the fence.

pub mod execute;
pub mod geometry;
pub mod part;
pub mod planner;
pub mod primitives;
pub mod pushes;
pub mod quasistatic;
pub mod sim;
pub mod stability;
pub mod support;

pub use geometry::{Pose, Vec2};
pub use part::{HullEdge, Part};

/// Why a feeder scene could not be built, planned or run. Messages name the scene key or
/// the physical cause.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum FeederError {
    /// A scene value is invalid: `key` is the dotted scene key, `requirement` what it
    /// must satisfy.
    Param {
        /// Dotted scene key, e.g. `feeder.belt.speed_mps`.
        key: String,
        /// What it must satisfy, in words.
        requirement: String,
    },
    /// No plan exists under the scene's limits; the message names the limit (belt width,
    /// fence length, fence angle range, ...) and what it would need to be.
    Infeasible(String),
}

impl FeederError {
    /// A [`FeederError::Param`] for `key`.
    pub fn param(key: &str, requirement: &str) -> Self {
        FeederError::Param {
            key: key.to_string(),
            requirement: requirement.to_string(),
        }
    }
}

impl core::fmt::Display for FeederError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FeederError::Param { key, requirement } => write!(f, "{key} {requirement}"),
            FeederError::Infeasible(why) => write!(f, "no feeding plan: {why}"),
        }
    }
}

impl std::error::Error for FeederError {}
