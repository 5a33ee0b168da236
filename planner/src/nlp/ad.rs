//! Exact derivatives by automatic differentiation with `num-dual`.
//!
//! Write the objective and constraints once, generic over the scalar, as an
//! [`AdModel`]; [`DenseAdProblem`] turns it into an [`NlpProblem`] with
//! forward-mode gradients and Jacobians (one [`Dual64`] pass per variable) and
//! exact Lagrangian Hessians (one [`HyperDual64`] pass per lower-triangle
//! entry). Patterns are dense, so this is meant for small problems (tens of
//! variables): test problems, sub-problems, cross-checks of hand-written or
//! sparse derivatives.

use num_dual::{Dual64, DualNum, HyperDual64};

use super::interface::{DomainError, NlpProblem, SparsityPattern};

/// A nonlinear program written once, generic over a dual-number scalar `D`.
pub trait AdModel {
    /// Number of variables `n`.
    fn num_variables(&self) -> usize;

    /// Number of constraints `m`.
    fn num_constraints(&self) -> usize;

    /// Fills the variable bounds; the default leaves every variable free.
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(f64::NEG_INFINITY);
        upper.fill(f64::INFINITY);
    }

    /// Fills the constraint bounds; the default makes every constraint `g(x) = 0`.
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(0.0);
        upper.fill(0.0);
    }

    /// Fills the initial point.
    fn initial_point(&self, x0: &mut [f64]);

    /// The objective `f(x)`.
    fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D;

    /// The constraints `g(x)` into `g` (length `m`).
    fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]);
}

/// An [`NlpProblem`] whose derivatives come from dense forward-mode AD of an [`AdModel`].
#[derive(Debug, Clone)]
pub struct DenseAdProblem<M> {
    model: M,
}

impl<M: AdModel> DenseAdProblem<M> {
    /// Wraps `model`.
    pub fn new(model: M) -> Self {
        Self { model }
    }

    /// The wrapped model.
    pub fn model(&self) -> &M {
        &self.model
    }
}

fn finite_or_domain_error(value: f64) -> Result<f64, DomainError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(DomainError)
    }
}

/// `x` as dual numbers with unit derivative direction along variable `seed`.
fn seeded_duals(x: &[f64], seed: usize) -> Vec<Dual64> {
    x.iter()
        .enumerate()
        .map(|(i, &xi)| Dual64::new(xi, if i == seed { 1.0 } else { 0.0 }))
        .collect()
}

impl<M: AdModel> NlpProblem for DenseAdProblem<M> {
    fn num_variables(&self) -> usize {
        self.model.num_variables()
    }

