//! Walk and Stop: the phase τ and its rate from the measured state (and the phase observer),
//! the swing foot's height and the stance switch at touchdown, and the desired outputs y^d(τ),
//! ẏ^d with the launch's and the braking step's blends.

use super::Controller;
use crate::config::PhaseSource;
use crate::control::orbit::add_lean;
use crate::control::speed::LEVER_BLEND_FROM;
use crate::control::tick::ControlState;
use crate::control::transitions::{blend_weight, BRAKE_BLEND_FROM, START_KNEE_BLEND_SPAN};
use crate::slots::{LEG_SLOTS, OUTPUTS};
use model::robot::MAX_DOF;

impl Controller {
    /// The phase observer: replaces the measured τ, τ̇ of `eval` by the observer's estimate
    /// and recomputes the references from it (a no-op when `walk.phase_observer_hz` is 0).
    ///
    /// τ̂̇ = r̂ + 2ω(τ − τ̂), r̂̇ = ω²(τ − τ̂): critically damped at ω = 2π f, so a phase that
    /// grows at a constant rate is tracked without lag, while pitch wobble faster than f is
    /// filtered out of y^d(τ̂) and ẏ^d = y^d'(τ̂) r̂.
    pub(super) fn observe_phase(&mut self, t_s: f64, eval: &mut WalkEval) {
        if self.phase_observer_hz <= 0.0 || !eval.phase.is_finite() {
            return;
        }
        let w = 2.0 * std::f64::consts::PI * self.phase_observer_hz;
        let (mut tau, mut rate) = match self.phase_hat {
            Some((tau, rate, t0)) => {
                let dt = (t_s - t0).clamp(0.0, 0.1);
                // Semi-implicit Euler, substepped so ω·h stays ≤ 0.2 at any tick rate.
                let n = ((w * dt / 0.2).ceil() as usize).clamp(1, 64);
                let h = dt / n as f64;
                let (mut tau, mut rate) = (tau, rate);
                for _ in 0..n {
                    let e = eval.phase - tau;
                    rate += h * w * w * e;
                    tau += h * (rate + 2.0 * w * e);
                }
                (tau, rate)
            }
            None => (eval.phase, eval.phase_rate),
        };
        rate = rate.clamp(-self.max_phase_rate_per_s, self.max_phase_rate_per_s);
        if !tau.is_finite() || !rate.is_finite() {
            (tau, rate) = (eval.phase, eval.phase_rate);
        }
        self.phase_hat = Some((tau, rate, t_s));
        let measured_touchdown = eval.foot_height_m <= self.touchdown_height_m;
        *eval = self.references(tau, rate, eval.foot_height_m);
        eval.touchdown = tau >= self.switch_min_phase && measured_touchdown;
    }

    /// Height of the swing foot above the stance foot at torso pitch `pitch_rad`, m (NaN if the
    /// kinematics fails, which fixed sizes rule out).
    pub(super) fn foot_height_at(&self, pitch_rad: f64, leg_q: &[f64; LEG_SLOTS]) -> f64 {
        self.feet_offset_at(pitch_rad, leg_q)[1]
    }

    /// The swing foot relative to the stance foot at torso pitch `pitch_rad`, [x (+ forward),
    /// z], m (NaN if the kinematics fails, which fixed sizes rule out). At an impact, x is the
    /// step's length.
    pub(super) fn feet_offset_at(&self, pitch_rad: f64, leg_q: &[f64; LEG_SLOTS]) -> [f64; 2] {
        let mut q = self.q_template;
        q[2] = pitch_rad;
        for k in 0..LEG_SLOTS {
            q[self.leg_coord[k]] = leg_q[k];
        }
        let swing = self.stance.other();
        self.model
            .body_poses(&q[..self.dof])
            .map(|st| {
                let a = self
                    .model
                    .frame_position_in(&st, self.legs.side(swing).foot);
                let b = self
                    .model
                    .frame_position_in(&st, self.legs.side(self.stance).foot);
                [a[0] - b[0], a[1] - b[1]]
            })
            .unwrap_or([f64::NAN; 2])
    }

