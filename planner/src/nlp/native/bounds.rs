//! Bounds under a logarithmic barrier: which are finite, the barrier objective, and the push
//! of a point inside them.

use super::constants::KAPPA_D;

/// One bounded quantity's barrier data: which bounds are finite.
#[derive(Clone, Copy)]
pub(super) struct Bounds {
    pub(super) lower: Option<f64>,
    pub(super) upper: Option<f64>,
}

/// The barrier objective φ_μ = f − μ Σ ln(slack) (+ IPOPT's damping of one-sided bounds) at
/// (x, s), for the bounds `xb` of x and `sb` of the inequality slacks.
pub(super) fn barrier_value(
    xb: &[Bounds],
    sb: &[Option<Bounds>],
    mu: f64,
    f: f64,
    x: &[f64],
    s: &[f64],
) -> f64 {
    let mut phi = f;
    let mut term = |slack: f64, one_sided: bool| {
        phi -= mu * slack.ln();
        if one_sided {
            phi += KAPPA_D * mu * slack;
        }
    };
    for (i, b) in xb.iter().enumerate() {
        let one = b.lower.is_some() != b.upper.is_some();
        if let Some(l) = b.lower {
            term(x[i] - l, one);
        }
        if let Some(u) = b.upper {
            term(u - x[i], one);
        }
    }
    for (i, b) in sb.iter().enumerate() {
        if let Some(b) = b {
            let one = b.lower.is_some() != b.upper.is_some();
            if let Some(l) = b.lower {
                term(s[i] - l, one);
            }
            if let Some(u) = b.upper {
                term(u - s[i], one);
            }
        }
    }
    phi
}

/// Moves v inside its bounds by IPOPT's bound push (relative to the bound and the gap).
pub(super) fn project(v: f64, b: Bounds, push: f64) -> f64 {
    match (b.lower, b.upper) {
        (Some(l), Some(u)) => {
            let pl = (push * l.abs().max(1.0)).min(push * (u - l));
            let pu = (push * u.abs().max(1.0)).min(push * (u - l));
            if l + pl <= u - pu {
                v.max(l + pl).min(u - pu)
            } else {
                0.5 * (l + u)
            }
        }
        (Some(l), None) => v.max(l + push * l.abs().max(1.0)),
        (None, Some(u)) => v.min(u - push * u.abs().max(1.0)),
        (None, None) => v,
    }
}
