//! The feasibility-restoration problem of the native interior point (IPOPT's formulation):
//!
//! ```text
//! minimise   ρ Σᵢ (pᵢ + nᵢ) + ζ/2 Σⱼ dⱼ² (xⱼ − x̄ⱼ)²      over x, s, p ≥ 0, n ≥ 0
//! subject to c(x, s) − p + n = 0,  the bounds of x and s
//! ```
//!
//! with c the outer problem's scaled constraint residual (g(x) − s for inequalities, g(x) − g_eq
//! for equalities), x̄ the point where the line search failed, ζ = √μ and dⱼ = min(1, 1/|x̄ⱼ|):
//! the least ℓ₁ constraint violation near x̄. It is an ordinary [`NlpProblem`], solved by the
//! same interior point (without a restoration phase of its own).

use crate::nlp::interface::{DomainError, NlpProblem, SparsityPattern};

/// Variables: x (n), the inequality slacks (one per inequality row), p (m), n (m).
pub(super) struct Restoration<'a> {
    problem: &'a dyn NlpProblem,
    /// Constraint scaling of the outer solve.
    sg: &'a [f64],
    n: usize,
    m: usize,
    /// Per row: the index of its slack among the slacks, `None` for an equality.
    slack_of: Vec<Option<usize>>,
    slacks: usize,
    /// Scaled right-hand side of each equality row.
    rhs: &'a [f64],
    /// Scaled bounds of each slack.
    slack_bounds: Vec<(f64, f64)>,
    start: Vec<f64>,
    reference: Vec<f64>,
    /// dⱼ².
    weights: Vec<f64>,
    zeta: f64,
    rho: f64,
    /// Slot of each x's diagonal in the Hessian values.
    diagonal_slots: Vec<usize>,
    /// Number of the outer problem's Hessian entries (the first slots).
    outer_hessian: usize,
    /// Row of each of the outer problem's Jacobian entries (the first slots).
    outer_jacobian_rows: Vec<usize>,
    hessian: SparsityPattern,
}

/// ρ, IPOPT's `resto_penalty_parameter`.
const PENALTY: f64 = 1000.0;

impl<'a> Restoration<'a> {
    /// The restoration problem at the outer iterate (x, s) with scaled residual `residual`,
    /// for barrier parameter `mu`. `slack_bounds[i]` is `Some((lower, upper))` (scaled) for an
    /// inequality row.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        problem: &'a dyn NlpProblem,
        sg: &'a [f64],
        rhs: &'a [f64],
        slack_bounds: &[Option<(f64, f64)>],
        x: &[f64],
        s: &[f64],
        residual: &[f64],
        mu: f64,
    ) -> Self {
        let n = x.len();
        let m = residual.len();
        let mut slack_of = vec![None; m];
        let mut bounds = Vec::new();
        let mut start: Vec<f64> = x.to_vec();
        for i in 0..m {
            if let Some(b) = slack_bounds[i] {
                slack_of[i] = Some(bounds.len());
                bounds.push(b);
                start.push(s[i]);
            }
        }
        let rho = PENALTY;
        // IPOPT's start for p and n: the minimizer of ρ(p + n) − μ ln p − μ ln n on p − n = c.
        let (mut p, mut nn) = (vec![0.0; m], vec![0.0; m]);
        for i in 0..m {
            let c = residual[i];
            let a = (mu - rho * c) / (2.0 * rho);
            nn[i] = a + (a * a + mu * c / (2.0 * rho)).sqrt();
            p[i] = c + nn[i];
        }
        start.extend_from_slice(&p);
        start.extend_from_slice(&nn);
        let mut hessian = problem.hessian_structure();
        let outer_hessian = hessian.len();
        let mut diagonal_slots = vec![usize::MAX; n];
        for (k, (&r, &c)) in hessian.rows.iter().zip(&hessian.cols).enumerate() {
            if r == c {
                diagonal_slots[r] = k;
            }
        }
        for (j, slot) in diagonal_slots.iter_mut().enumerate() {
            if *slot == usize::MAX {
                *slot = hessian.len();
                hessian.push(j, j);
            }
        }
        Self {
            problem,
            sg,
            n,
            m,
            slack_of,
            slacks: bounds.len(),
            rhs,
            slack_bounds: bounds,
            start,
            reference: x.to_vec(),
            weights: x.iter().map(|v| (1.0 / v.abs().max(1.0)).powi(2)).collect(),
            zeta: mu.sqrt(),
            rho,
            diagonal_slots,
            outer_hessian,
            outer_jacobian_rows: problem.jacobian_structure().rows,
            hessian,
        }
    }

    /// The x part of a restoration point.
    pub fn x<'b>(&self, w: &'b [f64]) -> &'b [f64] {
        &w[..self.n]
    }

    /// The slack of every inequality row of a restoration point (0 for equalities).
    pub fn slacks(&self, w: &[f64]) -> Vec<f64> {
        self.slack_of
            .iter()
            .map(|k| k.map_or(0.0, |k| w[self.n + k]))
            .collect()
    }

    fn p(&self, i: usize) -> usize {
        self.n + self.slacks + i
    }

    fn nn(&self, i: usize) -> usize {
        self.n + self.slacks + self.m + i
    }
}

