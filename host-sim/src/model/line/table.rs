//! The passive bounce on a fixed table in closed form: a ball leaving the table at speed
//! `v` returns after `2 v / g` and leaves again at `e` times its landing speed, so a run of
//! bounces needs no root finding, no flight-model dispatch and no plant state in memory
//! between impacts. Only the bounces whose every step is that closed form are taken here;
//! the first fall, a flight cut by the end time, the start of a Zeno sequence and rest go
//! through the general segment loop ([`LinePlant::advance_segments`]). The arithmetic is
//! the general loop's, operation for operation (`-c1 / c2` is the take-off root of
//! [`crate::engine::roots::first_contact`], the landing speed is
//! [`BallState::flown`]'s, the impact [`restitution_velocity`]), so the rows are the same
//! bit for bit (`tests::closed_form_bounces_equal_the_segment_loop`).

use super::{Advance, LinePlant, MAX_SEGMENTS_PER_CALL};
use crate::effects::jitter::NoJitter;
use crate::engine::{Ballistic, Flight};
use crate::model::impact::ImpactRow;
use crate::model::surface::Table;
use dexter_core::state::{restitution_velocity, BallState};

impl LinePlant<Ballistic, Table, NoJitter> {
    /// As [`LinePlant::advance_to`], bit for bit, with every bounce from the table in
    /// closed form (module docs). At most [`MAX_SEGMENTS_PER_CALL`] flights, as there.
    #[inline(always)]
    pub fn bounce_to(
        &mut self,
        t_end_s: f64,
        max_impacts: u64,
        on_impact: &mut impl FnMut(&ImpactRow),
    ) -> Advance {
        let mut segments = 0u32;
        while segments < MAX_SEGMENTS_PER_CALL {
            let (flown, end) = self.bounces(
                t_end_s,
                max_impacts,
                MAX_SEGMENTS_PER_CALL - segments,
                on_impact,
            );
            if let Some(end) = end {
                return end;
            }
            segments += flown;
            if segments == MAX_SEGMENTS_PER_CALL {
                break;
            }
            match self.advance_segments(t_end_s, max_impacts, 1, on_impact) {
                Advance::SegmentCap => segments += 1,
                end => return end,
            }
        }
        Advance::SegmentCap
    }

