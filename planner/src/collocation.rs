//! The HZD gait optimization as a sparse NLP: Hermite–Simpson direct collocation of the
//! single-domain hybrid system (paper Sec. II–III), with exact derivatives from dual numbers.
//!
//! # Transcription
//! N intervals, 2N + 1 points k (even k: nodes, odd k: midpoints), step duration T a variable and
//! h = T/N. At every point: reduced state q_r, q̇_r, q̈_r (pinned stance, see [`crate::biped`]),
//! torques u and the positive/negative parts p, n of each actuator's power. Global variables: the
//! Bézier coefficients α (m × (b+1)), θ⁺ and θ⁻ of the phase variable, T, and the step length d.
//!
//! Constraints (all from [`crate::config::PlannerConfig`]):
//! - **pinned-stance dynamics** at every point: D q̈ + H = B u + J_stᵀ λ with λ the stance force,
//!   computed from the x and z rows; λ_z ≥ λ_min and |λ_x| ≤ μ λ_z (friction cone);
//! - **Hermite–Simpson** (separated form): midpoint interpolation and Simpson defects for q and q̇;
//! - **virtual constraints** the way FROST enforces them: y = ẏ = 0 at the first point and the
//!   output dynamics ÿ + 2εẏ + ε²y = 0 at every point (PLANNER-NOTES: position-level y = 0 at
//!   every point over-constrains the interpolant and does not converge);
//! - **phase**: θ(q_0) = θ⁺, θ(q_2N) = θ⁻;
//! - **swing foot**: z_nsf ≥ 0 at every interior point, ≥ clearance at mid-step, = 0 at the end
//!   (the guard) with ż_nsf ≤ −v_impact, x_nsf = d at the end;
//! - **impact and periodicity** (the HZD condition, with y = ẏ = 0 at the start):
//!   x_0 = relabel(Δ(x_2N)); the impact impulse inside the friction cone; the old stance foot
//!   leaves the ground (upward velocity after impact);
//! - bounds: joint limits, A1 torque and speed limits, torso pitch, Table I (d, T).
//!
//! Cost: the weighted mechanical cost of transport Φ = 1/(M g d) Σ_i w_i ∫ |u_i q̇_i| dt with
//! |u q̇| = p + n, p − n = u q̇, p, n ≥ 0 (slack variables), integrated with Simpson's rule.
//!
//! # Derivatives
//! Each constraint group is a *block*: a generic function of a few variables. Jacobians come from
//! forward-mode `Dual64` sweeps (one per block variable), Lagrangian Hessians from `HyperDual64`
//! evaluations of Σ μ_r c_r (one per structurally non-zero variable pair). Structural zeros are
//! found once per block kind at set-up by evaluating at a random point. The objective's
//! derivatives are hand-derived and checked against finite differences in the tests.
//! Acceleration and torque variables are scaled by 1/10 (PLANNER-NOTES: 219 → 78 iterations).

use crate::biped::PlanarBiped;
use crate::config::PlannerConfig;
use crate::nlp::{DomainError, NlpProblem, SparsityPattern};
use model::bezier;
use model::num_dual::{Dual64, HyperDual64};
use model::Real;
use std::collections::HashMap;

/// Two lists of (row, column) index pairs (a block's Jacobian and Hessian patterns).
type BlockPatterns = (Vec<(usize, usize)>, Vec<(usize, usize)>);

/// q̈ = `ACC_SCALE` × its variable.
pub const ACC_SCALE: f64 = 10.0;
/// u = `TORQUE_SCALE` × its variable.
pub const TORQUE_SCALE: f64 = 10.0;

/// Where each variable lives in x.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Reduced coordinates.
    pub nq: usize,
    /// Actuators.
    pub nu: usize,
    /// Outputs.
    pub m: usize,
    /// Bézier degree.
    pub degree: usize,
    /// Intervals N.
    pub intervals: usize,
    /// Variables per point.
    pub stride: usize,
}