impl NlpProblem for Restoration<'_> {
    fn num_variables(&self) -> usize {
        self.n + self.slacks + 2 * self.m
    }

    fn num_constraints(&self) -> usize {
        self.m
    }

    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.problem
            .variable_bounds(&mut lower[..self.n], &mut upper[..self.n]);
        for (k, &(l, u)) in self.slack_bounds.iter().enumerate() {
            lower[self.n + k] = l;
            upper[self.n + k] = u;
        }
        for i in self.n + self.slacks..self.num_variables() {
            lower[i] = 0.0;
            upper[i] = f64::INFINITY;
        }
    }

    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(0.0);
        upper.fill(0.0);
    }

    fn initial_point(&self, x0: &mut [f64]) {
        x0.copy_from_slice(&self.start);
    }

    fn objective(&self, w: &[f64]) -> Result<f64, DomainError> {
        let penalty: f64 = w[self.n + self.slacks..].iter().sum();
        let proximity: f64 = (0..self.n)
            .map(|j| self.weights[j] * (w[j] - self.reference[j]).powi(2))
            .sum();
        Ok(self.rho * penalty + 0.5 * self.zeta * proximity)
    }

    fn gradient(&self, w: &[f64], gradient: &mut [f64]) -> Result<(), DomainError> {
        gradient.fill(0.0);
        for j in 0..self.n {
            gradient[j] = self.zeta * self.weights[j] * (w[j] - self.reference[j]);
        }
        gradient[self.n + self.slacks..].fill(self.rho);
        Ok(())
    }

    fn constraints(&self, w: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        self.problem.constraints(&w[..self.n], values)?;
        for i in 0..self.m {
            let b = match self.slack_of[i] {
                Some(k) => w[self.n + k],
                None => self.rhs[i],
            };
            values[i] = self.sg[i] * values[i] - b - w[self.p(i)] + w[self.nn(i)];
        }
        Ok(())
    }

    fn jacobian_structure(&self) -> SparsityPattern {
        let mut pattern = self.problem.jacobian_structure();
        for i in 0..self.m {
            if let Some(k) = self.slack_of[i] {
                pattern.push(i, self.n + k);
            }
            pattern.push(i, self.p(i));
            pattern.push(i, self.nn(i));
        }
        pattern
    }

    fn jacobian_values(&self, w: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        let len = self.outer_jacobian_rows.len();
        self.problem
            .jacobian_values(&w[..self.n], &mut values[..len])?;
        for (v, &r) in values[..len].iter_mut().zip(&self.outer_jacobian_rows) {
            *v *= self.sg[r];
        }
        let mut k = len;
        for i in 0..self.m {
            if self.slack_of[i].is_some() {
                values[k] = -1.0;
                k += 1;
            }
            values[k] = -1.0;
            values[k + 1] = 1.0;
            k += 2;
        }
        Ok(())
    }

    fn hessian_structure(&self) -> SparsityPattern {
        self.hessian.clone()
    }

    fn hessian_values(
        &self,
        w: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        let scaled: Vec<f64> = multipliers
            .iter()
            .zip(self.sg)
            .map(|(l, s)| l * s)
            .collect();
        values.fill(0.0);
        self.problem.hessian_values(
            &w[..self.n],
            0.0,
            &scaled,
            &mut values[..self.outer_hessian],
        )?;
        for j in 0..self.n {
            values[self.diagonal_slots[j]] += objective_factor * self.zeta * self.weights[j];
        }
        Ok(())
    }
}
