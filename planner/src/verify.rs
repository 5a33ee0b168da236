//! Independent verification of a gait, not by the optimizer: the closed-loop hybrid system is
//! simulated with the paper's input–output linearizing controller
//! `u = −A⁻¹ (L_f² y + 2ε L_f y + ε² y)`, impacts are located by bisection on z_nsf = 0 and mapped
//! with the model's impact map and relabeling, and the periodic orbit is found by Newton on the
//! Poincaré map P (post-impact state → next post-impact state).
//!
//! - y = y^a − y^d(τ(q), α): the gait's outputs and Bézier coefficients, τ the state-based phase.
//! - ÿ is affine in u under the pinned-stance dynamics: ÿ = L_f² y + A u; both are computed
//!   exactly from the model's constrained dynamics (one solve with u = 0 and one per actuator).
//! - Integration: classic RK4 with a fixed step (default 1 ms); the impact time is bisected to
//!   1e-12 s inside the step that crosses the guard.
//! - The Jacobian of P is taken by central finite differences of the simulated map: this is a
//!   check of the optimizer's result, not part of any solve loop.
//! - Stability: every eigenvalue of DP at the fixed point has |λ| < 1.
//! - Consistency: the orbit is the planned one, its joints within [`CONSISTENCY_TOLERANCE_RAD`]
//!   of the planned post-impact state and its step duration within [`STEP_DURATION_TOLERANCE`] of
//!   the planned one; Newton is stopped when it takes the joints more than
//!   [`NEWTON_RADIUS_RAD`] from the plan, and a simulated step is stopped as a fall when a
//!   reduced coordinate passes half a turn. The report also gives one closed-loop step from the
//!   planned state (the planned step as the closed loop walks it) and
//!   [`VerifyReport::failures`] says what fails, with the figure and its limit.

use crate::biped::PlanarBiped;
use crate::{PlannerError, Result};
use model::bezier;
use model::gait::{GaitFile, PhaseDefinition};
use model::PlanarModel;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::fmt;

/// Largest joint difference between the closed-loop fixed point and the planned post-impact
/// state for the gait to count as the planned one, rad (about 3°: collocation error with N = 20
/// is near 1e-3 rad; a different orbit is off by tenths of a radian).
pub const CONSISTENCY_TOLERANCE_RAD: f64 = 0.05;

/// Largest relative difference between the step duration of the closed-loop fixed point and the
/// planned one for the gait to count as the planned one. The fixed point's speed is sensitive:
/// the plan's collocation error, amplified by 1/(1 − |λ|max), moves it, and ADAM's N = 20 plan
/// (|λ|max 0.86) steps in 0.991 s at its fixed point against 0.900 s planned (10 %; N = 30: 3 %,
/// N = 40: 1 %); the co-designed ADAM 4 %, the five-link walker 0.6 %. 20 % leaves twice
/// ADAM's margin, and rejects a gait whose joints match but whose pace does not (a 0.005 rad
/// shift of the swing hip's Bézier coefficients: 0.497 s).
pub const STEP_DURATION_TOLERANCE: f64 = 0.2;

/// How far (joint angles, rad) Newton on the Poincaré map may take its iterate from the planned
/// post-impact state before the check gives up: ten times [`CONSISTENCY_TOLERANCE_RAD`], so an
/// orbit found there would fail the consistency check anyway, and the simulation is not asked
/// to step from states where the robot has long fallen (joints hundreds of radians off).
pub const NEWTON_RADIUS_RAD: f64 = 0.5;

/// Options of the verification.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VerifyOptions {
    /// ε of the output controller, 1/s.
    pub epsilon_per_s: f64,
    /// RK4 step, s.
    pub dt_s: f64,
    /// Newton iterations at most.
    pub max_newton_iterations: usize,
    /// Required fixed-point residual (max norm).
    pub fixed_point_tolerance: f64,
}

impl Default for VerifyOptions {
    fn default() -> Self {
        Self {
            epsilon_per_s: 10.0,
            dt_s: 1e-3,
            max_newton_iterations: 8,
            fixed_point_tolerance: 1e-6,
        }
    }
}

