//! The verdict of a run that reached its end time without failing.

use super::{Executed, Execution, GoalError, Runner, State};
use crate::model::arm::geometry::wrap_pi;
use crate::model::arm::task::TaskKind;

impl Runner<'_> {
    /// A task ending at rest must end grasped on the right edge.
    pub(super) fn judge_at_rest(&mut self) {
        let sys = self.sys;
        if sys.task.kind.catches() {
            self.judge_caught();
            return;
        }
        if sys.task.kind.throws() {
            self.fail(
                Executed::Missed,
                "the object never came down to the goal height".into(),
            );
            return;
        }
        let rig = &sys.rig;
        let want = match sys.task.kind {
            TaskKind::Snatch => sys.start,
            _ => rig.landed(&rig.pivot(&sys.start, sys.task.roll_dir)),
        };
        let State::Grasp(p) = self.state else {
            self.fail(
                Executed::Missed,
                "the object was still moving at the end".into(),
            );
            return;
        };
        let j_end = self.arm.joint(self.t);
        let j_goal = match sys.task.final_angle_rad {
            Some(a) => crate::model::arm::contact::Joint {
                angle_rad: a,
                ..Default::default()
            },
            None => crate::model::arm::contact::Joint {
                angle_rad: j_end.angle_rad,
                ..Default::default()
            },
        };
        let got = rig.grasped_state(&p, &j_end);
        let goal = rig.grasped_state(&want, &j_goal);
        self.out.goal_error = Some(GoalError {
            position_m: got.com.minus(goal.com).norm(),
            angle_rad: wrap_pi(got.angle_rad - goal.angle_rad),
        });
        if p.edge == want.edge {
            self.verdict = Some((
                Executed::Ok,
                format!("at rest on the arm on edge {}", p.edge),
            ));
        } else {
            self.fail(
                Executed::Missed,
                format!("ended on edge {} instead of edge {}", p.edge, want.edge),
            );
        }
    }

    /// A throw and catch must end at rest on the catching edge.
    fn judge_caught(&mut self) {
        let Some(c) = self.sys.task.catch else {
            return;
        };
        if self.out.catch_index.is_none() {
            self.fail(
                Executed::Missed,
                "the object never came down onto the arm".into(),
            );
            return;
        }
        let State::Grasp(p) = self.state else {
            self.fail(
                Executed::Missed,
                "the caught object was still moving at the end".into(),
            );
            return;
        };
        let rig = &self.sys.rig;
        let j_end = self.arm.joint(self.t);
        let got = rig.grasped_state(&p, &j_end);
        let goal = rig.grasped_state(
            &c.place,
            &crate::model::arm::contact::Joint {
                angle_rad: c.angle_rad,
                ..Default::default()
            },
        );
        self.out.goal_error = Some(GoalError {
            position_m: got.com.minus(goal.com).norm(),
            angle_rad: wrap_pi(got.angle_rad - goal.angle_rad),
        });
        if p.edge == c.place.edge {
            self.verdict = Some((
                Executed::Ok,
                format!("caught on edge {} and held at rest", p.edge),
            ));
        } else {
            self.fail(
                Executed::Missed,
                format!("caught on edge {} instead of edge {}", p.edge, c.place.edge),
            );
        }
    }

    pub(super) fn finish(mut self) -> Execution {
        let (mut how, mut why) = self
            .verdict
            .take()
            .unwrap_or((Executed::Missed, "no verdict".into()));
        self.out.phases = executed_phases(&self.out.events);
        let planned = self.sys.task.kind.executed_letters();
        if how == Executed::Ok && self.out.phases != planned {
            how = Executed::Missed;
            why = format!(
                "{why}, but through the phases {} instead of the planned {planned}",
                self.out.phases
            );
        }
        self.out.executed = how;
        self.out.reason = why;
        if let State::Grasp(p) = self.state {
            self.out.rest = Some(p);
        }
        // the last frame shows where the run ended
        self.next_frame = self.t;
        self.record();
        self.out
    }
}

/// The phase letters a run went through, from its events: `g` at the start, `r` at each
/// roll's start, `g` at a roll's end or fall back, `f` at the release. Rocks after an
/// impact (a `rock_*` event and the roll back that ends it) belong to the impact that
/// settles the object on its edge: they add no phase.
pub fn executed_phases(events: &[super::Event]) -> String {
    let mut letters = String::from("g");
    let mut rocking = false;
    for e in events {
        let letter = match e.kind {
            "rock_ccw" | "rock_cw" => {
                rocking = true;
                None
            }
            "roll_back" if rocking => None,
            "roll_start_ccw" | "roll_start_cw" => Some('r'),
            "roll_end" if rocking => {
                letters.push('r');
                Some('g')
            }
            "roll_end" | "roll_back" | "catch" => Some('g'),
            "release" => Some('f'),
            _ => continue,
        };
        if let Some(c) = letter {
            rocking = false;
            if !letters.ends_with(c) {
                letters.push(c);
            }
        }
    }
    letters
}

#[cfg(test)]
mod tests {
    use super::super::Event;
    use super::executed_phases;

    fn at(kinds: &[&'static str]) -> Vec<Event> {
        kinds
            .iter()
            .enumerate()
            .map(|(i, &kind)| Event {
                t_s: i as f64,
                kind,
            })
            .collect()
    }

    #[test]
    fn phase_letters_follow_the_events_and_rocks_add_none() {
        assert_eq!(executed_phases(&[]), "g");
        assert_eq!(executed_phases(&at(&["release", "landing"])), "gf");
        assert_eq!(
            executed_phases(&at(&[
                "roll_start_cw",
                "roll_back",
                "roll_start_cw",
                "release"
            ])),
            "grgrf"
        );
        let rocks = [
            "roll_start_ccw",
            "roll_end",
            "rock_ccw",
            "roll_back",
            "rock_cw",
            "roll_back",
        ];
        assert_eq!(executed_phases(&at(&rocks)), "grg");
        // a rock that rolls on over its vertex is a second roll
        let over = ["roll_start_ccw", "roll_end", "rock_ccw", "roll_end"];
        assert_eq!(executed_phases(&at(&over)), "grgrg");
    }
}
