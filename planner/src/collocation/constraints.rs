//! The transcription's constraint blocks (which variables, which bounds) and the variable
//! bounds: joint, speed and torque limits, torso pitch, Table I; the `[constraints]` switches
//! of the constraints that are ours; and the reader's grouping of every inequality row and
//! variable bound ([`ConstraintGroup`], [`HzdProblem::constraint_groups`]).

use super::blocks::{Block, Kind};
use super::layout::TORQUE_SCALE;
use super::problem::HzdProblem;
use crate::config::ClearanceProfile;

impl HzdProblem {
    pub(super) fn add(&mut self, kind: Kind, vars: Vec<usize>, lower: &[f64], upper: &[f64]) {
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

    pub(super) fn point_vars(&self, k: usize, with_ddq: bool) -> Vec<usize> {
        let l = &self.layout;
        let mut v: Vec<usize> = (l.q(k)..l.q(k) + l.nq)
            .chain(l.dq(k)..l.dq(k) + l.nq)
            .collect();
        if with_ddq {
            v.extend(l.ddq(k)..l.ddq(k) + l.nq);
        }
        v
    }

    pub(super) fn build_blocks(&mut self) {
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
                // Interior points keep the swing foot above a parabola in time that peaks at
                // the mid-step clearance: z ≥ 0 alone let the optimum graze the ground (0.04 mm
                // below it between points near τ = 0.85) and the robot tripped in simulation.
                let s = l.time_fraction(k);
                let (lo, hi) = if k == last {
                    (0.0, 0.0)
                } else {
                    match self.config.constraints.clearance_profile {
                        ClearanceProfile::Envelope => {
                            (g.swing_clearance_m * 4.0 * s * (1.0 - s), inf)
                        }
                        ClearanceProfile::Midstep if 2 * k == last => (g.swing_clearance_m, inf),
                        ClearanceProfile::Midstep => (0.0, inf),
                    }
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
                self.add(Kind::Interval(i), vars, &[0.0; 4], &[0.0; 4]);
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
        let liftoff = if self.config.constraints.liftoff {
            g.liftoff_velocity_mps
        } else {
            -inf
        };
        lo.extend([0.0, 0.0, 0.0, liftoff]);
        hi.extend([inf, inf, inf, inf]);
        self.add(Kind::Impact, vars, &lo, &hi);
        if g.max_zero_dynamics_eigenvalue.is_some() {
            let vars = self.point_vars(last, false);
            self.add(Kind::Contraction, vars, &[0.0], &[inf]);
        }
        if g.min_apex_margin.is_some() {
            // Every interior point against the first (the post-impact momentum).
            for k in 1..last {
                let mut vars = self.point_vars(k, false);
                vars.extend(self.point_vars(0, false));
                self.add(Kind::ApexMargin, vars, &[0.0], &[inf]);
            }
        }
        // Speed: linear rows in T and d (a quotient d/T would make the Hessian non-zero and
        // the rows' scale depend on T).
        match g.speed_mps {
            Some([v_lo, v_hi]) if v_lo == v_hi => {
                self.add(Kind::Speed, vec![l.duration(), l.length()], &[0.0], &[0.0]);
            }
            Some(_) => {
                let vars = vec![l.duration(), l.length()];
                self.add(Kind::Speed, vars, &[0.0, 0.0], &[inf, inf]);
            }
            None => {}
        }
        // Co-design: every block that evaluates the model also sees the two lengths.
        if l.design > 0 {
            let dv = [l.design_var(0), l.design_var(1)];
            for blk in &mut self.blocks {
                if Self::uses_model(blk.kind) {
                    blk.vars.extend(dv);
                }
            }
        }
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
}

/// An inequality constraint or variable bound as a reader of the landscape sees it: which
/// limit it is and whose (the paper's Table I, a physical limit the paper names, or ours).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ConstraintGroup {
    /// Step length d, m (Table I: 0.15–0.35).
    StepLength,
    /// Step duration T, s (Table I: 0.6–0.9).
    StepDuration,
    /// Thigh length, m (Table I: the design box).
    ThighLength,
    /// Shin length, m (Table I: the design box).
    ShinLength,
    /// Motor torques, N·m (A1 limit).
    Torque,
    /// Joint speeds, rad/s (A1 limit).
    JointSpeed,
    /// Joint angles, rad (the URDF's limits).
    JointAngle,
    /// Stance friction cone |λ_x| ≤ μ λ_z, N.
    FrictionCone,
    /// Stance normal force λ_z ≥ `min_normal_force_n`, N.
    NormalForce,
    /// Impact impulse inside the friction cone and pushing, N·s.
    ImpactImpulse,
    /// Swing foot above the clearance profile, m.
    SwingClearance,
    /// Downward swing-foot velocity at impact, m/s.
    ImpactVelocity,
    /// Old stance foot lifting off after impact, m/s.
    Liftoff,
    /// Torso pitch, rad.
    Pitch,
    /// Torso pitch rate, rad/s (±10).
    PitchRate,
    /// The step's mean speed `gait.speed_mps`: rows d − v·T, m.
    Speed,
    /// The zero dynamics' contraction `gait.max_zero_dynamics_eigenvalue`: λ·σ⁻² − σ⁺²,
    /// (kg·m²/s)².
    Contraction,
    /// The apex margin `gait.min_apex_margin`: σ² − (1 − (1 − m)²)·σ⁺² at every interior
    /// point, (kg·m²/s)².
    ApexMargin,
    /// Bounds that only keep the search finite: Bézier coefficients within the joint limits,
    /// θ± within ±1 rad, power slacks below the largest motor power.
    SearchBox,
}

impl ConstraintGroup {
    /// Every group, in report order.
    pub const ALL: [ConstraintGroup; 19] = [
        Self::StepLength,
        Self::StepDuration,
        Self::ThighLength,
        Self::ShinLength,
        Self::Torque,
        Self::JointSpeed,
        Self::JointAngle,
        Self::FrictionCone,
        Self::NormalForce,
        Self::ImpactImpulse,
        Self::SwingClearance,
        Self::ImpactVelocity,
        Self::Liftoff,
        Self::Pitch,
        Self::PitchRate,
        Self::Speed,
        Self::Contraction,
        Self::ApexMargin,
        Self::SearchBox,
    ];

    /// What the group is, with its unit.
    pub fn describe(self) -> &'static str {
        match self {
            Self::StepLength => "step length d (m)",
            Self::StepDuration => "step duration T (s)",
            Self::ThighLength => "thigh length (m)",
            Self::ShinLength => "shin length (m)",
            Self::Torque => "motor torque (N·m)",
            Self::JointSpeed => "joint speed (rad/s)",
            Self::JointAngle => "joint angle limits (rad)",
            Self::FrictionCone => "stance friction cone (N)",
            Self::NormalForce => "stance normal force (N)",
            Self::ImpactImpulse => "impact impulse: cone and push (N·s)",
            Self::SwingClearance => "swing-foot clearance (m)",
            Self::ImpactVelocity => "swing-foot descent at impact (m/s)",
            Self::Liftoff => "old stance foot lift-off (m/s)",
            Self::Pitch => "torso pitch (rad)",
            Self::PitchRate => "torso pitch rate (rad/s)",
            Self::Speed => "step speed rows d − v·T (m)",
            Self::Contraction => "zero-dynamics contraction λ·σ⁻² − σ⁺² ((kg·m²/s)²)",
            Self::ApexMargin => "apex margin σ² − (1 − (1 − m)²)·σ⁺² ((kg·m²/s)²)",
            Self::SearchBox => "search box: α, θ±, power slacks",
        }
    }

    /// Whose constraint it is: `Table I`, `physical` (a limit the paper names: friction cone,
    /// actuator limits, workspace) or `ours` (added by this planner; planner/CODESIGN.md,
    /// "Constraints").
    pub fn source(self) -> &'static str {
        match self {
            Self::StepLength | Self::StepDuration | Self::ThighLength | Self::ShinLength => {
                "Table I"
            }
            Self::Speed => "essential (speed)",
            Self::Torque
            | Self::JointSpeed
            | Self::JointAngle
            | Self::FrictionCone
            | Self::NormalForce
            | Self::ImpactImpulse => "physical",
            Self::SwingClearance
            | Self::ImpactVelocity
            | Self::Liftoff
            | Self::Pitch
            | Self::PitchRate
            | Self::Contraction
            | Self::ApexMargin
            | Self::SearchBox => "ours",
        }
    }
}

