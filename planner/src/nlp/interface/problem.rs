//! The problem side of the NLP interface: what a caller implements.

/// A sparse matrix pattern in triplet (coordinate) form: entry `k` sits at
/// `(rows[k], cols[k])`. Values are exchanged separately, in the same order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SparsityPattern {
    /// Row index of every structural non-zero.
    pub rows: Vec<usize>,
    /// Column index of every structural non-zero.
    pub cols: Vec<usize>,
}

impl SparsityPattern {
    /// An empty pattern (no structural non-zeros).
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of structural non-zeros.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when the pattern has no entries.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Appends one entry at `(row, col)`.
    pub fn push(&mut self, row: usize, col: usize) {
        self.rows.push(row);
        self.cols.push(col);
    }

    /// The dense pattern of an `n_rows × n_cols` matrix, row by row.
    pub fn dense(n_rows: usize, n_cols: usize) -> Self {
        let mut pattern = Self::default();
        for row in 0..n_rows {
            for col in 0..n_cols {
                pattern.push(row, col);
            }
        }
        pattern
    }

    /// The dense lower triangle (`row ≥ col`) of an `n × n` matrix, row by row.
    pub fn dense_lower_triangle(n: usize) -> Self {
        let mut pattern = Self::default();
        for row in 0..n {
            for col in 0..=row {
                pattern.push(row, col);
            }
        }
        pattern
    }
}

/// The problem cannot be evaluated at this point (e.g. `sqrt` of a negative
/// number). During a line search the solver shortens the step instead of failing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the problem functions cannot be evaluated at this point")]
pub struct DomainError;

/// A smooth nonlinear program
///
/// ```text
/// minimise f(x)  over x ∈ ℝⁿ
/// subject to  x_l ≤ x ≤ x_u           (variable bounds, ±∞ allowed)
///             g_l ≤ g(x) ≤ g_u        (m constraints; g_l = g_u is an equality)
/// ```
///
/// with exact first and second derivatives. Multipliers follow IPOPT's sign
/// convention: the Lagrangian is `L = σ f(x) + Σ λᵢ gᵢ(x)`.
///
/// The two sparsity patterns are queried once per solve and must not change.
/// Every evaluation receives the full `x`; an implementation that shares work
/// between `objective`, `constraints` and their derivatives may cache on `x`.
pub trait NlpProblem {
    /// Number of variables `n`.
    fn num_variables(&self) -> usize;

    /// Number of constraints `m`.
    fn num_constraints(&self) -> usize;

    /// Fills the variable bounds; use `f64::NEG_INFINITY` / `f64::INFINITY` for none.
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]);

    /// Fills the constraint bounds; equal entries make an equality constraint.
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]);

    /// Fills the initial point (used unless a warm start supplies one).
    fn initial_point(&self, x0: &mut [f64]);

    /// The objective `f(x)`.
    fn objective(&self, x: &[f64]) -> Result<f64, DomainError>;

    /// The objective gradient `∇f(x)`, length `n`.
    fn gradient(&self, x: &[f64], gradient: &mut [f64]) -> Result<(), DomainError>;

    /// The constraint values `g(x)`, length `m`.
    fn constraints(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError>;

    /// The structural non-zeros of the `m × n` constraint Jacobian `∂g/∂x`.
    fn jacobian_structure(&self) -> SparsityPattern;

    /// The Jacobian values in the order of [`NlpProblem::jacobian_structure`].
    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError>;

    /// The structural non-zeros of the lower triangle (`row ≥ col`) of the
    /// Lagrangian Hessian `σ∇²f + Σ λᵢ∇²gᵢ`. Each `(row, col)` must appear once.
    fn hessian_structure(&self) -> SparsityPattern;

    /// The Lagrangian Hessian values for objective factor `objective_factor`
    /// (σ) and constraint multipliers `multipliers` (λ), in the order of
    /// [`NlpProblem::hessian_structure`].
    fn hessian_values(
        &self,
        x: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        values: &mut [f64],
    ) -> Result<(), DomainError>;

    /// [`NlpProblem::jacobian_values`] and [`NlpProblem::hessian_values`] at one point, for
    /// a solver that needs both there (the interior point after accepting a step). The
    /// default calls the two; a problem whose Hessian passes give the Jacobian on the way
    /// (forward-mode hyper-dual numbers carry the first derivatives) overrides it. The values
    /// must be those of the two calls, bit for bit.
    fn jacobian_and_hessian_values(
        &self,
        x: &[f64],
        jacobian: &mut [f64],
        objective_factor: f64,
        multipliers: &[f64],
        hessian: &mut [f64],
    ) -> Result<(), DomainError> {
        self.jacobian_values(x, jacobian)?;
        self.hessian_values(x, objective_factor, multipliers, hessian)
    }
}
