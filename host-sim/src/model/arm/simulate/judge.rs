//! The verdict of a run that reached its end time without failing.

use super::{Executed, Execution, GoalError, Runner, State};
use crate::model::arm::geometry::wrap_pi;
use crate::model::arm::task::TaskKind;

impl Runner<'_> {
    /// A task ending at rest must end grasped on the right edge.
    pub(super) fn judge_at_rest(&mut self) {
        let sys = self.sys;
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

    pub(super) fn finish(mut self) -> Execution {
        let (how, why) = self
            .verdict
            .take()
            .unwrap_or((Executed::Missed, "no verdict".into()));
        self.out.executed = how;
        self.out.reason = why;
        // the last frame shows where the run ended
        self.next_frame = self.t;
        self.record();
        self.out
    }
}