/// What the verification found.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyReport {
    /// Residual |P(x*) − x*|∞ at the fixed point.
    pub fixed_point_residual: f64,
    /// Newton iterations used.
    pub newton_iterations: usize,
    /// Eigenvalues of DP at the fixed point, (re, im), sorted by decreasing modulus.
    pub eigenvalues: Vec<(f64, f64)>,
    /// Largest |λ|.
    pub spectral_radius: f64,
    /// Largest joint difference between the fixed point and the gait's planned x⁺, rad.
    pub max_joint_difference_rad: f64,
    /// Largest |y| (joint minus desired output) along the simulated step, rad.
    pub max_output_error_rad: f64,
    /// |P(x_plan) − x_plan|∞: how periodic the planned post-impact state is in closed loop.
    pub planned_state_residual: f64,
    /// Simulated step duration at the fixed point, s (planned in the gait file).
    pub step_duration_s: f64,
    /// Simulated step length, m.
    pub step_length_m: f64,
    /// The step the gait file plans.
    pub planned_step: StepFigures,
    /// One closed-loop step from the planned x⁺: the planned step as the closed loop walks it.
    pub step_from_plan: StepFigures,
}

/// How long and how far one step is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepFigures {
    /// Step duration, s.
    pub duration_s: f64,
    /// Step length, m.
    pub length_m: f64,
}

impl VerifyReport {
    /// Stable and consistent: the fixed point exists to `tol`, every |λ| < 1, and the orbit is
    /// the planned one (joints within [`CONSISTENCY_TOLERANCE_RAD`] of the planned x⁺, steps
    /// within [`STEP_DURATION_TOLERANCE`] of the planned duration).
    pub fn passed(&self, tol: f64) -> bool {
        self.failures(tol).is_empty()
    }

    /// What fails the check, one sentence each with the figure and its limit (empty: passed).
    pub fn failures(&self, tol: f64) -> Vec<String> {
        let mut failed = Vec::new();
        if !below(self.fixed_point_residual, tol) {
            failed.push(format!(
                "no periodic orbit: fixed-point residual {:.2e} (limit {tol:.0e})",
                self.fixed_point_residual
            ));
        }
        if !below(self.spectral_radius, 1.0) {
            failed.push(format!("unstable: |λ|max {:.4} ≥ 1", self.spectral_radius));
        }
        if !below(self.max_joint_difference_rad, CONSISTENCY_TOLERANCE_RAD) {
            failed.push(format!(
                "not the planned orbit: its joints are {:.4} rad from the planned x⁺ (limit \
                 {CONSISTENCY_TOLERANCE_RAD} rad)",
                self.max_joint_difference_rad
            ));
        }
        let planned_s = self.planned_step.duration_s;
        let off = (self.step_duration_s - planned_s).abs() / planned_s;
        if !below(off, STEP_DURATION_TOLERANCE) {
            failed.push(format!(
                "not the planned pace: the orbit steps in {:.4} s, the plan in {planned_s:.4} s \
                 ({:.0} % off, limit {:.0} %)",
                self.step_duration_s,
                100.0 * off,
                100.0 * STEP_DURATION_TOLERANCE
            ));
        }
        failed
    }
}

/// Largest difference of the joint angles (reduced coordinates 1..nq: the torso pitch, 0, is
/// left out) between two reduced states, rad; NaN if either has a NaN there, so that the checks
/// made with [`below`] fail on it (`f64::max` would drop the NaN).
fn joint_distance(x: &[f64], planned: &[f64], nq: usize) -> f64 {
    (1..nq)
        .map(|i| (x[i] - planned[i]).abs())
        .fold(
            0.0,
            |worst, d| if d.is_nan() || d > worst { d } else { worst },
        )
}

/// `value < limit`, false for NaN: a check that cannot be computed fails.
fn below(value: f64, limit: f64) -> bool {
    value < limit
}