    /// The legs' pitch ([`Self::touchdown_pitch_rad`]) into the estimator, with standard
    /// deviation `sigma_rad`, against its estimate `lag_samples` IMU samples back (the
    /// encoders' sample: `estimator.encoder_lag_samples` at a touchdown), set aside if further
    /// than `gate_rad` from it (0: never; a touchdown's: `estimator.touchdown_gate_rad`,
    /// `PitchEstimator::measure_pitch_gated`).
    pub(super) fn measure_legs_pitch(
        &mut self,
        leg_q: &[f64; LEG_SLOTS],
        sigma_rad: f64,
        lag_samples: usize,
        gate_rad: f64,
    ) {
        let pitch = self.touchdown_pitch_rad(leg_q);
        self.estimator
            .measure_pitch_gated(pitch, sigma_rad, lag_samples, gate_rad);
    }

    /// The torso pitch at which both feet are at the same height for these joint angles (both
    /// on the flat ground at a touchdown), by Newton from the current estimate, rad (NaN if the
    /// feet are too close together in x for the pitch to be observable).
    pub(super) fn touchdown_pitch_rad(&self, leg_q: &[f64; LEG_SLOTS]) -> f64 {
        let mut pitch = self.estimator.pitch_rad();
        for _ in 0..3 {
            let h = self.foot_height_at(pitch, leg_q);
            let eps = 1e-6;
            let slope = (self.foot_height_at(pitch + eps, leg_q) - h) / eps;
            // |dh/dθ| is the horizontal distance between the feet: ≥ 5 cm for a real step.
            if slope.abs().partial_cmp(&0.05) != Some(std::cmp::Ordering::Greater) || !h.is_finite()
            {
                return f64::NAN;
            }
            pitch -= h / slope;
        }
        pitch
    }

