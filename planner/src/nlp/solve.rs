//! The backend choice: [`solve`] checks the problem and the options, then hands them to the
//! backend [`SolveOptions::backend`] names (the native interior point or ripopt).

use super::interface::{
    Backend, IterationControl, IterationReport, NlpError, NlpProblem, NlpSolver, Result, Solution,
    SolveOptions,
};
use super::native::NativeSolver;
use super::ripopt_backend::RipoptSolver;
use super::validate::validate_problem;

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
        Backend::Native => NativeSolver.solve_with_callback(problem, options, on_iteration),
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

    use std::time::Duration;

    use super::*;
    use crate::nlp::ad::DenseAdProblem;
    use crate::nlp::test_problems::Hs71;
    use crate::nlp::{EvaluationCounts, PhaseTimes, SolveStatistics, SolveStatus, WarmStart};

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