impl fmt::Display for VerifyReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "fixed-point residual      {:.3e} ({} Newton iterations)",
            self.fixed_point_residual, self.newton_iterations
        )?;
        writeln!(f, "spectral radius |λ|max    {:.6}", self.spectral_radius)?;
        let eig: Vec<String> = self
            .eigenvalues
            .iter()
            .map(|(re, im)| {
                if im.abs() > 1e-12 {
                    format!("{re:.4}{im:+.4}i")
                } else {
                    format!("{re:.4}")
                }
            })
            .collect();
        writeln!(f, "eigenvalues of DP         {}", eig.join(", "))?;
        writeln!(
            f,
            "max joint diff vs plan    {:.3e} rad",
            self.max_joint_difference_rad
        )?;
        writeln!(
            f,
            "max output error |y|      {:.3e} rad",
            self.max_output_error_rad
        )?;
        writeln!(
            f,
            "simulated step            {:.4} m in {:.4} s",
            self.step_length_m, self.step_duration_s
        )?;
        writeln!(
            f,
            "step from the planned x⁺  {:.4} m in {:.4} s (planned {:.4} m in {:.4} s), |P(x⁺) − x⁺| {:.3e}",
            self.step_from_plan.length_m,
            self.step_from_plan.duration_s,
            self.planned_step.length_m,
            self.planned_step.duration_s,
            self.planned_state_residual
        )
    }
}

/// The feedback law that enforces the virtual constraints in the closed loop.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Law {
    /// The paper's input–output linearizing controller with ε of [`VerifyOptions`].
    #[default]
    IoLinearizing,
    /// What the runtime does: per-joint PD on each output with an optional feed-forward torque
    /// by phase, u_o = −kp y_o − kd ẏ_o + u_ff,o(τ).
    JointPd {
        /// Proportional gain, N·m/rad.
        kp_nm_per_rad: f64,
        /// Derivative gain, N·m·s/rad.
        kd_nm_s_per_rad: f64,
        /// Feed-forward torque per output (columns) at increasing phases τ, interpolated
        /// linearly and held outside; empty: none.
        feedforward: Vec<(f64, Vec<f64>)>,
        /// Age of the references when they act, s: y^d, ẏ^d and the feed-forward are taken at
        /// τ − τ̇·delay (first order), as on a bus that applies a command some milliseconds
        /// after the sample it was computed from. 0: none.
        reference_delay_s: f64,
    },
}

/// The closed-loop hybrid system of one gait.
pub struct ClosedLoop {
    /// The robot in pinned-stance coordinates.
    pub biped: PlanarBiped,
    alpha: Vec<Vec<f64>>,
    theta_plus: f64,
    theta_minus: f64,
    options: VerifyOptions,
    law: Law,
}

/// One simulated step.
#[derive(Clone, Debug)]
pub struct Step {
    /// Post-impact reduced state (q_r, q̇_r) after the relabeling.
    pub next: DVector<f64>,
    /// Time to impact, s.
    pub duration_s: f64,
    /// Swing-foot x at impact, m.
    pub length_m: f64,
    /// Largest |y| along the step, rad.
    pub max_output_error_rad: f64,
    /// Swing-foot height at the located impact, m.
    pub impact_height_m: f64,
}

/// The outputs y, ẏ and ÿ, one entry per output.
type Outputs = (Vec<f64>, Vec<f64>, Vec<f64>);

impl ClosedLoop {
    /// Builds the closed loop of `gait` on `model`.
    pub fn new(model: &PlanarModel, gait: &GaitFile, options: VerifyOptions) -> Result<Self> {
        let PhaseDefinition::StateBased {
            theta_plus_rad,
            theta_minus_rad,
        } = gait.phase
        else {
            return Err(PlannerError::Robot {
                robot: model.name.clone(),
                reason: "verification needs a state-based phase".into(),
            });
        };
        let biped = PlanarBiped::new(model.clone(), gait.stance_leg, &[])?;
        Ok(Self {
            biped,
            alpha: gait.bezier.alpha.clone(),
            theta_plus: theta_plus_rad,
            theta_minus: theta_minus_rad,
            options,
            law: Law::IoLinearizing,
        })
    }

    /// The same closed loop under another feedback law.
    pub fn with_law(mut self, law: Law) -> Self {
        self.law = law;
        self
    }

    /// Phase τ of a full configuration.
    fn phase(&self, qr: &[f64], dqr: &[f64]) -> Result<(f64, f64)> {
        let bp = &self.biped;
        let nq = self.nq();
        let [q, dq, ddq] = bp.full_state(qr, dqr, &vec![0.0; nq])?;
        let th = bp
            .model
            .stance_leg_angle_derivatives(&q, &dq, &ddq, &bp.legs, bp.stance)?;
        let span = self.theta_minus - self.theta_plus;
        Ok(((th.theta - self.theta_plus) / span, th.rate / span))
    }

