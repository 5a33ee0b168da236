//! Independent verification of a gait, not by the optimizer: the closed-loop hybrid system is
//! simulated with the paper's input–output linearizing controller
//! `u = −A⁻¹ (L_f² y + 2ε L_f y + ε² y)`, impacts are located by bisection on z_nsf = 0 and mapped
//! with the model's impact map and relabeling, and the periodic orbit is found by Newton on the
//! Poincaré map P (post-impact state → next post-impact state).
//!
//! - y = y^a − y^d(τ(q), α): the gait's outputs and Bézier coefficients, τ the state-based phase.
//! - The pinned-stance dynamics in reduced coordinates: q̈ = G q̈_r + c keeps the stance foot
//!   still and the design joints rigid, and M_r q̈_r + h_r = B_r u with M_r = GᵀDG (a Cholesky
//!   factor of nq × nq), h_r = Gᵀ(H + Dc): the model's constrained dynamics on their solution
//!   set, without eliminating the whole KKT system ([`ClosedLoop`]'s tests compare the two).
//! - ÿ is affine in u: ÿ = L_f² y + A u, from q̈_r at u = 0 and per unit torque.
//! - Integration: classic RK4 with a fixed step ([`DEFAULT_DT_S`]); the impact time inside the
//!   step that crosses the guard is found by regula falsi (Illinois) to 1e-12 s.
//! - The fixed point: chord iterations from the planned post-impact state with the Jacobian
//!   of P at the plan, taken again only where a step shrinks the residual by less than
//!   [`CHORD_CONTRACTION`]; the eigenvalues are those of the Jacobian at the fixed point. The
//!   Jacobians are forward finite differences of the simulated map (2·nq simulations on the
//!   rayon pool): this is a check of the optimizer's result, not part of any solve loop.
//! - Accuracy: [`VerifyReport::plan_mismatch`] and [`VerifyReport::accuracy_failures`] compare
//!   the orbit's step duration and length with the plan's ([`PLAN_ACCURACY`], 1 %);
//!   [`assert_orbit_matches_plan`] is the test helper every gait producer can call.
//! - Stability: every eigenvalue of DP at the fixed point has |λ| < 1.
//! - Consistency: the orbit is the planned one, its joints within [`CONSISTENCY_TOLERANCE_RAD`]
//!   of the planned post-impact state and its step duration within [`STEP_DURATION_TOLERANCE`] of
//!   the planned one; Newton is stopped when it takes the joints more than
//!   [`NEWTON_RADIUS_RAD`] from the plan, and a simulated step is stopped as a fall when a
//!   reduced coordinate passes half a turn. The report also gives one closed-loop step from the
//!   planned state (the planned step as the closed loop walks it) and
//!   [`VerifyReport::failures`] says what fails, with the figure and its limit.
//! - Robustness: [`VerifyReport::apex_margin`], the fraction of the orbit's post-impact angular
//!   momentum about the stance foot a step may lose and still pass over that foot
//!   ([`apex_margin`], from the momentum along the fixed point's step).

use crate::biped::PlanarBiped;
use crate::{PlannerError, Result};
use model::bezier;
use model::gait::{GaitFile, PhaseDefinition};
use model::PlanarModel;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

mod report;
#[cfg(test)]
mod tests;

pub use report::{
    apex_margin, StepFigures, VerifyReport, CONSISTENCY_TOLERANCE_RAD, PLAN_ACCURACY,
    STEP_DURATION_TOLERANCE,
};
use report::{below, joint_distance};

/// The chord iterations' Jacobian is taken again at the current iterate when a step shrinks
/// the fixed-point residual by less than this factor.
pub const CHORD_CONTRACTION: f64 = 0.25;

/// Chord steps allowed per allowed Newton iteration ([`VerifyOptions::max_newton_iterations`]):
/// a chord step costs one simulated step, a Newton step 2·nq + 1 (forward differences).
pub const CHORD_STEPS_PER_NEWTON: usize = 4;

