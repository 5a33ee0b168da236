//! The solver side of the NLP interface: options, results, backends.

use std::time::Duration;

use super::problem::NlpProblem;
use super::ripopt_backend::RipoptSolver;
use super::validate::validate_problem;

/// Errors that stop a solve before it starts (the problem or options are malformed).
///
/// A solve that runs and does not converge is not an error: it returns a
/// [`Solution`] whose [`Solution::status`] says why it stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NlpError {
    /// A bound is NaN, or a lower bound exceeds its upper bound.
    #[error("{kind} bound {index} is invalid: lower {lower}, upper {upper}")]
    InvalidBounds {
        /// "variable" or "constraint".
        kind: &'static str,
        /// Index of the offending variable or constraint.
        index: usize,
        /// The lower bound given.
        lower: f64,
        /// The upper bound given.
        upper: f64,
    },
    /// A sparsity pattern has an entry outside the matrix, or rows and cols differ in length.
    #[error(
        "{matrix} pattern entry {entry} at ({row}, {col}) is outside a {n_rows}×{n_cols} matrix"
    )]
    PatternOutOfRange {
        /// "jacobian" or "hessian".
        matrix: &'static str,
        /// Index of the entry in the triplet list.
        entry: usize,
        /// Its row.
        row: usize,
        /// Its column.
        col: usize,
        /// Rows of the matrix.
        n_rows: usize,
        /// Columns of the matrix.
        n_cols: usize,
    },
    /// The two index vectors of a sparsity pattern differ in length.
    #[error("{matrix} pattern has {rows} row indices but {cols} column indices")]
    PatternLengthMismatch {
        /// "jacobian" or "hessian".
        matrix: &'static str,
        /// Length of `rows`.
        rows: usize,
        /// Length of `cols`.
        cols: usize,
    },
    /// A Hessian pattern entry lies above the diagonal.
    #[error("hessian pattern entry {entry} at ({row}, {col}) is in the upper triangle")]
    HessianNotLowerTriangular {
        /// Index of the entry in the triplet list.
        entry: usize,
        /// Its row.
        row: usize,
        /// Its column.
        col: usize,
    },
    /// The initial point contains NaN or infinity.
    #[error("initial point entry {index} is not finite: {value}")]
    NonFiniteInitialPoint {
        /// Index of the offending entry.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A warm-start vector has the wrong length.
    #[error("warm start {field} has length {actual}, expected {expected}")]
    WarmStartLength {
        /// Which vector.
        field: &'static str,
        /// Expected length.
        expected: usize,
        /// Length given.
        actual: usize,
    },
    /// An option is out of range.
    #[error("option {name} = {value} is out of range ({reason})")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What is allowed.
        reason: &'static str,
    },
}

/// Result alias of this module.
pub type Result<T, E = NlpError> = std::result::Result<T, E>;

/// Why a solve stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SolveStatus {
    /// The KKT conditions hold to the requested tolerance.
    Optimal,
    /// The KKT conditions hold to the relaxed "acceptable" tolerances.
    Acceptable,
    /// The constraints appear (locally) infeasible.
    Infeasible,
    /// The iteration limit was reached.
    IterationLimit,
    /// The wall-time limit was reached.
    TimeLimit,
    /// The iterates grew without bound (an unbounded problem?).
    Diverging,
    /// The feasibility restoration phase failed.
    RestorationFailed,
    /// The search direction became too small to make progress.
    TinyStep,
    /// The problem functions could not be evaluated at an accepted iterate.
    EvaluationError,
    /// The iteration callback asked to stop.
    UserStop,
    /// Numerical trouble in the linear algebra, or an internal backend error.
    NumericalError,
}

impl SolveStatus {
    /// True for [`SolveStatus::Optimal`] and [`SolveStatus::Acceptable`].
    pub fn is_success(self) -> bool {
        matches!(self, Self::Optimal | Self::Acceptable)
    }
}

