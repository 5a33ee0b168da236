//! Small dense linear algebra generic over the scalar type, so that solves of the constrained
//! dynamics and of the impact map carry dual-number derivatives.

use crate::{ModelError, Real, Result};
use nalgebra::{DMatrix, DVector};

/// Solves `a x = b` in place (`b` becomes `x`) by Gaussian elimination with partial pivoting on
/// the real part. `a` is destroyed. Fails with [`ModelError::Singular`] when a pivot vanishes.
pub fn solve_in_place<S: Real>(
    a: &mut DMatrix<S>,
    b: &mut DVector<S>,
    what: &'static str,
) -> Result<()> {
    let n = a.nrows();
    debug_assert_eq!(a.ncols(), n);
    debug_assert_eq!(b.len(), n);
    let scale = a
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.re().abs()))
        .max(1e-300);
    for col in 0..n {
        let mut piv = col;
        let mut best = a[(col, col)].re().abs();
        for r in col + 1..n {
            let v = a[(r, col)].re().abs();
            if v > best {
                best = v;
                piv = r;
            }
        }
        if best <= 1e-13 * scale {
            return Err(ModelError::Singular { what });
        }
        if piv != col {
            a.swap_rows(piv, col);
            b.swap_rows(piv, col);
        }
        let inv = a[(col, col)].recip();
        for r in col + 1..n {
            let f = a[(r, col)] * inv;
            if f.re() == 0.0 && f == S::zero() {
                continue;
            }
            for c in col..n {
                let v = a[(col, c)];
                a[(r, c)] -= f * v;
            }
            let v = b[col];
            b[r] -= f * v;
        }
    }
    for col in (0..n).rev() {
        let mut acc = b[col];
        for c in col + 1..n {
            acc -= a[(col, c)] * b[c];
        }
        b[col] = acc / a[(col, col)];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pivoting_system_to_machine_precision() {
        let a = DMatrix::from_row_slice(3, 3, &[0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0]);
        let x = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let mut b = &a * &x;
        let mut a2 = a.clone();
        solve_in_place(&mut a2, &mut b, "test").expect("regular");
        assert!((b - x).norm() < 1e-14);
    }

    #[test]
    fn reports_a_singular_system() {
        let mut a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
        let mut b = DVector::from_vec(vec![1.0, 2.0]);
        assert!(matches!(
            solve_in_place(&mut a, &mut b, "test"),
            Err(ModelError::Singular { what: "test" })
        ));
    }
}
