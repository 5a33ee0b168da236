//! The joint commands of each driven state: PD on the desired outputs with the plan's
//! feed-forward (Walk, Stop), the held joints, the Stand pose, and the launch in double support.

use super::walk::WalkEval;
use super::Controller;
use crate::control::double_support::{self, Geometry};
use crate::control::gait_table::side_index;
use crate::control::orbit_table::OrbitTable;
use crate::control::recovery::CATCH_SIGMA_MARGIN;
use crate::control::tick::{CommandMode, JointCommand};
use crate::control::transitions::{
    Launch, LaunchTiming, LAUNCH_BEHIND_M, LAUNCH_MAX_DROP_M, LAUNCH_PASS_MARGIN,
    LAUNCH_POSE_KI_PER_S, LAUNCH_POSE_KP, LAUNCH_REACH_FRACTION, LAUNCH_SPEED_MPS,
};
use crate::estimator::GRAVITY_MPS2;
use crate::slots::{LEG_SLOTS, OUTPUTS, SLOTS};

impl Controller {
    /// Walk and Stop: PD on the desired outputs (relabeled to the stance leg's slots) with the
    /// plan's feed-forward; the held joints at their positions.
    pub(super) fn walk_commands(&self, eval: &WalkEval, commands: &mut [JointCommand; SLOTS]) {
        let stance = side_index(self.stance);
        for i in 0..OUTPUTS {
            let slot = self.gait.out_slot[stance][i];
            let ff = self.feedforward_nm[i] + self.plan_feedforward_scale * eval.feedforward_nm[i];
            commands[slot] = self.pd(
                slot,
                self.to_motor(slot, eval.y[i]),
                self.layout.motor_rate_rad_s(slot, eval.dy[i]),
                self.layout.motor_torque_nm(slot, ff),
            );
        }
        self.hold_commands(commands);
    }

    pub(super) fn hold_commands(&self, commands: &mut [JointCommand; SLOTS]) {
        for (slot, command) in commands.iter_mut().enumerate().skip(LEG_SLOTS) {
            *command = self.pd(slot, self.layout.held_center_rad[slot], 0.0, 0.0);
        }
    }

    /// Stand: after a Stop, the joint angles of the braking step's landing with the gravity
    /// torques of that pose fed forward ([`Self::stand_gravity_torques`]); otherwise the gait's
    /// first pose.
    pub(super) fn stand_commands(&self, commands: &mut [JointCommand; SLOTS]) {
        match self.stand_hold {
            Some(leg_q) => {
                for (k, &q) in leg_q.iter().enumerate() {
                    let ff = self.layout.motor_torque_nm(k, self.stand_ff_nm[k]);
                    commands[k] = self.pd(k, self.to_motor(k, q), 0.0, ff);
                }
                self.hold_commands(commands);
            }
            None => {
                let pose = self.stand_pose(self.stance);
                for (slot, &q) in pose.iter().enumerate() {
                    commands[slot] = self.pd(slot, q, 0.0, 0.0);
                }
            }
        }
    }

    /// The leg torques that hold the measured double-support pose against gravity with the
    /// smallest contact forces (both feet loaded; `Geometry::gravity_torques`), N·m model side;
    /// zero if the kinematics fail. Called once, when Stand after a Stop begins.
    pub(super) fn stand_gravity_torques(
        &self,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
    ) -> [f64; LEG_SLOTS] {
        let g = self.geometry();
        let pitch = self.estimator.pitch_rad();
        let rate = self.estimator.pitch_rate_rad_s();
        g.measure(self.stance, pitch, rate, leg_q, leg_dq)
            .and_then(|m| g.gravity_torques(self.stance, m.pose, leg_q))
            .unwrap_or([0.0; LEG_SLOTS])
    }

