//! A larger sparse problem: minimum-effort swing-up of a torque-limited
//! pendulum by trapezoidal collocation, with hand-written sparse derivatives
//! (checked against finite differences below).
//!
//! State (θ rad, ω rad/s), torque u N·m per unit inertia, dynamics
//! θ' = ω, ω' = u − (g/l) sin θ. From hanging still (θ = 0) to upright still
//! (θ = π) in a fixed time with |u| ≤ u_max. Cost ∫ u² dt.
//! Variables per node k: (θ_k, ω_k, u_k) at index 3k..3k+2.

#![allow(clippy::unwrap_used)]

use std::f64::consts::PI;

use planner::nlp::check::check_derivatives;
use planner::nlp::{solve, DomainError, NlpProblem, SolveOptions, SolveStatus, SparsityPattern};

const GRAVITY_OVER_LENGTH_PER_S2: f64 = 9.81;

struct PendulumSwingUp {
    intervals: usize,
    duration_s: f64,
    max_torque: f64,
}

impl PendulumSwingUp {
    fn nodes(&self) -> usize {
        self.intervals + 1
    }
    fn step_s(&self) -> f64 {
        self.duration_s / self.intervals as f64
    }
    /// Trapezoid weight of node k in ∫ u² dt.
    fn weight(&self, k: usize) -> f64 {
        if k == 0 || k == self.intervals {
            0.5 * self.step_s()
        } else {
            self.step_s()
        }
    }
}

fn theta(k: usize) -> usize {
    3 * k
}
fn omega(k: usize) -> usize {
    3 * k + 1
}
fn torque(k: usize) -> usize {
    3 * k + 2
}

impl NlpProblem for PendulumSwingUp {
    fn num_variables(&self) -> usize {
        3 * self.nodes()
    }
    fn num_constraints(&self) -> usize {
        2 * self.intervals
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        for k in 0..self.nodes() {
            lower[theta(k)] = f64::NEG_INFINITY;
            upper[theta(k)] = f64::INFINITY;
            lower[omega(k)] = f64::NEG_INFINITY;
            upper[omega(k)] = f64::INFINITY;
            lower[torque(k)] = -self.max_torque;
            upper[torque(k)] = self.max_torque;
        }
        // Boundary conditions as fixed variables.
        let last = self.intervals;
        for (index, value) in [
            (theta(0), 0.0),
            (omega(0), 0.0),
            (theta(last), PI),
            (omega(last), 0.0),
        ] {
            lower[index] = value;
            upper[index] = value;
        }
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(0.0);
        upper.fill(0.0);
    }
    fn initial_point(&self, x0: &mut [f64]) {
        for k in 0..self.nodes() {
            let s = k as f64 / self.intervals as f64;
            x0[theta(k)] = PI * s;
            x0[omega(k)] = PI / self.duration_s;
            x0[torque(k)] = 0.0;
        }
    }
    fn objective(&self, x: &[f64]) -> Result<f64, DomainError> {
        Ok((0..self.nodes())
            .map(|k| self.weight(k) * x[torque(k)].powi(2))
            .sum())
    }
    fn gradient(&self, x: &[f64], gradient: &mut [f64]) -> Result<(), DomainError> {
        gradient.fill(0.0);
        for k in 0..self.nodes() {
            gradient[torque(k)] = 2.0 * self.weight(k) * x[torque(k)];
        }
        Ok(())
    }
    fn constraints(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        let half_h = 0.5 * self.step_s();
        let a = GRAVITY_OVER_LENGTH_PER_S2;
        for k in 0..self.intervals {
            let acceleration = |j: usize| x[torque(j)] - a * x[theta(j)].sin();
            values[2 * k] =
                x[theta(k + 1)] - x[theta(k)] - half_h * (x[omega(k)] + x[omega(k + 1)]);
            values[2 * k + 1] =
                x[omega(k + 1)] - x[omega(k)] - half_h * (acceleration(k) + acceleration(k + 1));
        }
        Ok(())
    }
    fn jacobian_structure(&self) -> SparsityPattern {
        let mut pattern = SparsityPattern::new();
        for k in 0..self.intervals {
            for column in [theta(k), theta(k + 1), omega(k), omega(k + 1)] {
                pattern.push(2 * k, column);
            }
            for column in [
                omega(k),
                omega(k + 1),
                torque(k),
                torque(k + 1),
                theta(k),
                theta(k + 1),
            ] {
                pattern.push(2 * k + 1, column);
            }
        }
        pattern
    }
    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        let half_h = 0.5 * self.step_s();
        let a = GRAVITY_OVER_LENGTH_PER_S2;
        for (k, chunk) in values.chunks_exact_mut(10).enumerate() {
            chunk[..4].copy_from_slice(&[-1.0, 1.0, -half_h, -half_h]);
            chunk[4..].copy_from_slice(&[
                -1.0,
                1.0,
                -half_h,
                -half_h,
                half_h * a * x[theta(k)].cos(),
                half_h * a * x[theta(k + 1)].cos(),
            ]);
        }
        Ok(())
    }
    fn hessian_structure(&self) -> SparsityPattern {
        let mut pattern = SparsityPattern::new();
        for k in 0..self.nodes() {
            pattern.push(theta(k), theta(k));
            pattern.push(torque(k), torque(k));
        }
        pattern
    }
    fn hessian_values(
        &self,
        x: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        let half_h = 0.5 * self.step_s();
        let a = GRAVITY_OVER_LENGTH_PER_S2;
        for k in 0..self.nodes() {
            // θ_k enters the ω-defects of the intervals before and after node k.
            let before = if k > 0 {
                multipliers[2 * (k - 1) + 1]
            } else {
                0.0
            };
            let after = if k < self.intervals {
                multipliers[2 * k + 1]
            } else {
                0.0
            };
            values[2 * k] = -(before + after) * half_h * a * x[theta(k)].sin();
            values[2 * k + 1] = objective_factor * 2.0 * self.weight(k);
        }
        Ok(())
    }
}

