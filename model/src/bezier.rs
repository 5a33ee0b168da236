//! Bézier polynomials for the desired outputs `y^d(τ, α)` of the virtual constraints.
//!
//! A Bézier polynomial of degree b with coefficients α_0 … α_b is
//! `B(s) = Σ_k α_k C(b,k) s^k (1−s)^(b−k)`, s ∈ [0, 1]. It starts at α_0, ends at α_b, and its
//! derivative is a Bézier polynomial of degree b−1 with coefficients b (α_{k+1} − α_k).
//! Evaluation is de Casteljau (numerically stable), generic over the scalar type so that the
//! planner differentiates with respect to both τ and α, and allocation-free (stack buffers of
//! [`MAX_BEZIER_DEGREE`] + 1) so that the runtime may evaluate it inside its control tick.

use crate::Real;

/// Highest supported degree.
pub const MAX_BEZIER_DEGREE: usize = 12;

/// Value of the Bézier polynomial with coefficients `alpha` at `s` (de Casteljau).
///
/// # Panics
/// If `alpha` is empty or longer than `MAX_BEZIER_DEGREE + 1` (gait files are validated first).
pub fn eval<S: Real>(alpha: &[S], s: S) -> S {
    let n = alpha.len();
    assert!(
        (1..=MAX_BEZIER_DEGREE + 1).contains(&n),
        "Bezier degree out of range"
    );
    let mut buf = [S::zero(); MAX_BEZIER_DEGREE + 1];
    buf[..n].copy_from_slice(alpha);
    let one_minus = S::one() - s;
    for level in 1..n {
        for k in 0..n - level {
            buf[k] = buf[k] * one_minus + buf[k + 1] * s;
        }
    }
    buf[0]
}

/// Writes the coefficients of the derivative polynomial (degree b−1) into `out[..b]`; returns b.
fn derivative_coefficients<S: Real>(alpha: &[S], out: &mut [S; MAX_BEZIER_DEGREE + 1]) -> usize {
    let b = alpha.len() - 1;
    for k in 0..b {
        out[k] = (alpha[k + 1] - alpha[k]) * (b as f64);
    }
    b
}

/// dB/ds at `s`.
pub fn eval_d1<S: Real>(alpha: &[S], s: S) -> S {
    if alpha.len() < 2 {
        return S::zero();
    }
    let mut d = [S::zero(); MAX_BEZIER_DEGREE + 1];
    let b = derivative_coefficients(alpha, &mut d);
    eval(&d[..b], s)
}

/// d²B/ds² at `s`.
pub fn eval_d2<S: Real>(alpha: &[S], s: S) -> S {
    if alpha.len() < 3 {
        return S::zero();
    }
    let mut d1 = [S::zero(); MAX_BEZIER_DEGREE + 1];
    let b = derivative_coefficients(alpha, &mut d1);
    let mut d2 = [S::zero(); MAX_BEZIER_DEGREE + 1];
    let b2 = derivative_coefficients(&d1[..b], &mut d2);
    eval(&d2[..b2], s)
}

/// Value, first and second derivative at `s`.
pub fn eval_all<S: Real>(alpha: &[S], s: S) -> (S, S, S) {
    (eval(alpha, s), eval_d1(alpha, s), eval_d2(alpha, s))
}

/// The same polynomial written with one degree more (degree elevation).
pub fn elevate(alpha: &[f64]) -> Vec<f64> {
    let b = alpha.len() - 1;
    let n = (b + 1) as f64;
    let mut out = Vec::with_capacity(b + 2);
    out.push(alpha[0]);
    for k in 1..=b {
        let w = k as f64 / n;
        out.push(w * alpha[k - 1] + (1.0 - w) * alpha[k]);
    }
    out.push(alpha[b]);
    out
}