    /// The kinematics of double support on this robot.
    pub(super) fn geometry(&self) -> Geometry<'_> {
        Geometry {
            model: &self.model,
            legs: &self.legs,
            dof: self.dof,
            q_template: &self.q_template,
            leg_coord: &self.leg_coord,
        }
    }

    /// Starts a launch from the measured double-support pose at rest: the torso moves forward
    /// to [`LAUNCH_BEHIND_M`] behind the stance foot (less far if the rear leg would make it drop
    /// more than [`LAUNCH_MAX_DROP_M`]), no higher than keeps the rear leg within
    /// [`LAUNCH_REACH_FRACTION`] of its reach. From the gait's own stance (Stand after Ramp) it
    /// arrives at the planned orbit's angular momentum about the stance foot (`orbit_table`) and
    /// hands over as soon as the measured momentum reaches it ([`Self::launch_on_orbit`]); after
    /// a Stop at [`LAUNCH_SPEED_MPS`] (more if it ends further back: enough to pass over the
    /// stance foot, [`LAUNCH_PASS_MARGIN`]), handing over at the end. `timing`: the quintic's
    /// duration, the earliest hand-over onto the orbit and whether the torso starts at rest
    /// (from Stand: `FROM_STAND`; a relaunch after a stall is quicker and starts from the
    /// measured torso rate, `recovery`).
    pub(super) fn begin_launch(
        &mut self,
        t_s: f64,
        timing: LaunchTiming,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
    ) {
        let measured = self.geometry().measure(
            self.stance,
            self.estimator.pitch_rad(),
            self.estimator.pitch_rate_rad_s(),
            leg_q,
            leg_dq,
        );
        self.launch = measured.map(|m| {
            let reach = LAUNCH_REACH_FRACTION * self.leg_reach_m;
            // How far forward the rear leg lets the torso go without dropping more than
            // LAUNCH_MAX_DROP_M: after a Stop the feet stand 0.34 m apart with the torso midway;
            // carried to LAUNCH_BEHIND_M behind the front foot it had to drop 5 cm, and the
            // stance knee, bent 0.9 rad, could not carry the robot once the rear foot lifted
            // (torque saturation; `runtime/tests/restart_sim.rs`).
            let z_floor = m.pose[1] - LAUNCH_MAX_DROP_M;
            let reach_dx = (reach * reach - z_floor * z_floor).max(0.0).sqrt();
            let x = (-LAUNCH_BEHIND_M)
                .min(m.other_foot_xz_m[0] + reach_dx)
                .max(m.pose[0]);
            let dx = x - m.other_foot_xz_m[0];
            let z = m.pose[1].min((reach * reach - dx * dx).max(0.0).sqrt());
            // Further behind the stance foot, more speed carries the torso over it (an inverted
            // pendulum of height z passes over from x behind at speed > |x|·√(g/z)).
            let pass_mps = LAUNCH_PASS_MARGIN * (-x).max(0.0) * (GRAVITY_MPS2 / z).sqrt();
            let to = [x, z, m.pose[2]];
            // From the gait's own stance (after Ramp) the launch hands over onto the planned
            // orbit; after a Stop (the rear foot at the braking step's length, the rear leg at
            // its reach) it keeps the fixed law (module docs of `double_support`).
            let orbit = if self.stand_hold.is_none() {
                OrbitTable::of(&self.geometry(), &self.gait)
            } else {
                None
            };
            let speed_mps = orbit
                .and_then(|table| self.orbit_speed(&table, to, m.other_foot_xz_m, leg_q))
                .unwrap_or(LAUNCH_SPEED_MPS.max(pass_mps));
            Launch {
                start_t_s: t_s,
                timing,
                from: m.pose,
                from_rate: if timing.from_motion { m.rate } else { [0.0; 3] },
                to,
                orbit,
                speed_mps,
                other_foot_xz_m: m.other_foot_xz_m,
                leg_q: *leg_q,
                correction: [0.0; 3],
                last_t_s: t_s,
                catch: None,
            }
        });
    }

    /// The forward torso speed at which the launch's end pose `to` (the rear foot at
    /// `other_foot_xz_m`) has the planned orbit's angular momentum about the stance foot at its
    /// stance-leg angle, σ*(θ) of `table`, m/s. `None` if the kinematics fail.
    fn orbit_speed(
        &self,
        table: &OrbitTable,
        to: [f64; 3],
        other_foot_xz_m: [f64; 2],
        warm: &[f64; LEG_SLOTS],
    ) -> Option<f64> {
        let g = self.geometry();
        let unit = [1.0, 0.0, 0.0];
        let (q, dq) = g.solve(self.stance, to, unit, other_foot_xz_m, warm)?;
        let sigma_per_mps = g.angular_momentum(self.stance, to, unit, &q, &dq)?;
        let theta = g.stance_leg_angle(self.stance, to, &q)?;
        let v = table.sigma_at(theta) / sigma_per_mps;
        (v.is_finite() && v > 0.0).then_some(v)
    }

    /// Whether the launch has reached the planned orbit: the measured angular momentum about
    /// the stance foot at least σ*(θ) at the measured stance-leg angle (`orbit_table`), once
    /// its earliest hand-over time (`LAUNCH_ORBIT_EARLIEST_S` from Stand) has passed. Always
    /// false without a table.
    pub(super) fn launch_on_orbit(
        &self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
    ) -> bool {
        let Some(launch) = self.launch else {
            return false;
        };
        let Some(table) = launch.orbit else {
            return false;
        };
        if t_s - launch.start_t_s < launch.timing.earliest_s {
            return false;
        }
        let g = self.geometry();
        let pitch = self.estimator.pitch_rad();
        let pitch_rate = self.estimator.pitch_rate_rad_s();
        let Some(m) = g.measure(self.stance, pitch, pitch_rate, leg_q, leg_dq) else {
            return false;
        };
        // A catch hands over only once it carries the torso forward.
        if launch
            .catch
            .is_some_and(|c| c.at(t_s - launch.start_t_s).1 <= 0.0 || m.rate[0] <= 0.0)
        {
            return false;
        }
        let sigma = g.angular_momentum(self.stance, m.pose, m.rate, leg_q, leg_dq);
        let theta = g.stance_leg_angle(self.stance, m.pose, leg_q);
        match (sigma, theta) {
            (Some(s), Some(th)) => {
                // (a catch with a margin: measured, `recovery`)
                let margin = launch.catch.map_or(1.0, |_| CATCH_SIGMA_MARGIN);
                s >= margin * table.sigma_at(th)
            }
            _ => false,
        }
    }

    /// The launch's joint targets at `t_s`: both feet held, the torso on its quintic (pitch
    /// and height held), gravity fed forward.
    pub(super) fn launch_commands(
        &mut self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
        commands: &mut [JointCommand; SLOTS],
    ) {
        let Some(mut launch) = self.launch else {
            return;
        };
        let dt = t_s - launch.start_t_s;
        let mut pose = [0.0; 3];
        let mut rate = [0.0; 3];
        let end_rate = [launch.speed_mps, 0.0, 0.0];
        // A catch: the torso on its pendulum, lowered if the rear foot needs it; only its
        // pitch on the quintic.
        let quintic_from = if let Some(c) = launch.catch {
            (pose[0], rate[0]) = c.at(dt);
            (pose[1], rate[1]) = c.height(dt);
            2
        } else {
            0
        };
        for k in quintic_from..3 {
            (pose[k], rate[k]) = double_support::quintic(
                launch.from[k],
                launch.from_rate[k],
                launch.to[k],
                end_rate[k],
                launch.timing.duration_s,
                dt,
            );
        }
        let geometry = self.geometry();
        // Pose feedback (PI): the joints' compliance lets the torso sag off its plan (4° of
        // pitch over the launch without it); the joint targets aim past the plan by the
        // error. The proportional gain stays below 1: stable even if the joints followed their
        // targets within a tick.
        let h = (t_s - launch.last_t_s).clamp(0.0, 0.1);
        launch.last_t_s = t_s;
        let pitch = self.estimator.pitch_rad();
        let pitch_rate = self.estimator.pitch_rate_rad_s();
        let mut error = [0.0; 3];
        if let Some(m) = geometry.measure(self.stance, pitch, pitch_rate, leg_q, leg_dq) {
            for k in 0..3 {
                error[k] = pose[k] - m.pose[k];
                launch.correction[k] += LAUNCH_POSE_KI_PER_S * h * error[k];
            }
        }
        let mut pose_cmd = pose;
        for k in 0..3 {
            pose_cmd[k] += launch.correction[k] + error[k] * LAUNCH_POSE_KP;
        }
        let solved = geometry.solve(
            self.stance,
            pose_cmd,
            rate,
            launch.other_foot_xz_m,
            &launch.leg_q,
        );
        // Out of reach (not on a launch within LAUNCH_REACH_FRACTION): hold the last solution.
        let (q_des, dq_des) = solved.unwrap_or((launch.leg_q, [0.0; LEG_SLOTS]));
        let ff = geometry
            .gravity_torques(self.stance, pose, &q_des)
            .unwrap_or([0.0; LEG_SLOTS]);
        launch.leg_q = q_des;
        self.launch = Some(launch);
        for k in 0..LEG_SLOTS {
            commands[k] = self.pd(
                k,
                self.to_motor(k, q_des[k]),
                self.layout.motor_rate_rad_s(k, dq_des[k]),
                self.layout.motor_torque_nm(k, ff[k]),
            );
        }
        self.hold_commands(commands);
    }

    /// PD command for a slot with the slot's gains (leg gains, joint side, scaled to the motor
    /// side by the calibration's gear ratio; or held gains), times the gains ramp's factor.
    /// `q_des`, `dq_des` and `tau_ff` are motor side.
    pub(super) fn pd(&self, slot: usize, q_des: f64, dq_des: f64, tau_ff: f64) -> JointCommand {
        let (kp, kd) = if slot < LEG_SLOTS {
            (self.kp[slot], self.kd[slot])
        } else {
            (self.layout.held_kp[slot], self.layout.held_kd[slot])
        };
        let scale = self.gain_scale * self.layout.gain_factor(slot);
        let (kp, kd) = (kp * scale, kd * scale);
        JointCommand {
            mode: CommandMode::Pd,
            q_des_rad: q_des,
            dq_des_rad_s: dq_des,
            kp_nm_per_rad: kp,
            kd_nm_s_per_rad: kd,
            tau_ff_nm: tau_ff,
        }
    }
}
