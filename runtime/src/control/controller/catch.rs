//! The step-back catch in the controller (`runtime::control::recovery`, "The step-back
//! catch"): the swing foot set down behind the stance foot, then the catch proper in double
//! support, handed over onto the orbit as a launch is.

use super::walk::WalkEval;
use super::Controller;
use crate::control::double_support::{slots, Geometry};
use crate::control::gait_table::side_index;
use crate::control::orbit_table::OrbitTable;
use crate::control::pendulum::{Catch, Pendulum, CATCH_LOWER_S};
use crate::control::recovery::{
    FallingBack, SetDown, CATCH, CATCH_DOWN_M, CATCH_SET_DOWN_S, CATCH_STEP_BACK_M,
};
use crate::control::tick::ControlState;
use crate::control::transitions::Launch;
use crate::slots::{LEG_SLOTS, OUTPUTS};
use model::Side;

/// The set-down lowers the torso by at most this, m ...
const CATCH_MAX_DROP_M: f64 = 0.08;
/// ... searched in this many steps, for a rear knee bent at least this much, rad (a straighter
/// knee leaves no room for the torso's motion in double support).
const CATCH_DROP_STEPS: u32 = 16;
const CATCH_MIN_KNEE_RAD: f64 = 0.2;
/// The foot is clear of the ground above this, m.
const CATCH_CLEAR_M: f64 = 0.003;

impl Controller {
    /// A new step (an impact, a launch's hand-over): the phase's highest value starts again,
    /// no set-down.
    pub(super) fn restart_catch(&mut self) {
        self.catch_watch = FallingBack::default();
        self.set_down = None;
    }

    /// Starts setting the swing foot down if it is at least `speed.step_back_catch_m` behind
    /// the stance foot and the legs reach the landing point (the torso at most
    /// `CATCH_MAX_DROP_M` lower). No stall relaunch follows in this step.
    pub(super) fn begin_set_down(
        &mut self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
    ) {
        let pitch = self.estimator.pitch_rad();
        let rate = self.estimator.pitch_rate_rad_s();
        let g = self.geometry();
        let Some(m) = g.measure(self.stance, pitch, rate, leg_q, leg_dq) else {
            return;
        };
        if m.other_foot_xz_m[0] > -self.step_back_catch_m {
            return;
        }
        let to_x_m = m.other_foot_xz_m[0].min(-CATCH_STEP_BACK_M);
        // The torso where it will be when the foot lands (it keeps moving back), as high as the
        // legs reach the landing point from.
        let x1 = m.pose[0] + m.rate[0].min(0.0) * CATCH_SET_DOWN_S;
        let Some(z1_m) = reaching_height(&g, self.stance, [x1, m.pose[1], pitch], to_x_m, leg_q)
        else {
            return;
        };
        self.set_down = Some(SetDown {
            start_t_s: t_s,
            from_xz_m: m.other_foot_xz_m,
            to_x_m,
            pitch_rad: pitch,
            z0_m: m.pose[1],
            z1_m,
            last_q: *leg_q,
            v_air_mps: m.rate[0],
        });
        self.catch_watch.disarm();
        self.stall.disarm();
    }

    /// While the swing foot is set down: every output follows the legs' inverse kinematics of
    /// the measured torso x, the set-down's height and pitch, and the foot on its path
    /// ([`SetDown::at`]). Once it is down (or after twice the set-down's time) the catch
    /// proper starts; if no pivot can stop the robot, the walk goes on (the step timeout
    /// stays the last resort).
    pub(super) fn set_down_outputs(
        &mut self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
        eval: &mut WalkEval,
    ) {
        let Some(mut sd) = self.set_down else {
            return;
        };
        if self.state != ControlState::Walk || self.braking {
            self.set_down = None;
            return;
        }
        let pitch = self.estimator.pitch_rad();
        let rate = self.estimator.pitch_rate_rad_s();
        let g = self.geometry();
        let Some(m) = g.measure(self.stance, pitch, rate, leg_q, leg_dq) else {
            return;
        };
        let dt = t_s - sd.start_t_s;
        if m.other_foot_xz_m[1] <= CATCH_DOWN_M || dt >= 2.0 * CATCH_SET_DOWN_S {
            self.set_down = None;
            if self.begin_catch(t_s, leg_q, leg_dq, &sd) {
                self.catches = self.catches.saturating_add(1);
            }
            return;
        }
        let (foot, z) = sd.at(dt);
        let pose = [m.pose[0], z, sd.pitch_rad];
        if let Some((q, _)) = g.solve(self.stance, pose, [0.0; 3], foot, &sd.last_q) {
            let side = side_index(self.stance);
            for i in 0..OUTPUTS {
                eval.y[i] = q[self.gait.out_slot[side][i]];
                eval.dy[i] = 0.0;
            }
            sd.last_q = q;
        }
        if m.other_foot_xz_m[1] > CATCH_CLEAR_M {
            sd.v_air_mps = m.rate[0];
        }
        self.set_down = Some(sd);
    }