/// Bernstein basis polynomial weights `C(b,k) s^k (1−s)^(b−k)` for k = 0..=b, written to `out`.
/// `B(s) = Σ α_k w_k`: the planner uses them for the linear dependence on α.
pub fn bernstein_weights(degree: usize, s: f64, out: &mut [f64]) {
    let n = degree + 1;
    out[..n].fill(0.0);
    out[0] = 1.0;
    for level in 1..n {
        for k in (0..=level).rev() {
            let left = if k > 0 { out[k - 1] * s } else { 0.0 };
            let here = if k < level { out[k] * (1.0 - s) } else { 0.0 };
            out[k] = left + here;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn coeffs() -> impl Strategy<Value = Vec<f64>> {
        prop::collection::vec(-3.0..3.0f64, 1..=(MAX_BEZIER_DEGREE + 1))
    }

    proptest! {
        #[test]
        fn starts_at_first_and_ends_at_last_coefficient(a in coeffs()) {
            prop_assert!((eval(&a, 0.0) - a[0]).abs() < 1e-12);
            prop_assert!((eval(&a, 1.0) - a[a.len() - 1]).abs() < 1e-12);
        }

        #[test]
        fn end_slopes_are_b_times_first_differences(a in coeffs()) {
            prop_assume!(a.len() >= 2);
            let b = (a.len() - 1) as f64;
            prop_assert!((eval_d1(&a, 0.0) - b * (a[1] - a[0])).abs() < 1e-10);
            prop_assert!((eval_d1(&a, 1.0) - b * (a[a.len() - 1] - a[a.len() - 2])).abs() < 1e-10);
        }

        #[test]
        fn derivatives_match_central_differences(a in coeffs(), s in 0.05..0.95f64) {
            // Central differences with h = 1e-5 err by O(h²·B''') ≈ 1e-10·|B'''|; coefficients are
            // bounded by 3 and degree by 12, so B''' < 3·12³ and 1e-5 absolute is a safe bound.
            let h = 1e-5;
            let fd1 = (eval(&a, s + h) - eval(&a, s - h)) / (2.0 * h);
            let fd2 = (eval_d1(&a, s + h) - eval_d1(&a, s - h)) / (2.0 * h);
            prop_assert!((eval_d1(&a, s) - fd1).abs() < 1e-5 * (1.0 + fd1.abs()));
            prop_assert!((eval_d2(&a, s) - fd2).abs() < 1e-5 * (1.0 + fd2.abs()));
        }

        #[test]
        fn degree_elevation_leaves_the_curve_unchanged(a in coeffs(), s in 0.0..1.0f64) {
            prop_assume!(a.len() <= MAX_BEZIER_DEGREE);
            let e = elevate(&a);
            prop_assert_eq!(e.len(), a.len() + 1);
            prop_assert!((eval(&e, s) - eval(&a, s)).abs() < 1e-12);
            prop_assert!((eval_d1(&e, s) - eval_d1(&a, s)).abs() < 1e-9);
        }

        #[test]
        fn bernstein_weights_reproduce_de_casteljau(a in coeffs(), s in 0.0..1.0f64) {
            let mut w = [0.0; MAX_BEZIER_DEGREE + 1];
            bernstein_weights(a.len() - 1, s, &mut w);
            let sum: f64 = w[..a.len()].iter().sum();
            prop_assert!((sum - 1.0).abs() < 1e-12);
            let v: f64 = a.iter().zip(&w).map(|(x, y)| x * y).sum();
            prop_assert!((v - eval(&a, s)).abs() < 1e-12);
        }
    }

    #[test]
    fn dual_numbers_differentiate_with_respect_to_phase() {
        use num_dual::Dual64;
        let a = [0.1, -0.4, 0.7, 0.2, -0.3];
        let ad: Vec<Dual64> = a.iter().map(|&v| Dual64::from(v)).collect();
        let s = Dual64::from(0.37).derivative();
        let y = eval(&ad, s);
        assert!((y.eps - eval_d1(&a, 0.37)).abs() < 1e-13);
        assert!((y.re - eval(&a, 0.37)).abs() < 1e-15);
    }
}