#[test]
fn hand_written_derivatives_match_finite_differences() {
    let problem = PendulumSwingUp {
        intervals: 6,
        duration_s: 3.0,
        max_torque: 4.0,
    };
    let n = problem.num_variables();
    let x: Vec<f64> = (0..n).map(|i| 0.3 + 0.7 * (i as f64 * 1.7).sin()).collect();
    let multipliers: Vec<f64> = (0..problem.num_constraints())
        .map(|i| (i as f64 * 0.9).cos())
        .collect();
    let report = check_derivatives(&problem, &x, 0.8, &multipliers).unwrap();
    assert!(report.max_gradient_error < 1e-7, "{report:?}");
    assert!(report.max_jacobian_error < 1e-7, "{report:?}");
    assert!(report.max_hessian_error < 1e-6, "{report:?}");
    assert_eq!(report.jacobian_entries_outside_pattern, 0);
    assert_eq!(report.hessian_entries_outside_pattern, 0);
}

fn swing_up(intervals: usize) -> PendulumSwingUp {
    PendulumSwingUp {
        intervals,
        duration_s: 3.0,
        max_torque: 6.0,
    }
}

#[test]
fn swing_up_with_thousands_of_variables_converges() {
    for intervals in [500, 1500] {
        let problem = swing_up(intervals);
        let solution = solve(&problem, &SolveOptions::default()).unwrap();
        let stats = solution.statistics;
        println!(
            "pendulum N = {intervals}: n = {}, m = {}, {:?}, {} iterations, cost {:.6}, \
             total {:.3} s (evaluations {:.3} s, solver {:.3} s)",
            problem.num_variables(),
            problem.num_constraints(),
            solution.status,
            stats.iterations,
            stats.objective,
            stats.total_time.as_secs_f64(),
            stats.evaluation_time.as_secs_f64(),
            stats.solver_time.as_secs_f64(),
        );
        assert_eq!(solution.status, SolveStatus::Optimal);
        assert!(stats.primal_infeasibility < 1e-8, "{stats:?}");
        // Iterations stay moderate as the mesh is refined (mesh independence).
        assert!(stats.iterations < 200, "{stats:?}");
    }
}

#[test]
fn refined_meshes_agree_on_the_optimal_cost() {
    // Trapezoidal collocation is second order: the cost converges as h².
    let costs: Vec<f64> = [100, 200, 400]
        .into_iter()
        .map(|intervals| {
            let solution = solve(&swing_up(intervals), &SolveOptions::default()).unwrap();
            assert_eq!(solution.status, SolveStatus::Optimal);
            solution.statistics.objective
        })
        .collect();
    let coarse_change = (costs[1] - costs[0]).abs();
    let fine_change = (costs[2] - costs[1]).abs();
    assert!(
        fine_change < 0.5 * coarse_change,
        "costs {costs:?} do not converge"
    );
}

#[test]
fn warm_start_from_a_neighbouring_problem_saves_iterations() {
    let cold = solve(&swing_up(300), &SolveOptions::default()).unwrap();
    let neighbour = PendulumSwingUp {
        max_torque: 6.1,
        ..swing_up(300)
    };
    let cold_neighbour = solve(&neighbour, &SolveOptions::default()).unwrap();
    let warm_options = SolveOptions {
        warm_start: Some(cold.warm_start()),
        ..SolveOptions::default()
    };
    let warm_neighbour = solve(&neighbour, &warm_options).unwrap();
    println!(
        "neighbour: cold {} iterations, warm {} iterations",
        cold_neighbour.statistics.iterations, warm_neighbour.statistics.iterations
    );
    assert_eq!(warm_neighbour.status, SolveStatus::Optimal);
    assert!(
        (warm_neighbour.statistics.objective - cold_neighbour.statistics.objective).abs()
            < 1e-6 * cold_neighbour.statistics.objective
    );
    assert!(warm_neighbour.statistics.iterations < cold_neighbour.statistics.iterations);
}
