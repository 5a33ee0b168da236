//! # planner::nlp — nonlinear programming behind our own trait
//!
//! The collocation and co-design layers state their problem once as an
//! [`NlpProblem`] (bounds, `f`, `∇f`, `g`, sparse Jacobian, sparse lower-triangle
//! Lagrangian Hessian) and call [`solve`]; the backend behind it can be swapped
//! through [`SolveOptions::backend`] or by implementing [`NlpSolver`].
//!
//! ```text
//! NlpProblem ──validate──▶ backend adapter ──▶ ripopt IPM ─────────────▶ Solution
//!   (ours)                 (times evaluations,   or native IPM (native)    (x, λ, z_l, z_u, status,
//!                           relays iteration callback)                     iterations, timings)
//! ```
//!
//! * [`ad`]: write a small problem once, generic over a dual-number scalar
//!   ([`ad::AdModel`]), and get exact gradients, Jacobians and Hessians by
//!   forward-mode AD ([`ad::DenseAdProblem`]).
//! * [`check`]: compare any problem's derivatives with finite differences (tests only;
//!   no solve loop uses finite differences).
//! * `interface` (private, re-exported here): the vocabulary every backend shares — the
//!   [`NlpProblem`] trait, [`SolveOptions`], the [`NlpSolver`] trait and its iteration callback,
//!   [`Solution`] with its [`SolveStatus`] and [`SolveStatistics`], [`NlpError`]. It imports
//!   nothing else from `nlp`.
//! * `native` (private; [`NativeSolver`]): the native interior point — its state (`ipm`), start
//!   (`start`), main loop (`iteration`), Newton step with inertia correction (`newton`), filter
//!   line search (`line_search`), restoration phase (`restore`, on the `restoration` problem),
//!   evaluations and measures (`evaluate`), KKT system (`kkt`) and constants (`constants`).
//! * `ripopt_backend` (private; [`RipoptSolver`]): the adapter to ripopt.
//! * `solve` and `validate` (private; [`solve`]): the checks of a problem and its options, and
//!   the choice of backend by [`Backend`], above both backends.
//! * [`lanes`]: a real type of L lanes, so that one evaluation carries L dual seeds (the
//!   collocation problem's Jacobian columns and Hessian pairs, four at a time).
//!
//! Multipliers follow IPOPT's convention: `L = σ f + λᵀ g`; bound multipliers are ≥ 0.
//!
//! ## The backends: ripopt first, then our own (the default since December 2026)
//!
//! The HZD collocation NLP is nonconvex, equality-heavy and sparse (1258 variables, 1245
//! constraints for ADAM): it needs a primal–dual interior point with a filter line search, an
//! inertia-corrected sparse LDLᵀ and a restoration phase — what IPOPT does. The candidates, all
//! pure Rust from crates.io (`shared/CRATES.md`):
//! - **ripopt 0.8** (chosen first, the default until the fifth round): an IPOPT-class method
//!   with sparse LDLᵀ and inertia detection. It reproduced IPOPT's iteration counts on a
//!   pendulum swing-up (152–4502 variables) and here solves 50 of 57 Hock–Schittkowski
//!   problems to their published optima (the 7 others listed with reasons in
//!   `tests/hock_schittkowski.rs`: IPOPT stops at the same points on HS2, HS13, HS20 and HS44;
//!   HS116 ends below the published value),
//!   and the ADAM gait in 43 + 77 iterations (CasADi + IPOPT + MUMPS: 14 + 64 on a comparable
//!   five-link problem, `shared/PLANNER-NOTES.md`).
//! - **our own interior point** ([`NativeSolver`], [`Backend::Native`], built December 2026):
//!   IPOPT's algorithm (filter line search, second-order corrections, monotone barrier update,
//!   inertia correction, ℓ₁ feasibility restoration) on a condensed KKT system factorized by
//!   faer's supernodal LDLᵀ on a matching-paired ordering from feral (`kkt`). It reaches 51 of
//!   57 Hock–Schittkowski optima (ripopt 50) and plans ADAM in 43 + 78 iterations to the same
//!   gait, `adam bench plan` median 1.61 s against ripopt's ~2.3 s (`planner/NLP.md`, fifth
//!   round); since the sixth round (a factor faer cannot finish is a failed inertia trial, two
//!   trials factorized at once) 49 + 74 iterations and 1.41–1.50 s. The default since the
//!   fifth round; ripopt stays as the cross-check and as the fallback where the native
//!   restoration phase fails.
//! - **clarabel inside an SQP**: clarabel solves convex QPs/cones fast on banded structure, but
//!   an SQP on an indefinite Lagrangian Hessian needs convexification, a merit function or
//!   filter, and its own feasibility restoration; not attempted.
//! - **optimization_engine** (PANOC): did not converge on a 900-variable collocation problem
//!   (`shared/CRATES.md`).
//!
//! IPOPT itself (C++, needs system packages) is not used, not even as an optional feature.
//!
//! ## Example
//!
//! ```no_run
//! use num_dual::DualNum;
//! use planner::nlp::ad::{AdModel, DenseAdProblem};
//! use planner::nlp::{solve_with_callback, IterationControl, SolveOptions};
//!
//! /// Hock–Schittkowski 71.
//! struct Hs71;
//! impl AdModel for Hs71 {
//!     fn num_variables(&self) -> usize { 4 }
//!     fn num_constraints(&self) -> usize { 2 }
//!     fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
//!         lower.fill(1.0);
//!         upper.fill(5.0);
//!     }
//!     fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
//!         lower.copy_from_slice(&[25.0, 40.0]);
//!         upper.copy_from_slice(&[f64::INFINITY, 40.0]);
//!     }
//!     fn initial_point(&self, x0: &mut [f64]) { x0.copy_from_slice(&[1.0, 5.0, 5.0, 1.0]); }
//!     fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
//!         x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2]
//!     }
//!     fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
//!         g[0] = x[0] * x[1] * x[2] * x[3];
//!         g[1] = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3];
//!     }
//! }
//!
//! let problem = DenseAdProblem::new(Hs71);
//! let solution = solve_with_callback(&problem, &SolveOptions::default(), &mut |it| {
//!     println!("{:>4} {:>14.6e} {:>9.2e}", it.iteration, it.objective, it.primal_infeasibility);
//!     IterationControl::Continue
//! })?;
//! assert!(solution.status.is_success());
//!
//! // Warm start a neighbouring problem from this solution (point and multipliers):
//! let options = SolveOptions { warm_start: Some(solution.warm_start()), ..SolveOptions::default() };
//! let _again = planner::nlp::solve(&problem, &options)?;
//! # Ok::<(), planner::nlp::NlpError>(())
//! ```
//!
//! ## Why ripopt first (measured, 2 cores, release build; details in `planner/NLP.md`)
//!
//! The first backend was [`ripopt`] 0.8.2, a pure-Rust port of IPOPT's algorithm
//! (filter line search, adaptive barrier, inertia-corrected sparse LDLᵀ). Licence
//! **EPL-2.0** (as IPOPT): a weak copyleft on ripopt's own files, compatible with
//! linking from our MIT/Apache code. It was evaluated against IPOPT 3.14 + MUMPS
//! (CasADi 3.8.2 from PyPI, same formulations and starts):
//!
//! * Hock–Schittkowski, 57 problems: 50 reach the published optimum to 1e-6; of the 7
//!   others IPOPT ends at the same local/degenerate point on 4, ripopt is worse on one
//!   (HS16), one is degenerate (HS108), one beats the published value (HS116).
//! * Pendulum swing-up, trapezoidal collocation: 1503 variables in 13 iterations,
//!   0.047 s; 4503 variables in 14 iterations, 0.155 s. IPOPT: the same iterations and
//!   objective to 9 digits, 0.035 s / 0.111 s — ripopt is about 1.4× slower there.
//!
//! Same iteration counts as IPOPT, no system libraries, exact-Hessian support and
//! warm starts made ripopt the first default. The native backend was then written for speed
//! (issue #3: it owns its KKT system, so a faster factorization can be put under it) and
//! as an independent cross-check. With feral's factorization it matched ripopt's iterations
//! and was no faster; with faer's LDLᵀ on a paired ordering (`kkt`) it plans ADAM 1.2–1.5× faster
//! than ripopt to the same gait, and became the default (`planner/NLP.md`, "Fifth round").
//! Its restoration phase is younger than ripopt's: the planner re-solves a stage whose native
//! restoration fails with ripopt.

mod interface;
mod native;
mod ripopt_backend;
mod solve;
#[cfg(test)]
mod test_problems;
mod validate;

pub mod ad;
pub mod check;
pub mod lanes;

pub use interface::{
    sum_if_both, Backend, DomainError, EvaluationCounts, IterationControl, IterationReport,
    NlpError, NlpProblem, NlpSolver, PhaseTimes, Result, Solution, SolveOptions, SolveStatistics,
    SolveStatus, SparsityPattern, WarmStart,
};
pub use native::NativeSolver;
pub use ripopt_backend::RipoptSolver;
pub use solve::{solve, solve_with_callback};
