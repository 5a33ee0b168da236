//! Small problems shared by the backends' unit tests.

use num_dual::DualNum;

use super::ad::AdModel;

/// Hock–Schittkowski 71: f* = 17.0140173 at x ≈ (1, 4.743, 3.8211, 1.3794), with every
/// variable in [`lower_bound`, 5] (1 in the original; above 5 the bounds cross) and, with
/// `fix_first`, x₀ fixed at its optimal value 1 by equal bounds.
pub(crate) struct Hs71 {
    pub lower_bound: f64,
    pub fix_first: bool,
}

impl Hs71 {
    /// The original problem.
    pub fn standard() -> Self {
        Self {
            lower_bound: 1.0,
            fix_first: false,
        }
    }
}

impl AdModel for Hs71 {
    fn num_variables(&self) -> usize {
        4
    }
    fn num_constraints(&self) -> usize {
        2
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(self.lower_bound);
        upper.fill(5.0);
        if self.fix_first {
            upper[0] = lower[0];
        }
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&[25.0, 40.0]);
        upper.copy_from_slice(&[f64::INFINITY, 40.0]);
    }
    fn initial_point(&self, x0: &mut [f64]) {
        x0.copy_from_slice(&[1.0, 5.0, 5.0, 1.0]);
    }
    fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
        x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2]
    }
    fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
        g[0] = x[0] * x[1] * x[2] * x[3];
        g[1] = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3];
    }
}

/// min −x₀² subject to x₁ = 1, x₀ free: unbounded below (and nonconvex), the iterates run
/// off to infinity.
pub(crate) struct Unbounded;

impl AdModel for Unbounded {
    fn num_variables(&self) -> usize {
        2
    }
    fn num_constraints(&self) -> usize {
        1
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(f64::NEG_INFINITY);
        upper.fill(f64::INFINITY);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower[0] = 1.0;
        upper[0] = 1.0;
    }
    fn initial_point(&self, x0: &mut [f64]) {
        x0.copy_from_slice(&[1.0, 0.0]);
    }
    fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
        -x[0] * x[0]
    }
    fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
        g[0] = x[1];
    }
}

/// min x subject to x² ≤ −1: no feasible point.
pub(crate) struct Infeasible;

impl AdModel for Infeasible {
    fn num_variables(&self) -> usize {
        1
    }
    fn num_constraints(&self) -> usize {
        1
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower[0] = -10.0;
        upper[0] = 10.0;
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower[0] = f64::NEG_INFINITY;
        upper[0] = -1.0;
    }
    fn initial_point(&self, x0: &mut [f64]) {
        x0[0] = 3.0;
    }
    fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
        x[0]
    }
    fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
        g[0] = x[0] * x[0];
    }
}
