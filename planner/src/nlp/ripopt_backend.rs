//! The default backend: [`ripopt`], a pure-Rust IPOPT-class interior point method.
//!
//! The adapter translates our [`NlpProblem`] into `ripopt::NlpProblem`, times
//! every function evaluation and relays ripopt's per-iteration callback.
//!
//! ripopt's iteration callback is a C function pointer stored in a
//! thread-local. To stay free of `unsafe`, the C callback only queues an
//! [`IterationReport`] in our own thread-local; the adapter hands the queue
//! to the caller's closure at the next function evaluation (microseconds
//! later) and at the end of the solve. A `Stop` answer is passed back to
//! ripopt at its next iteration.

use std::cell::{Cell, RefCell};
use std::os::raw::{c_double, c_int, c_void};
use std::time::{Duration, Instant};

use super::interface::{
    DomainError, EvaluationCounts, IterationControl, IterationReport, NlpProblem, NlpSolver,
    Result, Solution, SolveOptions, SolveStatistics, SolveStatus, WarmStart,
};

/// The [`Backend::Ripopt`](super::Backend::Ripopt) solver.
#[derive(Debug, Clone, Copy, Default)]
pub struct RipoptSolver;

#[derive(Default)]
struct CallbackChannel {
    pending: Vec<IterationReport>,
    stop_requested: bool,
}

thread_local! {
    static CHANNEL: RefCell<CallbackChannel> = RefCell::new(CallbackChannel::default());
}

#[allow(clippy::too_many_arguments)]
extern "C" fn queue_iteration_report(
    algorithm_mode: c_int,
    iteration: c_int,
    objective: c_double,
    primal_infeasibility: c_double,
    dual_infeasibility: c_double,
    barrier_parameter: c_double,
    step_norm: c_double,
    _regularization: c_double,
    _dual_step: c_double,
    _primal_step: c_double,
    _line_search_trials: c_int,
    _user_data: *mut c_void,
) -> c_int {
    CHANNEL.with(|channel| {
        let mut channel = channel.borrow_mut();
        channel.pending.push(IterationReport {
            iteration: usize::try_from(iteration).unwrap_or(0),
            objective,
            primal_infeasibility,
            dual_infeasibility,
            barrier_parameter,
            step_norm,
            restoration: algorithm_mode != 0,
        });
        c_int::from(!channel.stop_requested)
    })
}

/// Installs the callback for one solve and restores the previous state on drop
/// (also on panic, and for a solve nested inside a callback).
struct CallbackGuard {
    previous: Option<CallbackChannel>,
}

impl CallbackGuard {
    fn install() -> Self {
        let previous = CHANNEL.with(|channel| channel.replace(CallbackChannel::default()));
        ripopt::intermediate::set_intermediate_callback(Some((
            queue_iteration_report,
            std::ptr::null_mut(),
        )));
        Self {
            previous: Some(previous),
        }
    }
}

impl Drop for CallbackGuard {
    fn drop(&mut self) {
        if let Some(previous) = self.previous.take() {
            CHANNEL.with(|channel| channel.replace(previous));
        }
        // Leave the hook installed: it only queues into our channel, and
        // a nested solve's guard keeps the outer one working.
    }
}

struct Adapter<'a> {
    problem: &'a dyn NlpProblem,
    warm_start: Option<&'a WarmStart>,
    on_iteration: RefCell<&'a mut dyn FnMut(&IterationReport) -> IterationControl>,
    evaluation_time: Cell<Duration>,
    counts: Cell<EvaluationCounts>,
}

