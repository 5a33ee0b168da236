//! What a caller chooses for a solve: the backend, the tolerances and limits, a warm start.

use std::time::Duration;

/// Multipliers (and optionally a primal point) to start a solve from, e.g.
/// the [`Solution`] of a neighbouring problem. See [`Solution::warm_start`].
///
/// [`Solution`]: super::Solution
/// [`Solution::warm_start`]: super::Solution::warm_start
#[derive(Debug, Clone, PartialEq)]
pub struct WarmStart {
    /// Primal start; `None` keeps [`NlpProblem::initial_point`](super::NlpProblem::initial_point).
    pub x: Option<Vec<f64>>,
    /// Constraint multipliers λ, length `m`.
    pub constraint_multipliers: Vec<f64>,
    /// Lower-bound multipliers z_l ≥ 0, length `n`.
    pub lower_bound_multipliers: Vec<f64>,
    /// Upper-bound multipliers z_u ≥ 0, length `n`.
    pub upper_bound_multipliers: Vec<f64>,
}

/// The available solver backends.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Backend {
    /// `ripopt` 0.8: a pure-Rust IPOPT-class primal–dual interior point
    /// method (filter line search, sparse LDLᵀ with inertia correction). EPL-2.0. The
    /// cross-check, and the planner's fallback where the native restoration phase fails.
    Ripopt,
    /// Our own primal–dual interior point ([`crate::nlp::NativeSolver`]): IPOPT's filter line search
    /// and restoration phase on a condensed KKT system factorized by faer's LDLᵀ on a paired
    /// ordering. The default: on the ADAM plan 1.2–1.5× faster than ripopt, the same optima.
    #[default]
    Native,
}

/// Options common to every backend.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveOptions {
    /// Which backend to use.
    pub backend: Backend,
    /// Overall KKT tolerance (scaled, as IPOPT's `tol`).
    pub tolerance: f64,
    /// Absolute tolerance on the constraint violation (IPOPT's `constr_viol_tol`).
    pub constraint_violation_tolerance: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Wall-time limit; `None` for none.
    pub max_wall_time: Option<Duration>,
    /// Backend console output: 0 silent, 5 one line per iteration, higher is chattier.
    pub print_level: u8,
    /// Start from these multipliers (and point); `None` for a cold start.
    pub warm_start: Option<WarmStart>,
    /// Initial barrier parameter μ₀ of a solve without `warm_start` (IPOPT's `mu_init`);
    /// `None`: 0.1. For a start point already near the central path of a small μ (a warm
    /// start's multipliers set μ₀ from their complementarity instead).
    pub initial_barrier: Option<f64>,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            backend: Backend::default(),
            tolerance: 1e-8,
            constraint_violation_tolerance: 1e-4,
            max_iterations: 3000,
            max_wall_time: None,
            print_level: 0,
            warm_start: None,
            initial_barrier: None,
        }
    }
}
