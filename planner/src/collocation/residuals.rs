//! What each constraint block computes at its local variables: pinned-stance dynamics and
//! contact forces, phase, virtual constraints, Hermite–Simpson defects, power slacks, swing
//! foot, impact and periodicity, step speed.

use super::blocks::Kind;
use super::layout::{ACC_SCALE, TORQUE_SCALE};
use super::problem::HzdProblem;
use crate::nlp::DomainError;
use model::bezier;
use model::kinematics::BodyStates;
use model::robot::MAX_DOF;
use model::Real;

/// Working memory of one block evaluation, reused across the seed passes of a derivative sweep.
pub(super) struct Scratch<S> {
    /// Body states of the evaluation's kinematics pass.
    pub(super) st: BodyStates<S>,
    /// Mass properties of each body (the first `bodies.len()`).
    pub(super) inertias: [model::robot::BodyInertia<S>; model::robot::MAX_BODIES],
    /// Joint accelerations (the first `dof` entries are used).
    pub(super) ddq: [S; MAX_DOF],
    /// Stance-foot Jacobian, column by column.
    pub(super) jac: [[S; 2]; MAX_DOF],
    /// Inverse-dynamics output.
    pub(super) r: [S; MAX_DOF],
}

impl<S: Real> Scratch<S> {
    pub(super) fn new() -> Self {
        let z = S::zero();
        Self {
            st: BodyStates::zeroed(),
            inertias: [model::robot::BodyInertia {
                mass_kg: z,
                com_xz_m: [z, z],
                inertia_yy_kgm2: z,
            }; model::robot::MAX_BODIES],
            ddq: [z; MAX_DOF],
            jac: [[z, z]; MAX_DOF],
            r: [z; MAX_DOF],
        }
    }
}

impl HzdProblem {
    /// Whether a block kind evaluates the robot model (and so depends on the design).
    pub(super) fn uses_model(kind: Kind) -> bool {
        matches!(
            kind,
            Kind::Dynamics
                | Kind::PhaseLift
                | Kind::SwingHeight
                | Kind::SwingEnd
                | Kind::Impact
                | Kind::Contraction
                | Kind::ApexMargin
        )
    }

    /// Evaluates one block at local variables `z` (set-up and tests; the solve loop reuses one
    /// [`Scratch`] per block and derivative sweep through [`Self::eval_block_in`]).
    pub(super) fn eval_block<S: Real>(
        &self,
        kind: Kind,
        z: &[S],
        out: &mut [S],
    ) -> Result<(), DomainError> {
        self.eval_block_in(kind, z, out, &mut Scratch::new())
    }

