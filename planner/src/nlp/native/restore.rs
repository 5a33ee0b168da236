//! The feasibility-restoration phase: the ℓ₁ restoration problem (`restoration`) solved by
//! this same method, left where the outer filter accepts a point, and the return from it.

use std::time::{Duration, Instant};

use super::bounds::{barrier_value, project};
use super::ipm::Ipm;
use super::line_search::Filter;
use super::restoration::Restoration;
use crate::nlp::interface::{
    IterationControl, IterationReport, PhaseTimes, SolveOptions, SolveStatus,
};

impl Ipm<'_> {
    /// IPOPT's feasibility-restoration phase: minimize the ℓ₁ constraint violation near the
    /// current point ([`super::restoration`]) with this same method until the outer problem
    /// has a point the filter accepts with θ reduced by 10 %, then reset the multipliers
    /// there. `Err` ends the solve: [`SolveStatus::Infeasible`] when the violation cannot be
    /// reduced (a local minimizer of it that is not feasible).
    pub(super) fn restore(
        &mut self,
        filter: &Filter,
        theta: f64,
        iteration: &mut usize,
        on_iteration: &mut dyn FnMut(&IterationReport) -> IterationControl,
    ) -> std::result::Result<(), SolveStatus> {
        let (n, m) = (self.n, self.m);
        let mut c = vec![0.0; m];
        self.residual(&self.g, &self.s, &mut c);
        let slack_bounds: Vec<Option<(f64, f64)>> = self
            .sb
            .iter()
            .map(|b| {
                b.map(|b| {
                    (
                        b.lower.unwrap_or(f64::NEG_INFINITY),
                        b.upper.unwrap_or(f64::INFINITY),
                    )
                })
            })
            .collect();
        let problem = self.prob.problem;
        let resto = Restoration::new(
            problem,
            &self.prob.sg,
            &self.rhs,
            &slack_bounds,
            &self.x,
            &self.s,
            &c,
            self.mu,
        );
        let options = SolveOptions {
            max_iterations: self.options.max_iterations.saturating_sub(*iteration),
            warm_start: None,
            ..self.options.clone()
        };
        // The outer problem at a restoration iterate: θ and φ_μ, for the exit test.
        let (xb, sb, rhs, sg, sf, mu) = (
            self.xb.clone(),
            self.sb.clone(),
            self.rhs.clone(),
            self.prob.sg.clone(),
            self.prob.sf,
            self.mu,
        );
        // Its evaluations count as the solve's evaluations (time and calls).
        let outer_time = std::cell::Cell::new(Duration::ZERO);
        let outer_calls = std::cell::Cell::new(0usize);
        let outer = |x: &[f64], s: &[f64]| -> Option<(f64, f64)> {
            let t = Instant::now();
            outer_calls.set(outer_calls.get() + 1);
            let f = problem.objective(x);
            let mut g = vec![0.0; m];
            let g_ok = problem.constraints(x, &mut g);
            outer_time.set(outer_time.get() + t.elapsed());
            let f = f.ok()? * sf;
            g_ok.ok()?;
            let mut theta = 0.0;
            for i in 0..m {
                let b = if sb[i].is_some() { s[i] } else { rhs[i] };
                theta += (sg[i] * g[i] - b).abs();
            }
            let phi = barrier_value(&xb, &sb, mu, f, x, s);
            (theta.is_finite() && phi.is_finite()).then_some((theta, phi))
        };
        let filter_copy = Filter(filter.0.clone());
        let exited = std::cell::Cell::new(false);
        let accept = |theta_t: f64, phi_t: f64| {
            theta_t <= 0.9 * theta && filter_copy.acceptable(theta_t, phi_t)
        };
        let user_stop = std::cell::Cell::new(false);
        let base = *iteration;
        let solution = {
            let mut inner = Ipm::new(&resto, &options);
            inner.allow_restoration = false;
            let resto_ref = &resto;
            let outer_ref = &outer;
            let accept_ref = &accept;
            let exited_ref = &exited;
            inner.exit_test = Some(Box::new(move |w: &[f64]| {
                let x = resto_ref.x(w);
                let s = resto_ref.slacks(w);
                let hit = outer_ref(x, &s).is_some_and(|(t, p)| accept_ref(t, p));
                exited_ref.set(hit);
                hit
            }));
            inner.run(&mut |r| {
                if r.iteration == 0 {
                    return IterationControl::Continue;
                }
                let report = IterationReport {
                    iteration: base + r.iteration,
                    restoration: true,
                    ..*r
                };
                let control = on_iteration(&report);
                if control == IterationControl::Stop {
                    user_stop.set(true);
                }
                control
            })
        };
        let stats = solution.statistics;
        self.prob.time += stats.evaluation_time;
        if let Some(p) = stats.phases {
            self.restoration_phases += PhaseTimes {
                other_time: Duration::ZERO,
                ..p
            };
        }
        self.restoration_iterations += stats.iterations;
        self.prob.counts += stats.evaluation_counts;
        // The restoration's iterations (reported with `restoration: true`), and its return to
        // the outer problem as one more (so the callback's numbers keep increasing).
        *iteration += stats.iterations + 1;
        self.iterations = *iteration;
        let w = &solution.x;
        let x_new = resto.x(w).to_vec();
        let s_new = resto.slacks(w);
        let done = exited.get()
            || (solution.status.is_success()
                && outer(&x_new, &s_new).is_some_and(|(t, p)| accept(t, p)));
        self.prob.time += outer_time.get();
        self.prob.counts.objective += outer_calls.get();
        self.prob.counts.constraints += outer_calls.get();
        if user_stop.get() {
            return Err(SolveStatus::UserStop);
        }
        if !done {
            return Err(match solution.status {
                // The violation has a local minimizer that is not feasible.
                SolveStatus::Optimal | SolveStatus::Acceptable => SolveStatus::Infeasible,
                SolveStatus::IterationLimit => SolveStatus::IterationLimit,
                SolveStatus::TimeLimit => SolveStatus::TimeLimit,
                _ => SolveStatus::RestorationFailed,
            });
        }
        // Back in the outer problem: strictly inside the bounds, bound multipliers centred at μ,
        // constraint multipliers by least squares.
        for i in 0..n {
            self.x[i] = if self.fixed[i] {
                self.x[i]
            } else {
                project(x_new[i], self.xb[i], 1e-8)
            };
        }
        for i in 0..m {
            if let Some(b) = self.sb[i] {
                self.s[i] = project(s_new[i], b, 1e-8);
            }
        }
        self.evaluate_point()
            .map_err(|_| SolveStatus::EvaluationError)?;
        self.evaluate_first_derivatives()
            .map_err(|_| SolveStatus::EvaluationError)?;
        let mu = self.mu;
        for i in 0..n {
            let b = self.xb[i];
            if let Some(l) = b.lower {
                self.zl[i] = mu / (self.x[i] - l);
            }
            if let Some(u) = b.upper {
                self.zu[i] = mu / (u - self.x[i]);
            }
        }
        for i in 0..m {
            if let Some(b) = self.sb[i] {
                if let Some(l) = b.lower {
                    self.vl[i] = mu / (self.s[i] - l);
                }
                if let Some(u) = b.upper {
                    self.vu[i] = mu / (u - self.s[i]);
                }
            }
        }
        self.y.fill(0.0);
        self.least_squares_multipliers();
        Ok(())
    }
}