/// Multipliers (and optionally a primal point) to start a solve from, e.g.
/// the [`Solution`] of a neighbouring problem. See [`Solution::warm_start`].
#[derive(Debug, Clone, PartialEq)]
pub struct WarmStart {
    /// Primal start; `None` keeps [`NlpProblem::initial_point`].
    pub x: Option<Vec<f64>>,
    /// Constraint multipliers λ, length `m`.
    pub constraint_multipliers: Vec<f64>,
    /// Lower-bound multipliers z_l ≥ 0, length `n`.
    pub lower_bound_multipliers: Vec<f64>,
    /// Upper-bound multipliers z_u ≥ 0, length `n`.
    pub upper_bound_multipliers: Vec<f64>,
}

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
    /// Stop now; the solve returns [`SolveStatus::UserStop`].
    Stop,
}

/// The available solver backends.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Backend {
    /// `ripopt` 0.8: a pure-Rust IPOPT-class primal–dual interior point
    /// method (filter line search, sparse LDLᵀ with inertia correction). EPL-2.0. The
    /// cross-check, and the planner's fallback where the native restoration phase fails.
    Ripopt,
    /// Our own primal–dual interior point ([`super::NativeSolver`]): IPOPT's filter line search
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

/// Counters and timings of one solve.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveStatistics {
    /// Iterations of the backend (restoration iterations included).
    pub iterations: usize,
    /// Final objective `f(x)`, unscaled.
    pub objective: f64,
    /// Final constraint violation (max norm, unscaled, bounds included).
    pub primal_infeasibility: f64,
    /// Final dual infeasibility as reported by the backend.
    pub dual_infeasibility: f64,
    /// Calls of `objective`, `gradient`, `constraints`, `jacobian_values`, `hessian_values`.
    pub evaluation_counts: EvaluationCounts,
    /// Wall time spent inside the problem's functions.
    pub evaluation_time: Duration,
    /// Wall time spent in the backend itself (total minus evaluation).
    pub solver_time: Duration,
    /// Wall time of the whole solve.
    pub total_time: Duration,
    /// Iterations spent in the feasibility-restoration phase (counted in `iterations` too),
    /// for the backends that say which ones those are (native; `None` for ripopt).
    pub restoration_iterations: Option<usize>,
    /// Where the backend's own time (`solver_time`) went, for the backends that measure it
    /// (the native interior point; `None` for ripopt).
    pub phases: Option<PhaseTimes>,
}

/// The backend's own work by phase: the KKT factorizations, the solves with their factors and
/// the rest. With the evaluation time these add up to the total: the phases are disjoint wall
/// times (two inertia-correction trials factorized at once count once).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PhaseTimes {
    /// KKT matrices assembled and factorized: every inertia-correction trial and the
    /// least-squares estimate of the multipliers at the start (and after a restoration).
    pub factorizations: usize,
    /// Wall time of those assemblies and factorizations.
    pub factorization_time: Duration,
    /// Solves with a factor: search directions and second-order corrections (iterative
    /// refinement inside each).
    pub linear_solves: usize,
    /// Wall time of those solves.
    pub linear_solve_time: Duration,
    /// The rest of the backend's time: start point, scaling, error norms, barrier updates, the
    /// line search's arithmetic and the restoration problem's set-up.
    pub other_time: Duration,
}

impl std::ops::AddAssign for PhaseTimes {
    fn add_assign(&mut self, other: Self) {
        self.factorizations += other.factorizations;
        self.factorization_time += other.factorization_time;
        self.linear_solves += other.linear_solves;
        self.linear_solve_time += other.linear_solve_time;
        self.other_time += other.other_time;
    }
}

/// The sum of a figure of two solves, if both measured it (`None` if either did not: the
/// restoration iterations or the phases of a solve that ran partly on ripopt).
pub fn sum_if_both<T: std::ops::AddAssign>(a: Option<T>, b: Option<T>) -> Option<T> {
    let (mut a, b) = (a?, b?);
    a += b;
    Some(a)
}

impl SolveStatistics {
    /// Adds the work of `earlier`, a solve this one continues (a fallback to another backend):
    /// iterations, evaluations and times are the sum; the phases only if both solves measured
    /// them.
    pub fn absorb(&mut self, earlier: &SolveStatistics) {
        self.iterations += earlier.iterations;
        self.restoration_iterations =
            sum_if_both(self.restoration_iterations, earlier.restoration_iterations);
        self.evaluation_counts += earlier.evaluation_counts;
        self.evaluation_time += earlier.evaluation_time;
        self.solver_time += earlier.solver_time;
        self.total_time += earlier.total_time;
        self.phases = sum_if_both(self.phases, earlier.phases);
    }
}