    /// The torque of the current law, per output, along one step from `x0`: (τ, u) at every
    /// integration step, for a feed-forward table.
    pub fn torque_profile(&self, x0: &[f64]) -> Result<Vec<(f64, Vec<f64>)>> {
        let nq = self.nq();
        let dt = self.options.dt_s;
        let mut x = x0.to_vec();
        let mut table = Vec::new();
        let mut t = 0.0;
        while t < 5.0 {
            let (f, u) = self.field(&x)?;
            let (tau, _) = self.phase(&x[..nq], &x[nq..])?;
            let by_output: Vec<f64> = self
                .biped
                .output_coords
                .iter()
                .map(|&c| {
                    self.biped
                        .actuators
                        .iter()
                        .position(|&a| a == c)
                        .map_or(0.0, |k| u[k])
                })
                .collect();
            if table
                .last()
                .is_none_or(|(t0, _): &(f64, Vec<f64>)| tau > *t0)
            {
                table.push((tau, by_output));
            }
            let next = self.rk4_from(&x, &f, dt)?;
            if t > 0.1 && self.swing_foot(&next)?[1] < 0.0 {
                break;
            }
            x = next;
            t += dt;
        }
        Ok(table)
    }

    fn nq(&self) -> usize {
        self.biped.nq()
    }

    /// Joint accelerations q̈_r for torques u (pinned stance, design rigid).
    fn accelerations(&self, q: &[f64], dq: &[f64], u: &[f64]) -> Result<Vec<f64>> {
        Ok(self.accelerations_for(q, dq, &[u])?.remove(0))
    }

    /// [`Self::accelerations`] for several torque vectors at one state.
    fn accelerations_for(&self, q: &[f64], dq: &[f64], inputs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        let bp = &self.biped;
        let stance_foot = bp.legs.side(bp.stance).foot;
        let all = bp
            .model
            .constrained_accelerations(q, dq, inputs, &[stance_foot])?;
        Ok(all
            .iter()
            .map(|ddq| bp.reduced.iter().map(|&c| ddq[c]).collect())
            .collect())
    }

    /// Outputs y, ẏ and ÿ for reduced accelerations `ddqr`.
    fn outputs(&self, qr: &[f64], dqr: &[f64], ddqr: &[f64]) -> Result<Outputs> {
        Ok(self.outputs_for(qr, dqr, &[ddqr])?.remove(0))
    }

    /// [`Self::outputs`] for several reduced accelerations at one state, from one pass of
    /// the kinematics for the full state and one for the stance-leg angle (each result bit
    /// for bit its own `outputs`).
    fn outputs_for(&self, qr: &[f64], dqr: &[f64], ddqrs: &[&[f64]]) -> Result<Vec<Outputs>> {
        let bp = &self.biped;
        let ([q, dq], ddqs) = bp.full_states(qr, dqr, ddqrs)?;
        let mut st = model::kinematics::BodyStates::zeroed();
        bp.model.body_states_into(&q, &dq, &mut st)?;
        let span = self.theta_minus - self.theta_plus;
        let m = self.alpha.len();
        ddqrs
            .iter()
            .zip(&ddqs)
            .map(|(ddqr, ddq)| {
                let th = bp
                    .model
                    .stance_leg_angle_derivatives_in(&st, ddq, &bp.legs, bp.stance)?;
                let tau = (th.theta - self.theta_plus) / span;
                let (td, tdd) = (th.rate / span, th.accel / span);
                let (mut y, mut dy, mut ddy) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
                for o in 0..m {
                    let (b0, b1, b2) = bezier::eval_all(&self.alpha[o], tau);
                    let j = bp.output_coords[o];
                    y[o] = qr[j] - b0;
                    dy[o] = dqr[j] - b1 * td;
                    ddy[o] = ddqr[j] - b2 * td * td - b1 * tdd;
                }
                Ok((y, dy, ddy))
            })
            .collect()
    }

