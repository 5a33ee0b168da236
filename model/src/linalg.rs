//! Small dense linear algebra generic over the scalar type, so that solves of the constrained
//! dynamics and of the impact map carry dual-number derivatives.

use crate::{ModelError, Real, Result};
use nalgebra::{DMatrix, DVector, Dim, Dyn, Matrix, StorageMut};

/// Solves `a x = b` in place (`b` becomes `x`) by Gaussian elimination with partial pivoting on
/// the real part. `a` is destroyed. Fails with [`ModelError::Singular`] when a pivot vanishes.
pub fn solve_in_place<S: Real>(
    a: &mut DMatrix<S>,
    b: &mut DVector<S>,
    what: &'static str,
) -> Result<()> {
    eliminate(a, b, what)
}

/// [`solve_in_place`] for several right-hand sides at once (the columns of `b`), with one
/// elimination of `a`. Each column's solution is bit for bit the one [`solve_in_place`] gives
/// for that column alone: the pivots depend on `a` only and every column sees the same
/// operations in the same order.
pub fn solve_many_in_place<S: Real>(
    a: &mut DMatrix<S>,
    b: &mut DMatrix<S>,
    what: &'static str,
) -> Result<()> {
    eliminate(a, b, what)
}

fn eliminate<S: Real, C: Dim, B: StorageMut<S, Dyn, C>>(
    a: &mut DMatrix<S>,
    b: &mut Matrix<S, Dyn, C, B>,
    what: &'static str,
) -> Result<()> {
    let n = a.nrows();
    debug_assert_eq!(a.ncols(), n);
    debug_assert_eq!(b.nrows(), n);
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
            for k in 0..b.ncols() {
                let v = b[(col, k)];
                b[(r, k)] -= f * v;
            }
        }
    }
    for k in 0..b.ncols() {
        for col in (0..n).rev() {
            let mut acc = b[(col, k)];
            for c in col + 1..n {
                acc -= a[(col, c)] * b[(c, k)];
            }
            b[(col, k)] = acc / a[(col, col)];
        }
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
    fn several_right_hand_sides_solve_bit_for_bit_like_one_at_a_time() {
        let a: DMatrix<f64> = DMatrix::from_row_slice(
            4,
            4,
            &[
                0.0, 2.0, 1.0, 0.3, 1.0, 1.0, 0.0, -2.0, 3.0, 0.0, 1.0, 0.7, 0.1, -1.0, 4.0, 1.0,
            ],
        );
        let b: DMatrix<f64> = DMatrix::from_row_slice(
            4,
            3,
            &[1.0, 0.0, -0.3, 2.0, 1.0, 0.1, 0.5, 0.0, 7.0, 3.0, 1.0, 0.0],
        );
        let mut many = b.clone();
        solve_many_in_place(&mut a.clone(), &mut many, "test").expect("regular");
        for k in 0..3 {
            let mut one = b.column(k).into_owned();
            solve_in_place(&mut a.clone(), &mut one, "test").expect("regular");
            for i in 0..4 {
                assert_eq!(
                    many[(i, k)].to_bits(),
                    one[i].to_bits(),
                    "column {k} row {i}"
                );
            }
            assert!((&a * &one - b.column(k)).norm() < 1e-14);
        }
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