/// How often each problem function was called.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EvaluationCounts {
    /// `objective` calls.
    pub objective: usize,
    /// `gradient` calls.
    pub gradient: usize,
    /// `constraints` calls.
    pub constraints: usize,
    /// `jacobian_values` calls.
    pub jacobian: usize,
    /// `hessian_values` calls.
    pub hessian: usize,
}

impl std::ops::AddAssign for EvaluationCounts {
    /// Adds the calls of another solve (a restoration phase's, or an earlier solve's).
    fn add_assign(&mut self, other: Self) {
        self.objective += other.objective;
        self.gradient += other.gradient;
        self.constraints += other.constraints;
        self.jacobian += other.jacobian;
        self.hessian += other.hessian;
    }
}

/// The outcome of a solve: the last iterate, its multipliers and how it ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Why the solve stopped; check [`SolveStatus::is_success`].
    pub status: SolveStatus,
    /// Final primal point.
    pub x: Vec<f64>,
    /// Constraint values `g(x)`.
    pub constraint_values: Vec<f64>,
    /// Constraint multipliers λ (Lagrangian `f + λᵀg`).
    pub constraint_multipliers: Vec<f64>,
    /// Lower-bound multipliers z_l ≥ 0.
    pub lower_bound_multipliers: Vec<f64>,
    /// Upper-bound multipliers z_u ≥ 0.
    pub upper_bound_multipliers: Vec<f64>,
    /// Counters and timings.
    pub statistics: SolveStatistics,
}

