//! The native interior point backend ([`NativeSolver`]): IPOPT's primal–dual method with a
//! filter line search, on our own KKT system (`kkt`) and ℓ₁ restoration problem
//! (`restoration`).

// The iteration works on parallel arrays (x, its bounds, multipliers, step) indexed together:
// index loops say that more plainly than zipped iterators.
#![allow(clippy::needless_range_loop)]

mod bounds;
mod constants;
mod evaluate;
mod ipm;
mod iteration;
mod kkt;
mod line_search;
mod newton;
mod restoration;
mod restore;
mod scaled;
mod start;
#[cfg(test)]
mod tests;

use super::interface::{
    IterationControl, IterationReport, NlpProblem, NlpSolver, Result, Solution, SolveOptions,
};
use ipm::Ipm;

/// The native backend: a primal–dual interior point method with a filter line search, the
/// algorithm of Wächter & Biegler (Math. Program. 106, 2006) that IPOPT implements, on a
/// condensed KKT system `[W + Σ_x + δ_w I, Jᵀ; J, −D]` (slacks eliminated) factorized by
/// faer's supernodal LDLᵀ on a matching-paired ordering from feral (`kkt`; feral's
/// multifrontal LDLᵀ only where faer's set-up fails; both give the inertia). The ordering and
/// symbolic analysis run once per solve, at its first factorization.
///
/// * Inequalities get slacks; every bound gets a logarithmic barrier (with IPOPT's damping of
///   one-sided bounds); bounds are relaxed by 1e-8 relative, as IPOPT's `bound_relax_factor`.
/// * Gradient-based scaling of the objective and each constraint at the start (largest
///   gradient entry 100, as IPOPT's `nlp_scaling_max_gradient`).
/// * Monotone (Fiacco–McCormick) barrier update: μ ← max(tol/10, min(0.2 μ, μ^1.5)) whenever
///   the barrier problem is solved to 10 μ, repeated while it holds.
/// * Inertia correction: the KKT matrix must have n positive and m negative eigenvalues; else
///   δ_w is raised (1e-4 first, ×100 / ×8 after, from a third of the last one later); a
///   factor that is not finite counts as a failed trial. With a core to spare, a trial and the
///   one after it are factorized at once on twin systems (the same factors and choices as one
///   after the other). The equality rows always carry δ_c = 1e-8 μ^¼ (IPOPT's
///   `perturb_always_cd`).
/// * Filter line search with the switching condition, Armijo on the barrier objective, and up
///   to four second-order corrections on the first trial step.
/// * Fraction to the boundary τ = max(0.99, 1 − μ); bound multipliers kept within a factor
///   1e10 of μ / slack.
///
/// * Feasibility restoration where the line search finds no acceptable step: IPOPT's ℓ₁
///   restoration problem (ρ = 1000, proximity weight √μ) solved by this same method, left as
///   soon as the outer filter accepts a point with 10 % less violation; its iterations are
///   reported with `restoration: true`. A restoration that converges to an infeasible point
///   ends the solve as [`SolveStatus::Infeasible`], one that fails as
///   [`SolveStatus::RestorationFailed`].
/// * Ends: [`SolveStatus::Optimal`] at the tolerances; [`SolveStatus::Acceptable`] after 15
///   iterations in a row within IPOPT's acceptable tolerances (KKT error 1e-6, violation 1e-2,
///   complementarity 1e-2), or when the solve fails numerically (no factorization with the
///   right inertia, no direction, a failed restoration) at a point within them, as IPOPT's
///   `STOP_AT_ACCEPTABLE_POINT`; [`SolveStatus::Diverging`] once |x| > 1e20;
///   [`SolveStatus::IterationLimit`], [`SolveStatus::TimeLimit`], [`SolveStatus::UserStop`].
///
/// [`SolveStatus::Acceptable`]: crate::nlp::SolveStatus::Acceptable
/// [`SolveStatus::Optimal`]: crate::nlp::SolveStatus::Optimal
/// [`SolveStatus::Diverging`]: crate::nlp::SolveStatus::Diverging
/// [`SolveStatus::Infeasible`]: crate::nlp::SolveStatus::Infeasible
/// [`SolveStatus::IterationLimit`]: crate::nlp::SolveStatus::IterationLimit
/// [`SolveStatus::TimeLimit`]: crate::nlp::SolveStatus::TimeLimit
/// [`SolveStatus::UserStop`]: crate::nlp::SolveStatus::UserStop
/// [`SolveStatus::RestorationFailed`]: crate::nlp::SolveStatus::RestorationFailed
#[derive(Debug, Clone, Copy, Default)]
pub struct NativeSolver;

impl NlpSolver for NativeSolver {
    fn solve_with_callback(
        &self,
        problem: &dyn NlpProblem,
        options: &SolveOptions,
        on_iteration: &mut dyn FnMut(&IterationReport) -> IterationControl,
    ) -> Result<Solution> {
        Ok(Ipm::new(problem, options).run(on_iteration))
    }
}
