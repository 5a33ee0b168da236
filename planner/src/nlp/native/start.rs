//! The start of a solve: gradient-based scaling, relaxed bounds, the start point pushed inside
//! them, slacks, bound multipliers, μ₀ and the least-squares constraint multipliers.

use std::time::Instant;

use super::bounds::{project, Bounds};
use super::constants::{
    BOUND_PUSH, BOUND_RELAX, LS_MULTIPLIER_MAX, MU_INIT, REFINEMENTS, SCALING_MAX_GRADIENT,
};
use super::ipm::Ipm;
use super::kkt::KktSystem;
use crate::nlp::interface::SolveStatus;

impl Ipm<'_> {
    /// Relaxed bounds, the scaled start point, slacks and multipliers. `Err` ends the solve.
    pub(super) fn initialize(&mut self) -> std::result::Result<(), SolveStatus> {
        let (n, m) = (self.n, self.m);
        let p = self.prob.problem;
        let (mut xl, mut xu) = (vec![0.0; n], vec![0.0; n]);
        p.variable_bounds(&mut xl, &mut xu);
        let (mut gl, mut gu) = (vec![0.0; m], vec![0.0; m]);
        p.constraint_bounds(&mut gl, &mut gu);
        let warm = self.options.warm_start.as_ref();
        match warm.and_then(|w| w.x.as_ref()) {
            Some(x) => self.x.copy_from_slice(x),
            None => p.initial_point(&mut self.x),
        }
        // Scaling from the gradients at the start point.
        let mut grad = vec![0.0; n];
        let mut jac = vec![0.0; self.jac.len()];
        let t = Instant::now();
        let ok =
            p.gradient(&self.x, &mut grad).is_ok() && p.jacobian_values(&self.x, &mut jac).is_ok();
        self.prob.time += t.elapsed();
        self.prob.counts.gradient += 1;
        self.prob.counts.jacobian += 1;
        if !ok {
            return Err(SolveStatus::EvaluationError);
        }
        let gmax = grad.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        self.prob.sf = (SCALING_MAX_GRADIENT / gmax).min(1.0);
        let mut rowmax = vec![0.0f64; m];
        for (k, &r) in self.jac_rows.iter().enumerate() {
            rowmax[r] = rowmax[r].max(jac[k].abs());
        }
        for i in 0..m {
            self.prob.sg[i] = if rowmax[i] > 0.0 {
                (SCALING_MAX_GRADIENT / rowmax[i]).min(1.0)
            } else {
                1.0
            };
        }
        let relax = |v: f64, dir: f64| v + dir * BOUND_RELAX * v.abs().max(1.0);
        let push = if warm.is_some() { 1e-6 } else { BOUND_PUSH };
        self.xb = (0..n)
            .map(|i| {
                if xl[i] == xu[i] {
                    self.fixed[i] = true;
                    self.x[i] = xl[i];
                }
                Bounds {
                    lower: (xl[i].is_finite() && !self.fixed[i]).then(|| relax(xl[i], -1.0)),
                    upper: (xu[i].is_finite() && !self.fixed[i]).then(|| relax(xu[i], 1.0)),
                }
            })
            .collect();
        for i in 0..n {
            self.x[i] = project(self.x[i], self.xb[i], push);
        }
        self.sb = (0..m)
            .map(|i| {
                let (lo, hi) = (gl[i] * self.prob.sg[i], gu[i] * self.prob.sg[i]);
                if gl[i] == gu[i] {
                    self.rhs[i] = lo;
                    None
                } else {
                    Some(Bounds {
                        lower: lo.is_finite().then(|| relax(lo, -1.0)),
                        upper: hi.is_finite().then(|| relax(hi, 1.0)),
                    })
                }
            })
            .collect();
        self.evaluate_point()
            .map_err(|_| SolveStatus::EvaluationError)?;
        self.evaluate_first_derivatives()
            .map_err(|_| SolveStatus::EvaluationError)?;
        for i in 0..m {
            if let Some(b) = self.sb[i] {
                self.s[i] = project(self.g[i], b, push);
            }
        }
        // Bound multipliers and μ.
        let mult_push = 1e-6;
        for i in 0..n {
            let (wl, wu) = match warm {
                Some(w) => (
                    w.lower_bound_multipliers[i] / self.prob.sf,
                    w.upper_bound_multipliers[i] / self.prob.sf,
                ),
                None => (1.0, 1.0),
            };
            self.zl[i] = if self.xb[i].lower.is_some() {
                wl.max(mult_push)
            } else {
                0.0
            };
            self.zu[i] = if self.xb[i].upper.is_some() {
                wu.max(mult_push)
            } else {
                0.0
            };
        }
        for i in 0..m {
            let b = self.sb[i];
            let (wl, wu) = match (warm, b) {
                (Some(w), Some(_)) => {
                    // λ < 0 at an active lower bound of g (L = f + λᵀg).
                    let lam = w.constraint_multipliers[i] * self.prob.sg[i].recip() * self.prob.sf;
                    ((-lam).max(0.0), lam.max(0.0))
                }
                _ => (1.0, 1.0),
            };
            self.vl[i] = if b.is_some_and(|b| b.lower.is_some()) {
                wl.max(mult_push)
            } else {
                0.0
            };
            self.vu[i] = if b.is_some_and(|b| b.upper.is_some()) {
                wu.max(mult_push)
            } else {
                0.0
            };
        }
        self.kkt = Some(
            KktSystem::new(
                self.n,
                self.m,
                (&self.hess_rows, &self.hess_cols),
                (&self.jac_rows, &self.jac_cols),
            )
            .map_err(|_| SolveStatus::NumericalError)?,
        );
        match warm {
            Some(w) => {
                for i in 0..m {
                    // y is the scaled λ: λ_scaled = λ s_f / s_g.
                    self.y[i] = w.constraint_multipliers[i] * self.prob.sf / self.prob.sg[i];
                }
                let (sum, count) = self.complementarity_sum();
                self.mu = if count > 0 {
                    (sum / count as f64).clamp(self.options.tolerance / 10.0, MU_INIT)
                } else {
                    MU_INIT
                };
            }
            None => {
                if let Some(mu) = self.options.initial_barrier {
                    self.mu = mu;
                }
                self.least_squares_multipliers();
            }
        }
        Ok(())
    }

    /// IPOPT's least-squares estimate of y at the start (y = 0 if it is large or fails).
    pub(super) fn least_squares_multipliers(&mut self) {
        let (n, m) = (self.n, self.m);
        let mut rx = self.grad.clone();
        for i in 0..n {
            rx[i] += self.zu[i] - self.zl[i];
            if self.fixed[i] {
                rx[i] = 0.0;
            }
        }
        let mut rs = vec![0.0; m];
        for i in 0..m {
            rs[i] = self.vu[i] - self.vl[i];
        }
        let zero_hess = vec![0.0; self.hess.len()];
        let primal = vec![1.0; n];
        let mut dual = vec![0.0; m];
        for i in 0..m {
            if self.sb[i].is_some() {
                dual[i] = -1.0;
            }
        }
        let Some(kkt) = self.kkt.as_mut() else { return };
        let t = Instant::now();
        kkt.assemble(&zero_hess, &self.jac, &primal, &dual, &self.fixed);
        let factorized = kkt.factorize();
        // A factorization like the iterations' (counted in `kkt`'s statistics): timed with them.
        self.factorization_time += t.elapsed();
        let Some(inertia) = factorized else {
            return;
        };
        if inertia.positive != n || inertia.negative != m {
            return;
        }
        let mut rhs = vec![0.0; n + m];
        for i in 0..n {
            rhs[i] = -rx[i];
        }
        for i in 0..m {
            if self.sb[i].is_some() {
                // Δs = Δy − r_s (Σ_s = 1) folded into the constraint row.
                rhs[n + i] = -rs[i];
            }
        }
        let Some(sol) = kkt.solve(&rhs, REFINEMENTS) else {
            return;
        };
        let ymax = sol[n..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if ymax <= LS_MULTIPLIER_MAX {
            self.y.copy_from_slice(&sol[n..]);
        }
    }
}