    /// The closed-loop vector field: (q̇_r, q̈_r) and the torque used.
    fn field(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        let nq = self.nq();
        let nu = self.biped.nu();
        let (qr, dqr) = (&x[..nq], &x[nq..]);
        let [q, dq, _] = self.biped.full_state(qr, dqr, &vec![0.0; nq])?;
        if let Law::JointPd {
            kp_nm_per_rad,
            kd_nm_s_per_rad,
            feedforward,
            reference_delay_s,
        } = &self.law
        {
            let (mut y, mut dy, _) = self.outputs(qr, dqr, &vec![0.0; nq])?;
            let (mut tau, tau_rate) = self.phase(qr, dqr)?;
            if *reference_delay_s > 0.0 {
                tau -= tau_rate * reference_delay_s;
                for (o, (yo, dyo)) in y.iter_mut().zip(dy.iter_mut()).enumerate() {
                    let (b0, b1, _) = bezier::eval_all(&self.alpha[o], tau);
                    let j = self.biped.output_coords[o];
                    *yo = qr[j] - b0;
                    *dyo = dqr[j] - b1 * tau_rate;
                }
            }
            let mut ff = vec![0.0; y.len()];
            let knots: Vec<f64> = feedforward.iter().map(|(t, _)| *t).collect();
            let rows: Vec<&[f64]> = feedforward.iter().map(|(_, u)| u.as_slice()).collect();
            model::gait::interpolate(&knots, &rows, tau, &mut ff);
            let mut u = vec![0.0; nu];
            for (k, &a) in self.biped.actuators.iter().enumerate() {
                if let Some(o) = self.biped.output_coords.iter().position(|&c| c == a) {
                    u[k] = -kp_nm_per_rad * y[o] - kd_nm_s_per_rad * dy[o] + ff[o];
                }
            }
            let ddq = self.accelerations(&q, &dq, &u)?;
            let mut f = dqr.to_vec();
            f.extend(ddq);
            return Ok((f, u));
        }
        // The accelerations for u = 0 and for each unit torque, from one dynamics pass and one
        // elimination (each bit for bit its own constrained-dynamics solve).
        let mut inputs = vec![vec![0.0; nu]; nu + 1];
        for k in 0..nu {
            inputs[k + 1][k] = 1.0;
        }
        let inputs: Vec<&[f64]> = inputs.iter().map(Vec::as_slice).collect();
        let all = self.accelerations_for(&q, &dq, &inputs)?;
        let slices: Vec<&[f64]> = all.iter().map(Vec::as_slice).collect();
        let mut outputs = self.outputs_for(qr, dqr, &slices)?.into_iter();
        let (y, dy, ddy0) = outputs.next().unwrap_or_default();
        let mut accelerations = all.into_iter();
        let a0 = accelerations.next().unwrap_or_default();
        let m = y.len();
        let mut big_a = DMatrix::zeros(m, nu);
        let mut cols = Vec::with_capacity(nu);
        for (k, (ak, (_, _, ddyk))) in accelerations.zip(outputs).enumerate() {
            let col: Vec<f64> = ak.iter().zip(&a0).map(|(a, b)| a - b).collect();
            for o in 0..m {
                big_a[(o, k)] = ddyk[o] - ddy0[o];
            }
            cols.push(col);
        }
        let eps = self.options.epsilon_per_s;
        let rhs = DVector::from_iterator(
            m,
            (0..m).map(|o| -(ddy0[o] + 2.0 * eps * dy[o] + eps * eps * y[o])),
        );
        let u = big_a.clone().lu().solve(&rhs).ok_or_else(|| {
            PlannerError::Solver(format!(
                "decoupling matrix A is singular at q = [{}] (reduced coordinates): {big_a}",
                qr.iter()
                    .map(|v| format!("{v:.4}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })?;
        let mut ddq = a0;
        for k in 0..nu {
            for i in 0..nq {
                ddq[i] += cols[k][i] * u[k];
            }
        }
        let mut f = dqr.to_vec();
        f.extend(ddq);
        Ok((f, u.iter().copied().collect()))
    }

    fn rk4(&self, x: &[f64], h: f64) -> Result<Vec<f64>> {
        let k1 = self.field(x)?.0;
        self.rk4_from(x, &k1, h)
    }

    /// [`Self::rk4`] with its first stage `k1` = f(x) already evaluated.
    fn rk4_from(&self, x: &[f64], k1: &[f64], h: f64) -> Result<Vec<f64>> {
        let add = |a: &[f64], k: &[f64], s: f64| -> Vec<f64> {
            a.iter().zip(k).map(|(p, q)| p + s * q).collect()
        };
        let k2 = self.field(&add(x, k1, h / 2.0))?.0;
        let k3 = self.field(&add(x, &k2, h / 2.0))?.0;
        let k4 = self.field(&add(x, &k3, h))?.0;
        Ok((0..x.len())
            .map(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
            .collect())
    }

    fn swing_foot(&self, x: &[f64]) -> Result<[f64; 2]> {
        let nq = self.nq();
        let [q, _, _] = self
            .biped
            .full_state(&x[..nq], &vec![0.0; nq], &vec![0.0; nq])?;
        Ok(self
            .biped
            .model
            .frame_position(&q, self.biped.legs.side(self.biped.swing()).foot)?)
    }

    /// Simulates one step from the post-impact reduced state `x0` to the next post-impact state.
    pub fn step(&self, x0: &[f64]) -> Result<Step> {
        let nq = self.nq();
        let dt = self.options.dt_s;
        let mut x = x0.to_vec();
        let mut t = 0.0;
        let mut max_y = 0.0_f64;
        let max_time = 5.0;
        loop {
            let next = self.rk4(&x, dt)?;
            // A walking robot turns no joint (nor its torso) half a turn within a step: past
            // that it has fallen, and the controller's decoupling matrix soon turns singular.
            if let Some(i) = (0..nq).find(|&i| !below(next[i].abs(), std::f64::consts::PI)) {
                return Err(PlannerError::Solver(format!(
                    "the robot falls {:.3} s into a simulated step: reduced coordinate {i} \
                     (full coordinate {}) reaches {:.2} rad",
                    t + dt,
                    self.biped.reduced[i],
                    next[i]
                )));
            }
            let z_next = self.swing_foot(&next)?[1];
            // The guard counts once the swing foot has left the ground and comes back down.
            if t > 0.1 && z_next < 0.0 {
                let (mut lo, mut hi) = (0.0, dt);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if self.swing_foot(&self.rk4(&x, mid)?)?[1] > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                    if hi - lo < 1e-12 {
                        break;
                    }
                }
                let s = 0.5 * (lo + hi);
                let pre = self.rk4(&x, s)?;
                let foot = self.swing_foot(&pre)?;
                let bp = &self.biped;
                let [q, dq, _] = bp.full_state(&pre[..nq], &pre[nq..], &vec![0.0; nq])?;
                let reset = bp.model.reset_map(&q, &dq, bp.swing())?;
                let mut next = Vec::with_capacity(2 * nq);
                next.extend(bp.reduced.iter().map(|&c| reset.q[c]));
                next.extend(bp.reduced.iter().map(|&c| reset.dq[c]));
                return Ok(Step {
                    next: DVector::from_vec(next),
                    duration_s: t + s,
                    length_m: foot[0],
                    max_output_error_rad: max_y,
                    impact_height_m: foot[1],
                });
            }
            x = next;
            t += dt;
            let (y, _, _) = self.outputs(&x[..nq], &x[nq..], &vec![0.0; nq])?;
            max_y = y.iter().fold(max_y, |m, v| m.max(v.abs()));
            if t > max_time {
                return Err(PlannerError::Solver(format!(
                    "no impact within {max_time} s: the robot does not step"
                )));
            }
        }
    }

    /// The Poincaré map.
    pub fn poincare(&self, x: &[f64]) -> Result<DVector<f64>> {
        Ok(self.step(x)?.next)
    }
}

/// Samples kept in a feed-forward table made by [`feedforward_from_orbit`].
pub const FEEDFORWARD_SAMPLES: usize = 101;

/// The feed-forward table of a gait: the torque of each output's joint along one closed-loop
/// step from the gait's planned post-impact state under the input–output linearizing
/// controller, i.e. the torque that keeps the model on the planned orbit, resampled at
/// [`FEEDFORWARD_SAMPLES`] evenly spaced phases. (The collocation torques at the 2N + 1 points,
/// interpolated linearly, are too coarse: under joint PD the robot loses ~2 % of its speed per
/// step with them; see the `shipped_gait_needs_its_feedforward_under_joint_pd` test.)
pub fn feedforward_from_orbit(
    model: &PlanarModel,
    gait: &GaitFile,
    options: VerifyOptions,
) -> Result<model::gait::FeedforwardTable> {
    let cl = ClosedLoop::new(model, gait, options)?;
    let state = gait
        .initial_state
        .as_ref()
        .ok_or_else(|| PlannerError::Robot {
            robot: model.name.clone(),
            reason: "the gait file has no initial_state to simulate the orbit from".into(),
        })?;
    let bp = &cl.biped;
    let x0: Vec<f64> = bp
        .reduced
        .iter()
        .map(|&c| state.q[c])
        .chain(bp.reduced.iter().map(|&c| state.dq[c]))
        .collect();
    let profile = cl.torque_profile(&x0)?;
    let knots: Vec<f64> = profile.iter().map(|(t, _)| *t).collect();
    let rows: Vec<&[f64]> = profile.iter().map(|(_, u)| u.as_slice()).collect();
    let m = gait.outputs.len();
    let mut table = model::gait::FeedforwardTable {
        phase: Vec::with_capacity(FEEDFORWARD_SAMPLES),
        torque_nm: Vec::with_capacity(FEEDFORWARD_SAMPLES),
    };
    for i in 0..FEEDFORWARD_SAMPLES {
        let tau = i as f64 / (FEEDFORWARD_SAMPLES - 1) as f64;
        let mut row = vec![0.0; m];
        model::gait::interpolate(&knots, &rows, tau, &mut row);
        table.phase.push(tau);
        table.torque_nm.push(row);
    }
    Ok(table)
}

/// Verifies `gait` on `model`: fixed point, eigenvalues, consistency with the plan.
pub fn verify_gait(
    model: &PlanarModel,
    gait: &GaitFile,
    options: VerifyOptions,
) -> Result<VerifyReport> {
    verify_gait_with(model, gait, options, Law::IoLinearizing)
}

/// [`verify_gait`] under another feedback law (e.g. the runtime's joint PD).
pub fn verify_gait_with(
    model: &PlanarModel,
    gait: &GaitFile,
    options: VerifyOptions,
    law: Law,
) -> Result<VerifyReport> {
    let cl = ClosedLoop::new(model, gait, options)?.with_law(law);
    let bp = &cl.biped;
    let nq = bp.nq();
    let state = gait
        .initial_state
        .as_ref()
        .ok_or_else(|| PlannerError::Robot {
            robot: model.name.clone(),
            reason: "the gait file has no initial_state to start the Poincaré map from".into(),
        })?;
    let planned: Vec<f64> = bp
        .reduced
        .iter()
        .map(|&c| state.q[c])
        .chain(bp.reduced.iter().map(|&c| state.dq[c]))
        .collect();
    let mut x = DVector::from_vec(planned.clone());
    let from_plan = cl.step(x.as_slice())?;
    let planned_state_residual = (&from_plan.next - &x).amax();
    let n = 2 * nq;
    let mut iterations = 0;
    let mut residual;
    let h = 1e-6;
    // Central differences of the Poincaré map, one column per state: 2n independent one-step
    // simulations, spread over the rayon pool (each column is computed exactly as it would be
    // sequentially, so the Jacobian does not depend on the schedule).
    let jacobian = |x: &DVector<f64>| -> Result<DMatrix<f64>> {
        let columns = (0..n)
            .into_par_iter()
            .map(|i| {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[i] += h;
                xm[i] -= h;
                Ok((cl.poincare(xp.as_slice())? - cl.poincare(xm.as_slice())?) / (2.0 * h))
            })
            .collect::<Result<Vec<DVector<f64>>>>()?;
        Ok(DMatrix::from_columns(&columns))
    };
    for _ in 0..options.max_newton_iterations {
        let px = cl.poincare(x.as_slice())?;
        let r = &px - &x;
        residual = r.amax();
        if residual < options.fixed_point_tolerance * 1e-2 {
            break;
        }
        let jac = jacobian(&x)?;
        let m = jac - DMatrix::identity(n, n);
        let dx = m
            .lu()
            .solve(&(-r))
            .ok_or_else(|| PlannerError::Solver("DP − I is singular".into()))?;
        x += dx;
        iterations += 1;
        let away = joint_distance(x.as_slice(), &planned, nq);
        if !below(away, NEWTON_RADIUS_RAD) {
            return Err(PlannerError::Solver(format!(
                "no periodic orbit near the planned step: Newton on the Poincaré map took the \
                 joints {away:.3} rad from the planned post-impact state at iteration \
                 {iterations} (more than {NEWTON_RADIUS_RAD} rad; one step from the planned \
                 state misses it by {planned_state_residual:.2e})"
            )));
        }
    }
    let step = cl.step(x.as_slice())?;
    residual = (&step.next - &x).amax();
    let jac = jacobian(&x)?;
    let mut eigenvalues: Vec<(f64, f64)> = jac
        .complex_eigenvalues()
        .iter()
        .map(|c| (c.re, c.im))
        .collect();
    eigenvalues.sort_by(|a, b| b.0.hypot(b.1).total_cmp(&a.0.hypot(a.1)));
    let spectral_radius = eigenvalues.first().map_or(0.0, |e| e.0.hypot(e.1));
    let max_joint_difference_rad = joint_distance(x.as_slice(), &planned, nq);
    Ok(VerifyReport {
        fixed_point_residual: residual,
        newton_iterations: iterations,
        eigenvalues,
        spectral_radius,
        planned_state_residual,
        max_joint_difference_rad,
        max_output_error_rad: step.max_output_error_rad,
        step_duration_s: step.duration_s,
        step_length_m: step.length_m,
        planned_step: StepFigures {
            duration_s: gait.step_duration_s,
            length_m: gait.step_length_m,
        },
        step_from_plan: StepFigures {
            duration_s: from_plan.duration_s,
            length_m: from_plan.length_m,
        },
    })
}

/// Loads a gait file and the robot it names (its URDF path is relative to the gait file's
/// folder), refusing a URDF whose SHA-256 differs from the one recorded in the gait and a gait
/// that does not fit the robot ([`GaitFile::check_against`]).
pub fn load_gait_and_robot(gait_path: &std::path::Path) -> Result<(GaitFile, PlanarModel)> {
    let gait = GaitFile::load_unchecked(gait_path)?;
    let (urdf_path, text) = gait.read_urdf(gait_path)?;
    let hash = model::gait::sha256_hex(&text);
    if hash != gait.robot.sha256 {
        return Err(PlannerError::InvalidField {
            origin: gait_path.display().to_string(),
            field: "robot.sha256".into(),
            value: gait.robot.sha256.clone(),
            reason: format!(
                "{} now hashes to {hash}: the robot changed since the gait was planned",
                urdf_path.display()
            ),
        });
    }
    let urdf_origin = urdf_path.display().to_string();
    let model = PlanarModel::from_urdf_str(&text, &urdf_origin)?;
    gait.check_against(&model, &gait_path.display().to_string(), &urdf_origin)?;
    Ok((gait, model))
}

#[cfg(test)]
mod tests {
    use super::{below, joint_distance};

    /// The joint distance leaves the torso pitch out, takes the worst joint, and carries a NaN
    /// through (where `fold(0.0, f64::max)` would return the other joints' worst), so that a
    /// check on it fails.
    #[test]
    fn the_joint_distance_is_the_worst_joint_and_keeps_a_nan() {
        let planned = [0.0, 0.1, 0.2, 0.3];
        assert_eq!(
            joint_distance(&[5.0, 0.1, 0.25, 0.3], &planned, 4),
            0.25 - 0.2
        );
        let nan_first = joint_distance(&[0.0, f64::NAN, 0.9, 0.3], &planned, 4);
        let nan_last = joint_distance(&[0.0, 0.1, 0.9, f64::NAN], &planned, 4);
        assert!(nan_first.is_nan() && nan_last.is_nan());
        assert!(!below(nan_first, 0.5) && !below(nan_last, 0.5));
    }
}
