//! The HZD gait optimization as a sparse NLP: Hermite–Simpson direct collocation of the
//! single-domain hybrid system (paper Sec. II–III), with exact derivatives from dual numbers.
//!
//! # Transcription
//! N intervals, 2N + 1 points k (even k: nodes, odd k: midpoints), step duration T a variable and
//! h = T/N. At every point: reduced state q_r, q̇_r, q̈_r (pinned stance, see [`crate::biped`]),
//! torques u and, in the cost-of-transport problem, the positive/negative parts p, n of each
//! actuator's power (the feasibility problem has no cost and no power slacks). Global variables: the
//! Bézier coefficients α (m × (b+1)), θ⁺ and θ⁻ of the phase variable, T, and the step length d.
//!
//! Constraints (all from [`crate::config::PlannerConfig`]):
//! - **pinned-stance dynamics** at every point: D q̈ + H = B u + J_stᵀ λ with λ the stance force,
//!   computed from the x and z rows; λ_z ≥ λ_min and |λ_x| ≤ μ λ_z (friction cone);
//! - **Hermite–Simpson** (separated form): midpoint interpolation and Simpson defects for q and q̇;
//! - **virtual constraints** the way FROST enforces them: y = ẏ = 0 at the first point and the
//!   output dynamics ÿ + 2εẏ + ε²y = 0 at every point (PLANNER-NOTES: position-level y = 0 at
//!   every point over-constrains the interpolant and does not converge);
//! - **phase** (lifted: τ, τ̇, τ̈ are variables at every point): θ(q) − θ⁺ = τ (θ⁻ − θ⁺) and its
//!   first and second time derivatives, with τ = 0 at the first point and τ = 1 at the last;
//! - **swing foot**: z_nsf ≥ c·4s(1−s) at every interior point (s = k/2N, c the mid-step
//!   clearance: the foot stays clear of the ground, not merely above it), = 0 at the end
//!   (the guard) with ż_nsf ≤ −v_impact, x_nsf = d at the end;
//! - **impact and periodicity** (the HZD condition, with y = ẏ = 0 at the start):
//!   x_0 = relabel(Δ(x_2N)); the impact impulse inside the friction cone; the old stance foot
//!   leaves the ground (upward velocity after impact);
//! - bounds: joint limits, A1 torque and speed limits, torso pitch, Table I (d, T).
//!
//! Cost: the weighted mechanical cost of transport Φ = 1/(M g d) Σ_i w_i ∫ |u_i q̇_i| dt with
//! |u q̇| = p + n, p − n = u q̇, p, n ≥ 0 (slack variables), integrated with Simpson's rule.
//! The cost stage creates p and n from the feasible point's u q̇, just off the bound the cost
//! pushes them to ([`Layout::with_slacks`], [`HzdProblem::centre_power_slacks`]). (A smooth
//! √(P² + δ²) − δ instead of the slacks was measured and not kept: planner/NLP.md, "Eleventh
//! round".)
//!
//! # Derivatives
//! Each constraint group is a *block*: a generic function of a few variables. Jacobians come from
//! forward-mode `Dual64` sweeps (one per block variable), Lagrangian Hessians from `HyperDual64`
//! evaluations of Σ μ_r c_r (one per structurally non-zero variable pair). Structural zeros are
//! found once per block kind at set-up by evaluating at a random point. In the solve loop the
//! sweeps run four at a time ([`crate::nlp::lanes`]: `Dual<Lanes<4>>`, `HyperDual<Lanes<4>>`,
//! bit for bit the scalar results) and the blocks are spread over the rayon pool when the
//! caller is not already on it; contributions to shared Hessian entries are added in block
//! order, so the values never depend on the schedule. Each model block runs the kinematics once
//! per evaluation, with the floating base at rest at the origin
//! ([`PlanarBiped::states_at_rest_base`]): inverse dynamics, the stance-foot Jacobian, the
//! stance-leg angle and the swing foot relative to the stance foot depend only on relative
//! positions, so the pinned-stance base enters only through the base acceleration that keeps
//! the stance foot still. The objective's
//! derivatives are hand-derived and checked against finite differences in the tests.
//! Acceleration and torque variables are scaled by 1/10 (PLANNER-NOTES: 219 → 78 iterations).

use crate::biped::PlanarBiped;
use crate::config::PlannerConfig;
use crate::nlp::lanes::Lanes;
use crate::nlp::{DomainError, NlpProblem, SparsityPattern};
use model::bezier;
use model::kinematics::{BodyStates, Constant};
use model::num_dual::{Dual, Dual64, HyperDual, HyperDual64};
use model::robot::BodyInertia;
use model::robot::MAX_DOF;
use model::Real;
use std::collections::HashMap;

/// q̈ = `ACC_SCALE` × its variable.
pub const ACC_SCALE: f64 = 10.0;
/// u = `TORQUE_SCALE` × its variable.
pub const TORQUE_SCALE: f64 = 10.0;

/// Seeds (Jacobian columns or Hessian pairs) differentiated together in one block evaluation
/// ([`Lanes`]): bit for bit the one-seed-per-evaluation results, with the kinematics and the
/// bookkeeping of an evaluation shared by this many seeds.
const SEED_LANES: usize = 4;

