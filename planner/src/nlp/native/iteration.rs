//! The main loop: convergence and acceptable-point tests, the barrier update, the Newton
//! step, the line search (or restoration) and the update of the iterate and its multipliers.

use std::time::Instant;

use super::constants::{
    ACCEPTABLE_ITER, COMPL_INF_TOL, DELTA_SWITCH, DUAL_INF_TOL, GAMMA_ALPHA, GAMMA_PHI,
    GAMMA_THETA, KAPPA_EPS, KAPPA_MU, KAPPA_SIGMA, S_PHI, S_THETA, TAU_MIN, THETA_MU,
};
use super::ipm::Ipm;
use super::line_search::{Filter, Trial};
use crate::nlp::interface::{IterationControl, IterationReport, SolveStatus};

impl Ipm<'_> {
    pub(super) fn iterate(
        &mut self,
        on_iteration: &mut dyn FnMut(&IterationReport) -> IterationControl,
        start: Instant,
    ) -> SolveStatus {
        if let Err(status) = self.initialize() {
            return status;
        }
        let (n, m) = (self.n, self.m);
        let tol = self.options.tolerance;
        let mut filter = Filter::default();
        let mut c = vec![0.0; m];
        self.residual(&self.g, &self.s, &mut c);
        let theta0: f64 = c.iter().map(|v| v.abs()).sum();
        let theta_max = 1e4 * theta0.max(1.0);
        let theta_min = 1e-4 * theta0.max(1.0);
        self.tau = TAU_MIN.max(1.0 - self.mu);
        let mut acceptable_count = 0;
        let mut last_step = 0.0;
        let mut iteration = 0;
        loop {
            let (error, viol, dual_inf, compl) = self.errors(0.0);
            let report = IterationReport {
                iteration,
                objective: self.f / self.prob.sf,
                primal_infeasibility: viol,
                dual_infeasibility: dual_inf,
                barrier_parameter: self.mu,
                step_norm: last_step,
                restoration: false,
            };
            if self.options.print_level >= 5 {
                eprintln!(
                    "{iteration:>4} {:>14.7e} {viol:>9.2e} {dual_inf:>9.2e} {:>9.2e} {last_step:>9.2e} δw {:.1e}",
                    report.objective, self.mu, self.delta_w_last
                );
            }
            if error <= tol
                && viol <= self.options.constraint_violation_tolerance
                && dual_inf / self.prob.sf <= DUAL_INF_TOL
                && compl / self.prob.sf <= COMPL_INF_TOL
            {
                on_iteration(&report);
                return SolveStatus::Optimal;
            }
            if self.within_acceptable_tolerances(error, viol, compl) {
                acceptable_count += 1;
                if acceptable_count >= ACCEPTABLE_ITER {
                    on_iteration(&report);
                    return SolveStatus::Acceptable;
                }
            } else {
                acceptable_count = 0;
            }
            if on_iteration(&report) == IterationControl::Stop {
                return SolveStatus::UserStop;
            }
            if iteration > 0 {
                if let Some(exit) = self.exit_test.as_mut() {
                    if exit(&self.x) {
                        return SolveStatus::UserStop;
                    }
                }
            }
            if iteration >= self.options.max_iterations {
                return SolveStatus::IterationLimit;
            }
            if self
                .options
                .max_wall_time
                .is_some_and(|limit| start.elapsed() >= limit)
            {
                return SolveStatus::TimeLimit;
            }
            if self.x.iter().any(|v| v.abs() > 1e20) {
                return SolveStatus::Diverging;
            }
            // Barrier update (monotone), repeated while the barrier problem is solved.
            loop {
                let (e_mu, ..) = self.errors(self.mu);
                let mu_min = tol / 10.0;
                if e_mu > KAPPA_EPS * self.mu || self.mu <= mu_min {
                    break;
                }
                self.mu = mu_min.max((KAPPA_MU * self.mu).min(self.mu.powf(THETA_MU)));
                self.tau = TAU_MIN.max(1.0 - self.mu);
                filter = Filter::default();
            }
            // W at this iterate: evaluated with J when the step to it was accepted, else now.
            if !std::mem::take(&mut self.hessian_current) && self.evaluate_hessian().is_err() {
                return SolveStatus::EvaluationError;
            }
            let (sx, ss) = self.sigmas();
            let t = Instant::now();
            let factorized = self.factorize(&sx, &ss);
            self.factorization_time += t.elapsed();
            let Some(delta_w) = factorized else {
                return SolveStatus::NumericalError;
            };
            let (gphi_x, gphi_s) = self.barrier_gradient();
            let mut rx = gphi_x.clone();
            for (k, (&r, &col)) in self.jac_rows.iter().zip(&self.jac_cols).enumerate() {
                if !self.fixed[col] {
                    rx[col] += self.jac[k] * self.y[r];
                }
            }
            let mut rs = vec![0.0; m];
            for i in 0..m {
                if self.sb[i].is_some() {
                    rs[i] = gphi_s[i] - self.y[i];
                }
            }
            self.residual(&self.g, &self.s, &mut c);
            let Some(d) = self.direction(&rx, &rs, &c, &ss, delta_w) else {
                return SolveStatus::NumericalError;
            };
            // Line search.
            let theta: f64 = c.iter().map(|v| v.abs()).sum();
            let phi = self.barrier(self.f, &self.x, &self.s);
            let dphi: f64 = (0..n).map(|i| gphi_x[i] * d.x[i]).sum::<f64>()
                + (0..m).map(|i| gphi_s[i] * d.s[i]).sum::<f64>();
            let alpha_max = self.primal_step_limit(&d.x, &d.s);
            let alpha_z = self.dual_step_limit(&d);
            let alpha_min = if dphi < 0.0 {
                GAMMA_ALPHA
                    * GAMMA_THETA
                        .min(GAMMA_PHI * theta / -dphi)
                        .min(DELTA_SWITCH * theta.powf(S_THETA) / (-dphi).powf(S_PHI))
            } else {
                GAMMA_ALPHA * GAMMA_THETA
            };
            let tiny =
                (0..n).all(|i| d.x[i].abs() <= 10.0 * f64::EPSILON * (1.0 + self.x[i].abs()));
            let mut alpha = alpha_max;
            let mut accepted: Option<Trial> = None;
            let mut x_t = vec![0.0; n];
            let mut s_t = vec![0.0; m];
            let mut g_t = vec![0.0; m];
            let mut c_t = vec![0.0; m];
            let mut first = true;
            while accepted.is_none() {
                for i in 0..n {
                    x_t[i] = self.x[i] + alpha * d.x[i];
                }
                for i in 0..m {
                    s_t[i] = self.s[i] + alpha * d.s[i];
                }
                let trial = self
                    .prob
                    .objective(&x_t)
                    .and_then(|f| self.prob.constraints(&x_t, &mut g_t).map(|_| f));
                if let Ok(f_t) = trial {
                    self.residual(&g_t, &s_t, &mut c_t);
                    let theta_t: f64 = c_t.iter().map(|v| v.abs()).sum();
                    let phi_t = self.barrier(f_t, &x_t, &s_t);
                    let verdict = if tiny {
                        Some(true)
                    } else {
                        self.acceptable(
                            theta, phi, dphi, theta_t, phi_t, alpha, theta_max, theta_min, &filter,
                        )
                    };
                    match verdict {
                        Some(f_type) => {
                            accepted = Some(Trial {
                                x: x_t.clone(),
                                s: s_t.clone(),
                                f: f_t,
                                g: g_t.clone(),
                                alpha,
                                f_type,
                            });
                            break;
                        }
                        None => {
                            if first && theta_t >= theta {
                                if let Some(soc) = self.second_order_correction(
                                    &rx, &rs, &ss, delta_w, &c, &c_t, alpha, theta, phi, dphi,
                                    theta_max, theta_min, &filter,
                                ) {
                                    accepted = Some(soc);
                                    break;
                                }
                            }
                        }
                    }
                }
                first = false;
                alpha *= 0.5;
                if alpha < alpha_min {
                    break;
                }
            }
            let Some(trial) = accepted else {
                // No acceptable step: the feasibility-restoration phase.
                if !self.allow_restoration {
                    return SolveStatus::RestorationFailed;
                }
                filter.add((1.0 - GAMMA_THETA) * theta, phi - GAMMA_PHI * theta);
                match self.restore(&filter, theta, &mut iteration, on_iteration) {
                    Ok(()) => {
                        last_step = 0.0;
                        continue;
                    }
                    Err(status) => return status,
                }
            };
            if !trial.f_type {
                filter.add((1.0 - GAMMA_THETA) * theta, phi - GAMMA_PHI * theta);
            }
            let alpha_p = trial.alpha;
            last_step = (0..n).fold(0.0f64, |a, i| a.max((trial.x[i] - self.x[i]).abs()));
            self.x = trial.x;
            self.s = trial.s;
            self.f = trial.f;
            self.g = trial.g;
            for i in 0..m {
                self.y[i] += alpha_p * d.y[i];
            }
            let mu = self.mu;
            let reset = |z: f64, slack: f64| -> f64 {
                z.min(KAPPA_SIGMA * mu / slack)
                    .max(mu / (KAPPA_SIGMA * slack))
            };
            for i in 0..n {
                let b = self.xb[i];
                if let Some(l) = b.lower {
                    self.zl[i] = reset(self.zl[i] + alpha_z * d.zl[i], self.x[i] - l);
                }
                if let Some(u) = b.upper {
                    self.zu[i] = reset(self.zu[i] + alpha_z * d.zu[i], u - self.x[i]);
                }
            }
            for i in 0..m {
                if let Some(b) = self.sb[i] {
                    if let Some(l) = b.lower {
                        self.vl[i] = reset(self.vl[i] + alpha_z * d.vl[i], self.s[i] - l);
                    }
                    if let Some(u) = b.upper {
                        self.vu[i] = reset(self.vu[i] + alpha_z * d.vu[i], u - self.s[i]);
                    }
                }
            }
            iteration += 1;
            self.iterations = iteration;
            if self.evaluate_derivatives_and_hessian().is_err() {
                return SolveStatus::EvaluationError;
            }
        }
    }
}