    /// Evaluates one block at local variables `z`, with `scratch` for the body states and mass
    /// properties (wide dual numbers make these tens of kilobytes: zeroing them once per block
    /// instead of once per seed pass matters).
    pub(super) fn eval_block_in<S: Real>(
        &self,
        kind: Kind,
        z: &[S],
        out: &mut [S],
        scratch: &mut Scratch<S>,
    ) -> Result<(), DomainError> {
        let Scratch {
            st,
            inertias,
            ddq,
            jac,
            r,
        } = scratch;
        let design = self.design_joints_of(kind, z);
        let bp = &self.biped;
        let l = &self.layout;
        let (nq, nu) = (l.nq, l.nu);
        let g = &self.config.gait;
        let mu = g.friction_coefficient;
        match kind {
            Kind::Dynamics => {
                // One kinematics pass with the base at rest at the origin: inverse dynamics
                // and the stance-foot Jacobian depend only on relative positions, so they are
                // those of the pinned robot once the base acceleration keeps the foot still.
                let (qr, dqr) = (&z[..nq], &z[nq..2 * nq]);
                let us = &z[3 * nq..3 * nq + nu];
                bp.states_at_rest_base(qr, dqr, design, st)
                    .map_err(|_| DomainError)?;
                let n = bp.model.dof();
                // Scratch arrays: only the first n entries are read, and the ones not set
                // below must be zero.
                ddq[..n].fill(S::zero());
                for (i, &c) in bp.reduced.iter().enumerate() {
                    ddq[c] = z[2 * nq + i] * ACC_SCALE;
                }
                let foot = bp.legs.side(bp.stance).foot;
                let p = bp.model.frame_position_in(st, foot);
                let mut a = bp.model.frame_bias_acceleration_in(st, foot);
                jac[..n].fill([S::zero(); 2]);
                bp.model
                    .point_jacobian_into(st, bp.model.frames[foot].body, p, |r, c, v| {
                        jac[c][r] = v;
                        a[r] += v * ddq[c];
                    });
                ddq[0] = -a[0];
                ddq[1] = -a[1];
                let done = match self.constant_inertias_for(kind) {
                    Some(c) => bp.model.inverse_dynamics_in(c, st, &ddq[..n], &mut r[..n]),
                    None => {
                        self.inertias_of(kind, z, inertias);
                        let i = &inertias[..bp.model.bodies.len()];
                        bp.model.inverse_dynamics_in(i, st, &ddq[..n], &mut r[..n])
                    }
                };
                done.map_err(|_| DomainError)?;
                let lam = [r[0], r[1]];
                for (i, &c) in bp.reduced.iter().enumerate() {
                    out[i] = r[c] - jac[c][0] * lam[0] - jac[c][1] * lam[1];
                }
                for (a, &i) in bp.actuators.iter().enumerate() {
                    out[i] -= us[a] * TORQUE_SCALE;
                }
                out[nq] = lam[1];
                out[nq + 1] = lam[1] * mu - lam[0];
                out[nq + 2] = lam[1] * mu + lam[0];
            }
            Kind::PhaseLift => {
                let (qr, dqr) = (&z[..nq], &z[nq..2 * nq]);
                let r = &z[3 * nq..];
                let (tp, tm, tau, tau_d, tau_dd) = (r[0], r[1], r[2], r[3], r[4]);
                // The hip-to-foot angle needs no pinned base: states with the base at rest.
                bp.states_at_rest_base(qr, dqr, design, st)
                    .map_err(|_| DomainError)?;
                ddq[..bp.model.dof()].fill(S::zero());
                for (i, &c) in bp.reduced.iter().enumerate() {
                    ddq[c] = z[2 * nq + i] * ACC_SCALE;
                }
                let th = bp
                    .model
                    .stance_leg_angle_derivatives_in(
                        st,
                        &ddq[..bp.model.dof()],
                        &bp.legs,
                        bp.stance,
                    )
                    .map_err(|_| DomainError)?;
                let span = tm - tp;
                out[0] = th.theta - tp - tau * span;
                out[1] = th.rate - tau_d * span;
                out[2] = th.accel - tau_dd * span;
            }
            Kind::OutputDynamics(_) | Kind::OutputStart(_) => {
                let (qj, dqj, ddqj) = (z[0], z[1], z[2] * ACC_SCALE);
                let (tau, tau_d, tau_dd) = (z[3], z[4], z[5]);
                let (yd, yd1, yd2) = bezier::eval_all(&z[6..], tau);
                let y = qj - yd;
                let dy = dqj - yd1 * tau_d;
                if matches!(kind, Kind::OutputStart(_)) {
                    out[0] = y;
                    out[1] = dy;
                } else {
                    let ddy = ddqj - yd2 * tau_d * tau_d - yd1 * tau_dd;
                    let eps = self.config.collocation.output_gain_per_s;
                    out[0] = (ddy + dy * (2.0 * eps) + y * (eps * eps)) / eps;
                }
            }
            Kind::Interval(i) => {
                let h = z[9] * l.interval_fraction(i);
                let (qa, qm, qe, va, vm, ve) = (z[0], z[1], z[2], z[3], z[4], z[5]);
                let (aa, am, ae) = (z[6] * ACC_SCALE, z[7] * ACC_SCALE, z[8] * ACC_SCALE);
                out[0] = qm - (qa + qe) * 0.5 - h * (va - ve) / 8.0;
                out[1] = vm - (va + ve) * 0.5 - h * (aa - ae) / 8.0;
                out[2] = qe - qa - h * (va + vm * 4.0 + ve) / 6.0;
                out[3] = ve - va - h * (aa + am * 4.0 + ae) / 6.0;
            }
            Kind::TauEnds => {
                out[0] = z[0];
                out[1] = z[1];
            }
            Kind::Speed => {
                // z = [T, d]; the rows' bounds are set in `build_blocks`.
                let (duration, length) = (z[0], z[1]);
                let [lo, hi] = g.speed_mps.unwrap_or([0.0, 0.0]);
                out[0] = length - duration * lo;
                if let Some(upper) = out.get_mut(1) {
                    *upper = duration * hi - length;
                }
            }
            Kind::Power(_) => {
                out[0] = z[0] - z[1] - z[2] * TORQUE_SCALE * z[3];
            }
            Kind::SwingHeight | Kind::SwingEnd => {
                // Swing foot relative to the stance foot, from one pass with the base at rest.
                let zero = [S::zero(); MAX_DOF];
                let dqr = if kind == Kind::SwingEnd {
                    &z[nq..2 * nq]
                } else {
                    &zero[..nq]
                };
                bp.states_at_rest_base(&z[..nq], dqr, design, st)
                    .map_err(|_| DomainError)?;
                let (swing, stance) = (bp.legs.side(bp.swing()).foot, bp.legs.side(bp.stance).foot);
                let ps = bp.model.frame_position_in(st, stance);
                let p = bp.model.frame_position_in(st, swing);
                if kind == Kind::SwingHeight {
                    out[0] = p[1] - ps[1];
                } else {
                    let vs = bp.model.frame_velocity_in(st, stance);
                    let v = bp.model.frame_velocity_in(st, swing);
                    out[0] = p[0] - ps[0] - z[2 * nq];
                    out[1] = v[1] - vs[1];
                }
            }
            Kind::Impact => {
                let (qn, dqn) = (&z[..nq], &z[nq..2 * nq]);
                let (q0, dq0) = (&z[2 * nq..3 * nq], &z[3 * nq..4 * nq]);
                let zero = vec![S::zero(); nq];
                let [q, dq, _] = bp
                    .full_state_design(qn, dqn, &zero, design)
                    .map_err(|_| DomainError)?;
                let swing_foot = bp.legs.side(bp.swing()).foot;
                self.inertias_of(kind, z, inertias);
                let imp = bp
                    .model
                    .impact_with(&inertias[..bp.model.bodies.len()], &q, &dq, swing_foot)
                    .map_err(|_| DomainError)?;
                let dq_plus: Vec<S> = imp.dq_plus.iter().copied().collect();
                for i in 0..nq {
                    let src = bp.relabel[i];
                    out[i] = q0[i] - qn[src];
                    out[nq + i] = dq0[i] - dq_plus[bp.reduced[src]];
                }
                let lam = imp.impulse_ns;
                out[2 * nq] = lam[1];
                out[2 * nq + 1] = lam[1] * mu - lam[0];
                out[2 * nq + 2] = lam[1] * mu + lam[0];
                bp.model
                    .body_states_into(&q, &dq_plus, st)
                    .map_err(|_| DomainError)?;
                let v = bp.model.frame_velocity_in(st, bp.legs.side(bp.stance).foot);
                out[2 * nq + 3] = v[1];
            }
            Kind::Contraction => {
                let (qn, dqn) = (&z[..nq], &z[nq..2 * nq]);
                let zero = [S::zero(); MAX_DOF];
                let [q, dq, _] = bp
                    .full_state_design(qn, dqn, &zero[..nq], design)
                    .map_err(|_| DomainError)?;
                self.inertias_of(kind, z, inertias);
                bp.model
                    .body_states_into(&q, &dq, st)
                    .map_err(|_| DomainError)?;
                let at = |side| bp.model.frame_position_in(st, bp.legs.side(side).foot);
                let (p_st, p_sw) = (at(bp.stance), at(bp.swing()));
                let (mut h_st, mut h_sw) = (S::zero(), S::zero());
                for (b, i) in inertias[..bp.model.bodies.len()].iter().enumerate() {
                    h_st += bp.model.body_angular_momentum_in(st, b, i, p_st);
                    h_sw += bp.model.body_angular_momentum_in(st, b, i, p_sw);
                }
                let lambda = S::from(g.max_zero_dynamics_eigenvalue.unwrap_or(1.0));
                out[0] = lambda * h_st * h_st - h_sw * h_sw;
            }
            Kind::ApexMargin => {
                self.inertias_of(kind, z, inertias);
                let zero = [S::zero(); MAX_DOF];
                let mut sigma = [S::zero(); 2];
                for (p, s) in sigma.iter_mut().enumerate() {
                    let at = 2 * nq * p;
                    let (qn, dqn) = (&z[at..at + nq], &z[at + nq..at + 2 * nq]);
                    let [q, dq, _] = bp
                        .full_state_design(qn, dqn, &zero[..nq], design)
                        .map_err(|_| DomainError)?;
                    bp.model
                        .body_states_into(&q, &dq, st)
                        .map_err(|_| DomainError)?;
                    let foot = bp.model.frame_position_in(st, bp.legs.side(bp.stance).foot);
                    for (b, i) in inertias[..bp.model.bodies.len()].iter().enumerate() {
                        *s += bp.model.body_angular_momentum_in(st, b, i, foot);
                    }
                }
                let kept = 1.0 - g.min_apex_margin.unwrap_or(0.0);
                let c = S::from(1.0 - kept * kept);
                out[0] = sigma[0] * sigma[0] - c * sigma[1] * sigma[1];
            }
        }
        Ok(())
    }
}