impl Adapter<'_> {
    /// Hands queued iteration reports to the caller's closure.
    fn deliver_reports(&self) {
        let pending = CHANNEL.with(|channel| std::mem::take(&mut channel.borrow_mut().pending));
        if pending.is_empty() {
            return;
        }
        // A re-entrant call (the closure evaluating the problem) finds the borrow taken and skips.
        let Ok(mut on_iteration) = self.on_iteration.try_borrow_mut() else {
            return;
        };
        for report in &pending {
            if on_iteration(report) == IterationControl::Stop {
                CHANNEL.with(|channel| channel.borrow_mut().stop_requested = true);
            }
        }
    }

    fn timed<T>(&self, count: impl FnOnce(&mut EvaluationCounts), f: impl FnOnce() -> T) -> T {
        self.deliver_reports();
        let start = Instant::now();
        let out = f();
        self.evaluation_time
            .set(self.evaluation_time.get() + start.elapsed());
        let mut counts = self.counts.get();
        count(&mut counts);
        self.counts.set(counts);
        out
    }
}

fn ok(result: std::result::Result<(), DomainError>) -> bool {
    result.is_ok()
}

impl ripopt::NlpProblem for Adapter<'_> {
    fn num_variables(&self) -> usize {
        self.problem.num_variables()
    }

    fn num_constraints(&self) -> usize {
        self.problem.num_constraints()
    }

    fn bounds(&self, x_l: &mut [f64], x_u: &mut [f64]) {
        self.problem.variable_bounds(x_l, x_u);
    }

    fn constraint_bounds(&self, g_l: &mut [f64], g_u: &mut [f64]) {
        self.problem.constraint_bounds(g_l, g_u);
    }

    fn initial_point(&self, x0: &mut [f64]) {
        match self.warm_start.and_then(|start| start.x.as_ref()) {
            Some(x) => x0.copy_from_slice(x),
            None => self.problem.initial_point(x0),
        }
    }

    fn objective(&self, x: &[f64], _new_x: bool, obj: &mut f64) -> bool {
        self.timed(
            |c| c.objective += 1,
            || match self.problem.objective(x) {
                Ok(value) => {
                    *obj = value;
                    true
                }
                Err(DomainError) => false,
            },
        )
    }

    fn gradient(&self, x: &[f64], _new_x: bool, grad: &mut [f64]) -> bool {
        self.timed(|c| c.gradient += 1, || ok(self.problem.gradient(x, grad)))
    }

    fn constraints(&self, x: &[f64], _new_x: bool, g: &mut [f64]) -> bool {
        self.timed(
            |c| c.constraints += 1,
            || ok(self.problem.constraints(x, g)),
        )
    }

    fn jacobian_structure(&self) -> (Vec<usize>, Vec<usize>) {
        let pattern = self.problem.jacobian_structure();
        (pattern.rows, pattern.cols)
    }

    fn jacobian_values(&self, x: &[f64], _new_x: bool, vals: &mut [f64]) -> bool {
        self.timed(
            |c| c.jacobian += 1,
            || ok(self.problem.jacobian_values(x, vals)),
        )
    }

    fn hessian_structure(&self) -> (Vec<usize>, Vec<usize>) {
        let pattern = self.problem.hessian_structure();
        (pattern.rows, pattern.cols)
    }

    fn hessian_values(
        &self,
        x: &[f64],
        _new_x: bool,
        obj_factor: f64,
        lambda: &[f64],
        vals: &mut [f64],
    ) -> bool {
        self.timed(
            |c| c.hessian += 1,
            || ok(self.problem.hessian_values(x, obj_factor, lambda, vals)),
        )
    }
}

