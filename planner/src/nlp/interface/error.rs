//! The errors that stop a solve before it starts: a malformed problem or malformed options.

/// Errors that stop a solve before it starts (the problem or options are malformed).
///
/// A solve that runs and does not converge is not an error: it returns a
/// [`Solution`] whose [`Solution::status`] says why it stopped.
///
/// [`Solution`]: super::Solution
/// [`Solution::status`]: super::Solution::status
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NlpError {
    /// A bound is NaN, or a lower bound exceeds its upper bound.
    #[error("{kind} bound {index} is invalid: lower {lower}, upper {upper}")]
    InvalidBounds {
        /// "variable" or "constraint".
        kind: &'static str,
        /// Index of the offending variable or constraint.
        index: usize,
        /// The lower bound given.
        lower: f64,
        /// The upper bound given.
        upper: f64,
    },
    /// A sparsity pattern has an entry outside the matrix, or rows and cols differ in length.
    #[error(
        "{matrix} pattern entry {entry} at ({row}, {col}) is outside a {n_rows}×{n_cols} matrix"
    )]
    PatternOutOfRange {
        /// "jacobian" or "hessian".
        matrix: &'static str,
        /// Index of the entry in the triplet list.
        entry: usize,
        /// Its row.
        row: usize,
        /// Its column.
        col: usize,
        /// Rows of the matrix.
        n_rows: usize,
        /// Columns of the matrix.
        n_cols: usize,
    },
    /// The two index vectors of a sparsity pattern differ in length.
    #[error("{matrix} pattern has {rows} row indices but {cols} column indices")]
    PatternLengthMismatch {
        /// "jacobian" or "hessian".
        matrix: &'static str,
        /// Length of `rows`.
        rows: usize,
        /// Length of `cols`.
        cols: usize,
    },
    /// A Hessian pattern entry lies above the diagonal.
    #[error("hessian pattern entry {entry} at ({row}, {col}) is in the upper triangle")]
    HessianNotLowerTriangular {
        /// Index of the entry in the triplet list.
        entry: usize,
        /// Its row.
        row: usize,
        /// Its column.
        col: usize,
    },
    /// The initial point contains NaN or infinity.
    #[error("initial point entry {index} is not finite: {value}")]
    NonFiniteInitialPoint {
        /// Index of the offending entry.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A warm-start vector has the wrong length.
    #[error("warm start {field} has length {actual}, expected {expected}")]
    WarmStartLength {
        /// Which vector.
        field: &'static str,
        /// Expected length.
        expected: usize,
        /// Length given.
        actual: usize,
    },
    /// An option is out of range.
    #[error("option {name} = {value} is out of range ({reason})")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What is allowed.
        reason: &'static str,
    },
}

/// Result alias of this module.
pub type Result<T, E = NlpError> = std::result::Result<T, E>;
