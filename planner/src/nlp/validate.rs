//! Checks a problem before any backend sees it, so malformed input becomes a
//! typed [`NlpError`] instead of a backend panic or a silent wrong answer.

use super::interface::{NlpError, NlpProblem, Result, SparsityPattern, WarmStart};

/// Checks bounds, patterns, the initial point and warm-start lengths.
pub(crate) fn validate_problem(
    problem: &dyn NlpProblem,
    warm_start: Option<&WarmStart>,
) -> Result<()> {
    let n = problem.num_variables();
    let m = problem.num_constraints();

    let (mut lower, mut upper) = (vec![0.0; n], vec![0.0; n]);
    problem.variable_bounds(&mut lower, &mut upper);
    check_bounds("variable", &lower, &upper)?;
    let (mut g_lower, mut g_upper) = (vec![0.0; m], vec![0.0; m]);
    problem.constraint_bounds(&mut g_lower, &mut g_upper);
    check_bounds("constraint", &g_lower, &g_upper)?;

    check_pattern("jacobian", &problem.jacobian_structure(), m, n)?;
    let hessian = problem.hessian_structure();
    check_pattern("hessian", &hessian, n, n)?;
    for (entry, (&row, &col)) in hessian.rows.iter().zip(&hessian.cols).enumerate() {
        if col > row {
            return Err(NlpError::HessianNotLowerTriangular { entry, row, col });
        }
    }

    let mut x0 = vec![0.0; n];
    problem.initial_point(&mut x0);
    if let Some(start) = warm_start {
        check_length("x", start.x.as_ref().map_or(n, Vec::len), n)?;
        if let Some(x) = &start.x {
            x0.clone_from(x);
        }
        check_length(
            "constraint_multipliers",
            start.constraint_multipliers.len(),
            m,
        )?;
        check_length(
            "lower_bound_multipliers",
            start.lower_bound_multipliers.len(),
            n,
        )?;
        check_length(
            "upper_bound_multipliers",
            start.upper_bound_multipliers.len(),
            n,
        )?;
    }
    if let Some((index, &value)) = x0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(NlpError::NonFiniteInitialPoint { index, value });
    }
    Ok(())
}

fn check_bounds(kind: &'static str, lower: &[f64], upper: &[f64]) -> Result<()> {
    for (index, (&lo, &up)) in lower.iter().zip(upper).enumerate() {
        let malformed = lo.is_nan() || up.is_nan() || lo > up;
        if malformed || lo == f64::INFINITY || up == f64::NEG_INFINITY {
            return Err(NlpError::InvalidBounds {
                kind,
                index,
                lower: lo,
                upper: up,
            });
        }
    }
    Ok(())
}

fn check_pattern(
    matrix: &'static str,
    pattern: &SparsityPattern,
    n_rows: usize,
    n_cols: usize,
) -> Result<()> {
    if pattern.rows.len() != pattern.cols.len() {
        return Err(NlpError::PatternLengthMismatch {
            matrix,
            rows: pattern.rows.len(),
            cols: pattern.cols.len(),
        });
    }
    for (entry, (&row, &col)) in pattern.rows.iter().zip(&pattern.cols).enumerate() {
        if row >= n_rows || col >= n_cols {
            return Err(NlpError::PatternOutOfRange {
                matrix,
                entry,
                row,
                col,
                n_rows,
                n_cols,
            });
        }
    }
    Ok(())
}

fn check_length(field: &'static str, actual: usize, expected: usize) -> Result<()> {
    if actual == expected {
        Ok(())
    } else {
        Err(NlpError::WarmStartLength {
            field,
            expected,
            actual,
        })
    }
}