    /// At most `budget` bounces in closed form from a ball leaving the table: how many, and
    /// why they ended if the call must return (`None`: a case for the general loop, the
    /// plant untouched since the last bounce).
    #[inline(always)]
    fn bounces(
        &mut self,
        t_end_s: f64,
        max_impacts: u64,
        budget: u32,
        on_impact: &mut impl FnMut(&ImpactRow),
    ) -> (u32, Option<Advance>) {
        let (g, e, z) = (self.gravity_mps2, self.restitution, self.surface.height_m);
        // Ballistic::fly's coefficients against the table's polynomial (0 velocity and
        // acceleration); the paddle's velocity at impact, as LinePlant::impact forms it
        let c2 = -0.5 * (g + 0.0);
        let rv = 0.0 + 0.0 * 0.0;
        let falls = c2 < 0.0 && c2.is_finite();
        if !falls || self.resting || self.ball.height_m - z != 0.0 {
            return (0, None);
        }
        let (mut t, mut v, mut index) = (self.time_s, self.ball.velocity_mps, self.impacts);
        let mut row = self.last_row;
        let mut n = 0;
        let end = loop {
            if n == budget {
                break None;
            }
            let window = t_end_s - t;
            if window <= 0.0 {
                break Some(Advance::Reached);
            }
            // first_contact's take-off root, c0 == 0 < c1 with every coefficient and the
            // window finite (c2 checked above). With c2 < 0, dt has c1's sign, is NaN
            // for a NaN c1 and infinite for an infinite one, so these comparisons are
            // first_contact's conditions on c1 and on the root together.
            let c1 = v - 0.0;
            let dt = -c1 / c2;
            if !(dt > 0.0 && dt <= window && window < f64::INFINITY) {
                break None;
            }
            let v_in = v - g * dt;
            let v_out = restitution_velocity(v_in, rv, e);
            if self.zeno.is_zeno(v_out - rv, rv) {
                break None;
            }
            t += dt;
            row = ImpactRow {
                index,
                time_s: t,
                ball_height_m: z,
                ball_velocity_before_mps: v_in,
                ball_velocity_after_mps: v_out,
                paddle_height_m: z,
                paddle_velocity_mps: rv,
                apex_height_m: self.flight.apex_m(&BallState::new(z, v_out), g),
            };
            index += 1;
            n += 1;
            v = v_out;
            on_impact(&row);
            if index >= max_impacts {
                break Some(Advance::ImpactLimit);
            }
        };
        if n > 0 {
            self.time_s = t;
            self.ball = BallState::new(z, v);
            self.impacts = index;
            self.last_row = row;
        }
        (n, end)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::zeno::ZenoPolicy;
    use proptest::prelude::*;

    type TablePlant = LinePlant<Ballistic, Table, NoJitter>;

    fn plant(g: f64, e: f64, z: f64, ball: (f64, f64), zeno_mps: f64) -> TablePlant {
        let zeno = ZenoPolicy {
            velocity_threshold_mps: zeno_mps,
            relative_threshold: 1e-3,
            max_impacts_per_segment: 1000,
        };
        let ball = BallState::new(ball.0, ball.1);
        LinePlant::new(g, e, Ballistic, Table { height_m: z }, NoJitter, zeno, ball)
    }

    /// Every row and the end state of `p` advanced in calls of `chunk` impacts to `t_end`,
    /// by `closed_form` or the general loop.
    fn run(
        mut p: TablePlant,
        t_end: f64,
        chunk: u64,
        closed_form: bool,
    ) -> (Vec<ImpactRow>, String) {
        let mut rows = Vec::new();
        let mut ends = Vec::new();
        for _ in 0..50 {
            let goal = p.impacts + chunk;
            let mut push = |r: &ImpactRow| rows.push(*r);
            let end = match closed_form {
                true => p.bounce_to(t_end, goal, &mut push),
                false => p.advance_to(t_end, goal, &mut push),
            };
            ends.push(end);
            if matches!(end, Advance::Reached | Advance::RestForever) {
                break;
            }
        }
        let state = format!(
            "{ends:?} t={:e} ball={:?} n={} resting={} rests={:?} last={:?}",
            p.time_s, p.ball, p.impacts, p.resting, p.rests, p.last_row
        );
        (rows, state)
    }

    fn bits(rows: &[ImpactRow]) -> Vec<[u64; 8]> {
        rows.iter()
            .map(|r| {
                [
                    r.index,
                    r.time_s.to_bits(),
                    r.ball_height_m.to_bits(),
                    r.ball_velocity_before_mps.to_bits(),
                    r.ball_velocity_after_mps.to_bits(),
                    r.paddle_height_m.to_bits(),
                    r.paddle_velocity_mps.to_bits(),
                    r.apex_height_m.to_bits(),
                ]
            })
            .collect()
    }

    fn same(p: TablePlant, t_end: f64, chunk: u64) {
        let (a, sa) = run(p.clone(), t_end, chunk, true);
        let (b, sb) = run(p, t_end, chunk, false);
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(sa, sb);
    }

    #[test]
    fn closed_form_bounces_equal_the_segment_loop() {
        // elastic (never at rest), lossy to a Zeno rest, a ball thrown up from the table,
        // one dropped onto a raised table, a run cut by its end time mid-flight
        same(plant(9.81, 1.0, 0.0, (1.0, 0.0), 1e-6), 1e3, 97);
        same(plant(9.81, 0.8, 0.0, (1.0, 0.0), 1e-6), 60.0, 1000);
        same(plant(9.81, 0.8, 0.0, (1.0, 0.0), 0.5), 60.0, 7);
        same(plant(9.81, 0.9, 0.0, (0.0, 3.0), 1e-6), 60.0, 1000);
        same(plant(1.62, 0.95, 0.25, (2.0, -1.0), 1e-6), 17.3, 5);
        same(plant(9.81, 1.0, -3.0, (-3.0, 1e-300), 1e-320), 1.0, 10);
    }

    #[test]
    fn a_run_of_bounces_is_taken_in_closed_form() {
        // the elastic ball from 1 m: every bounce after the first fall is a closed-form one
        let mut p = plant(9.81, 1.0, 0.0, (1.0, 0.0), 1e-6);
        assert_eq!(
            p.advance_segments(1e9, 1, 1, &mut |_| {}),
            Advance::ImpactLimit
        );
        let (n, end) = p.bounces(1e9, 1001, u32::MAX, &mut |_| {});
        assert_eq!((n, end), (1000, Some(Advance::ImpactLimit)));
        // the flight time is 2 sqrt(2 h / g) and the speed stays sqrt(2 g h)
        let v = (2.0f64 * 9.81).sqrt();
        assert!((p.time_s - 2001.0 * (2.0f64 / 9.81).sqrt()).abs() < 1e-9);
        assert!((p.ball.velocity_mps - v).abs() < 1e-12);
        assert!((p.last_row.apex_height_m - 1.0).abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn closed_form_bounces_equal_the_segment_loop_anywhere(
            g in 0.1f64..100.0,
            e in 0.0f64..=1.0,
            z in -10.0f64..10.0,
            above in 0.0f64..5.0,
            v0 in -5.0f64..5.0,
            t_end in 0.0f64..30.0,
            chunk in 1u64..300,
            zeno in prop_oneof![Just(1e-9), 1e-6f64..1.0],
        ) {
            same(plant(g, e, z, (z + above, v0), zeno), t_end, chunk);
        }
    }
}
