//! A derivative checker: compares a problem's gradient, Jacobian and Hessian
//! with central finite differences (IPOPT's `derivative_test`, as a function).
//!
//! Only for tests and diagnosis: it costs O(n) function evaluations and
//! dense n×n storage, and no solver calls it.

use super::interface::{DomainError, NlpProblem};

/// Largest discrepancies found by [`check_derivatives`].
///
/// Errors are `|analytic − finite difference| / max(1, |finite difference|)`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DerivativeCheck {
    /// Worst gradient entry.
    pub max_gradient_error: f64,
    /// Worst Jacobian entry (inside and outside the pattern).
    pub max_jacobian_error: f64,
    /// Worst lower-triangle Lagrangian Hessian entry (inside and outside the pattern).
    pub max_hessian_error: f64,
    /// Finite-difference Jacobian entries above `1e-5` that the pattern lacks.
    pub jacobian_entries_outside_pattern: usize,
    /// Finite-difference Hessian entries above `1e-5` that the pattern lacks.
    pub hessian_entries_outside_pattern: usize,
}

fn step_for(x: f64) -> f64 {
    f64::EPSILON.cbrt() * x.abs().max(1.0)
}

fn scaled_error(analytic: f64, finite_difference: f64) -> f64 {
    (analytic - finite_difference).abs() / finite_difference.abs().max(1.0)
}

/// σ∇f + Jᵀλ at `x`, from the problem's own first derivatives.
fn lagrangian_gradient(
    problem: &dyn NlpProblem,
    x: &[f64],
    objective_factor: f64,
    multipliers: &[f64],
) -> Result<Vec<f64>, DomainError> {
    let n = problem.num_variables();
    let mut gradient = vec![0.0; n];
    problem.gradient(x, &mut gradient)?;
    for g in &mut gradient {
        *g *= objective_factor;
    }
    let pattern = problem.jacobian_structure();
    let mut values = vec![0.0; pattern.len()];
    problem.jacobian_values(x, &mut values)?;
    for ((&row, &col), value) in pattern.rows.iter().zip(&pattern.cols).zip(values) {
        gradient[col] += multipliers[row] * value;
    }
    Ok(gradient)
}

