//! The backend side of the interface: the [`NlpSolver`] trait every backend implements, and
//! the iteration callback's report and answer.

use super::error::Result;
use super::options::SolveOptions;
use super::outcome::Solution;
use super::problem::NlpProblem;

/// What the iteration callback sees once per iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IterationReport {
    /// Iteration number, 0 for the initial point.
    pub iteration: usize,
    /// Objective at the current iterate (in the backend's scaling).
    pub objective: f64,
    /// Constraint violation (max norm).
    pub primal_infeasibility: f64,
    /// Dual infeasibility (max norm of the Lagrangian gradient).
    pub dual_infeasibility: f64,
    /// Barrier parameter μ.
    pub barrier_parameter: f64,
    /// Max norm of the primal step.
    pub step_norm: f64,
    /// True while the backend is in its feasibility-restoration phase.
    pub restoration: bool,
}

/// What the iteration callback tells the solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IterationControl {
    /// Keep iterating.
    Continue,
    /// Stop now; the solve returns [`SolveStatus::UserStop`](super::SolveStatus::UserStop).
    Stop,
}

/// A swappable NLP backend.
pub trait NlpSolver {
    /// Solves `problem`, calling `on_iteration` once per iteration.
    fn solve_with_callback(
        &self,
        problem: &dyn NlpProblem,
        options: &SolveOptions,
        on_iteration: &mut dyn FnMut(&IterationReport) -> IterationControl,
    ) -> Result<Solution>;
}