impl Layout {
    /// Number of points, 2N + 1.
    pub fn points(&self) -> usize {
        2 * self.intervals + 1
    }
    /// First index of q_r at point k.
    pub fn q(&self, k: usize) -> usize {
        k * self.stride
    }
    /// First index of q̇_r at point k.
    pub fn dq(&self, k: usize) -> usize {
        k * self.stride + self.nq
    }
    /// First index of the scaled q̈_r at point k.
    pub fn ddq(&self, k: usize) -> usize {
        k * self.stride + 2 * self.nq
    }
    /// First index of the scaled u at point k.
    pub fn u(&self, k: usize) -> usize {
        k * self.stride + 3 * self.nq
    }
    /// First index of the positive power parts at point k.
    pub fn p(&self, k: usize) -> usize {
        k * self.stride + 3 * self.nq + self.nu
    }
    /// First index of the negative power parts at point k.
    pub fn n(&self, k: usize) -> usize {
        k * self.stride + 3 * self.nq + 2 * self.nu
    }
    fn globals(&self) -> usize {
        self.points() * self.stride
    }
    /// Index of α[o][j].
    pub fn alpha(&self, o: usize, j: usize) -> usize {
        self.globals() + o * (self.degree + 1) + j
    }
    /// Index of θ⁺.
    pub fn theta_plus(&self) -> usize {
        self.globals() + self.m * (self.degree + 1)
    }
    /// Index of θ⁻.
    pub fn theta_minus(&self) -> usize {
        self.theta_plus() + 1
    }
    /// Index of the step duration T.
    pub fn duration(&self) -> usize {
        self.theta_plus() + 2
    }
    /// Index of the step length d.
    pub fn length(&self) -> usize {
        self.theta_plus() + 3
    }
    /// Number of variables.
    pub fn len(&self) -> usize {
        self.theta_plus() + 4
    }
    /// Whether there are no variables (never).
    pub fn is_empty(&self) -> bool {
        false
    }
    /// Simpson weight of point k in ∫ ≈ h/6 Σ c_k f_k.
    pub fn simpson_weight(&self, k: usize) -> f64 {
        if k % 2 == 1 {
            4.0
        } else if k == 0 || k == 2 * self.intervals {
            1.0
        } else {
            2.0
        }
    }
}

/// The kinds of constraint block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Kind {
    /// Dynamics residual (nq) and 3 contact-force rows.
    Dynamics,
    /// Output dynamics of output o.
    OutputDynamics(usize),
    /// y and ẏ of output o at the first point.
    OutputStart(usize),
    /// Hermite–Simpson rows of one reduced coordinate in one interval.
    Interval,
    /// p − n − u q̇ of one actuator at one point (carries the actuator's reduced index).
    Power(usize),
    /// Swing-foot height.
    SwingHeight,
    /// Swing foot at the end: x − d and ż.
    SwingEnd,
    /// θ(q) − θ⁺ (false) or θ(q) − θ⁻ (true).
    Phase(bool),
    /// Impact and periodicity.
    Impact,
}

#[derive(Clone, Debug)]
struct Block {
    kind: Kind,
    vars: Vec<usize>,
    row0: usize,
    n_out: usize,
    /// (local output, local var) of the structurally non-zero Jacobian entries.
    jac: Vec<(usize, usize)>,
    /// Local vars with at least one Jacobian entry.
    jac_vars: Vec<usize>,
    /// Local variable pairs (a ≥ b by global index) with a structurally non-zero Hessian.
    hess: Vec<(usize, usize)>,
    /// Slot in the global Hessian value array of each pair.
    hess_slots: Vec<usize>,
}

/// The HZD collocation problem.
pub struct HzdProblem {
    /// The robot.
    pub biped: PlanarBiped,
    /// The config.
    pub config: PlannerConfig,
    /// Variable layout.
    pub layout: Layout,
    /// Whether the cost of transport is minimized (false: the feasibility stage).
    pub with_cost: bool,
    blocks: Vec<Block>,
    lower_g: Vec<f64>,
    upper_g: Vec<f64>,
    jac_rows: Vec<usize>,
    jac_cols: Vec<usize>,
    hess_pattern: SparsityPattern,
    /// Objective Hessian slots: (T,T unused) T–slack, T–d, slack–d, d–d.
    obj_slots: ObjectiveSlots,
    /// Cost weight of each slack variable: c_k w_a.
    slack_weights: Vec<(usize, f64)>,
    initial: Vec<f64>,
    total_mass_kg: f64,
}

