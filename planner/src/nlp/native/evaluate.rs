//! The problem's functions at the iterate, and what the iteration measures there: residuals,
//! complementarity, the optimality error, the barrier objective and its gradient, Σ.

use super::bounds::{barrier_value, Bounds};
use super::constants::{KAPPA_D, S_MAX};
use super::ipm::Ipm;
use crate::nlp::interface::DomainError;

impl Ipm<'_> {
    /// f and g at x.
    pub(super) fn evaluate_point(&mut self) -> std::result::Result<(), DomainError> {
        self.f = self.prob.objective(&self.x)?;
        let mut g = std::mem::take(&mut self.g);
        let r = self.prob.constraints(&self.x, &mut g);
        self.g = g;
        r
    }

    /// ∇f and J at x. Every change of x (the start, an accepted step, the return from
    /// restoration) is followed by this, so an iteration's top finds them current and adds only
    /// [`Self::evaluate_hessian`].
    pub(super) fn evaluate_first_derivatives(&mut self) -> std::result::Result<(), DomainError> {
        self.hessian_current = false;
        let mut grad = std::mem::take(&mut self.grad);
        let r = self.prob.gradient(&self.x, &mut grad);
        self.grad = grad;
        r?;
        let mut jac = std::mem::take(&mut self.jac);
        let r = self.prob.jacobian(&self.x, &self.jac_rows, &mut jac);
        self.jac = jac;
        r
    }

    /// ∇f, J and W at (x, y) after an accepted step, J and W from one call of the problem
    /// (which may share their work): the next iteration's top then finds W current. If that
    /// call fails, ∇f and J alone: W is then evaluated at the top, only if the solve goes on
    /// (a W that cannot be evaluated at the last iterate must not turn a converged solve into
    /// an evaluation error).
    pub(super) fn evaluate_derivatives_and_hessian(
        &mut self,
    ) -> std::result::Result<(), DomainError> {
        let (mut jac, mut hess) = (
            std::mem::take(&mut self.jac),
            std::mem::take(&mut self.hess),
        );
        let both =
            self.prob
                .jacobian_and_hessian(&self.x, &self.jac_rows, &self.y, &mut jac, &mut hess);
        (self.jac, self.hess) = (jac, hess);
        if both.is_err() {
            return self.evaluate_first_derivatives();
        }
        let mut grad = std::mem::take(&mut self.grad);
        let r = self.prob.gradient(&self.x, &mut grad);
        self.grad = grad;
        self.hessian_current = r.is_ok();
        r
    }

    /// W at (x, y).
    pub(super) fn evaluate_hessian(&mut self) -> std::result::Result<(), DomainError> {
        let mut hess = std::mem::take(&mut self.hess);
        let r = self.prob.hessian(&self.x, &self.y, &mut hess);
        self.hess = hess;
        r
    }

    /// c = g − s (inequalities) or g − g_eq (equalities), at given g and s.
    pub(super) fn residual(&self, g: &[f64], s: &[f64], out: &mut [f64]) {
        for i in 0..self.m {
            out[i] = match self.sb[i] {
                Some(_) => g[i] - s[i],
                None => g[i] - self.rhs[i],
            };
        }
    }

    pub(super) fn complementarity_sum(&self) -> (f64, usize) {
        let mut sum = 0.0;
        let mut count = 0;
        for i in 0..self.n {
            let b = self.xb[i];
            if let Some(l) = b.lower {
                sum += (self.x[i] - l) * self.zl[i];
                count += 1;
            }
            if let Some(u) = b.upper {
                sum += (u - self.x[i]) * self.zu[i];
                count += 1;
            }
        }
        for i in 0..self.m {
            if let Some(b) = self.sb[i] {
                if let Some(l) = b.lower {
                    sum += (self.s[i] - l) * self.vl[i];
                    count += 1;
                }
                if let Some(u) = b.upper {
                    sum += (u - self.s[i]) * self.vu[i];
                    count += 1;
                }
            }
        }
        (sum, count)
    }

    /// (scaled optimality error at μ, unscaled constraint violation, dual, complementarity).
    pub(super) fn errors(&self, mu: f64) -> (f64, f64, f64, f64) {
        let (n, m) = (self.n, self.m);
        let mut dual = self.grad.clone();
        for (k, (&r, &c)) in self.jac_rows.iter().zip(&self.jac_cols).enumerate() {
            dual[c] += self.jac[k] * self.y[r];
        }
        let mut dual_inf = 0.0f64;
        for i in 0..n {
            if !self.fixed[i] {
                dual_inf = dual_inf.max((dual[i] - self.zl[i] + self.zu[i]).abs());
            }
        }
        for i in 0..m {
            if self.sb[i].is_some() {
                dual_inf = dual_inf.max((-self.y[i] - self.vl[i] + self.vu[i]).abs());
            }
        }
        let mut c = vec![0.0; m];
        self.residual(&self.g, &self.s, &mut c);
        let primal = c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let primal_unscaled = c
            .iter()
            .zip(&self.prob.sg)
            .fold(0.0f64, |a, (v, s)| a.max((v / s).abs()));
        let mut compl = 0.0f64;
        let mut zsum = 0.0;
        let mut nz = 0usize;
        let mut upd = |slack: f64, z: f64| {
            compl = compl.max((slack * z - mu).abs());
            zsum += z.abs();
            nz += 1;
        };
        for i in 0..n {
            let b = self.xb[i];
            if let Some(l) = b.lower {
                upd(self.x[i] - l, self.zl[i]);
            }
            if let Some(u) = b.upper {
                upd(u - self.x[i], self.zu[i]);
            }
        }
        for i in 0..m {
            if let Some(b) = self.sb[i] {
                if let Some(l) = b.lower {
                    upd(self.s[i] - l, self.vl[i]);
                }
                if let Some(u) = b.upper {
                    upd(u - self.s[i], self.vu[i]);
                }
            }
        }
        let ysum: f64 = self.y.iter().map(|v| v.abs()).sum();
        let sd = (S_MAX.max((ysum + zsum) / (m + nz).max(1) as f64)) / S_MAX;
        let sc = (S_MAX.max(zsum / nz.max(1) as f64)) / S_MAX;
        let error = (dual_inf / sd).max(primal).max(compl / sc);
        (error, primal_unscaled, dual_inf, compl)
    }

    /// Barrier objective at (f, x, s) for the current μ.
    pub(super) fn barrier(&self, f: f64, x: &[f64], s: &[f64]) -> f64 {
        barrier_value(&self.xb, &self.sb, self.mu, f, x, s)
    }

    /// Gradient of the barrier objective in x and s.
    pub(super) fn barrier_gradient(&self) -> (Vec<f64>, Vec<f64>) {
        let mu = self.mu;
        let mut gx = self.grad.clone();
        let mut gs = vec![0.0; self.m];
        let grad_of = |v: f64, b: Bounds| -> f64 {
            let one = b.lower.is_some() != b.upper.is_some();
            let mut d = 0.0;
            if let Some(l) = b.lower {
                d -= mu / (v - l);
                if one {
                    d += KAPPA_D * mu;
                }
            }
            if let Some(u) = b.upper {
                d += mu / (u - v);
                if one {
                    d -= KAPPA_D * mu;
                }
            }
            d
        };
        for i in 0..self.n {
            gx[i] = if self.fixed[i] {
                0.0
            } else {
                gx[i] + grad_of(self.x[i], self.xb[i])
            };
        }
        for i in 0..self.m {
            if let Some(b) = self.sb[i] {
                gs[i] = grad_of(self.s[i], b);
            }
        }
        (gx, gs)
    }

    /// Σ_x and Σ_s.
    pub(super) fn sigmas(&self) -> (Vec<f64>, Vec<f64>) {
        let mut sx = vec![0.0; self.n];
        for i in 0..self.n {
            let b = self.xb[i];
            if let Some(l) = b.lower {
                sx[i] += self.zl[i] / (self.x[i] - l);
            }
            if let Some(u) = b.upper {
                sx[i] += self.zu[i] / (u - self.x[i]);
            }
        }
        let mut ss = vec![0.0; self.m];
        for i in 0..self.m {
            if let Some(b) = self.sb[i] {
                if let Some(l) = b.lower {
                    ss[i] += self.vl[i] / (self.s[i] - l);
                }
                if let Some(u) = b.upper {
                    ss[i] += self.vu[i] / (u - self.s[i]);
                }
            }
        }
        (sx, ss)
    }
}
