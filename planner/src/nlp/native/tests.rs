#![allow(clippy::unwrap_used)]

use num_dual::DualNum;

use crate::nlp::ad::{AdModel, DenseAdProblem};
use crate::nlp::test_problems::{Hs71, Infeasible};
use crate::nlp::{
    solve, solve_with_callback, Backend, DomainError, IterationControl, NlpProblem, SolveOptions,
    SolveStatus, SparsityPattern,
};

fn native() -> SolveOptions {
    SolveOptions {
        backend: Backend::Native,
        ..SolveOptions::default()
    }
}

#[test]
fn hs71_optimum_and_multipliers_agree_with_ripopt() {
    let problem = DenseAdProblem::new(Hs71::standard());
    let ours = solve(&problem, &native()).unwrap();
    let reference = solve(
        &problem,
        &SolveOptions {
            backend: Backend::Ripopt,
            ..SolveOptions::default()
        },
    )
    .unwrap();
    assert_eq!(ours.status, SolveStatus::Optimal);
    let stats = ours.statistics;
    assert!((stats.objective - 17.014_017_3).abs() < 1e-6, "{stats:?}");
    assert!(stats.primal_infeasibility < 1e-6, "{stats:?}");
    assert_eq!(stats.evaluation_time + stats.solver_time, stats.total_time);
    // Same sign convention and scale as ripopt's (IPOPT's) multipliers: L = f + λᵀg. Both
    // stop at a tolerance of 1e-8 on the scaled KKT error, so they agree to ~1e-6.
    let close = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-5 * (1.0 + y.abs()))
    };
    assert!(
        close(
            &ours.constraint_multipliers,
            &reference.constraint_multipliers
        ),
        "{:?} vs {:?}",
        ours.constraint_multipliers,
        reference.constraint_multipliers
    );
    assert!(close(
        &ours.lower_bound_multipliers,
        &reference.lower_bound_multipliers
    ));
    assert!(close(
        &ours.upper_bound_multipliers,
        &reference.upper_bound_multipliers
    ));
    assert!(close(&ours.x, &reference.x));
}

#[test]
fn the_gradient_and_jacobian_are_evaluated_once_per_iterate() {
    let problem = DenseAdProblem::new(Hs71::standard());
    let sol = solve(&problem, &native()).unwrap();
    assert_eq!(sol.status, SolveStatus::Optimal);
    let stats = sol.statistics;
    let counts = stats.evaluation_counts;
    // HS71 needs no restoration: the scaling and the start point, then one evaluation per
    // accepted iterate. W is evaluated at the first iteration's top and then with J at
    // each accepted iterate (the last one's is not used: the solve ends there), never
    // again at a top.
    assert!(stats.iterations > 3, "{stats:?}");
    assert_eq!(counts.jacobian, stats.iterations + 2, "{counts:?}");
    assert_eq!(counts.gradient, stats.iterations + 2, "{counts:?}");
    assert_eq!(counts.hessian, stats.iterations + 1, "{counts:?}");
}

/// HS71 whose Hessian cannot be evaluated at the point of its `fail_at`-th call (counting
/// from 1), then or at any later call there.
struct HessianFailsOnce {
    inner: DenseAdProblem<Hs71>,
    calls: std::cell::Cell<usize>,
    fail_at: usize,
    failing_x: std::cell::RefCell<Option<Vec<f64>>>,
}

impl NlpProblem for HessianFailsOnce {
    fn num_variables(&self) -> usize {
        self.inner.num_variables()
    }
    fn num_constraints(&self) -> usize {
        self.inner.num_constraints()
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.inner.variable_bounds(lower, upper)
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.inner.constraint_bounds(lower, upper)
    }
    fn initial_point(&self, x0: &mut [f64]) {
        self.inner.initial_point(x0)
    }
    fn objective(&self, x: &[f64]) -> Result<f64, DomainError> {
        self.inner.objective(x)
    }
    fn gradient(&self, x: &[f64], g: &mut [f64]) -> Result<(), DomainError> {
        self.inner.gradient(x, g)
    }
    fn constraints(&self, x: &[f64], g: &mut [f64]) -> Result<(), DomainError> {
        self.inner.constraints(x, g)
    }
    fn jacobian_structure(&self) -> SparsityPattern {
        self.inner.jacobian_structure()
    }
    fn jacobian_values(&self, x: &[f64], v: &mut [f64]) -> Result<(), DomainError> {
        self.inner.jacobian_values(x, v)
    }
    fn hessian_structure(&self) -> SparsityPattern {
        self.inner.hessian_structure()
    }
    fn hessian_values(
        &self,
        x: &[f64],
        sigma: f64,
        lambda: &[f64],
        v: &mut [f64],
    ) -> Result<(), DomainError> {
        self.calls.set(self.calls.get() + 1);
        if self.calls.get() == self.fail_at {
            *self.failing_x.borrow_mut() = Some(x.to_vec());
        }
        if self.failing_x.borrow().as_deref() == Some(x) {
            return Err(DomainError);
        }
        self.inner.hessian_values(x, sigma, lambda, v)
    }
}