#[derive(Clone, Debug, Default)]
struct ObjectiveSlots {
    t_slack: Vec<usize>,
    slack_d: Vec<usize>,
    t_d: usize,
    d_d: usize,
}

fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64) / ((1u64 << 53) as f64)
}

impl HzdProblem {
    /// Builds the problem; `initial` is the starting point (see [`crate::guess`]).
    pub fn new(
        biped: PlanarBiped,
        config: PlannerConfig,
        initial: Vec<f64>,
        with_cost: bool,
    ) -> crate::Result<Self> {
        let layout = Layout {
            nq: biped.nq(),
            nu: biped.nu(),
            m: biped.outputs.len(),
            degree: config.collocation.bezier_degree,
            intervals: config.collocation.intervals,
            stride: 3 * biped.nq() + 3 * biped.nu(),
        };
        if config.cost.weights.len() != layout.nu {
            return Err(crate::PlannerError::InvalidField {
                origin: "planner config".into(),
                field: "cost.weights".into(),
                value: format!("{} weights", config.cost.weights.len()),
                reason: format!("the robot has {} actuated joints", layout.nu),
            });
        }
        let total_mass_kg = biped.model.total_mass_kg();
        let mut p = Self {
            biped,
            config,
            layout,
            with_cost,
            blocks: Vec::new(),
            lower_g: Vec::new(),
            upper_g: Vec::new(),
            jac_rows: Vec::new(),
            jac_cols: Vec::new(),
            hess_pattern: SparsityPattern::default(),
            obj_slots: ObjectiveSlots::default(),
            slack_weights: Vec::new(),
            initial,
            total_mass_kg,
        };
        p.build_blocks();
        p.build_patterns();
        Ok(p)
    }

    fn add(&mut self, kind: Kind, vars: Vec<usize>, lower: &[f64], upper: &[f64]) {
        let row0 = self.lower_g.len();
        self.lower_g.extend_from_slice(lower);
        self.upper_g.extend_from_slice(upper);
        self.blocks.push(Block {
            kind,
            vars,
            row0,
            n_out: lower.len(),
            jac: Vec::new(),
            jac_vars: Vec::new(),
            hess: Vec::new(),
            hess_slots: Vec::new(),
        });
    }

    fn point_vars(&self, k: usize, with_ddq: bool) -> Vec<usize> {
        let l = &self.layout;
        let mut v: Vec<usize> = (l.q(k)..l.q(k) + l.nq)
            .chain(l.dq(k)..l.dq(k) + l.nq)
            .collect();
        if with_ddq {
            v.extend(l.ddq(k)..l.ddq(k) + l.nq);
        }
        v
    }

