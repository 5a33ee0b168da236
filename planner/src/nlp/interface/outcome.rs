//! What a solve returns: how it ended ([`SolveStatus`]), the point and multipliers
//! ([`Solution`]) and what it cost ([`SolveStatistics`], [`PhaseTimes`], [`EvaluationCounts`]).

use std::time::Duration;

use super::options::WarmStart;

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