/// W is evaluated with J after every accepted step, so also at the last iterate, where
/// the solve ends without using it. If it cannot be evaluated there, the solve still
/// converges to the same point; if it cannot be evaluated at an iterate that needs it,
/// the solve reports an evaluation error.
#[test]
fn a_hessian_the_solve_does_not_need_cannot_fail_it() {
    let reference = solve(&DenseAdProblem::new(Hs71::standard()), &native()).unwrap();
    let last = reference.statistics.evaluation_counts.hessian;
    let failing = |fail_at| HessianFailsOnce {
        inner: DenseAdProblem::new(Hs71::standard()),
        calls: std::cell::Cell::new(0),
        fail_at,
        failing_x: std::cell::RefCell::new(None),
    };
    let sol = solve(&failing(last), &native()).unwrap();
    assert_eq!(sol.status, SolveStatus::Optimal);
    assert_eq!(sol.x, reference.x);
    assert_eq!(sol.statistics.iterations, reference.statistics.iterations);
    let sol = solve(&failing(last - 1), &native()).unwrap();
    assert_eq!(sol.status, SolveStatus::EvaluationError);
}

#[test]
fn a_warm_start_from_the_optimum_converges_at_once() {
    let problem = DenseAdProblem::new(Hs71::standard());
    let cold = solve(&problem, &native()).unwrap();
    let warm = solve(
        &problem,
        &SolveOptions {
            warm_start: Some(cold.warm_start()),
            ..native()
        },
    )
    .unwrap();
    println!(
        "HS71, native: cold {} iterations, warm {}",
        cold.statistics.iterations, warm.statistics.iterations
    );
    assert_eq!(warm.status, SolveStatus::Optimal);
    assert!(
        warm.statistics.iterations <= 3 && cold.statistics.iterations >= 6,
        "warm {} cold {}",
        warm.statistics.iterations,
        cold.statistics.iterations
    );
    assert!((warm.statistics.objective - 17.014_017_3).abs() < 1e-6);
}

#[test]
fn a_fixed_variable_stays_at_its_value() {
    let problem = DenseAdProblem::new(Hs71 {
        lower_bound: 1.0,
        fix_first: true,
    });
    let s = solve(&problem, &native()).unwrap();
    assert_eq!(s.status, SolveStatus::Optimal);
    assert_eq!(s.x[0], 1.0);
    assert!((s.statistics.objective - 17.014_017_3).abs() < 1e-6);
}

/// min −‖x‖² on the disc ‖x − c‖² ≤ 1 inside the box [−3, 3]²: a concave objective, so every
/// iteration needs the inertia correction, with δ_w of the order of the curvature.
struct Concave;

impl AdModel for Concave {
    fn num_variables(&self) -> usize {
        2
    }
    fn num_constraints(&self) -> usize {
        1
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(-3.0);
        upper.fill(3.0);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower[0] = f64::NEG_INFINITY;
        upper[0] = 1.0;
    }
    fn initial_point(&self, x0: &mut [f64]) {
        x0.copy_from_slice(&[0.5, 0.2]);
    }
    fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
        -(x[0] * x[0] + x[1] * x[1])
    }
    fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
        g[0] = (x[0] - 1.0).powi(2) + (x[1] - 0.5).powi(2);
    }
}

/// Runs the interior point on `problem`, with δ_w trials in pairs if `pair`, and returns its
/// solution with the number of paired trials and of pairs the twin decided.
fn run_counting(problem: &dyn super::NlpProblem, pair: bool) -> (super::Solution, usize, usize) {
    let options = native();
    let mut ipm = super::Ipm::new(problem, &options);
    ipm.pair_trials = pair;
    let start = std::time::Instant::now();
    let status = ipm.iterate(&mut |_| IterationControl::Continue, start);
    let (pairs, twin) = (ipm.paired_trials, ipm.twin_accepted);
    (ipm.finish(status, start), pairs, twin)
}

#[test]
fn two_inertia_trials_at_once_give_the_sequential_iterates_bit_for_bit() {
    let problem = DenseAdProblem::new(Concave);
    let (paired, pairs, twin) = run_counting(&problem, true);
    let (sequential, seq_pairs, _) = run_counting(&problem, false);
    println!(
        "concave: {} iterations, {pairs} pairs, {twin} decided by the second trial",
        paired.statistics.iterations
    );
    assert_eq!(seq_pairs, 0);
    // The pairing happened, and the second trial of a pair decided some iterations: the
    // twin's factor was used in place of the first system's.
    assert!(pairs > 0 && twin > 0, "{pairs} pairs, {twin} by the twin");
    assert_eq!(paired.status, SolveStatus::Optimal);
    assert_eq!(sequential.status, SolveStatus::Optimal);
    assert_eq!(
        paired.statistics.iterations,
        sequential.statistics.iterations
    );
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&paired.x), bits(&sequential.x));
    assert_eq!(
        bits(&paired.constraint_multipliers),
        bits(&sequential.constraint_multipliers)
    );
    // The farthest point of the disc from the origin: c + c/‖c‖, ‖x‖² = (‖c‖ + 1)².
    let c = (1.25f64).sqrt();
    assert!(
        (paired.statistics.objective + (c + 1.0).powi(2)).abs() < 1e-6,
        "{:?}",
        paired.x
    );
}

