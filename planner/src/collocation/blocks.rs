//! The constraint blocks: the kinds of constraint group, and what a block records (its rows,
//! its variables, its Jacobian entries, its Hessian seeds and slots).

/// The kinds of constraint block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Kind {
    /// Dynamics residual (nq) and 3 contact-force rows.
    Dynamics,
    /// θ(q) − θ⁺ = τ Δθ, θ̇ = τ̇ Δθ, θ̈ = τ̈ Δθ at one point.
    PhaseLift,
    /// Output dynamics of output o.
    OutputDynamics(usize),
    /// y and ẏ of output o at the first point.
    OutputStart(usize),
    /// Hermite–Simpson rows of one reduced coordinate in interval i (carries i: its length is
    /// its own fraction of T).
    Interval(usize),
    /// p − n − u q̇ of one actuator at one point (carries the actuator's reduced index).
    Power(usize),
    /// Swing-foot height.
    SwingHeight,
    /// Swing foot at the end: x − d and ż.
    SwingEnd,
    /// Impact and periodicity.
    Impact,
    /// The step's mean speed against `gait.speed_mps` = [lo, hi]: d − lo·T ≥ 0 and
    /// hi·T − d ≥ 0 (one row d − v·T = 0 when lo = hi). Linear in T and d: its Jacobian is
    /// constant and its Hessian zero. Only when the config asks for a speed.
    Speed,
    /// The zero dynamics' contraction at the impact: λ·σ⁻² − σ_sw⁻² ≥ 0 at the last point (σ⁻
    /// about the stance foot, σ_sw⁻ about the swing foot, which the impact conserves as σ⁺).
    /// Only when the config bounds `gait.max_zero_dynamics_eigenvalue`.
    Contraction,
    /// The apex margin at one interior point: σ_k² − (1 − (1 − m)²)·σ_0² ≥ 0, σ about the
    /// stance foot at point k and at the first point (the post-impact momentum). Only when the
    /// config bounds `gait.min_apex_margin`.
    ApexMargin,
    /// τ at the first and last point (equalities, not fixed bounds: fixed variables make an
    /// interior point's barrier ill-conditioned).
    TauEnds,
}

impl Kind {
    /// What the constraint group means, for reports and errors.
    pub(super) fn describe(self) -> String {
        match self {
            Kind::Dynamics => "pinned-stance dynamics and contact forces".into(),
            Kind::PhaseLift => "phase variable".into(),
            Kind::OutputDynamics(o) => format!("virtual constraint {o} (output dynamics)"),
            Kind::OutputStart(o) => format!("virtual constraint {o} at the step start"),
            Kind::Interval(_) => "collocation defects".into(),
            Kind::Power(c) => format!("power slacks (coordinate {c})"),
            Kind::SwingHeight => "swing-foot clearance".into(),
            Kind::SwingEnd => "swing foot at impact (guard, step length, descent)".into(),
            Kind::Impact => "impact, periodicity, impulse and lift-off".into(),
            Kind::TauEnds => "phase at the step ends".into(),
            Kind::Speed => "step speed (gait.speed_mps)".into(),
            Kind::Contraction => {
                "zero-dynamics contraction (gait.max_zero_dynamics_eigenvalue)".into()
            }
            Kind::ApexMargin => "apex margin (gait.min_apex_margin)".into(),
        }
    }
}

#[derive(Clone, Debug)]
pub(super) struct Block {
    pub(super) kind: Kind,
    pub(super) vars: Vec<usize>,
    pub(super) row0: usize,
    pub(super) n_out: usize,
    /// (local output, local var) of the structurally non-zero Jacobian entries.
    pub(super) jac: Vec<(usize, usize)>,
    /// Local vars with at least one Jacobian entry.
    pub(super) jac_vars: Vec<usize>,
    /// Hyper-dual seeds: first the local variable pairs `(a, Some(b))` (a ≥ b by global
    /// index) with a structurally non-zero Hessian, one per `hess_slots` entry; then, for the
    /// kinds whose Jacobian is read off these passes
    /// ([`HzdProblem::shares_jacobian_with_hessian`]), `(j, None)` for every Jacobian column
    /// no pair covers.
    ///
    /// [`HzdProblem::shares_jacobian_with_hessian`]: super::HzdProblem::shares_jacobian_with_hessian
    pub(super) seeds: Vec<(usize, Option<usize>)>,
    /// Slot in the global Hessian value array of each pair.
    pub(super) hess_slots: Vec<usize>,
}

impl Block {
    /// The Hessian pairs: the first seeds.
    pub(super) fn pairs(&self) -> &[(usize, Option<usize>)] {
        &self.seeds[..self.hess_slots.len()]
    }

    /// Whether all of this block's multipliers are zero (it adds nothing to the Hessian).
    pub(super) fn inactive(&self, multipliers: &[f64]) -> bool {
        multipliers[self.row0..self.row0 + self.n_out]
            .iter()
            .all(|&m| m == 0.0)
    }
}