    fn num_constraints(&self) -> usize {
        self.model.num_constraints()
    }

    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.model.variable_bounds(lower, upper);
    }

    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.model.constraint_bounds(lower, upper);
    }

    fn initial_point(&self, x0: &mut [f64]) {
        self.model.initial_point(x0);
    }

    fn objective(&self, x: &[f64]) -> Result<f64, DomainError> {
        finite_or_domain_error(self.model.objective(x))
    }

    fn gradient(&self, x: &[f64], gradient: &mut [f64]) -> Result<(), DomainError> {
        for (j, slot) in gradient.iter_mut().enumerate() {
            let value = self.model.objective(&seeded_duals(x, j));
            *slot = finite_or_domain_error(value.eps)?;
        }
        Ok(())
    }

    fn constraints(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        self.model.constraints(x, values);
        for value in values.iter() {
            finite_or_domain_error(*value)?;
        }
        Ok(())
    }

    fn jacobian_structure(&self) -> SparsityPattern {
        SparsityPattern::dense(self.model.num_constraints(), self.model.num_variables())
    }

    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        let n = self.model.num_variables();
        let mut g = vec![Dual64::from(0.0); self.model.num_constraints()];
        for j in 0..n {
            self.model.constraints(&seeded_duals(x, j), &mut g);
            for (i, gi) in g.iter().enumerate() {
                values[i * n + j] = finite_or_domain_error(gi.eps)?;
            }
        }
        Ok(())
    }

    fn hessian_structure(&self) -> SparsityPattern {
        SparsityPattern::dense_lower_triangle(self.model.num_variables())
    }

    fn hessian_values(
        &self,
        x: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        let n = self.model.num_variables();
        let mut xd: Vec<HyperDual64> = x.iter().map(|&xi| HyperDual64::from(xi)).collect();
        let mut g = vec![HyperDual64::from(0.0); self.model.num_constraints()];
        let mut entry = 0;
        for row in 0..n {
            for col in 0..=row {
                xd[row].eps1 = 1.0;
                xd[col].eps2 = 1.0;
                let mut second_derivative = 0.0;
                if objective_factor != 0.0 {
                    second_derivative += objective_factor * self.model.objective(&xd).eps1eps2;
                }
                if !g.is_empty() {
                    self.model.constraints(&xd, &mut g);
                    second_derivative += g
                        .iter()
                        .zip(multipliers)
                        .map(|(gi, &lambda)| lambda * gi.eps1eps2)
                        .sum::<f64>();
                }
                values[entry] = finite_or_domain_error(second_derivative)?;
                entry += 1;
                xd[row].eps1 = 0.0;
                xd[col].eps2 = 0.0;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::nlp::check::check_derivatives;

    /// Transcendental functions, products and quotients, coupling every variable.
    struct Wiggly;

    impl AdModel for Wiggly {
        fn num_variables(&self) -> usize {
            3
        }
        fn num_constraints(&self) -> usize {
            2
        }
        fn initial_point(&self, x0: &mut [f64]) {
            x0.copy_from_slice(&[0.3, -0.7, 1.2]);
        }
        fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
            x[0].sin() * x[1].exp() + x[2].powi(3) / (x[0] * x[0] + 1.0) + (x[1] * x[2]).cos()
        }
        fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
            g[0] = x[0] * x[1] * x[2] - (x[2] * x[2] + 2.0).sqrt();
            g[1] = (x[0] + x[1]).tanh() + x[2].ln() * x[0];
        }
    }

    #[test]
    fn gradient_jacobian_and_hessian_match_finite_differences() {
        let problem = DenseAdProblem::new(Wiggly);
        for x in [[0.3, -0.7, 1.2], [-1.1, 0.4, 0.5], [2.0, 1.5, 3.0]] {
            let report = check_derivatives(&problem, &x, 0.7, &[1.3, -0.4]).unwrap();
            // Central differences with h ≈ 6e-6 are accurate to ~1e-9 here.
            assert!(report.max_gradient_error < 1e-7, "{report:?}");
            assert!(report.max_jacobian_error < 1e-7, "{report:?}");
            assert!(report.max_hessian_error < 1e-6, "{report:?}");
            assert_eq!(report.jacobian_entries_outside_pattern, 0);
            assert_eq!(report.hessian_entries_outside_pattern, 0);
        }
    }

    #[test]
    fn hessian_is_the_lower_triangle_of_the_lagrangian_hessian() {
        // f = x0² x1, g = x0 x1²  ⇒  ∇²(σf + λg) = [[2σx1, 2σx0 + 2λx1], [·, 2λx0]].
        struct Poly;
        impl AdModel for Poly {
            fn num_variables(&self) -> usize {
                2
            }
            fn num_constraints(&self) -> usize {
                1
            }
            fn initial_point(&self, x0: &mut [f64]) {
                x0.fill(1.0);
            }
            fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
                x[0] * x[0] * x[1]
            }
            fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
                g[0] = x[0] * x[1] * x[1];
            }
        }
        let problem = DenseAdProblem::new(Poly);
        let (x0, x1, sigma, lambda) = (2.0, 3.0, 0.5, -1.5);
        let mut h = [0.0; 3];
        problem
            .hessian_values(&[x0, x1], sigma, &[lambda], &mut h)
            .unwrap();
        let expected = [
            2.0 * sigma * x1,
            2.0 * sigma * x0 + 2.0 * lambda * x1,
            2.0 * lambda * x0,
        ];
        for (got, want) in h.iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "{h:?} vs {expected:?}");
        }
        let pattern = problem.hessian_structure();
        assert_eq!(pattern.rows, vec![0, 1, 1]);
        assert_eq!(pattern.cols, vec![0, 0, 1]);
    }

    #[test]
    fn non_finite_values_are_domain_errors() {
        let problem = DenseAdProblem::new(Wiggly);
        // ln(x2) with x2 < 0 is NaN.
        let mut g = [0.0; 2];
        assert_eq!(
            problem.constraints(&[0.1, 0.2, -1.0], &mut g),
            Err(DomainError)
        );
    }
}