fn ripopt_options(problem: &dyn NlpProblem, options: &SolveOptions) -> ripopt::SolverOptions {
    let mut out = ripopt::SolverOptions {
        tol: options.tolerance,
        constr_viol_tol: options.constraint_violation_tolerance,
        max_iter: options.max_iterations,
        print_level: options.print_level,
        max_wall_time: options.max_wall_time.map_or(0.0, |t| t.as_secs_f64()),
        // Our problems give exact Hessians; ripopt's linearity detection compares Jacobians at
        // two points and may drop the Hessian of a weakly nonlinear constraint.
        detect_linear_constraints: false,
        ..ripopt::SolverOptions::default()
    };
    if let (Some(mu), None) = (options.initial_barrier, &options.warm_start) {
        out.mu_init = mu;
    }
    if let Some(start) = &options.warm_start {
        out.warm_start = true;
        // IPOPT's advice for warm starts: push the start only slightly off the bounds.
        out.warm_start_bound_push = 1e-6;
        out.warm_start_bound_frac = 1e-6;
        out.warm_start_mult_bound_push = 1e-6;
        // IPOPT pushes a warm start by the warm-start values only; ripopt first applies
        // `bound_push`/`bound_frac` (1e-2) to every start, which moved an optimal point's slacks
        // a hundredth off their bounds and cost a re-converged solve (~130 iterations for the
        // co-design polish). The same 1e-6 for both, as IPOPT does.
        out.bound_push = out.warm_start_bound_push;
        out.bound_frac = out.warm_start_bound_frac;
        // A start point where the problem cannot be evaluated keeps only x; ripopt's own
        // first evaluation there then reports the domain error.
        let _ = warm_start_multipliers(problem, start, &mut out);
    }
    out
}

/// IPOPT's gradient-based scaling factor for a row (or the objective) whose largest
/// derivative magnitude at the start is `max_abs`: 100 / max_abs when that exceeds 100, at
/// least 1e-8 (`nlp_scaling_max_gradient`, `nlp_scaling_min_value`, ripopt's defaults).
fn gradient_scaling(max_abs: f64) -> f64 {
    const MAX_GRADIENT: f64 = 100.0;
    const MIN_VALUE: f64 = 1e-8;
    if max_abs > MAX_GRADIENT && max_abs.is_finite() {
        (MAX_GRADIENT / max_abs).max(MIN_VALUE)
    } else {
        1.0
    }
}

/// Hands a warm start's multipliers to ripopt through its options.
///
/// ripopt 0.8.2 never sees `NlpProblem::initial_multipliers`: its internal scaling wrapper
/// does not forward the call, so a warm start used to keep the point and silently restart
/// every multiplier at 1 (and then centre the barrier parameter on that: μ₀ = 129 from an
/// optimum). The options path works but takes the multipliers in ripopt's *scaled* space, so
/// this fixes the scaling itself, the same gradient-based rule ripopt applies at the start
/// point, passes it as the user scaling, and converts: z → z·s_f, λᵢ → λᵢ·s_f / s_gᵢ.
///
/// The slacks of the inequality rows and their bound multipliers cannot be warm-started:
/// ripopt initialises them *after* applying the warm-start options (overwriting
/// `warm_start_s` / `warm_start_v_l` / `warm_start_v_u`), with `bound_mult_init_val` as the
/// multipliers. Setting that to the multiplier push starts them small instead of at 1; the
/// first Newton step then restores the active ones.
fn warm_start_multipliers(
    problem: &dyn NlpProblem,
    start: &WarmStart,
    out: &mut ripopt::SolverOptions,
) -> std::result::Result<(), DomainError> {
    let (n, m) = (problem.num_variables(), problem.num_constraints());
    let x0 = match &start.x {
        Some(x) => x.clone(),
        None => {
            let mut x0 = vec![0.0; n];
            problem.initial_point(&mut x0);
            x0
        }
    };
    let mut gradient = vec![0.0; n];
    problem.gradient(&x0, &mut gradient)?;
    let obj_scaling = gradient_scaling(gradient.iter().fold(0.0, |a: f64, g| a.max(g.abs())));
    let pattern = problem.jacobian_structure();
    let mut jacobian = vec![0.0; pattern.rows.len()];
    problem.jacobian_values(&x0, &mut jacobian)?;
    let mut row_max = vec![0.0_f64; m];
    for (&row, value) in pattern.rows.iter().zip(&jacobian) {
        if value.is_finite() {
            row_max[row] = row_max[row].max(value.abs());
        }
    }
    let g_scaling: Vec<f64> = row_max.into_iter().map(gradient_scaling).collect();

    let scaled =
        |multipliers: &[f64]| -> Vec<f64> { multipliers.iter().map(|z| z * obj_scaling).collect() };
    out.warm_start_z_l = Some(scaled(&start.lower_bound_multipliers));
    out.warm_start_z_u = Some(scaled(&start.upper_bound_multipliers));
    out.warm_start_y = Some(
        (start.constraint_multipliers.iter().zip(&g_scaling))
            .map(|(&l, &sg)| l * obj_scaling / sg)
            .collect(),
    );
    out.bound_mult_init_val = out.warm_start_mult_bound_push;
    out.user_obj_scaling = Some(obj_scaling);
    out.user_g_scaling = Some(g_scaling);
    Ok(())
}