#[test]
fn trials_are_paired_outside_the_rayon_pool_only() {
    let problem = DenseAdProblem::new(Concave);
    let options = native();
    let outside = super::Ipm::new(&problem, &options).pair_trials;
    assert_eq!(outside, rayon::current_num_threads() > 1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    assert!(!pool.install(|| super::Ipm::new(&problem, &options).pair_trials));
}

#[test]
fn an_infeasible_problem_is_reported_infeasible() {
    let s = solve(&DenseAdProblem::new(Infeasible), &native()).unwrap();
    // The restoration phase converges to x = 0, the least violation (x² + 1 ≥ 1 > 0).
    assert_eq!(s.status, SolveStatus::Infeasible);
    assert!(s.x[0].abs() < 1e-3, "{:?}", s.x);
    assert!(s.statistics.primal_infeasibility >= 1.0 - 1e-9);
}

#[test]
fn the_callback_sees_each_iteration_and_can_stop() {
    let problem = DenseAdProblem::new(Hs71::standard());
    let mut seen = Vec::new();
    let full = solve_with_callback(&problem, &native(), &mut |r| {
        seen.push(r.iteration);
        IterationControl::Continue
    })
    .unwrap();
    let expected: Vec<usize> = (0..=full.statistics.iterations).collect();
    assert_eq!(seen, expected);
    let stopped = solve_with_callback(&problem, &native(), &mut |r| {
        if r.iteration >= 2 {
            IterationControl::Stop
        } else {
            IterationControl::Continue
        }
    })
    .unwrap();
    assert_eq!(stopped.status, SolveStatus::UserStop);
    assert_eq!(stopped.statistics.iterations, 2);
}

/// Hock–Schittkowski 27 from (−5, −5, −5): the line search gets stuck far from the optimum
/// (f* = 0.04 at (−1, 1, 0)) and only the restoration phase gets it out. (From the standard
/// start (2, 2, 2) it needed restoration with feral's LDLᵀ; with faer's it converges in 31
/// iterations without.)
struct Hs27;

impl AdModel for Hs27 {
    fn num_variables(&self) -> usize {
        3
    }
    fn num_constraints(&self) -> usize {
        1
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(f64::NEG_INFINITY);
        upper.fill(f64::INFINITY);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower[0] = 0.0;
        upper[0] = 0.0;
    }
    fn initial_point(&self, x0: &mut [f64]) {
        x0.fill(-5.0);
    }
    fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
        (x[0] - 1.0).powi(2) * 0.01 + (x[1] - x[0] * x[0]).powi(2)
    }
    fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
        g[0] = x[0] + x[2] * x[2] + 1.0;
    }
}

#[test]
fn the_restoration_phase_rescues_a_stuck_line_search() {
    let mut reports = Vec::new();
    let s = solve_with_callback(&DenseAdProblem::new(Hs27), &native(), &mut |r| {
        reports.push(*r);
        IterationControl::Continue
    })
    .unwrap();
    let restoring = reports.iter().filter(|r| r.restoration).count();
    println!(
        "HS27: {:?} in {} iterations ({restoring} in restoration), f = {}",
        s.status, s.statistics.iterations, s.statistics.objective
    );
    assert_eq!(s.status, SolveStatus::Optimal);
    assert!((s.statistics.objective - 0.04).abs() < 1e-8);
    assert!(restoring > 0);
    assert!(reports.windows(2).all(|w| w[1].iteration > w[0].iteration));
    assert_eq!(reports.last().unwrap().iteration, s.statistics.iterations);
    // The statistics name the restoration iterations. Every iteration that steps, outer or
    // restoration, factorizes at least once; the return from each restoration counts one
    // iteration more with no factorization of its own. (A lower bound: it does not tell
    // the restoration's own factorizations from the outer ones.) The phases are disjoint.
    assert_eq!(s.statistics.restoration_iterations, Some(restoring));
    let entries = reports
        .windows(2)
        .filter(|w| !w[0].restoration && w[1].restoration)
        .count();
    let p = s.statistics.phases.unwrap();
    println!("{entries} restoration phase(s), {p:?}");
    assert!(entries > 0);
    assert!(
        p.factorizations + entries >= s.statistics.iterations,
        "{p:?}"
    );
    assert_eq!(
        p.factorization_time + p.linear_solve_time + p.other_time,
        s.statistics.solver_time
    );
}