/// The group of every inequality row and every bounded variable of a problem
/// ([`HzdProblem::constraint_groups`]); `None` for equality rows and free variables.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstraintGroups {
    /// One per constraint row.
    pub rows: Vec<Option<ConstraintGroup>>,
    /// One per variable.
    pub variables: Vec<Option<ConstraintGroup>>,
    /// Factor from a variable's own unit to its group's unit (10 for the scaled torques, else
    /// 1): a bound's sensitivity per group unit is its multiplier divided by this.
    pub variable_scale: Vec<f64>,
}

impl HzdProblem {
    /// The swing foot's height above the stance foot at points 1..=2N (the last is the guard,
    /// 0 at a solution), m; empty if the constraints do not evaluate at x.
    pub fn swing_heights_m(&self, x: &[f64]) -> Vec<f64> {
        let mut g = vec![0.0; self.lower_g.len()];
        if crate::nlp::NlpProblem::constraints(self, x, &mut g).is_err() {
            return Vec::new();
        }
        self.blocks
            .iter()
            .filter(|b| b.kind == Kind::SwingHeight)
            .map(|b| g[b.row0])
            .collect()
    }

    /// The reader's group of every inequality row and variable bound.
    pub fn constraint_groups(&self) -> ConstraintGroups {
        use ConstraintGroup as G;
        let l = &self.layout;
        let nq = l.nq;
        let mut rows = vec![None; self.lower_g.len()];
        for b in &self.blocks {
            let groups: Vec<Option<G>> = match b.kind {
                Kind::Dynamics => (0..b.n_out)
                    .map(|r| match r.checked_sub(nq) {
                        Some(0) => Some(G::NormalForce),
                        Some(_) => Some(G::FrictionCone),
                        None => None,
                    })
                    .collect(),
                Kind::SwingHeight => vec![Some(G::SwingClearance)],
                Kind::Speed => vec![Some(G::Speed); b.n_out],
                Kind::Contraction => vec![Some(G::Contraction)],
                Kind::ApexMargin => vec![Some(G::ApexMargin)],
                Kind::SwingEnd => vec![None, Some(G::ImpactVelocity)],
                Kind::Impact => (0..b.n_out)
                    .map(|r| match r.checked_sub(2 * nq) {
                        Some(3) => Some(G::Liftoff),
                        Some(_) => Some(G::ImpactImpulse),
                        None => None,
                    })
                    .collect(),
                _ => vec![None; b.n_out],
            };
            for (r, g) in groups.into_iter().enumerate() {
                let i = b.row0 + r;
                // Equalities (the guard among the swing heights) belong to no group.
                rows[i] = g.filter(|_| self.lower_g[i] < self.upper_g[i]);
            }
        }
        let bp = &self.biped;
        let mut variables = vec![None; l.len()];
        let mut variable_scale = vec![1.0; l.len()];
        let is_joint = |c: usize| bp.model.joints.iter().any(|j| j.coordinate == c);
        for k in 0..l.points() {
            for (i, &c) in bp.reduced.iter().enumerate() {
                let joint = is_joint(c);
                variables[l.q(k) + i] = Some(if joint { G::JointAngle } else { G::Pitch });
                variables[l.dq(k) + i] = Some(if joint { G::JointSpeed } else { G::PitchRate });
            }
            for a in 0..l.nu {
                variables[l.u(k) + a] = Some(G::Torque);
                variable_scale[l.u(k) + a] = TORQUE_SCALE;
                if l.slacks {
                    variables[l.p(k) + a] = Some(G::SearchBox);
                    variables[l.n(k) + a] = Some(G::SearchBox);
                }
            }
        }
        for o in 0..l.m {
            for jj in 0..=l.degree {
                variables[l.alpha(o, jj)] = Some(G::SearchBox);
            }
        }
        variables[l.theta_plus()] = Some(G::SearchBox);
        variables[l.theta_minus()] = Some(G::SearchBox);
        variables[l.duration()] = Some(G::StepDuration);
        variables[l.length()] = Some(G::StepLength);
        if l.design > 0 {
            variables[l.design_var(0)] = Some(G::ThighLength);
            variables[l.design_var(1)] = Some(G::ShinLength);
        }
        let (lo, hi) = self.bounds();
        for (i, v) in variables.iter_mut().enumerate() {
            if !(lo[i].is_finite() || hi[i].is_finite()) {
                *v = None;
            }
        }
        ConstraintGroups {
            rows,
            variables,
            variable_scale,
        }
    }
}