    fn build_blocks(&mut self) {
        let l = self.layout.clone();
        let g = self.config.gait.clone();
        let (nq, nu, b) = (l.nq, l.nu, l.degree);
        let last = l.points() - 1;
        let inf = f64::INFINITY;
        for k in 0..l.points() {
            // Dynamics and contact.
            let mut vars = self.point_vars(k, true);
            vars.extend(l.u(k)..l.u(k) + nu);
            let mut lo = vec![0.0; nq];
            let mut hi = vec![0.0; nq];
            lo.extend([g.min_normal_force_n, 0.0, 0.0]);
            hi.extend([inf, inf, inf]);
            self.add(Kind::Dynamics, vars, &lo, &hi);
            // Output dynamics.
            for o in 0..l.m {
                let mut vars = self.point_vars(k, true);
                vars.extend((0..=b).map(|j| l.alpha(o, j)));
                vars.extend([l.theta_plus(), l.theta_minus()]);
                self.add(Kind::OutputDynamics(o), vars, &[0.0], &[0.0]);
            }
            // Power slacks.
            for a in 0..nu {
                let c = self.biped.actuators[a];
                let vars = vec![l.p(k) + a, l.n(k) + a, l.u(k) + a, l.dq(k) + c];
                self.add(Kind::Power(c), vars, &[0.0], &[0.0]);
            }
            // Swing foot height.
            if k > 0 {
                let vars: Vec<usize> = (l.q(k)..l.q(k) + nq).collect();
                let (lo, hi) = if k == last {
                    (0.0, 0.0)
                } else if k == l.intervals {
                    (g.swing_clearance_m, inf)
                } else {
                    (0.0, inf)
                };
                self.add(Kind::SwingHeight, vars, &[lo], &[hi]);
            }
        }
        for o in 0..l.m {
            let mut vars = self.point_vars(0, false);
            vars.extend((0..=b).map(|j| l.alpha(o, j)));
            vars.extend([l.theta_plus(), l.theta_minus()]);
            self.add(Kind::OutputStart(o), vars, &[0.0, 0.0], &[0.0, 0.0]);
        }
        for i in 0..l.intervals {
            let (a, m, e) = (2 * i, 2 * i + 1, 2 * i + 2);
            for j in 0..nq {
                let vars = vec![
                    l.q(a) + j,
                    l.q(m) + j,
                    l.q(e) + j,
                    l.dq(a) + j,
                    l.dq(m) + j,
                    l.dq(e) + j,
                    l.ddq(a) + j,
                    l.ddq(m) + j,
                    l.ddq(e) + j,
                    l.duration(),
                ];
                self.add(Kind::Interval, vars, &[0.0; 4], &[0.0; 4]);
            }
        }
        let mut vars = self.point_vars(last, false);
        vars.push(l.length());
        self.add(
            Kind::SwingEnd,
            vars,
            &[0.0, -inf],
            &[0.0, -g.impact_velocity_mps],
        );
        let mut vars: Vec<usize> = (l.q(0)..l.q(0) + nq).collect();
        vars.push(l.theta_plus());
        self.add(Kind::Phase(false), vars, &[0.0], &[0.0]);
        let mut vars: Vec<usize> = (l.q(last)..l.q(last) + nq).collect();
        vars.push(l.theta_minus());
        self.add(Kind::Phase(true), vars, &[0.0], &[0.0]);
        let mut vars = self.point_vars(last, false);
        vars.extend(self.point_vars(0, false));
        let mut lo = vec![0.0; 2 * nq];
        let mut hi = vec![0.0; 2 * nq];
        lo.extend([0.0, 0.0, 0.0, g.liftoff_velocity_mps]);
        hi.extend([inf, inf, inf, inf]);
        self.add(Kind::Impact, vars, &lo, &hi);
        // Cost weights of the slack variables.
        for k in 0..l.points() {
            for a in 0..nu {
                let w = l.simpson_weight(k) * self.config.cost.weights[a];
                self.slack_weights.push((l.p(k) + a, w));
                self.slack_weights.push((l.n(k) + a, w));
            }
        }
    }

    /// A random point used to find structural zeros (deterministic).
    fn probe_point(&self) -> Vec<f64> {
        let mut s = 0x5eed_u64;
        let (lo, hi) = self.bounds();
        (0..self.layout.len())
            .map(|i| {
                let r = lcg(&mut s);
                let (a, b) = (lo[i].max(-1.0), hi[i].min(1.0));
                if a < b {
                    a + (b - a) * (0.2 + 0.6 * r)
                } else {
                    a
                }
            })
            .collect()
    }

    fn build_patterns(&mut self) {
        let x = self.probe_point();
        let mut cache: HashMap<Kind, BlockPatterns> = HashMap::new();
        let mut hess_index: HashMap<(usize, usize), usize> = HashMap::new();
        let mut hess = SparsityPattern::default();
        let mut slot = |r: usize, c: usize, hess: &mut SparsityPattern| -> usize {
            let key = (r.max(c), r.min(c));
            *hess_index.entry(key).or_insert_with(|| {
                hess.push(key.0, key.1);
                hess.rows.len() - 1
            })
        };
        let blocks = std::mem::take(&mut self.blocks);
        let mut built = Vec::with_capacity(blocks.len());
        for mut blk in blocks {
            let (jac, pairs) = cache
                .entry(blk.kind)
                .or_insert_with(|| self.detect(&blk, &x))
                .clone();
            blk.jac_vars = {
                let mut v: Vec<usize> = jac.iter().map(|&(_, j)| j).collect();
                v.sort_unstable();
                v.dedup();
                v
            };
            for &(r, j) in &jac {
                self.jac_rows.push(blk.row0 + r);
                self.jac_cols.push(blk.vars[j]);
            }
            blk.jac = jac;
            blk.hess_slots = pairs
                .iter()
                .map(|&(a, b)| slot(blk.vars[a], blk.vars[b], &mut hess))
                .collect();
            blk.hess = pairs;
            built.push(blk);
        }
        self.blocks = built;
        // Objective: T–slack, slack–d, T–d, d–d.
        let (t, d) = (self.layout.duration(), self.layout.length());
        let sw = self.slack_weights.clone();
        self.obj_slots.t_slack = sw.iter().map(|&(i, _)| slot(t, i, &mut hess)).collect();
        self.obj_slots.slack_d = sw.iter().map(|&(i, _)| slot(i, d, &mut hess)).collect();
        self.obj_slots.t_d = slot(t, d, &mut hess);
        self.obj_slots.d_d = slot(d, d, &mut hess);
        self.hess_pattern = hess;
    }