impl Solution {
    /// A warm start from this solution: its point and all its multipliers.
    pub fn warm_start(&self) -> WarmStart {
        WarmStart {
            x: Some(self.x.clone()),
            constraint_multipliers: self.constraint_multipliers.clone(),
            lower_bound_multipliers: self.lower_bound_multipliers.clone(),
            upper_bound_multipliers: self.upper_bound_multipliers.clone(),
        }
    }
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

/// Solves `problem` with the backend named in `options`.
///
/// Fails only when the problem or options are malformed; see [`Solution::status`]
/// for how the iteration ended.
pub fn solve(problem: &dyn NlpProblem, options: &SolveOptions) -> Result<Solution> {
    solve_with_callback(problem, options, &mut |_| IterationControl::Continue)
}

/// Like [`solve`], calling `on_iteration` once per iteration (live progress, early stop).
pub fn solve_with_callback(
    problem: &dyn NlpProblem,
    options: &SolveOptions,
    on_iteration: &mut dyn FnMut(&IterationReport) -> IterationControl,
) -> Result<Solution> {
    validate_options(options)?;
    validate_problem(problem, options.warm_start.as_ref())?;
    match options.backend {
        Backend::Ripopt => RipoptSolver.solve_with_callback(problem, options, on_iteration),
        Backend::Native => {
            super::ipm::NativeSolver.solve_with_callback(problem, options, on_iteration)
        }
    }
}

fn validate_options(options: &SolveOptions) -> Result<()> {
    for (name, value) in [
        ("tolerance", options.tolerance),
        (
            "constraint_violation_tolerance",
            options.constraint_violation_tolerance,
        ),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(NlpError::InvalidOption {
                name,
                value,
                reason: "must be finite and positive",
            });
        }
    }
    if let Some(value) = options.initial_barrier {
        if !(value.is_finite() && value > 0.0) {
            return Err(NlpError::InvalidOption {
                name: "initial_barrier",
                value,
                reason: "must be finite and positive",
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::nlp::ad::DenseAdProblem;
    use crate::nlp::test_problems::Hs71;

    fn hs71() -> DenseAdProblem<Hs71> {
        DenseAdProblem::new(Hs71::standard())
    }

    #[test]
    fn solves_hs71_and_reports_consistent_statistics() {
        let solution = solve(&hs71(), &SolveOptions::default()).unwrap();
        assert_eq!(solution.status, SolveStatus::Optimal);
        let stats = solution.statistics;
        assert!((stats.objective - 17.014_017_3).abs() < 1e-6, "{stats:?}");
        // Like IPOPT, ripopt relaxes bounds by 1e-8 relative (`bound_relax_factor`).
        assert!(stats.primal_infeasibility < 1e-6, "{stats:?}");
        // The product constraint is active (λ ≠ 0), the norm constraint too.
        assert!((solution.constraint_values[0] - 25.0).abs() < 1e-6);
        assert!((solution.constraint_values[1] - 40.0).abs() < 1e-6);
        assert!(stats.evaluation_counts.hessian >= stats.iterations.saturating_sub(1));
        assert!(stats.evaluation_time <= stats.total_time);
        assert_eq!(stats.evaluation_time + stats.solver_time, stats.total_time);
    }

    /// The native backend splits its own time into disjoint phases that add up to it: were a
    /// phase to overlap the evaluations (or another phase), the derived rest would be clipped
    /// at zero and the sum would exceed the solver time.
    #[test]
    fn the_native_backend_splits_its_time_by_phase_and_ripopt_says_it_does_not() {
        let native = solve(&hs71(), &SolveOptions::default()).unwrap().statistics;
        let p = native.phases.expect("the native backend times its phases");
        println!("{native:?}");
        assert_eq!(native.restoration_iterations, Some(0));
        // At least one factorization and one solve per iteration (the last iterate is only
        // tested, not stepped from).
        assert!(p.factorizations >= native.iterations, "{p:?}");
        assert!(p.linear_solves >= native.iterations, "{p:?}");
        assert!(p.factorization_time > Duration::ZERO && p.linear_solve_time > Duration::ZERO);
        assert_eq!(
            p.factorization_time + p.linear_solve_time + p.other_time,
            native.solver_time,
            "{p:?}"
        );
        let ripopt = solve(
            &hs71(),
            &SolveOptions {
                backend: Backend::Ripopt,
                ..SolveOptions::default()
            },
        )
        .unwrap()
        .statistics;
        assert_eq!((ripopt.phases, ripopt.restoration_iterations), (None, None));
    }

    /// A solve continued on another backend reports the sum of both, and a phase split only
    /// where both solves measured it.
    #[test]
    fn absorbing_an_earlier_solve_adds_its_work() {
        let phases = PhaseTimes {
            factorizations: 3,
            factorization_time: Duration::from_millis(30),
            linear_solves: 4,
            linear_solve_time: Duration::from_millis(4),
            other_time: Duration::from_millis(6),
        };
        let native = SolveStatistics {
            iterations: 3,
            restoration_iterations: Some(1),
            evaluation_counts: EvaluationCounts {
                objective: 5,
                hessian: 3,
                ..EvaluationCounts::default()
            },
            evaluation_time: Duration::from_millis(10),
            solver_time: Duration::from_millis(40),
            total_time: Duration::from_millis(50),
            phases: Some(phases),
            ..SolveStatistics::default()
        };
        let mut twice = native;
        twice.absorb(&native);
        assert_eq!(twice.iterations, 6);
        assert_eq!(twice.restoration_iterations, Some(2));
        assert_eq!(
            (
                twice.evaluation_counts.objective,
                twice.evaluation_counts.hessian
            ),
            (10, 6)
        );
        assert_eq!(twice.total_time, Duration::from_millis(100));
        assert_eq!(twice.evaluation_time + twice.solver_time, twice.total_time);
        let p = twice.phases.unwrap();
        assert_eq!((p.factorizations, p.linear_solves), (6, 8));
        assert_eq!(
            p.factorization_time + p.linear_solve_time + p.other_time,
            twice.solver_time
        );
        let mut fallback = SolveStatistics {
            iterations: 7,
            ..SolveStatistics::default()
        };
        fallback.absorb(&native);
        assert_eq!(fallback.iterations, 10);
        assert_eq!(
            (fallback.phases, fallback.restoration_iterations),
            (None, None)
        );
    }

    /// Every end the trait names is reached, by both backends where they share it: Optimal
    /// (HS71), Infeasible (x² ≤ −1), IterationLimit (HS71 in 2 iterations), TimeLimit (1 ns of
    /// wall time), Diverging
    /// (min −x₀², both at iteration 67, x₀ ≈ 2.5e21 past IPOPT's 1e20) and Acceptable: HS71 to
    /// an unreachable tolerance of 1e-20 fails numerically once μ is tiny, at a point within
    /// the acceptable tolerances, which the native backend reports as IPOPT does
    /// (`STOP_AT_ACCEPTABLE_POINT`); ripopt ends with a tiny step there.
    #[test]
    fn every_status_is_reached_by_both_backends() {
        use crate::nlp::test_problems::{Infeasible, Unbounded};
        for backend in [Backend::Native, Backend::Ripopt] {
            let options = SolveOptions {
                backend,
                ..SolveOptions::default()
            };
            let status = |problem: &dyn NlpProblem, options: &SolveOptions| {
                let s = solve(problem, options).unwrap();
                println!(
                    "{backend:?}: {:?} in {} iterations, f = {}",
                    s.status, s.statistics.iterations, s.statistics.objective
                );
                s
            };
            let optimal = status(&hs71(), &options);
            assert_eq!(optimal.status, SolveStatus::Optimal);
            let infeasible = status(&DenseAdProblem::new(Infeasible), &options);
            assert_eq!(infeasible.status, SolveStatus::Infeasible, "{backend:?}");
            let capped = SolveOptions {
                max_iterations: 2,
                ..options.clone()
            };
            let limited = status(&hs71(), &capped);
            assert_eq!(limited.status, SolveStatus::IterationLimit, "{backend:?}");
            assert!(limited.statistics.iterations <= 2);
            let timed = SolveOptions {
                max_wall_time: Some(Duration::from_nanos(1)),
                ..options.clone()
            };
            assert_eq!(status(&hs71(), &timed).status, SolveStatus::TimeLimit);
            let diverging = status(&DenseAdProblem::new(Unbounded), &options);
            assert_eq!(diverging.status, SolveStatus::Diverging, "{backend:?}");
            assert!(diverging.x[0].abs() > 1e20 && diverging.statistics.iterations < 100);
            let unreachable = SolveOptions {
                tolerance: 1e-20,
                ..options.clone()
            };
            let tight = status(&hs71(), &unreachable);
            assert!(
                (tight.statistics.objective - 17.014_017_3).abs() < 1e-6,
                "{backend:?}"
            );
            let expected = match backend {
                Backend::Native => SolveStatus::Acceptable,
                Backend::Ripopt => SolveStatus::TinyStep,
            };
            assert_eq!(tight.status, expected);
        }
    }

    #[test]
    fn callback_sees_every_iteration_and_can_stop_the_solve() {
        let mut seen = Vec::new();
        let solution = solve_with_callback(&hs71(), &SolveOptions::default(), &mut |report| {
            seen.push(*report);
            IterationControl::Continue
        })
        .unwrap();
        assert!(!seen.is_empty());
        assert_eq!(seen[0].iteration, 0);
        let last = seen.last().unwrap();
        assert_eq!(last.iteration, solution.statistics.iterations);
        assert!(last.primal_infeasibility < 1e-6);

        let mut calls = 0;
        let stopped = solve_with_callback(&hs71(), &SolveOptions::default(), &mut |_| {
            calls += 1;
            if calls >= 2 {
                IterationControl::Stop
            } else {
                IterationControl::Continue
            }
        })
        .unwrap();
        assert_eq!(stopped.status, SolveStatus::UserStop);
        assert!(stopped.statistics.iterations < solution.statistics.iterations);
    }

    #[test]
    fn warm_start_from_the_optimum_needs_fewer_iterations() {
        let cold = solve(&hs71(), &SolveOptions::default()).unwrap();
        let options = SolveOptions {
            warm_start: Some(cold.warm_start()),
            ..SolveOptions::default()
        };
        let warm = solve(&hs71(), &options).unwrap();
        assert_eq!(warm.status, SolveStatus::Optimal);
        assert!(
            warm.statistics.iterations < cold.statistics.iterations,
            "warm {} vs cold {}",
            warm.statistics.iterations,
            cold.statistics.iterations
        );
        assert!((warm.statistics.objective - cold.statistics.objective).abs() < 1e-7);
    }

    /// The multipliers of a warm start reach the backend (ripopt 0.8.2 drops those of its
    /// `initial_multipliers` hook; the adapter passes them through its options instead). The
    /// first barrier parameter of a warm start is the average complementarity of the start:
    /// small from an optimum with its multipliers (it was 2.0 here while they were dropped and
    /// reset to 1), and the solve ends at the same optimum.
    #[test]
    fn warm_start_multipliers_reach_the_solver() {
        let cold = solve(&hs71(), &SolveOptions::default()).unwrap();
        let mut first_mu = None;
        let warm = solve_with_callback(
            &hs71(),
            &SolveOptions {
                warm_start: Some(cold.warm_start()),
                ..SolveOptions::default()
            },
            &mut |r| {
                first_mu.get_or_insert(r.barrier_parameter);
                IterationControl::Continue
            },
        )
        .unwrap();
        let first_mu = first_mu.unwrap();
        assert!(first_mu < 1e-3, "first μ {first_mu}");
        assert_eq!(warm.status, SolveStatus::Optimal);
        assert!((warm.statistics.objective - cold.statistics.objective).abs() < 1e-7);
        for (w, c) in warm
            .constraint_multipliers
            .iter()
            .zip(&cold.constraint_multipliers)
        {
            assert!((w - c).abs() < 1e-5 * c.abs().max(1.0), "λ {w} vs {c}");
        }
    }

    #[test]
    fn malformed_input_is_rejected_with_a_typed_error() {
        let crossed = DenseAdProblem::new(Hs71 {
            lower_bound: 6.0,
            fix_first: false,
        });
        assert_eq!(
            solve(&crossed, &SolveOptions::default()),
            Err(NlpError::InvalidBounds {
                kind: "variable",
                index: 0,
                lower: 6.0,
                upper: 5.0
            })
        );
        let short_start = SolveOptions {
            warm_start: Some(WarmStart {
                x: None,
                constraint_multipliers: vec![0.0; 1],
                lower_bound_multipliers: vec![0.0; 4],
                upper_bound_multipliers: vec![0.0; 4],
            }),
            ..SolveOptions::default()
        };
        assert_eq!(
            solve(&hs71(), &short_start),
            Err(NlpError::WarmStartLength {
                field: "constraint_multipliers",
                expected: 2,
                actual: 1
            })
        );
        let bad_tolerance = SolveOptions {
            tolerance: 0.0,
            ..SolveOptions::default()
        };
        assert!(matches!(
            solve(&hs71(), &bad_tolerance),
            Err(NlpError::InvalidOption {
                name: "tolerance",
                ..
            })
        ));
        for value in [0.0, -1e-3, f64::NAN] {
            let bad_barrier = SolveOptions {
                initial_barrier: Some(value),
                ..SolveOptions::default()
            };
            assert!(matches!(
                solve(&hs71(), &bad_barrier),
                Err(NlpError::InvalidOption {
                    name: "initial_barrier",
                    ..
                })
            ));
        }
    }

    /// `initial_barrier` is the first iterate's μ on a cold start, with either backend; the
    /// default is IPOPT's 0.1; a warm start's multipliers set μ instead.
    #[test]
    fn initial_barrier_sets_the_cold_start_mu() {
        for backend in [Backend::Native, Backend::Ripopt] {
            let first_mu = |options: SolveOptions| {
                let mut mu = Vec::new();
                solve_with_callback(&hs71(), &options, &mut |r| {
                    mu.push(r.barrier_parameter);
                    IterationControl::Continue
                })
                .unwrap();
                mu[0]
            };
            let base = SolveOptions {
                backend,
                ..SolveOptions::default()
            };
            assert_eq!(first_mu(base.clone()), 0.1, "{backend:?}");
            let small = SolveOptions {
                initial_barrier: Some(1e-3),
                ..base.clone()
            };
            assert_eq!(first_mu(small), 1e-3, "{backend:?}");
        }
        let cold = solve(&hs71(), &SolveOptions::default()).unwrap();
        let warm = SolveOptions {
            warm_start: Some(cold.warm_start()),
            initial_barrier: Some(0.05),
            ..SolveOptions::default()
        };
        let mut mu = Vec::new();
        solve_with_callback(&hs71(), &warm, &mut |r| {
            mu.push(r.barrier_parameter);
            IterationControl::Continue
        })
        .unwrap();
        assert!(mu[0] < 1e-3, "{mu:?}");
    }
}