/// Working memory of one block evaluation, reused across the seed passes of a derivative sweep.
struct Scratch<S> {
    /// Body states of the evaluation's kinematics pass.
    st: BodyStates<S>,
    /// Mass properties of each body (the first `bodies.len()`).
    inertias: [model::robot::BodyInertia<S>; model::robot::MAX_BODIES],
    /// Joint accelerations (the first `dof` entries are used).
    ddq: [S; MAX_DOF],
    /// Stance-foot Jacobian, column by column.
    jac: [[S; 2]; MAX_DOF],
    /// Inverse-dynamics output.
    r: [S; MAX_DOF],
}

impl<S: Real> Scratch<S> {
    fn new() -> Self {
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

/// Per-worker buffers of a derivative sweep over the blocks: the block scratch, the seeded
/// local variables, the block outputs and a dense Jacobian.
struct SweepWork<S> {
    scratch: Scratch<S>,
    z: Vec<S>,
    out: Vec<S>,
    dense: Vec<f64>,
}

impl<S: Real> SweepWork<S> {
    fn new() -> Self {
        Self {
            scratch: Scratch::new(),
            z: Vec::new(),
            out: Vec::new(),
            dense: Vec::new(),
        }
    }

    /// Zeroed outputs (`n_out`) and dense Jacobian (`n_out` × `nv`) for a block's sweep.
    fn prepare(&mut self, n_out: usize, nv: usize) {
        self.dense.clear();
        self.dense.resize(n_out * nv, 0.0);
        self.out.clear();
        self.out.resize(n_out, S::zero());
    }
}

/// Fills `z` with a block's local variables at `x` (global indices `vars`) as four-lane
/// hyper-dual numbers: lane l has ε₁ on local variable a and ε₂ on b for the l-th seed
/// (a, Some(b)), or ε₁ alone for (a, None) (at most [`SEED_LANES`] seeds).
fn seed_hyper_duals(
    x: &[f64],
    vars: &[usize],
    seeds: impl Iterator<Item = (usize, Option<usize>)> + Clone,
    z: &mut Vec<HyperDual<Lanes<SEED_LANES>>>,
) {
    z.clear();
    z.extend(vars.iter().enumerate().map(|(i, &g)| {
        let (mut eps1, mut eps2) = ([0.0; SEED_LANES], [0.0; SEED_LANES]);
        for (l, (a, b)) in seeds.clone().enumerate() {
            if i == a {
                eps1[l] = 1.0;
            }
            if b == Some(i) {
                eps2[l] = 1.0;
            }
        }
        HyperDual::new(
            Lanes::splat(x[g]),
            Lanes(eps1),
            Lanes(eps2),
            Lanes::splat(0.0),
        )
    }));
}

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
    /// Design variables (0, or 2 in a co-design: thigh and shin length, m).
    pub design: usize,
    /// Whether each point has the power slacks p, n (the cost-of-transport problem does; the
    /// feasibility problem, which has no cost on them, does not).
    pub slacks: bool,
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
    /// Index of the phase τ at point k (followed by τ̇ and τ̈): lifted variables, so that the
    /// costly stance-leg kinematics is differentiated once per point, not once per output.
    pub fn tau(&self, k: usize) -> usize {
        k * self.stride + self.stride - 3
    }
    /// Number of variables of the same problem without power slacks (the feasibility layout).
    pub fn len_without_slacks(&self) -> usize {
        if self.slacks {
            self.len() - 2 * self.nu * self.points()
        } else {
            self.len()
        }
    }

    /// A point of the layout without power slacks (`x`, [`Self::len_without_slacks`] long)
    /// in this one, with p = n = 0 (see [`HzdProblem::centre_power_slacks`]). An `x` of
    /// another length (or a layout without slacks) is an error naming both lengths.
    pub fn with_slacks(&self, x: &[f64]) -> crate::Result<Vec<f64>> {
        let expected = self.len_without_slacks();
        if !self.slacks || x.len() != expected {
            return Err(crate::PlannerError::Solver(format!(
                "a point without power slacks has {expected} variables here, this one {}{}",
                x.len(),
                if self.slacks {
                    ""
                } else {
                    " (and this layout has no slacks to add)"
                }
            )));
        }
        let short = self.stride - 2 * self.nu;
        let mut out = vec![0.0; self.len()];
        for k in 0..self.points() {
            let (a, b) = (k * short, k * self.stride);
            out[b..b + 3 * self.nq + self.nu].copy_from_slice(&x[a..a + 3 * self.nq + self.nu]);
            out[b + self.stride - 3..b + self.stride].copy_from_slice(&x[a + short - 3..a + short]);
        }
        let (ga, gb) = (self.points() * short, self.points() * self.stride);
        out[gb..].copy_from_slice(&x[ga..]);
        Ok(out)
    }
    fn globals(&self) -> usize {
        self.points() * self.stride
    }
    /// Index of `α[o][j]`.
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
    /// Index of design variable i (0: thigh length, 1: shin length, m) in a co-design.
    pub fn design_var(&self, i: usize) -> usize {
        self.theta_plus() + 4 + i
    }
    /// Number of variables.
    pub fn len(&self) -> usize {
        self.theta_plus() + 4 + self.design
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
    /// θ(q) − θ⁺ = τ Δθ, θ̇ = τ̇ Δθ, θ̈ = τ̈ Δθ at one point.
    PhaseLift,
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
    /// Impact and periodicity.
    Impact,
    /// τ at the first and last point (equalities, not fixed bounds: fixed variables make an
    /// interior point's barrier ill-conditioned).
    TauEnds,
}

impl Kind {
    /// What the constraint group means, for reports and errors.
    fn describe(self) -> String {
        match self {
            Kind::Dynamics => "pinned-stance dynamics and contact forces".into(),
            Kind::PhaseLift => "phase variable".into(),
            Kind::OutputDynamics(o) => format!("virtual constraint {o} (output dynamics)"),
            Kind::OutputStart(o) => format!("virtual constraint {o} at the step start"),
            Kind::Interval => "collocation defects".into(),
            Kind::Power(c) => format!("power slacks (coordinate {c})"),
            Kind::SwingHeight => "swing-foot clearance".into(),
            Kind::SwingEnd => "swing foot at impact (guard, step length, descent)".into(),
            Kind::Impact => "impact, periodicity, impulse and lift-off".into(),
            Kind::TauEnds => "phase at the step ends".into(),
        }
    }
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
    /// Hyper-dual seeds: first the local variable pairs `(a, Some(b))` (a ≥ b by global
    /// index) with a structurally non-zero Hessian, one per `hess_slots` entry; then, for the
    /// kinds whose Jacobian is read off these passes
    /// ([`HzdProblem::shares_jacobian_with_hessian`]), `(j, None)` for every Jacobian column
    /// no pair covers.
    seeds: Vec<(usize, Option<usize>)>,
    /// Slot in the global Hessian value array of each pair.
    hess_slots: Vec<usize>,
}

impl Block {
    /// The Hessian pairs: the first seeds.
    fn pairs(&self) -> &[(usize, Option<usize>)] {
        &self.seeds[..self.hess_slots.len()]
    }

    /// Whether all of this block's multipliers are zero (it adds nothing to the Hessian).
    fn inactive(&self, multipliers: &[f64]) -> bool {
        multipliers[self.row0..self.row0 + self.n_out]
            .iter()
            .all(|&m| m == 0.0)
    }
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
    design: Option<DesignModel>,
    /// The model's mass properties, body by body, as [`Constant`]s.
    constant_inertias: Vec<BodyInertia<Constant>>,
    /// The barrier parameter the start point is centred for ([`Self::centre_power_slacks`]).
    initial_barrier: Option<f64>,
}

#[derive(Clone, Debug, Default)]
struct ObjectiveSlots {
    t_slack: Vec<usize>,
    slack_d: Vec<usize>,
    t_d: usize,
    d_d: usize,
    /// Diagonal slots of the scaled torques (feasibility-stage regularizer).
    torque: Vec<usize>,
}

/// Weight of the feasibility stage's torque regularizer Σ_k Σ_a (u_ka / 10 N·m)²: small enough
/// not to shape the gait, large enough to give the interior point a bounded, strictly convex
/// objective in the torques (a zero objective left the first solve wandering for minutes).
pub const FEASIBILITY_TORQUE_WEIGHT: f64 = 1e-4;

/// Co-design (paper Sec. III): the thigh and shin lengths become NLP variables. They enter
/// through the design virtual joints q_D = L − L_nominal, the same in both legs (so q_LT = q_RT
/// and q_LS = q_RS hold by construction) and constant over the step (q̇_D = 0: they are
/// parameters of every point); the relabeling keeps them.
#[derive(Clone, Debug, PartialEq)]
pub struct Codesign {
    /// Total thigh and shin length at design-joint zero (the model's own links), m.
    pub nominal_m: [f64; 2],
    /// Bounds on the total thigh and shin length, m (paper Table I: 0.15–0.35).
    pub bounds_m: [[f64; 2]; 2],
    /// Link mass properties follow the lengths through the cubic fits inside the NLP (exact
    /// coupling, differentiated with everything else); false: frozen at the model's (the
    /// inner solve of the paper's Alg. 1).
    pub exact_inertia: bool,
}

/// What the co-design needs of the model: the thigh and shin bodies of both legs and the fits.
#[derive(Clone, Debug)]
struct DesignModel {
    spec: Codesign,
    /// Body index of the left and right thigh, and of the left and right shin.
    thigh_bodies: [usize; 2],
    shin_bodies: [usize; 2],
    fits: model::design::InertiaFits,
    base: Vec<model::robot::BodyInertia<f64>>,
}

/// Structural Jacobian entries (local output, local var) and Hessian pairs (local, local).
type Pattern = (Vec<(usize, usize)>, Vec<(usize, usize)>);

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
        Self::with_codesign(biped, config, initial, with_cost, None)
    }