    /// Structural Jacobian entries and Hessian pairs of a block at the probe point.
    fn detect(&self, blk: &Block, x: &[f64]) -> BlockPatterns {
        let nv = blk.vars.len();
        let z: Vec<f64> = blk.vars.iter().map(|&i| x[i]).collect();
        let mut jac = Vec::new();
        let mut out = vec![Dual64::from(0.0); blk.n_out];
        for j in 0..nv {
            let zd: Vec<Dual64> = z
                .iter()
                .enumerate()
                .map(|(i, &v)| Dual64::new(v, if i == j { 1.0 } else { 0.0 }))
                .collect();
            if self.eval_block(blk.kind, &zd, &mut out).is_err() {
                continue;
            }
            for (r, o) in out.iter().enumerate() {
                if o.eps != 0.0 {
                    jac.push((r, j));
                }
            }
        }
        jac.sort_unstable();
        let mut pairs = Vec::new();
        let mut outh = vec![HyperDual64::from(0.0); blk.n_out];
        for a in 0..nv {
            for b in 0..=a {
                if self.hyper_eval(blk.kind, &z, a, b, &mut outh).is_err() {
                    continue;
                }
                if outh.iter().any(|o| o.eps1eps2 != 0.0) {
                    // Order each pair so the global row index is the larger.
                    pairs.push(if blk.vars[a] >= blk.vars[b] {
                        (a, b)
                    } else {
                        (b, a)
                    });
                }
            }
        }
        (jac, pairs)
    }