/// Checks all derivatives of `problem` at `x` for the Lagrangian
/// `objective_factor·f + multipliersᵀ g`.
pub fn check_derivatives(
    problem: &dyn NlpProblem,
    x: &[f64],
    objective_factor: f64,
    multipliers: &[f64],
) -> Result<DerivativeCheck, DomainError> {
    let n = problem.num_variables();
    let m = problem.num_constraints();
    let mut report = DerivativeCheck::default();
    let mut gradient = vec![0.0; n];
    problem.gradient(x, &mut gradient)?;

    // Dense analytic Jacobian and Hessian (lower triangle), duplicates summed.
    let jacobian_pattern = problem.jacobian_structure();
    let mut jacobian_values = vec![0.0; jacobian_pattern.len()];
    problem.jacobian_values(x, &mut jacobian_values)?;
    let mut jacobian = vec![vec![None::<f64>; n]; m];
    for ((&row, &col), value) in jacobian_pattern
        .rows
        .iter()
        .zip(&jacobian_pattern.cols)
        .zip(jacobian_values)
    {
        *jacobian[row][col].get_or_insert(0.0) += value;
    }
    let hessian_pattern = problem.hessian_structure();
    let mut hessian_values = vec![0.0; hessian_pattern.len()];
    problem.hessian_values(x, objective_factor, multipliers, &mut hessian_values)?;
    let mut hessian = vec![vec![None::<f64>; n]; n];
    for ((&row, &col), value) in hessian_pattern
        .rows
        .iter()
        .zip(&hessian_pattern.cols)
        .zip(hessian_values)
    {
        *hessian[row][col].get_or_insert(0.0) += value;
    }

    let mut shifted = x.to_vec();
    let (mut g_plus, mut g_minus) = (vec![0.0; m], vec![0.0; m]);
    for j in 0..n {
        let h = step_for(x[j]);
        shifted[j] = x[j] + h;
        let f_plus = problem.objective(&shifted)?;
        problem.constraints(&shifted, &mut g_plus)?;
        let lagrangian_plus =
            lagrangian_gradient(problem, &shifted, objective_factor, multipliers)?;
        shifted[j] = x[j] - h;
        let f_minus = problem.objective(&shifted)?;
        problem.constraints(&shifted, &mut g_minus)?;
        let lagrangian_minus =
            lagrangian_gradient(problem, &shifted, objective_factor, multipliers)?;
        shifted[j] = x[j];

        let fd = (f_plus - f_minus) / (2.0 * h);
        report.max_gradient_error = report.max_gradient_error.max(scaled_error(gradient[j], fd));
        for i in 0..m {
            let fd = (g_plus[i] - g_minus[i]) / (2.0 * h);
            if jacobian[i][j].is_none() && fd.abs() > 1e-5 {
                report.jacobian_entries_outside_pattern += 1;
            }
            let error = scaled_error(jacobian[i][j].unwrap_or(0.0), fd);
            report.max_jacobian_error = report.max_jacobian_error.max(error);
        }
        // Column j of the Hessian; compare the entries on or below the diagonal.
        for i in j..n {
            let fd = (lagrangian_plus[i] - lagrangian_minus[i]) / (2.0 * h);
            if hessian[i][j].is_none() && fd.abs() > 1e-5 {
                report.hessian_entries_outside_pattern += 1;
            }
            let error = scaled_error(hessian[i][j].unwrap_or(0.0), fd);
            report.max_hessian_error = report.max_hessian_error.max(error);
        }
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::nlp::SparsityPattern;

    /// f = x0² x1 with a deliberately wrong Hessian entry and a Jacobian
    /// pattern missing ∂g/∂x1 of g = x0 + x1³.
    struct Faulty;

    impl NlpProblem for Faulty {
        fn num_variables(&self) -> usize {
            2
        }
        fn num_constraints(&self) -> usize {
            1
        }
        fn variable_bounds(&self, _: &mut [f64], _: &mut [f64]) {}
        fn constraint_bounds(&self, _: &mut [f64], _: &mut [f64]) {}
        fn initial_point(&self, _: &mut [f64]) {}
        fn objective(&self, x: &[f64]) -> Result<f64, DomainError> {
            Ok(x[0] * x[0] * x[1])
        }
        fn gradient(&self, x: &[f64], g: &mut [f64]) -> Result<(), DomainError> {
            g[0] = 2.0 * x[0] * x[1];
            g[1] = x[0] * x[0];
            Ok(())
        }
        fn constraints(&self, x: &[f64], g: &mut [f64]) -> Result<(), DomainError> {
            g[0] = x[0] + x[1].powi(3);
            Ok(())
        }
        fn jacobian_structure(&self) -> SparsityPattern {
            SparsityPattern {
                rows: vec![0],
                cols: vec![0],
            }
        }
        fn jacobian_values(&self, _: &[f64], v: &mut [f64]) -> Result<(), DomainError> {
            v[0] = 1.0;
            Ok(())
        }
        fn hessian_structure(&self) -> SparsityPattern {
            SparsityPattern::dense_lower_triangle(2)
        }
        fn hessian_values(
            &self,
            x: &[f64],
            sigma: f64,
            _: &[f64],
            v: &mut [f64],
        ) -> Result<(), DomainError> {
            v[0] = sigma * 2.0 * x[1];
            v[1] = sigma * 3.0 * x[0]; // should be 2·x0
            v[2] = 0.0;
            Ok(())
        }
    }

    #[test]
    fn wrong_derivatives_and_missing_pattern_entries_are_reported() {
        let report = check_derivatives(&Faulty, &[1.5, 2.0], 1.0, &[0.0]).unwrap();
        assert!(report.max_gradient_error < 1e-8, "{report:?}");
        // Hessian (1,0) is 4.5 instead of 3.0: error 1.5 / 3.0 = 0.5.
        assert!((report.max_hessian_error - 0.5).abs() < 1e-6, "{report:?}");
        // ∂g/∂x1 = 3·x1² = 12 is missing from the pattern.
        assert_eq!(report.jacobian_entries_outside_pattern, 1);
        assert!(report.max_jacobian_error > 0.9, "{report:?}");
    }
}