    /// Builds the problem, with the thigh and shin lengths as variables if `codesign` is given
    /// (the model must have design joints in both legs).
    pub fn with_codesign(
        biped: PlanarBiped,
        config: PlannerConfig,
        initial: Vec<f64>,
        with_cost: bool,
        codesign: Option<Codesign>,
    ) -> crate::Result<Self> {
        // The power slacks only serve the cost: the feasibility problem has none.
        let slacks = with_cost;
        let design = match codesign {
            None => None,
            Some(spec) => {
                let robot_error = |reason: String| crate::PlannerError::Robot {
                    robot: biped.model.name.clone(),
                    reason,
                };
                let mut thigh_bodies = [0; 2];
                let mut shin_bodies = [0; 2];
                for (k, side) in [model::Side::Left, model::Side::Right]
                    .into_iter()
                    .enumerate()
                {
                    let leg = biped.legs.side(side);
                    if leg.thigh_design.is_none() || leg.shin_design.is_none() {
                        return Err(robot_error(format!(
                            "co-design needs thigh and shin design joints in the {side:?} leg"
                        )));
                    }
                    thigh_bodies[k] = biped.model.joints[leg.hip].body;
                    shin_bodies[k] = biped.model.joints[leg.knee].body;
                }
                Some(DesignModel {
                    spec,
                    thigh_bodies,
                    shin_bodies,
                    fits: model::design::InertiaFits::adam(),
                    base: biped.model.bodies.iter().map(|b| b.inertia).collect(),
                })
            }
        };
        let layout = Layout {
            nq: biped.nq(),
            nu: biped.nu(),
            m: biped.outputs.len(),
            degree: config.collocation.bezier_degree,
            intervals: config.collocation.intervals,
            stride: 3 * biped.nq() + if slacks { 3 } else { 1 } * biped.nu() + 3,
            design: if design.is_some() { 2 } else { 0 },
            slacks,
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
        let constant_inertias = biped.model.constant_inertias();
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
            constant_inertias,
            initial_barrier: None,
            design,
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
            seeds: Vec::new(),
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
            // Lifted phase and output dynamics.
            let mut vars = self.point_vars(k, true);
            vars.extend([
                l.theta_plus(),
                l.theta_minus(),
                l.tau(k),
                l.tau(k) + 1,
                l.tau(k) + 2,
            ]);
            self.add(Kind::PhaseLift, vars, &[0.0; 3], &[0.0; 3]);
            for o in 0..l.m {
                let j = self.biped.output_coords[o];
                let mut vars = vec![
                    l.q(k) + j,
                    l.dq(k) + j,
                    l.ddq(k) + j,
                    l.tau(k),
                    l.tau(k) + 1,
                    l.tau(k) + 2,
                ];
                vars.extend((0..=b).map(|jj| l.alpha(o, jj)));
                self.add(Kind::OutputDynamics(o), vars, &[0.0], &[0.0]);
            }
            // Power slacks.
            for a in (0..nu).filter(|_| l.slacks) {
                let c = self.biped.actuators[a];
                let vars = vec![l.p(k) + a, l.n(k) + a, l.u(k) + a, l.dq(k) + c];
                self.add(Kind::Power(c), vars, &[0.0], &[0.0]);
            }
            // Swing foot height.
            if k > 0 {
                let vars: Vec<usize> = (l.q(k)..l.q(k) + nq).collect();
                // Interior points keep the swing foot above a parabola that peaks at the
                // mid-step clearance: z ≥ 0 alone let the optimum graze the ground (0.04 mm
                // below it between points near τ = 0.85) and the robot tripped in simulation.
                let s = k as f64 / last as f64;
                let (lo, hi) = if k == last {
                    (0.0, 0.0)
                } else {
                    (g.swing_clearance_m * 4.0 * s * (1.0 - s), inf)
                };
                self.add(Kind::SwingHeight, vars, &[lo], &[hi]);
            }
        }
        for o in 0..l.m {
            let j = self.biped.output_coords[o];
            let mut vars = vec![
                l.q(0) + j,
                l.dq(0) + j,
                l.ddq(0) + j,
                l.tau(0),
                l.tau(0) + 1,
                l.tau(0) + 2,
            ];
            vars.extend((0..=b).map(|jj| l.alpha(o, jj)));
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
        self.add(
            Kind::TauEnds,
            vec![l.tau(0), l.tau(last)],
            &[0.0, 1.0],
            &[0.0, 1.0],
        );
        let mut vars = self.point_vars(last, false);
        vars.extend(self.point_vars(0, false));
        let mut lo = vec![0.0; 2 * nq];
        let mut hi = vec![0.0; 2 * nq];
        lo.extend([0.0, 0.0, 0.0, g.liftoff_velocity_mps]);
        hi.extend([inf, inf, inf, inf]);
        self.add(Kind::Impact, vars, &lo, &hi);
        // Co-design: every block that evaluates the model also sees the two lengths.
        if l.design > 0 {
            let dv = [l.design_var(0), l.design_var(1)];
            for blk in &mut self.blocks {
                if Self::uses_model(blk.kind) {
                    blk.vars.extend(dv);
                }
            }
        }
        // Cost weights of the slack variables.
        for k in 0..l.points() {
            for a in (0..nu).filter(|_| l.slacks) {
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
        let mut cache: HashMap<Kind, Pattern> = HashMap::new();
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
            blk.seeds = pairs.iter().map(|&(a, b)| (a, Some(b))).collect();
            if Self::shares_jacobian_with_hessian(blk.kind) {
                let covered = |j: usize| pairs.iter().any(|&(a, b)| a == j || b == j);
                blk.seeds.extend(
                    blk.jac_vars
                        .iter()
                        .filter(|&&j| !covered(j))
                        .map(|&j| (j, None)),
                );
            }
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
        let l = &self.layout;
        self.obj_slots.torque = (0..l.points())
            .flat_map(|k| (0..l.nu).map(move |a| l.u(k) + a))
            .map(|i| slot(i, i, &mut hess))
            .collect();
        self.hess_pattern = hess;
    }

    /// Structural Jacobian entries and Hessian pairs of a block at the probe point.
    fn detect(&self, blk: &Block, x: &[f64]) -> Pattern {
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

    /// Whether a block kind's Jacobian is read off its Hessian passes
    /// ([`Self::block_hyper_sweep`]): the kinds with Hessian pairs whose evaluation
    /// divides no dual number by another. num-dual's `Dual` and `HyperDual` apply the same
    /// first-order rules to sums, products, scalars and functions (the same products, added
    /// in either order), so a hyper-dual pass's ε₁ and ε₂ parts are the `Dual` sweep's
    /// Jacobian columns bit for bit; their quotient rules round differently (the stance-leg
    /// angle's rate, `atan2`, the impact map's elimination), so those kinds keep their own
    /// sweep. The test `merged_jacobian_and_hessian_are_the_separate_sweeps_bits` compares the
    /// merged values with the separate sweeps' bits; it fails with `PhaseLift` or `Impact`
    /// added here.
    fn shares_jacobian_with_hessian(kind: Kind) -> bool {
        matches!(
            kind,
            Kind::Dynamics
                | Kind::OutputDynamics(_)
                | Kind::OutputStart(_)
                | Kind::Interval
                | Kind::Power(_)
                | Kind::SwingHeight
                | Kind::SwingEnd
        )
    }

    /// Whether a block kind evaluates the robot model (and so depends on the design).
    fn uses_model(kind: Kind) -> bool {
        matches!(
            kind,
            Kind::Dynamics | Kind::PhaseLift | Kind::SwingHeight | Kind::SwingEnd | Kind::Impact
        )
    }

    /// The design-joint values [thigh, shin] of a model block's local variables (its last two
    /// are the total lengths in a co-design), or None without co-design.
    fn design_joints_of<S: Real>(&self, kind: Kind, z: &[S]) -> Option<[S; 2]> {
        let d = self.design.as_ref()?;
        if !Self::uses_model(kind) {
            return None;
        }
        let n = z.len();
        Some([
            z[n - 2] - d.spec.nominal_m[0],
            z[n - 1] - d.spec.nominal_m[1],
        ])
    }

    /// The model's own mass properties as constants, unless a model block's depend on its
    /// variables (co-design with exact inertia coupling): then `None`, and
    /// [`Self::inertias_of`] gives them.
    fn constant_inertias_for(&self, kind: Kind) -> Option<&[BodyInertia<Constant>]> {
        let exact = self
            .design
            .as_ref()
            .is_some_and(|d| d.spec.exact_inertia && Self::uses_model(kind));
        (!exact).then_some(self.constant_inertias.as_slice())
    }

    /// Body mass properties at the lengths of a model block's local variables: the cubic fits
    /// for thighs and shins under exact coupling, the model's own otherwise. Written into a
    /// caller's fixed array (no allocation or copy per evaluation); the first `bodies.len()`
    /// entries are set.
    fn inertias_of<S: Real>(
        &self,
        kind: Kind,
        z: &[S],
        all: &mut [model::robot::BodyInertia<S>; model::robot::MAX_BODIES],
    ) {
        let lift = |i: &model::robot::BodyInertia<f64>| model::robot::BodyInertia {
            mass_kg: S::from(i.mass_kg),
            com_xz_m: [S::from(i.com_xz_m[0]), S::from(i.com_xz_m[1])],
            inertia_yy_kgm2: S::from(i.inertia_yy_kgm2),
        };
        let design = self
            .design
            .as_ref()
            .filter(|d| d.spec.exact_inertia && Self::uses_model(kind));
        let Some(d) = design else {
            for (a, b) in all.iter_mut().zip(&self.biped.model.bodies) {
                *a = lift(&b.inertia);
            }
            return;
        };
        for (a, i) in all.iter_mut().zip(&d.base) {
            *a = lift(i);
        }
        let n = z.len();
        let (lt, ls) = (z[n - 2], z[n - 1]);
        let link = |fit: &model::design::LinkFit, len: S| model::robot::BodyInertia {
            mass_kg: fit.mass_kg.eval(len),
            com_xz_m: [S::zero(), -fit.com_distance_m.eval(len)],
            inertia_yy_kgm2: fit.iyy_kgm2.eval(len),
        };
        for &b in &d.thigh_bodies {
            all[b] = link(&d.fits.thigh, lt);
        }
        for &b in &d.shin_bodies {
            all[b] = link(&d.fits.shin, ls);
        }
    }

    /// Evaluates one block at local variables `z` (set-up and tests; the solve loop reuses one
    /// [`Scratch`] per block and derivative sweep through [`Self::eval_block_in`]).
    fn eval_block<S: Real>(&self, kind: Kind, z: &[S], out: &mut [S]) -> Result<(), DomainError> {
        self.eval_block_in(kind, z, out, &mut Scratch::new())
    }

    /// Evaluates one block at local variables `z`, with `scratch` for the body states and mass
    /// properties (wide dual numbers make these tens of kilobytes: zeroing them once per block
    /// instead of once per seed pass matters).
    fn eval_block_in<S: Real>(
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
            Kind::Interval => {
                let h = z[9] / l.intervals as f64;
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
        }
        Ok(())
    }

    fn torque_vars(&self) -> impl Iterator<Item = usize> + '_ {
        let l = &self.layout;
        (0..l.points()).flat_map(move |k| (0..l.nu).map(move |a| l.u(k) + a))
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

    /// Moves the start point's power slacks onto the central path of the barrier parameter
    /// `mu_init` for this problem's cost, and makes `mu_init` the solve's initial barrier
    /// parameter ([`Self::initial_barrier`]).
    ///
    /// p = max(u q̇, 0) + δ and n = max(−u q̇, 0) + δ, so p − n = u q̇ holds, with
    /// δ = μ₀ / (∂Φ/∂p) the distance from the bound at which the barrier's push μ₀/δ equals the
    /// cost's pull (1 W where an actuator's weight is zero; the solver's bound push keeps a p or n
    /// that ends above its bound inside). Nothing else moves. (When the
    /// feasibility problem still had the slacks, with no cost on them, its barrier left them near
    /// the middle of their bounds, hundreds of watts where |u q̇| is below one: started there, the
    /// cost stage began at a cost of transport of ~100 and spent most of its iterations bringing
    /// them down.)
    pub fn centre_power_slacks(&mut self, mu_init: f64) {
        let l = &self.layout;
        let (t, d) = (self.initial[l.duration()], self.initial[l.length()]);
        let pull = self.cost_factor() * t / d;
        for k in 0..l.points() {
            for (a, &c) in self.biped.actuators.iter().enumerate() {
                let power = TORQUE_SCALE * self.initial[l.u(k) + a] * self.initial[l.dq(k) + c];
                let w = l.simpson_weight(k) * self.config.cost.weights[a];
                let delta = if pull * w > 0.0 {
                    mu_init / (pull * w)
                } else {
                    1.0
                };
                self.initial[l.p(k) + a] = power.max(0.0) + delta;
                self.initial[l.n(k) + a] = (-power).max(0.0) + delta;
            }
        }
        self.initial_barrier = Some(mu_init);
    }

    /// Replaces the start point (`x`, [`Layout::len`] long).
    pub fn set_initial(&mut self, x: Vec<f64>) {
        debug_assert_eq!(x.len(), self.layout.len());
        self.initial = x;
        self.initial_barrier = None;
    }

    /// The initial barrier parameter the start point is centred for, if any
    /// ([`Self::centre_power_slacks`]).
    pub fn initial_barrier(&self) -> Option<f64> {
        self.initial_barrier
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
                if l.slacks {
                    lo[l.p(k) + a] = 0.0;
                    hi[l.p(k) + a] = p_max;
                    lo[l.n(k) + a] = 0.0;
                    hi[l.n(k) + a] = p_max;
                }
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
        if let Some(d) = &self.design {
            for i in 0..2 {
                lo[l.design_var(i)] = d.spec.bounds_m[i][0];
                hi[l.design_var(i)] = d.spec.bounds_m[i][1];
            }
        }
        (lo, hi)
    }

    /// Per block kind: (blocks, Jacobian entries per block, Hessian pairs per block), for profiling.
    pub fn block_statistics(&self) -> Vec<(String, usize, usize, usize)> {
        let mut out: Vec<(String, usize, usize, usize)> = Vec::new();
        for b in &self.blocks {
            let name = format!("{:?}", b.kind);
            if let Some(e) = out.iter_mut().find(|e| e.0 == name) {
                e.1 += 1;
            } else {
                out.push((name, 1, b.jac.len(), b.hess_slots.len()));
            }
        }
        out
    }

    /// Largest violation per block kind at x, for diagnosing a start point or a failed solve.
    pub fn violation_by_kind(&self, x: &[f64]) -> Vec<(String, f64)> {
        let mut g = vec![0.0; self.num_constraints()];
        let _ = self.constraints(x, &mut g);
        let mut out: Vec<(String, f64)> = Vec::new();
        for b in &self.blocks {
            let v = (b.row0..b.row0 + b.n_out)
                .map(|i| {
                    (self.lower_g[i] - g[i])
                        .max(g[i] - self.upper_g[i])
                        .max(0.0)
                })
                .fold(0.0, f64::max);
            let name = b.kind.describe();
            match out.iter_mut().find(|e| e.0 == name) {
                Some(e) => e.1 = e.1.max(v),
                None => out.push((name, v)),
            }
        }
        out
    }

    /// `f(work, block, values)` for every block with its own run of `values` (`len(block)`
    /// entries each, in block order): on the rayon pool when called outside it (one plan: both
    /// cores evaluate), sequentially inside it (a co-design sweep already keeps every core busy
    /// with whole runs). Each worker reuses one [`SweepWork`], so a sweep allocates and zeroes
    /// its dual-number buffers a few times, not once per block. Results do not depend on the
    /// schedule: each block writes only its own run.
    fn for_each_block<S: Real + Send>(
        &self,
        values: &mut [f64],
        len: impl Fn(&Block) -> usize,
        f: impl Fn(&mut SweepWork<S>, &Block, &mut [f64]) -> Result<(), DomainError> + Sync + Send,
    ) -> Result<(), DomainError> {
        self.for_each_run(self.runs(values, len), SweepWork::new, f)
    }

    /// Each block with its own run of `values` (`len(block)` entries each, in block order).
    fn runs<'v>(&self, values: &'v mut [f64], len: impl Fn(&Block) -> usize) -> Vec<&'v mut [f64]> {
        let mut runs = Vec::with_capacity(self.blocks.len());
        let mut rest = values;
        for blk in &self.blocks {
            let (run, tail) = rest.split_at_mut(len(blk));
            runs.push(run);
            rest = tail;
        }
        runs
    }

    /// `f(work, block, run)` for every block and its run (see [`Self::for_each_block`]), with
    /// per-worker buffers from `init`.
    fn for_each_run<W: Send, R: Send>(
        &self,
        runs: Vec<R>,
        init: impl Fn() -> W + Sync + Send,
        f: impl Fn(&mut W, &Block, R) -> Result<(), DomainError> + Sync + Send,
    ) -> Result<(), DomainError> {
        use rayon::prelude::*;
        let runs: Vec<(&Block, R)> = self.blocks.iter().zip(runs).collect();
        if rayon::current_thread_index().is_some() {
            let mut work = init();
            runs.into_iter()
                .try_for_each(|(blk, run)| f(&mut work, blk, run))
        } else {
            runs.into_par_iter()
                .try_for_each_init(init, |work, (blk, run)| f(work, blk, run))
        }
    }

    /// A block's structural Jacobian entries, in [`Block::jac`] order, into `values`. Lane l of
    /// one evaluation is the `Dual64` sweep of the chunk's column l.
    fn block_jacobian(
        &self,
        x: &[f64],
        blk: &Block,
        work: &mut SweepWork<Dual<Lanes<SEED_LANES>>>,
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        let nv = blk.vars.len();
        work.prepare(blk.n_out, nv);
        let SweepWork {
            scratch,
            z,
            out,
            dense,
        } = work;
        for chunk in blk.jac_vars.chunks(SEED_LANES) {
            z.clear();
            z.extend(blk.vars.iter().enumerate().map(|(i, &g)| {
                let mut eps = [0.0; SEED_LANES];
                for (l, &j) in chunk.iter().enumerate() {
                    if i == j {
                        eps[l] = 1.0;
                    }
                }
                Dual::new(Lanes::splat(x[g]), Lanes(eps))
            }));
            self.eval_block_in(blk.kind, z, out, scratch)?;
            for (l, &j) in chunk.iter().enumerate() {
                for (r, o) in out.iter().enumerate() {
                    dense[r * nv + j] = o.eps.0[l];
                }
            }
        }
        for (v, &(r, j)) in values.iter_mut().zip(&blk.jac) {
            *v = dense[r * nv + j];
        }
        Ok(())
    }

    /// A block's contribution Σ_r μ_r ∂²c_r to each of its Hessian pairs, in
    /// [`Block::pairs`] order, into `hess`; with `jac`, also its Jacobian entries
    /// ([`Block::jac`] order) read off the same passes, over all of [`Block::seeds`] (for an
    /// active block of a kind that [`Self::shares_jacobian_with_hessian`]). Lane l of one
    /// evaluation is the `HyperDual64` evaluation of the chunk's seed l: its ε₁ (and ε₂) parts
    /// are the Jacobian columns of its variables as a `Dual64` sweep gives them, its ε₁ε₂
    /// part the pair's second derivatives; a Jacobian-only seed has no ε₂ and adds no
    /// Hessian entry.
    fn block_hyper_sweep(
        &self,
        x: &[f64],
        multipliers: &[f64],
        blk: &Block,
        work: &mut SweepWork<HyperDual<Lanes<SEED_LANES>>>,
        hess: &mut [f64],
        jac: Option<&mut [f64]>,
    ) -> Result<(), DomainError> {
        let nv = blk.vars.len();
        let mu = &multipliers[blk.row0..blk.row0 + blk.n_out];
        let seeds = if jac.is_some() {
            &blk.seeds[..]
        } else {
            blk.pairs()
        };
        work.prepare(blk.n_out, if jac.is_some() { nv } else { 0 });
        let SweepWork {
            scratch,
            z,
            out,
            dense,
        } = work;
        let mut at = 0;
        for chunk in seeds.chunks(SEED_LANES) {
            seed_hyper_duals(x, &blk.vars, chunk.iter().copied(), z);
            self.eval_block_in(blk.kind, z, out, scratch)?;
            for (l, &(a, b)) in chunk.iter().enumerate() {
                if jac.is_some() {
                    for (r, o) in out.iter().enumerate() {
                        dense[r * nv + a] = o.eps1.0[l];
                        if let Some(b) = b {
                            dense[r * nv + b] = o.eps2.0[l];
                        }
                    }
                }
                if b.is_some() {
                    hess[at] = out
                        .iter()
                        .zip(mu)
                        .map(|(o, m)| o.eps1eps2.0[l] * m)
                        .sum::<f64>();
                    at += 1;
                }
            }
        }
        if let Some(jac) = jac {
            for (v, &(r, j)) in jac.iter_mut().zip(&blk.jac) {
                *v = dense[r * nv + j];
            }
        }
        Ok(())
    }

    /// A block's Hessian contribution ([`Self::block_hyper_sweep`] without the Jacobian),
    /// left alone when its multipliers are all zero.
    fn block_hessian(
        &self,
        x: &[f64],
        multipliers: &[f64],
        blk: &Block,
        work: &mut SweepWork<HyperDual<Lanes<SEED_LANES>>>,
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        if blk.inactive(multipliers) {
            return Ok(());
        }
        self.block_hyper_sweep(x, multipliers, blk, work, values, None)
    }

    /// Zeroed room for every block's Hessian contribution, in block order.
    fn hessian_parts(&self) -> Vec<f64> {
        vec![0.0; self.blocks.iter().map(|b| b.hess_slots.len()).sum()]
    }

    /// The Lagrangian Hessian from the blocks' contributions `parts` (each block's run in
    /// block order, as [`Self::block_hessian`] writes them) and the objective's.
    fn assemble_hessian(
        &self,
        x: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        parts: &[f64],
        values: &mut [f64],
    ) {
        values.fill(0.0);
        // Blocks share Hessian slots: their contributions are added in block order, as a
        // sequential loop would, whatever order they were computed in.
        let mut at = 0;
        for blk in &self.blocks {
            let run = &parts[at..at + blk.hess_slots.len()];
            at += blk.hess_slots.len();
            // Skipped, not added as zeros: +0.0 would turn a −0.0 entry into +0.0.
            if blk.inactive(multipliers) {
                continue;
            }
            for (&slot, value) in blk.hess_slots.iter().zip(run) {
                values[slot] += value;
            }
        }
        if !self.with_cost {
            for &slot in &self.obj_slots.torque {
                values[slot] += 2.0 * FEASIBILITY_TORQUE_WEIGHT * objective_factor;
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
            FEASIBILITY_TORQUE_WEIGHT * self.torque_vars().map(|i| x[i] * x[i]).sum::<f64>()
        })
    }

    fn gradient(&self, x: &[f64], gradient: &mut [f64]) -> Result<(), DomainError> {
        gradient.fill(0.0);
        if !self.with_cost {
            for i in self.torque_vars() {
                gradient[i] = 2.0 * FEASIBILITY_TORQUE_WEIGHT * x[i];
            }
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
        // Blocks own consecutive rows in block order, so each writes its own run.
        self.for_each_block(
            values,
            |blk| blk.n_out,
            |work: &mut SweepWork<f64>, blk, out| {
                let SweepWork { scratch, z, .. } = work;
                z.clear();
                z.extend(blk.vars.iter().map(|&i| x[i]));
                self.eval_block_in(blk.kind, z, out, scratch)
            },
        )
    }

    fn jacobian_structure(&self) -> SparsityPattern {
        SparsityPattern {
            rows: self.jac_rows.clone(),
            cols: self.jac_cols.clone(),
        }
    }

    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        // Each block fills its own run of entries, in block order.
        self.for_each_block(
            values,
            |blk| blk.jac.len(),
            |work, blk, run| self.block_jacobian(x, blk, work, run),
        )
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
        let mut parts = self.hessian_parts();
        self.for_each_block(
            &mut parts,
            |blk| blk.hess_slots.len(),
            |work, blk, run| self.block_hessian(x, multipliers, blk, work, run),
        )?;
        self.assemble_hessian(x, objective_factor, multipliers, &parts, values);
        Ok(())
    }

    fn jacobian_and_hessian_values(
        &self,
        x: &[f64],
        jacobian: &mut [f64],
        objective_factor: f64,
        multipliers: &[f64],
        hessian: &mut [f64],
    ) -> Result<(), DomainError> {
        let mut parts = self.hessian_parts();
        let runs: Vec<_> = self
            .runs(jacobian, |blk| blk.jac.len())
            .into_iter()
            .zip(self.runs(&mut parts, |blk| blk.hess_slots.len()))
            .collect();
        self.for_each_run(
            runs,
            || (SweepWork::new(), SweepWork::new()),
            |(jac_work, hess_work), blk, (jac, hess)| {
                if Self::shares_jacobian_with_hessian(blk.kind) && !blk.inactive(multipliers) {
                    self.block_hyper_sweep(x, multipliers, blk, hess_work, hess, Some(jac))
                } else {
                    self.block_jacobian(x, blk, jac_work, jac)?;
                    self.block_hessian(x, multipliers, blk, hess_work, hess)
                }
            },
        )?;
        self.assemble_hessian(x, objective_factor, multipliers, &parts, hessian);
        Ok(())
    }
}