    fn hyper_eval(
        &self,
        kind: Kind,
        z: &[f64],
        a: usize,
        b: usize,
        out: &mut [HyperDual64],
    ) -> Result<(), DomainError> {
        let zh: Vec<HyperDual64> = z
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                HyperDual64::new(
                    v,
                    if i == a { 1.0 } else { 0.0 },
                    if i == b { 1.0 } else { 0.0 },
                    0.0,
                )
            })
            .collect();
        self.eval_block(kind, &zh, out)
    }

    /// Evaluates one block at local variables `z`.
    fn eval_block<S: Real>(&self, kind: Kind, z: &[S], out: &mut [S]) -> Result<(), DomainError> {
        let bp = &self.biped;
        let l = &self.layout;
        let (nq, nu) = (l.nq, l.nu);
        let g = &self.config.gait;
        let mu = g.friction_coefficient;
        match kind {
            Kind::Dynamics => {
                let (qr, dqr) = (&z[..nq], &z[nq..2 * nq]);
                let ddqr: Vec<S> = z[2 * nq..3 * nq].iter().map(|&v| v * ACC_SCALE).collect();
                let us = &z[3 * nq..3 * nq + nu];
                let [q, dq, ddq] = bp.full_state(qr, dqr, &ddqr).map_err(|_| DomainError)?;
                let r = bp
                    .model
                    .inverse_dynamics(&q, &dq, &ddq)
                    .map_err(|_| DomainError)?;
                let lam = [r[0], r[1]];
                let jac = bp.stance_jacobian(&q).map_err(|_| DomainError)?;
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
            Kind::OutputDynamics(o) | Kind::OutputStart(o) => {
                let start = matches!(kind, Kind::OutputStart(_));
                let (qr, dqr) = (&z[..nq], &z[nq..2 * nq]);
                let (ddqr, rest): (Vec<S>, &[S]) = if start {
                    (vec![S::zero(); nq], &z[2 * nq..])
                } else {
                    (
                        z[2 * nq..3 * nq].iter().map(|&v| v * ACC_SCALE).collect(),
                        &z[3 * nq..],
                    )
                };
                let alpha = &rest[..=l.degree];
                let (tp, tm) = (rest[l.degree + 1], rest[l.degree + 2]);
                let [q, dq, ddq] = bp.full_state(qr, dqr, &ddqr).map_err(|_| DomainError)?;
                let th = bp
                    .model
                    .stance_leg_angle_derivatives(&q, &dq, &ddq, &bp.legs, bp.stance)
                    .map_err(|_| DomainError)?;
                let span = tm - tp;
                if span.re().abs() < 1e-9 {
                    return Err(DomainError);
                }
                let tau = (th.theta - tp) / span;
                let (tau_d, tau_dd) = (th.rate / span, th.accel / span);
                let (yd, yd1, yd2) = bezier::eval_all(alpha, tau);
                let j = bp.output_coords[o];
                let y = qr[j] - yd;
                let dy = dqr[j] - yd1 * tau_d;
                if start {
                    out[0] = y;
                    out[1] = dy;
                } else {
                    let ddy = ddqr[j] - yd2 * tau_d * tau_d - yd1 * tau_dd;
                    let eps = self.config.collocation.output_gain_per_s;
                    out[0] = (ddy + dy * (2.0 * eps) + y * (eps * eps)) / eps;
                }
            }
            Kind::Interval => {
                let h = z[9] / l.intervals as f64;
                let (qa, qm, qe, va, vm, ve) = (z[0], z[1], z[2], z[3], z[4], z[5]);
                let (aa, am, ae) = (z[6] * ACC_SCALE, z[7] * ACC_SCALE, z[8] * ACC_SCALE);
                out[0] = qm - (qa + qe) * 0.5 - h * (va - ve) / 8.0;
                out[1] = vm - (va + ve) * 0.5 - h * (aa - ae) / 8.0;
                out[2] = qe - qa - h * (va + vm * 4.0 + ve) / 6.0;
                out[3] = ve - va - h * (aa + am * 4.0 + ae) / 6.0;
            }
            Kind::Power(_) => {
                out[0] = z[0] - z[1] - z[2] * TORQUE_SCALE * z[3];
            }
            Kind::SwingHeight | Kind::SwingEnd => {
                let zero = vec![S::zero(); nq];
                let dqr = if kind == Kind::SwingEnd {
                    &z[nq..2 * nq]
                } else {
                    &zero[..]
                };
                let [q, dq, _] = bp
                    .full_state(&z[..nq], dqr, &zero)
                    .map_err(|_| DomainError)?;
                let st = bp.model.body_states(&q, &dq).map_err(|_| DomainError)?;
                let foot = bp.legs.side(bp.swing()).foot;
                let p = bp.model.frame_position_in(&st, foot);
                if kind == Kind::SwingHeight {
                    out[0] = p[1];
                } else {
                    let v = bp.model.frame_velocity_in(&st, foot);
                    out[0] = p[0] - z[2 * nq];
                    out[1] = v[1];
                }
            }
            Kind::Phase(_) => {
                let zero = vec![S::zero(); nq];
                let [q, _, _] = bp
                    .full_state(&z[..nq], &zero, &zero)
                    .map_err(|_| DomainError)?;
                let th = bp
                    .model
                    .stance_leg_angle(&q, &bp.legs, bp.stance)
                    .map_err(|_| DomainError)?;
                out[0] = th - z[nq];
            }
            Kind::Impact => {
                let (qn, dqn) = (&z[..nq], &z[nq..2 * nq]);
                let (q0, dq0) = (&z[2 * nq..3 * nq], &z[3 * nq..4 * nq]);
                let zero = vec![S::zero(); nq];
                let [q, dq, _] = bp.full_state(qn, dqn, &zero).map_err(|_| DomainError)?;
                let swing_foot = bp.legs.side(bp.swing()).foot;
                let imp = bp
                    .model
                    .impact(&q, &dq, swing_foot)
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
                let st = bp
                    .model
                    .body_states(&q, &dq_plus)
                    .map_err(|_| DomainError)?;
                let v = bp
                    .model
                    .frame_velocity_in(&st, bp.legs.side(bp.stance).foot);
                out[2 * nq + 3] = v[1];
            }
        }
        Ok(())
    }

    fn local<T: Copy>(x: &[T], vars: &[usize]) -> Vec<T> {
        vars.iter().map(|&i| x[i]).collect()
    }

    /// Σ_k c_k Σ_a w_a (p + n): the Simpson sum of the absolute power.
    fn power_sum(&self, x: &[f64]) -> f64 {
        self.slack_weights.iter().map(|&(i, w)| w * x[i]).sum()
    }

    /// K = 1 / (6 N M g): Φ = K T S / d.
    fn cost_factor(&self) -> f64 {
        1.0 / (6.0
            * self.layout.intervals as f64
            * self.total_mass_kg
            * self.biped.model.gravity_mps2)
    }

    /// The mechanical cost of transport at x (whether or not it is the objective).
    pub fn cost_of_transport(&self, x: &[f64]) -> f64 {
        self.cost_factor() * x[self.layout.duration()] * self.power_sum(x) / x[self.layout.length()]
    }

    /// Largest violation of any constraint or bound at x.
    pub fn max_violation(&self, x: &[f64]) -> f64 {
        let mut g = vec![0.0; self.num_constraints()];
        if self.constraints(x, &mut g).is_err() {
            return f64::INFINITY;
        }
        let (lo, hi) = self.bounds();
        let cons = g
            .iter()
            .enumerate()
            .map(|(i, &v)| (self.lower_g[i] - v).max(v - self.upper_g[i]).max(0.0));
        let vars = x
            .iter()
            .enumerate()
            .map(|(i, &v)| (lo[i] - v).max(v - hi[i]).max(0.0));
        cons.chain(vars).fold(0.0, f64::max)
    }

    /// Variable bounds.
    pub fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        let l = &self.layout;
        let bp = &self.biped;
        let g = &self.config.gait;
        let inf = f64::INFINITY;
        let mut lo = vec![-inf; l.len()];
        let mut hi = vec![inf; l.len()];
        let joint_of = |c: usize| bp.model.joints.iter().find(|j| j.coordinate == c);
        let p_max = bp
            .model
            .joints
            .iter()
            .filter(|j| j.role == model::robot::JointRole::Actuated)
            .map(|j| j.effort_limit * j.velocity_limit)
            .fold(0.0, f64::max);
        for k in 0..l.points() {
            for (i, &c) in bp.reduced.iter().enumerate() {
                match joint_of(c) {
                    Some(j) => {
                        lo[l.q(k) + i] = j.lower;
                        hi[l.q(k) + i] = j.upper;
                        lo[l.dq(k) + i] = -j.velocity_limit;
                        hi[l.dq(k) + i] = j.velocity_limit;
                    }
                    None => {
                        lo[l.q(k) + i] = g.pitch_limits_rad[0];
                        hi[l.q(k) + i] = g.pitch_limits_rad[1];
                        lo[l.dq(k) + i] = -10.0;
                        hi[l.dq(k) + i] = 10.0;
                    }
                }
            }
            for a in 0..l.nu {
                let c = bp.reduced[bp.actuators[a]];
                let effort = joint_of(c).map(|j| j.effort_limit).unwrap_or(0.0);
                lo[l.u(k) + a] = -effort / TORQUE_SCALE;
                hi[l.u(k) + a] = effort / TORQUE_SCALE;
                lo[l.p(k) + a] = 0.0;
                hi[l.p(k) + a] = p_max;
                lo[l.n(k) + a] = 0.0;
                hi[l.n(k) + a] = p_max;
            }
        }
        for o in 0..l.m {
            let c = bp.reduced[bp.output_coords[o]];
            if let Some(j) = joint_of(c) {
                for jj in 0..=l.degree {
                    lo[l.alpha(o, jj)] = j.lower;
                    hi[l.alpha(o, jj)] = j.upper;
                }
            }
        }
        for i in [l.theta_plus(), l.theta_minus()] {
            lo[i] = -1.0;
            hi[i] = 1.0;
        }
        lo[l.duration()] = g.step_duration_s[0];
        hi[l.duration()] = g.step_duration_s[1];
        lo[l.length()] = g.step_length_m[0];
        hi[l.length()] = g.step_length_m[1];
        (lo, hi)
    }

    /// Constraint bounds (lower, upper).
    pub fn constraint_bounds_vec(&self) -> (&[f64], &[f64]) {
        (&self.lower_g, &self.upper_g)
    }
}