fn map_status(status: ripopt::SolveStatus) -> SolveStatus {
    use ripopt::SolveStatus as R;
    match status {
        R::Optimal => SolveStatus::Optimal,
        R::Acceptable => SolveStatus::Acceptable,
        R::Infeasible | R::LocalInfeasibility => SolveStatus::Infeasible,
        R::MaxIterations => SolveStatus::IterationLimit,
        R::MaxTimeExceeded => SolveStatus::TimeLimit,
        R::DivergingIterates => SolveStatus::Diverging,
        R::RestorationFailed => SolveStatus::RestorationFailed,
        R::StopAtTinyStep => SolveStatus::TinyStep,
        R::EvaluationError => SolveStatus::EvaluationError,
        R::UserRequestedStop => SolveStatus::UserStop,
        R::NumericalError | R::InternalError => SolveStatus::NumericalError,
    }
}

/// Max-norm violation of `lower ≤ value ≤ upper` over all entries.
pub(crate) fn max_violation(values: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
    values
        .iter()
        .zip(lower.iter().zip(upper))
        .map(|(&v, (&lo, &up))| (lo - v).max(v - up).max(0.0))
        .fold(0.0, f64::max)
}

impl NlpSolver for RipoptSolver {
    fn solve_with_callback(
        &self,
        problem: &dyn NlpProblem,
        options: &SolveOptions,
        on_iteration: &mut dyn FnMut(&IterationReport) -> IterationControl,
    ) -> Result<Solution> {
        let started = Instant::now();
        let guard = CallbackGuard::install();
        let adapter = Adapter {
            problem,
            warm_start: options.warm_start.as_ref(),
            on_iteration: RefCell::new(on_iteration),
            evaluation_time: Cell::new(Duration::ZERO),
            counts: Cell::new(EvaluationCounts::default()),
        };
        let result = ripopt::solve(&adapter, &ripopt_options(problem, options));
        adapter.deliver_reports();
        drop(guard);

        let n = problem.num_variables();
        let m = problem.num_constraints();
        let (mut x_lower, mut x_upper) = (vec![0.0; n], vec![0.0; n]);
        problem.variable_bounds(&mut x_lower, &mut x_upper);
        let (mut g_lower, mut g_upper) = (vec![0.0; m], vec![0.0; m]);
        problem.constraint_bounds(&mut g_lower, &mut g_upper);
        let primal_infeasibility = max_violation(&result.x, &x_lower, &x_upper).max(max_violation(
            &result.constraint_values,
            &g_lower,
            &g_upper,
        ));

        let total_time = started.elapsed();
        let evaluation_time = adapter.evaluation_time.get();
        Ok(Solution {
            status: map_status(result.status),
            statistics: SolveStatistics {
                iterations: result.iterations,
                objective: result.objective,
                primal_infeasibility,
                dual_infeasibility: result.diagnostics.final_dual_inf,
                evaluation_counts: adapter.counts.get(),
                evaluation_time,
                solver_time: total_time.saturating_sub(evaluation_time),
                total_time,
                // ripopt's restoration is a nested solve whose reports are not flagged
                // (`queue_iteration_report`), and it does not time its linear algebra.
                restoration_iterations: None,
                phases: None,
            },
            x: result.x,
            constraint_values: result.constraint_values,
            constraint_multipliers: result.constraint_multipliers,
            lower_bound_multipliers: result.bound_multipliers_lower,
            upper_bound_multipliers: result.bound_multipliers_upper,
        })
    }
}