    /// Desired outputs, their rates and the feed-forward at phase `phase` and rate `rate`.
    pub(super) fn references(&self, phase: f64, rate: f64, foot_height_m: f64) -> WalkEval {
        let rate = rate.clamp(-self.max_phase_rate_per_s, self.max_phase_rate_per_s);
        // Latency compensation: the command acts a few milliseconds after the sample it was
        // computed from, so the references are taken that much further along the step.
        let s = if phase.is_finite() {
            let ahead = if rate > 0.0 {
                phase + self.reference_lead_s * rate
            } else {
                phase
            };
            ahead.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let inside = (0.0..=1.0).contains(&phase);
        let mut y = [0.0; OUTPUTS];
        let mut dy = [0.0; OUTPUTS];
        for i in 0..OUTPUTS {
            let (v, d) = self.gait.eval(i, s);
            y[i] = v;
            // Outside [0, 1] the reference is held at its end value: no velocity.
            dy[i] = if inside { d * rate } else { 0.0 };
        }
        // The first step after a launch: from the launch's end pose into the gait's outputs.
        if let Some(blend) = self.start_blend {
            for i in 0..OUTPUTS {
                // The swing knee bends sooner (the foot clears the ground), then the rest.
                let span = if i == 3 {
                    START_KNEE_BLEND_SPAN
                } else {
                    blend.span
                };
                let (b, db) = blend_weight(s, blend.from_phase, span, inside, rate);
                y[i] += (1.0 - b) * blend.offset[i];
                dy[i] -= db * blend.offset[i];
            }
        }
        // The braking step: the gait's outputs, stretched over the longer stance-leg swing,
        // blend into the braking touchdown pose over the second part of the step.
        if self.braking {
            let lunge = &self.lunge;
            let (b, db) = blend_weight(s, BRAKE_BLEND_FROM, 1.0 - BRAKE_BLEND_FROM, inside, rate);
            for i in 0..OUTPUTS {
                y[i] += b * lunge.dy_end[i];
                dy[i] += db * lunge.dy_end[i];
            }
        }
        // The step lever (speed control): a longer or shorter step, its touchdown pose blended in
        // over the second part of the step as the braking step's.
        let lever = &self.step_lever;
        if !self.braking && lever.offset_m != 0.0 {
            let (b, db) = blend_weight(s, LEVER_BLEND_FROM, 1.0 - LEVER_BLEND_FROM, inside, rate);
            for i in 0..OUTPUTS {
                y[i] += b * lever.dy_end(i);
                dy[i] += db * lever.dy_end(i);
            }
        }
        // The step lean (speed control): both hips offset alike all through the step.
        if !self.braking && lever.lean_rad != 0.0 {
            lever.add_lean(&mut y);
        }
        let touchdown = phase >= self.switch_min_phase && foot_height_m <= self.touchdown_height_m;
        WalkEval {
            feedforward_nm: self.gait.feedforward(s),
            phase,
            phase_rate: rate,
            y,
            dy,
            foot_height_m,
            touchdown,
        }
    }

    /// The orbit lever (`runtime::control::orbit`): leans the torso (stance and swing hip
    /// together) by the lever's rate-limited lean, toward the planned orbit's momentum about the
    /// stance foot in a Walk step, back to zero otherwise (a Stop, the braking step, and while
    /// the speed control switches library gaits unless `orbit.with_speed_control`).
    pub(super) fn lean(
        &mut self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
        eval: &mut WalkEval,
    ) {
        if !self.orbit.enabled() {
            return;
        }
        // Off while the speed control switches library gaits (unless asked for): measured worse.
        let switching = self.library.is_some() && self.regulator.active();
        let on = self.state == ControlState::Walk
            && !self.braking
            && (!switching || self.orbit.with_speed_control);
        let sigma = if on {
            let (q, dq) = self.measured_state(leg_q, leg_dq);
            self.geometry()
                .pinned_momentum(self.stance, &q, &dq)
                .map_or(f64::NAN, |(sigma, _)| sigma)
        } else {
            f64::NAN
        };
        // The lean's rate is not fed to ẏ^d: it is the derivative of a filtered noisy error,
        // and through the hips' damping it chattered them (measured: false impacts).
        let (lean, _rate) = self.orbit.update(t_s, eval.phase, sigma, self.stance, on);
        add_lean(&mut eval.y, self.orbit.sign, lean);
    }

    /// The model's coordinates and rates as measured: the estimated torso pitch and its rate,
    /// the legs' joints, the rest from the template (allocation-free: arrays by value).
    fn measured_state(
        &self,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
    ) -> ([f64; MAX_DOF], [f64; MAX_DOF]) {
        let mut q = self.q_template;
        let mut dq = [0.0; MAX_DOF];
        q[2] = self.estimator.pitch_rad();
        dq[2] = self.estimator.pitch_rate_rad_s();
        for k in 0..LEG_SLOTS {
            q[self.leg_coord[k]] = leg_q[k];
            dq[self.leg_coord[k]] = leg_dq[k];
        }
        (q, dq)
    }

    /// Phase, desired outputs and the touchdown condition for the current stance leg.
    pub(super) fn walk_references(
        &self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
    ) -> WalkEval {
        let dof = self.dof;
        let (q, dq) = self.measured_state(leg_q, leg_dq);
        let swing = self.stance.other();
        // Sizes are fixed at construction, so these calls cannot fail; NaN marks "unknown".
        let foot_height_m = self
            .model
            .body_poses(&q[..dof])
            .map(|st| {
                let zs = self
                    .model
                    .frame_position_in(&st, self.legs.side(swing).foot)[1];
                let zf = self
                    .model
                    .frame_position_in(&st, self.legs.side(self.stance).foot)[1];
                zs - zf
            })
            .unwrap_or(f64::NAN);
        let (phase, rate) = match self.phase_source {
            PhaseSource::StateBased => {
                // The braking step ends at its own, larger stance-leg angle; a step of the lever
                // at its own too.
                let theta_end = if self.braking {
                    self.lunge.theta_rad
                } else {
                    self.gait.theta_minus_rad + self.step_lever.theta_offset_rad()
                };
                let span = theta_end - self.gait.theta_plus_rad;
                let (theta, theta_rate) = self
                    .model
                    .stance_leg_angle_rate(&q[..dof], &dq[..dof], &self.legs, self.stance)
                    .unwrap_or((f64::NAN, 0.0));
                (
                    model::phase::state_phase(theta, self.gait.theta_plus_rad, theta_end),
                    theta_rate / span,
                )
            }
            PhaseSource::TimeBased => (
                model::phase::time_phase(t_s - self.step_start_t_s, self.gait.step_duration_s),
                1.0 / self.gait.step_duration_s,
            ),
        };
        self.references(phase, rate, foot_height_m)
    }
}

/// One walking tick's evaluation: phase, desired outputs and touchdown.
#[derive(Clone, Copy, Debug)]
pub(super) struct WalkEval {
    /// The plan's torque per output at this phase, N·m.
    pub(super) feedforward_nm: [f64; OUTPUTS],
    pub(super) phase: f64,
    pub(super) phase_rate: f64,
    pub(super) y: [f64; OUTPUTS],
    pub(super) dy: [f64; OUTPUTS],
    pub(super) foot_height_m: f64,
    pub(super) touchdown: bool,
}