impl NlpProblem for HzdProblem {
    fn num_variables(&self) -> usize {
        self.layout.len()
    }

    fn num_constraints(&self) -> usize {
        self.lower_g.len()
    }

    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        let (lo, hi) = self.bounds();
        lower.copy_from_slice(&lo);
        upper.copy_from_slice(&hi);
    }

    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.lower_g);
        upper.copy_from_slice(&self.upper_g);
    }

    fn initial_point(&self, x0: &mut [f64]) {
        x0.copy_from_slice(&self.initial);
    }

    fn objective(&self, x: &[f64]) -> Result<f64, DomainError> {
        Ok(if self.with_cost {
            self.cost_of_transport(x)
        } else {
            0.0
        })
    }

    fn gradient(&self, x: &[f64], gradient: &mut [f64]) -> Result<(), DomainError> {
        gradient.fill(0.0);
        if !self.with_cost {
            return Ok(());
        }
        let (t_i, d_i) = (self.layout.duration(), self.layout.length());
        let (k, t, d) = (self.cost_factor(), x[t_i], x[d_i]);
        let s = self.power_sum(x);
        for &(i, w) in &self.slack_weights {
            gradient[i] = k * t * w / d;
        }
        gradient[t_i] = k * s / d;
        gradient[d_i] = -k * t * s / (d * d);
        Ok(())
    }

    fn constraints(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        for blk in &self.blocks {
            let z = Self::local(x, &blk.vars);
            self.eval_block(blk.kind, &z, &mut values[blk.row0..blk.row0 + blk.n_out])?;
        }
        Ok(())
    }

    fn jacobian_structure(&self) -> SparsityPattern {
        SparsityPattern {
            rows: self.jac_rows.clone(),
            cols: self.jac_cols.clone(),
        }
    }

    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        let mut at = 0;
        let mut out = Vec::new();
        for blk in &self.blocks {
            let z = Self::local(x, &blk.vars);
            let mut dense = vec![0.0; blk.n_out * blk.vars.len()];
            out.resize(blk.n_out, Dual64::from(0.0));
            for &j in &blk.jac_vars {
                let zd: Vec<Dual64> = z
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| Dual64::new(v, if i == j { 1.0 } else { 0.0 }))
                    .collect();
                self.eval_block(blk.kind, &zd, &mut out[..blk.n_out])?;
                for (r, o) in out[..blk.n_out].iter().enumerate() {
                    dense[r * blk.vars.len() + j] = o.eps;
                }
            }
            for &(r, j) in &blk.jac {
                values[at] = dense[r * blk.vars.len() + j];
                at += 1;
            }
        }
        Ok(())
    }

    fn hessian_structure(&self) -> SparsityPattern {
        self.hess_pattern.clone()
    }

    fn hessian_values(
        &self,
        x: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        values.fill(0.0);
        let mut out = Vec::new();
        for blk in &self.blocks {
            let mu = &multipliers[blk.row0..blk.row0 + blk.n_out];
            if mu.iter().all(|&m| m == 0.0) {
                continue;
            }
            let z = Self::local(x, &blk.vars);
            out.resize(blk.n_out, HyperDual64::from(0.0));
            for (&(a, b), &slot) in blk.hess.iter().zip(&blk.hess_slots) {
                self.hyper_eval(blk.kind, &z, a, b, &mut out[..blk.n_out])?;
                values[slot] += out[..blk.n_out]
                    .iter()
                    .zip(mu)
                    .map(|(o, m)| o.eps1eps2 * m)
                    .sum::<f64>();
            }
        }
        if self.with_cost && objective_factor != 0.0 {
            let (k, t, d) = (
                self.cost_factor(),
                x[self.layout.duration()],
                x[self.layout.length()],
            );
            let s = self.power_sum(x);
            let sf = objective_factor * k;
            for (n, &(_, w)) in self.slack_weights.iter().enumerate() {
                values[self.obj_slots.t_slack[n]] += sf * w / d;
                values[self.obj_slots.slack_d[n]] += -sf * t * w / (d * d);
            }
            values[self.obj_slots.t_d] += -sf * s / (d * d);
            values[self.obj_slots.d_d] += 2.0 * sf * t * s / (d * d * d);
        }
        Ok(())
    }
}