/// How far (joint angles, rad) Newton on the Poincaré map may take its iterate from the planned
/// post-impact state before the check gives up: ten times [`CONSISTENCY_TOLERANCE_RAD`], so an
/// orbit found there would fail the consistency check anyway, and the simulation is not asked
/// to step from states where the robot has long fallen (joints hundreds of radians off).
pub const NEWTON_RADIUS_RAD: f64 = 0.5;

/// The verification's default RK4 step, s. Against 1 ms on ADAM's plan (N = 20, graded mesh):
/// the orbit's step duration within 3e-5 s and |λ|max within 5e-4 at 5 ms, within 1e-5 s and
/// 1e-6 at 2.5 ms (planner/CODESIGN.md, "Plan accuracy"); the check costs ~1/4 of 1 ms's.
pub const DEFAULT_DT_S: f64 = 4e-3;

/// The largest RK4 step under [`Law::JointPd`], s (the step the verification used for every
/// law before the default became [`DEFAULT_DT_S`]).
pub const JOINT_PD_DT_S: f64 = 1e-3;

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
            dt_s: DEFAULT_DT_S,
            max_newton_iterations: 8,
            fixed_point_tolerance: 1e-6,
        }
    }
}

/// Test helper for every producer of gaits (the planner, the co-design, a sweep, a library):
/// verifies `gait` on `model` with the default options and panics, naming the gait's robot and
/// the figures, unless it is a stable periodic orbit ([`VerifyReport::failures`]) whose step
/// duration and length are the plan's within [`PLAN_ACCURACY`]. Returns the report.
pub fn assert_orbit_matches_plan(model: &PlanarModel, gait: &GaitFile) -> VerifyReport {
    let options = VerifyOptions::default();
    let report = match verify_gait(model, gait, options) {
        Ok(r) => r,
        Err(e) => panic!("{}: the gait does not verify: {e}", model.name),
    };
    let mut failed = report.failures(options.fixed_point_tolerance);
    failed.extend(report.accuracy_failures());
    assert!(
        failed.is_empty(),
        "{}: {}\n{report}",
        model.name,
        failed.join("; ")
    );
    report
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

impl Law {
    /// The runtime's law for `gait`: joint PD with gains `kp_nm_per_rad`, `kd_nm_s_per_rad` on
    /// every output, the gait's feed-forward table times `feedforward_scale` (none without a
    /// table), the references `reference_delay_s` late.
    pub fn runtime_pd(
        gait: &GaitFile,
        kp_nm_per_rad: f64,
        kd_nm_s_per_rad: f64,
        feedforward_scale: f64,
        reference_delay_s: f64,
    ) -> Self {
        let feedforward = gait
            .feedforward
            .as_ref()
            .map(|ff| {
                ff.phase
                    .iter()
                    .zip(&ff.torque_nm)
                    .map(|(&t, row)| (t, row.iter().map(|u| feedforward_scale * u).collect()))
                    .collect()
            })
            .unwrap_or_default();
        Law::JointPd {
            kp_nm_per_rad,
            kd_nm_s_per_rad,
            feedforward,
            reference_delay_s,
        }
    }
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
    /// Angular momentum about the stance foot at the step's start (the post-impact state),
    /// kg·m²/s, signed forward.
    pub start_momentum_kgm2_s: f64,
    /// Its smallest value along the step (at the RK4 samples), kg·m²/s: over the top of the
    /// stance foot.
    pub min_momentum_kgm2_s: f64,
}

/// The closed-loop vector field at one state.
struct Field {
    /// (q̇_r, q̈_r).
    f: Vec<f64>,
    /// The torque of each actuator, N·m.
    u: Vec<f64>,
    /// The outputs y, rad.
    y: Vec<f64>,
    /// The angular momentum about the stance foot, kg·m²/s.
    momentum: f64,
}

/// The pinned-stance dynamics at one reduced state ([`ClosedLoop::pinned`]).
struct Pinned {
    /// q̈ = G q̈_r + c: G (dof × nq).
    g: DMatrix<f64>,
    /// c, the full q̈ at q̈_r = 0.
    c: DVector<f64>,
    /// a₀ = −M_r⁻¹ h_r: q̈_r without torque.
    drift_acceleration: DVector<f64>,
    /// M_r⁻¹ (nq × nq): its column i is q̈_r per unit generalized force on reduced coordinate i.
    inverse: DMatrix<f64>,
    /// The body states at the full (q, q̇).
    st: model::kinematics::BodyStates<f64>,
}

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

    /// The same closed loop under another feedback law. Joint PD is stiff (300 N·m/rad on a
    /// shin of ~2e-3 kg·m²: ω ≈ 400 rad/s, out of RK4's stability at 4 ms), so under it the
    /// step is at most [`JOINT_PD_DT_S`].
    pub fn with_law(mut self, law: Law) -> Self {
        if matches!(law, Law::JointPd { .. }) {
            self.options.dt_s = self.options.dt_s.min(JOINT_PD_DT_S);
        }
        self.law = law;
        self
    }

    /// Phase τ and its rate τ̇ at the reduced state (q_r, q̇_r).
    fn phase(&self, qr: &[f64], dqr: &[f64]) -> Result<(f64, f64)> {
        let p = self.pinned(qr, dqr)?;
        let th = self.stance_angle(&p, &p.c)?;
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
            let field = self.field(&x)?;
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
                        .map_or(0.0, |k| field.u[k])
                })
                .collect();
            if table
                .last()
                .is_none_or(|(t0, _): &(f64, Vec<f64>)| tau > *t0)
            {
                table.push((tau, by_output));
            }
            let next = self.rk4_from(&x, &field.f, dt)?;
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

    /// The pinned-stance dynamics at (q_r, q̇_r) in reduced coordinates: the full state, the
    /// affine map q̈ = G q̈_r + c that keeps the stance foot still and the design joints rigid,
    /// and M_r q̈_r + h_r = B_r u with M_r = GᵀDG, h_r = Gᵀ(H + Dc) (the model's D and H).
    /// Since the contact and design constraints' rows A satisfy AG = 0, Gᵀ removes their
    /// forces: this is the constrained dynamics [D −Aᵀ; A 0] restricted to its solution set,
    /// solved by a Cholesky factor of the nq × nq M_r instead of an elimination of the full
    /// (dof + constraints)-square system. B_r selects the actuated reduced coordinates.
    fn pinned(&self, qr: &[f64], dqr: &[f64]) -> Result<Pinned> {
        let bp = &self.biped;
        let nq = self.nq();
        let mut accelerations = vec![vec![0.0; nq]; nq + 1];
        for (i, a) in accelerations.iter_mut().skip(1).enumerate() {
            a[i] = 1.0;
        }
        let inputs: Vec<&[f64]> = accelerations.iter().map(Vec::as_slice).collect();
        let ([q, dq], ddqs) = bp.full_states(qr, dqr, &inputs)?;
        let n = q.len();
        let c = DVector::from_column_slice(&ddqs[0]);
        let g = DMatrix::from_fn(n, nq, |r, i| ddqs[i + 1][r] - ddqs[0][r]);
        let dy = bp.model.dynamics(&q, &dq)?;
        let dg = &dy.mass_matrix * &g;
        let m_r = g.transpose() * &dg;
        let h_r = g.transpose() * (&dy.drift + &dy.mass_matrix * &c);
        let chol = m_r.cholesky().ok_or_else(|| {
            PlannerError::Solver(format!(
                "the pinned-stance mass matrix is not positive definite at q = [{}] (reduced \
                 coordinates)",
                qr.iter()
                    .map(|v| format!("{v:.4}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })?;
        let drift_acceleration = chol.solve(&(-h_r));
        let inverse = chol.inverse();
        let mut st = model::kinematics::BodyStates::zeroed();
        bp.model.body_states_into(&q, &dq, &mut st)?;
        Ok(Pinned {
            g,
            c,
            drift_acceleration,
            inverse,
            st,
        })
    }

    /// The stance-leg angle and its derivatives for full accelerations `ddq`.
    fn stance_angle(
        &self,
        p: &Pinned,
        ddq: &DVector<f64>,
    ) -> Result<model::phase::AngleDerivatives<f64>> {
        let bp = &self.biped;
        Ok(bp
            .model
            .stance_leg_angle_derivatives_in(&p.st, ddq.as_slice(), &bp.legs, bp.stance)?)
    }

    /// q̈_r for the actuator torques `u`: a₀ + M_r⁻¹ B_r u.
    fn reduced_accelerations(&self, p: &Pinned, u: &[f64]) -> DVector<f64> {
        let mut ddqr = p.drift_acceleration.clone();
        for (k, &a) in self.biped.actuators.iter().enumerate() {
            ddqr.axpy(u[k], &p.inverse.column(a), 1.0);
        }
        ddqr
    }

    /// The closed-loop vector field at x: (q̇_r, q̈_r), the torque used and the outputs y.
    fn field(&self, x: &[f64]) -> Result<Field> {
        let nq = self.nq();
        let nu = self.biped.nu();
        let (qr, dqr) = (&x[..nq], &x[nq..]);
        let p = self.pinned(qr, dqr)?;
        let span = self.theta_minus - self.theta_plus;
        let th = self.stance_angle(&p, &(&p.g * &p.drift_acceleration + &p.c))?;
        let (tau, tau_rate) = ((th.theta - self.theta_plus) / span, th.rate / span);
        let m = self.alpha.len();
        let coords = &self.biped.output_coords;
        let (mut y, mut dy) = (vec![0.0; m], vec![0.0; m]);
        let mut slopes = Vec::with_capacity(m);
        for o in 0..m {
            let (b0, b1, b2) = bezier::eval_all(&self.alpha[o], tau);
            y[o] = qr[coords[o]] - b0;
            dy[o] = dqr[coords[o]] - b1 * tau_rate;
            slopes.push((b1, b2));
        }
        let u = match &self.law {
            Law::JointPd {
                kp_nm_per_rad,
                kd_nm_s_per_rad,
                feedforward,
                reference_delay_s,
            } => {
                let (mut yd, mut dyd) = (y.clone(), dy.clone());
                let mut tau = tau;
                if *reference_delay_s > 0.0 {
                    tau -= tau_rate * reference_delay_s;
                    for o in 0..m {
                        let (b0, b1, _) = bezier::eval_all(&self.alpha[o], tau);
                        yd[o] = qr[coords[o]] - b0;
                        dyd[o] = dqr[coords[o]] - b1 * tau_rate;
                    }
                }
                let mut ff = vec![0.0; m];
                let knots: Vec<f64> = feedforward.iter().map(|(t, _)| *t).collect();
                let rows: Vec<&[f64]> = feedforward.iter().map(|(_, u)| u.as_slice()).collect();
                model::gait::interpolate(&knots, &rows, tau, &mut ff);
                let mut u = vec![0.0; nu];
                for (k, &a) in self.biped.actuators.iter().enumerate() {
                    if let Some(o) = coords.iter().position(|&c| c == a) {
                        u[k] = -kp_nm_per_rad * yd[o] - kd_nm_s_per_rad * dyd[o] + ff[o];
                    }
                }
                u
            }
            Law::IoLinearizing => {
                // ÿ is affine in u: ÿ = L_f²y + A u. ÿ at u = 0 and at each unit torque,
                // through q̈_r and the stance-leg angle's θ̈ (affine in q̈).
                let ddy = |ddqr: &DVector<f64>| -> Result<Vec<f64>> {
                    let th = self.stance_angle(&p, &(&p.g * ddqr + &p.c))?;
                    let tau_accel = th.accel / span;
                    Ok((0..m)
                        .map(|o| {
                            let (b1, b2) = slopes[o];
                            ddqr[coords[o]] - b2 * tau_rate * tau_rate - b1 * tau_accel
                        })
                        .collect())
                };
                let ddy0 = ddy(&p.drift_acceleration)?;
                let mut big_a = DMatrix::zeros(m, nu);
                for (k, &a) in self.biped.actuators.iter().enumerate() {
                    let ddyk = ddy(&(&p.drift_acceleration + p.inverse.column(a)))?;
                    for o in 0..m {
                        big_a[(o, k)] = ddyk[o] - ddy0[o];
                    }
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
                u.iter().copied().collect()
            }
        };
        let ddqr = self.reduced_accelerations(&p, &u);
        let mut f = dqr.to_vec();
        f.extend(ddqr.iter());
        // The stance foot is pinned at the origin in these body states.
        let momentum = self.biped.model.angular_momentum_in(&p.st, [0.0, 0.0]);
        Ok(Field { f, u, y, momentum })
    }

    fn rk4(&self, x: &[f64], h: f64) -> Result<Vec<f64>> {
        let k1 = self.field(x)?.f;
        self.rk4_from(x, &k1, h)
    }

    /// [`Self::rk4`] with its first stage `k1` = f(x) already evaluated.
    fn rk4_from(&self, x: &[f64], k1: &[f64], h: f64) -> Result<Vec<f64>> {
        let add = |a: &[f64], k: &[f64], s: f64| -> Vec<f64> {
            a.iter().zip(k).map(|(p, q)| p + s * q).collect()
        };
        let k2 = self.field(&add(x, k1, h / 2.0))?.f;
        let k3 = self.field(&add(x, &k2, h / 2.0))?.f;
        let k4 = self.field(&add(x, &k3, h))?.f;
        Ok((0..x.len())
            .map(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
            .collect())
    }

    /// The swing foot's position relative to the stance foot (which is at the origin), m: one
    /// pass of the poses with the base anywhere.
    fn swing_foot(&self, x: &[f64]) -> Result<[f64; 2]> {
        let bp = &self.biped;
        let nq = self.nq();
        let mut st = model::kinematics::BodyStates::zeroed();
        bp.states_at_rest_base(&x[..nq], &x[nq..], None, &mut st)?;
        let swing = bp
            .model
            .frame_position_in(&st, bp.legs.side(bp.swing()).foot);
        let stance = bp
            .model
            .frame_position_in(&st, bp.legs.side(bp.stance).foot);
        Ok([swing[0] - stance[0], swing[1] - stance[1]])
    }

    /// The impact inside the RK4 step from `x` to `end` (whose swing foot is below the ground):
    /// the sub-step s where z_nsf(RK4(x, s)) = 0, by the Illinois variant of regula falsi
    /// (superlinear; bisection took 40 RK4 sub-steps), to |z| < 1e-14 m or a bracket under
    /// 1e-12 s. Returns s, the state there and the swing foot's position.
    fn locate_impact(&self, x: &[f64], end: &[f64]) -> Result<(f64, Vec<f64>, [f64; 2])> {
        let (mut lo, mut hi) = (0.0, self.options.dt_s);
        let end_foot = self.swing_foot(end)?;
        let (mut z_lo, mut z_hi) = (self.swing_foot(x)?[1].max(f64::MIN_POSITIVE), end_foot[1]);
        let mut side = 0;
        let mut best = (hi, end.to_vec(), end_foot);
        for _ in 0..60 {
            let s = (lo * z_hi - hi * z_lo) / (z_hi - z_lo);
            let s = if s > lo && s < hi { s } else { 0.5 * (lo + hi) };
            let state = self.rk4(x, s)?;
            let foot = self.swing_foot(&state)?;
            let z = foot[1];
            best = (s, state, foot);
            if z.abs() < 1e-14 {
                break;
            }
            if z > 0.0 {
                lo = s;
                z_lo = z;
                if side == 1 {
                    z_hi *= 0.5;
                }
                side = 1;
            } else {
                hi = s;
                z_hi = z;
                if side == -1 {
                    z_lo *= 0.5;
                }
                side = -1;
            }
            if hi - lo < 1e-12 {
                break;
            }
        }
        Ok(best)
    }

    /// Simulates one step from the post-impact reduced state `x0` to the next post-impact state.
    pub fn step(&self, x0: &[f64]) -> Result<Step> {
        let nq = self.nq();
        let dt = self.options.dt_s;
        let mut x = x0.to_vec();
        let mut t = 0.0;
        let mut max_y = 0.0_f64;
        let max_time = 5.0;
        let mut start_momentum = None;
        let mut min_momentum = f64::INFINITY;
        loop {
            // The outputs and the momentum at x come with the step's first stage.
            let field = self.field(&x)?;
            start_momentum.get_or_insert(field.momentum);
            min_momentum = min_momentum.min(field.momentum);
            max_y = field.y.iter().fold(max_y, |m, v| m.max(v.abs()));
            let next = self.rk4_from(&x, &field.f, dt)?;
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
                let (s, pre, foot) = self.locate_impact(&x, &next)?;
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
                    start_momentum_kgm2_s: start_momentum.unwrap_or(f64::NAN),
                    min_momentum_kgm2_s: min_momentum,
                });
            }
            x = next;
            t += dt;
            if t > max_time {
                return Err(PlannerError::Solver(format!(
                    "no impact within {max_time} s: the robot does not step"
                )));
            }
        }
    }

    /// The closed-loop state `duration_s` after `x0`, by RK4 steps of at most the options' step
    /// (no impact is looked for): the flow the plan's intervals are compared with.
    pub fn flow(&self, x0: &[f64], duration_s: f64) -> Result<Vec<f64>> {
        let steps = (duration_s / self.options.dt_s).ceil().max(1.0) as usize;
        let h = duration_s / steps as f64;
        let mut x = x0.to_vec();
        for _ in 0..steps {
            x = self.rk4(&x, h)?;
        }
        Ok(x)
    }

    /// The Poincaré map.
    pub fn poincare(&self, x: &[f64]) -> Result<DVector<f64>> {
        Ok(self.step(x)?.next)
    }

    /// The gait's planned post-impact state (its `initial_state`) in this closed loop's
    /// reduced coordinates (q_r, q̇_r); `what` says what it is for, in the error of a gait
    /// without one.
    pub fn planned_state(&self, gait: &GaitFile, what: &str) -> Result<Vec<f64>> {
        let state = gait
            .initial_state
            .as_ref()
            .ok_or_else(|| PlannerError::Robot {
                robot: self.biped.model.name.clone(),
                reason: format!("the gait file has no initial_state to {what}"),
            })?;
        let r = &self.biped.reduced;
        Ok(r.iter()
            .map(|&c| state.q[c])
            .chain(r.iter().map(|&c| state.dq[c]))
            .collect())
    }

    /// Walks `steps` steps from the post-impact reduced state `x0` and measures the last
    /// `measured` of them (Σ length / Σ duration): the speed this closed loop settles at from
    /// the plan, whether or not that is the plan's orbit (under the runtime's joint PD with late
    /// references it is not). An error names the step the robot fell or stopped in.
    pub fn walk(&self, x0: &[f64], steps: usize, measured: usize) -> Result<Walked> {
        if !(1..=steps).contains(&measured) {
            return Err(PlannerError::Solver(format!(
                "walk: {measured} steps measured of {steps} walked (1 to {steps})"
            )));
        }
        let mut x = x0.to_vec();
        let (mut length_m, mut duration_s) = (0.0, 0.0);
        for k in 0..steps {
            let step = self
                .step(&x)
                .map_err(|e| PlannerError::Solver(format!("step {} of {steps}: {e}", k + 1)))?;
            if step.length_m <= 0.0 {
                return Err(PlannerError::Solver(format!(
                    "step {} of {steps} lands {:.3} m behind the stance foot: the robot stopped \
                     short of it and fell back",
                    k + 1,
                    -step.length_m
                )));
            }
            if k + measured >= steps {
                length_m += step.length_m;
                duration_s += step.duration_s;
            }
            x = step.next.as_slice().to_vec();
        }
        Ok(Walked {
            length_m: length_m / measured as f64,
            duration_s: duration_s / measured as f64,
        })
    }
}

/// The mean step of the last steps of [`ClosedLoop::walk`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Walked {
    /// Mean step length, m.
    pub length_m: f64,
    /// Mean step duration, s.
    pub duration_s: f64,
}

impl Walked {
    /// The walked speed, m/s.
    pub fn speed_mps(&self) -> f64 {
        self.length_m / self.duration_s
    }
}

/// Largest RK4 step of the simulation a feed-forward table is sampled from, s: the table
/// keeps its 1 ms source whatever the verification's step.
pub const FEEDFORWARD_DT_S: f64 = 1e-3;

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
    let fine = VerifyOptions {
        dt_s: options.dt_s.min(FEEDFORWARD_DT_S),
        ..options
    };
    let cl = ClosedLoop::new(model, gait, fine)?;
    let x0 = cl.planned_state(gait, "simulate the orbit from")?;
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
    let planned = cl.planned_state(gait, "start the Poincaré map from")?;
    let mut x = DVector::from_vec(planned.clone());
    let from_plan = cl.step(x.as_slice())?;
    let planned_state_residual = (&from_plan.next - &x).amax();
    let n = 2 * nq;
    let h = 1e-6;
    // Forward differences of the Poincaré map at x, whose image `px` is known: n independent
    // one-step simulations, spread over the rayon pool (each column is computed exactly as it
    // would be sequentially, so the Jacobian does not depend on the schedule).
    let jacobian = |x: &DVector<f64>, px: &DVector<f64>| -> Result<DMatrix<f64>> {
        let columns = (0..n)
            .into_par_iter()
            .map(|i| {
                let mut xp = x.clone();
                xp[i] += h;
                Ok((cl.poincare(xp.as_slice())? - px) / h)
            })
            .collect::<Result<Vec<DVector<f64>>>>()?;
        Ok(DMatrix::from_columns(&columns))
    };
    let singular = || PlannerError::Solver("DP − I is singular".into());
    // Chord iterations from the plan: the Jacobian of the planned state serves every step, and
    // is taken again only where the residual shrinks by less than CHORD_CONTRACTION per step
    // (each step is one simulation; a Jacobian, 2·nq of them).
    let mut step = from_plan.clone();
    let mut jac = jacobian(&x, &step.next)?;
    let mut jac_is_current = true;
    let mut lu = (jac.clone() - DMatrix::identity(n, n)).lu();
    let mut residual = planned_state_residual;
    let mut iterations = 0;
    let max_steps = CHORD_STEPS_PER_NEWTON * options.max_newton_iterations;
    while !below(residual, options.fixed_point_tolerance * 1e-2) && iterations < max_steps {
        let r = &step.next - &x;
        x += lu.solve(&(-r)).ok_or_else(singular)?;
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
        step = cl.step(x.as_slice())?;
        let previous = residual;
        residual = (&step.next - &x).amax();
        jac_is_current = false;
        if !below(residual, CHORD_CONTRACTION * previous)
            && !below(residual, options.fixed_point_tolerance * 1e-2)
        {
            jac = jacobian(&x, &step.next)?;
            jac_is_current = true;
            lu = (jac.clone() - DMatrix::identity(n, n)).lu();
        }
    }
    // The eigenvalues are those of DP at the fixed point itself.
    if !jac_is_current {
        jac = jacobian(&x, &step.next)?;
    }
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
        apex_margin: apex_margin(step.start_momentum_kgm2_s, step.min_momentum_kgm2_s),
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