    /// Starts the catch proper from the measured state, the rear foot down: the centre of
    /// mass on its pendulum ([`Catch`]) from the rate measured before the landing, the torso
    /// back to the set-down's pitch from rest, lowered if the rear foot needs it; the phase
    /// observer restarts at the hand-over. True if a pivot ahead of the rear foot stops it.
    fn begin_catch(
        &mut self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
        sd: &SetDown,
    ) -> bool {
        let g = self.geometry();
        let pitch = self.estimator.pitch_rad();
        let rate = self.estimator.pitch_rate_rad_s();
        let Some(m) = g.measure(self.stance, pitch, rate, leg_q, leg_dq) else {
            return false;
        };
        let Some(com) = g.com_offset(pitch, leg_q) else {
            return false;
        };
        let rear_x_m = m.other_foot_xz_m[0];
        // A catch never starts forward: it stops a robot moving back.
        let v0 = sd.v_air_mps.min(0.0);
        let Some(pendulum) = Pendulum::new(
            (m.pose[0] + com[0], v0),
            m.pose[1] + com[1],
            rear_x_m,
            com[0],
        ) else {
            return false;
        };
        // Lowered, if the rear foot needs it, where the torso is once the lowering ends.
        let end = [pendulum.at(CATCH_LOWER_S).0, m.pose[1], sd.pitch_rad];
        let Some(z1_m) = reaching_height(&g, self.stance, end, rear_x_m, leg_q) else {
            return false;
        };
        let catch = Catch {
            pendulum,
            z0_m: m.pose[1],
            z1_m,
        };
        let orbit = OrbitTable::of(&g, &self.gait);
        // The pitch goes back to the set-down's from rest on the launch's quintic; its x and
        // height follow the catch (`launch_commands`).
        self.launch = Some(Launch {
            start_t_s: t_s,
            timing: CATCH,
            from: m.pose,
            from_rate: [m.rate[0], m.rate[1], 0.0],
            to: [end[0], z1_m, sd.pitch_rad],
            speed_mps: 0.0,
            orbit,
            other_foot_xz_m: [rear_x_m, 0.0],
            leg_q: *leg_q,
            correction: [0.0; 3],
            last_t_s: t_s,
            catch: Some(catch),
        });
        self.phase_hat = None;
        true
    }
}

/// The highest torso, from `pose`'s height down by at most [`CATCH_MAX_DROP_M`] (x and pitch
/// held), whose legs reach the rear foot at `rear_x_m` on the ground with its knee bent at
/// least [`CATCH_MIN_KNEE_RAD`], by inverse kinematics; `None` if none does. (The reach from
/// the torso origin, the launch's estimate, kept the torso at its height where the legs did
/// not reach.) At most `CATCH_DROP_STEPS + 1` Newton solves, allocation-free.
fn reaching_height(
    g: &Geometry<'_>,
    stance: Side,
    pose: [f64; 3],
    rear_x_m: f64,
    warm: &[f64; LEG_SLOTS],
) -> Option<f64> {
    let knee = slots(stance.other())[1];
    (0..=CATCH_DROP_STEPS)
        .map(|k| pose[1] - CATCH_MAX_DROP_M * f64::from(k) / f64::from(CATCH_DROP_STEPS))
        .find(|&z| {
            g.solve(
                stance,
                [pose[0], z, pose[2]],
                [0.0; 3],
                [rear_x_m, 0.0],
                warm,
            )
            .is_some_and(|(q, _)| q[knee].abs() >= CATCH_MIN_KNEE_RAD)
        })
}
