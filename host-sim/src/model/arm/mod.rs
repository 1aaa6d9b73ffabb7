//! One-motor dynamic manipulation (Akella, Huang, Lynch & Mason, "From Robotic Juggling to
//! Robotic Parts Feeding", sec. 2): a one-joint arm in the vertical plane, like the
//! paper's NSK arm (a 1.22 m link of 10 cm square section with a palm at 45 degrees), moves
//! a polygonal object that it does not grasp: dynamic grasp, roll about a vertex, free
//! flight. Plans are cubic B-spline joint trajectories found by sequential quadratic
//! programming that minimizes the friction coefficient they need (sec. 2.1-2.4).
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`geometry`] | plane vectors, the convex polygon, the arm's surfaces |
//! | [`contact`] | grasp and roll forces, phase conditions, flight, the arm's torque (derived) |

pub mod contact;
pub mod geometry;
