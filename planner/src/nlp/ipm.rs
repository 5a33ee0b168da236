//! The native interior point backend: see [`NativeSolver`].

// The iteration works on parallel arrays (x, its bounds, multipliers, step) indexed together:
// index loops say that more plainly than zipped iterators.
#![allow(clippy::needless_range_loop)]

use super::kkt::{KktStats, KktSystem};
use super::restoration::Restoration;
use super::solver::{
    EvaluationCounts, IterationControl, IterationReport, NlpSolver, PhaseTimes, Result, Solution,
    SolveOptions, SolveStatistics, SolveStatus,
};
use super::{DomainError, NlpProblem};
use std::time::{Duration, Instant};

/// The native backend: a primal–dual interior point method with a filter line search, the
/// algorithm of Wächter & Biegler (Math. Program. 106, 2006) that IPOPT implements, on a
/// condensed KKT system `[W + Σ_x + δ_w I, Jᵀ; J, −D]` (slacks eliminated) factorized by
/// faer's supernodal LDLᵀ on a matching-paired ordering from feral (`kkt`; feral's
/// multifrontal LDLᵀ only where faer's set-up fails; both give the inertia). The ordering and
/// symbolic analysis run once per solve, at its first factorization.
///
/// * Inequalities get slacks; every bound gets a logarithmic barrier (with IPOPT's damping of
///   one-sided bounds); bounds are relaxed by 1e-8 relative, as IPOPT's `bound_relax_factor`.
/// * Gradient-based scaling of the objective and each constraint at the start (largest
///   gradient entry 100, as IPOPT's `nlp_scaling_max_gradient`).
/// * Monotone (Fiacco–McCormick) barrier update: μ ← max(tol/10, min(0.2 μ, μ^1.5)) whenever
///   the barrier problem is solved to 10 μ, repeated while it holds.
/// * Inertia correction: the KKT matrix must have n positive and m negative eigenvalues; else
///   δ_w is raised (1e-4 first, ×100 / ×8 after, from a third of the last one later); a
///   factor that is not finite counts as a failed trial. With a core to spare, a trial and the
///   one after it are factorized at once on twin systems (the same factors and choices as one
///   after the other). The equality rows always carry δ_c = 1e-8 μ^¼ (IPOPT's
///   `perturb_always_cd`).
/// * Filter line search with the switching condition, Armijo on the barrier objective, and up
///   to four second-order corrections on the first trial step.
/// * Fraction to the boundary τ = max(0.99, 1 − μ); bound multipliers kept within a factor
///   1e10 of μ / slack.
///
/// * Feasibility restoration where the line search finds no acceptable step: IPOPT's ℓ₁
///   restoration problem (ρ = 1000, proximity weight √μ) solved by this same method, left as
///   soon as the outer filter accepts a point with 10 % less violation; its iterations are
///   reported with `restoration: true`. A restoration that converges to an infeasible point
///   ends the solve as [`SolveStatus::Infeasible`], one that fails as
///   [`SolveStatus::RestorationFailed`].
/// * Ends: [`SolveStatus::Optimal`] at the tolerances; [`SolveStatus::Acceptable`] after 15
///   iterations in a row within IPOPT's acceptable tolerances (KKT error 1e-6, violation 1e-2,
///   complementarity 1e-2), or when the solve fails numerically (no factorization with the
///   right inertia, no direction, a failed restoration) at a point within them, as IPOPT's
///   `STOP_AT_ACCEPTABLE_POINT`; [`SolveStatus::Diverging`] once |x| > 1e20;
///   [`SolveStatus::IterationLimit`], [`SolveStatus::TimeLimit`], [`SolveStatus::UserStop`].
#[derive(Debug, Clone, Copy, Default)]
pub struct NativeSolver;

impl NlpSolver for NativeSolver {
    fn solve_with_callback(
        &self,
        problem: &dyn NlpProblem,
        options: &SolveOptions,
        on_iteration: &mut dyn FnMut(&IterationReport) -> IterationControl,
    ) -> Result<Solution> {
        Ok(Ipm::new(problem, options).run(on_iteration))
    }
}

// Algorithm constants (IPOPT's defaults).
const MU_INIT: f64 = 0.1;
const KAPPA_EPS: f64 = 10.0;
const KAPPA_MU: f64 = 0.2;
const THETA_MU: f64 = 1.5;
const TAU_MIN: f64 = 0.99;
const S_MAX: f64 = 100.0;
const KAPPA_SIGMA: f64 = 1e10;
const BOUND_PUSH: f64 = 1e-2;
const BOUND_RELAX: f64 = 1e-8;
const KAPPA_D: f64 = 1e-5;
const GAMMA_THETA: f64 = 1e-5;
const GAMMA_PHI: f64 = 1e-8;
const DELTA_SWITCH: f64 = 1.0;
const S_THETA: f64 = 1.1;
const S_PHI: f64 = 2.3;
const ETA_PHI: f64 = 1e-8;
const GAMMA_ALPHA: f64 = 0.05;
const MAX_SOC: usize = 4;
const KAPPA_SOC: f64 = 0.99;
const DELTA_W_0: f64 = 1e-4;
const DELTA_W_MIN: f64 = 1e-20;
const DELTA_W_MAX: f64 = 1e40;
const KAPPA_W_MINUS: f64 = 1.0 / 3.0;
const KAPPA_W_PLUS: f64 = 8.0;
const KAPPA_W_PLUS_BAR: f64 = 100.0;
/// Inertia-correction trials (factorizations) per iteration, at most.
const MAX_CORRECTIONS: usize = 60;
const DELTA_C_BAR: f64 = 1e-8;
const KAPPA_C: f64 = 0.25;
const SCALING_MAX_GRADIENT: f64 = 100.0;
const ACCEPTABLE_TOL: f64 = 1e-6;
const ACCEPTABLE_ITER: usize = 15;
const ACCEPTABLE_VIOLATION: f64 = 1e-2;
const ACCEPTABLE_COMPLEMENTARITY: f64 = 1e-2;
const DUAL_INF_TOL: f64 = 1.0;
const COMPL_INF_TOL: f64 = 1e-4;
const LS_MULTIPLIER_MAX: f64 = 1e3;
const REFINEMENTS: usize = 3;

/// The problem in the solver's scaling, with evaluation counts and time.
struct Scaled<'a> {
    problem: &'a dyn NlpProblem,
    sf: f64,
    sg: Vec<f64>,
    counts: EvaluationCounts,
    time: Duration,
}

impl Scaled<'_> {
    fn timed<T>(&mut self, f: impl FnOnce(&dyn NlpProblem) -> T) -> T {
        let t = Instant::now();
        let out = f(self.problem);
        self.time += t.elapsed();
        out
    }
    fn objective(&mut self, x: &[f64]) -> std::result::Result<f64, DomainError> {
        self.counts.objective += 1;
        let v = self.timed(|p| p.objective(x))?;
        if v.is_finite() {
            Ok(self.sf * v)
        } else {
            Err(DomainError)
        }
    }
    fn gradient(&mut self, x: &[f64], out: &mut [f64]) -> std::result::Result<(), DomainError> {
        self.counts.gradient += 1;
        self.timed(|p| p.gradient(x, out))?;
        let sf = self.sf;
        out.iter_mut().for_each(|v| *v *= sf);
        finite(out)
    }
    fn constraints(&mut self, x: &[f64], out: &mut [f64]) -> std::result::Result<(), DomainError> {
        self.counts.constraints += 1;
        self.timed(|p| p.constraints(x, out))?;
        out.iter_mut().zip(&self.sg).for_each(|(v, s)| *v *= s);
        finite(out)
    }
    fn jacobian(
        &mut self,
        x: &[f64],
        rows: &[usize],
        out: &mut [f64],
    ) -> std::result::Result<(), DomainError> {
        self.counts.jacobian += 1;
        self.timed(|p| p.jacobian_values(x, out))?;
        out.iter_mut()
            .zip(rows)
            .for_each(|(v, &r)| *v *= self.sg[r]);
        finite(out)
    }
    fn hessian(
        &mut self,
        x: &[f64],
        y: &[f64],
        out: &mut [f64],
    ) -> std::result::Result<(), DomainError> {
        self.counts.hessian += 1;
        let lambda: Vec<f64> = y.iter().zip(&self.sg).map(|(a, b)| a * b).collect();
        let sf = self.sf;
        self.timed(|p| p.hessian_values(x, sf, &lambda, out))?;
        finite(out)
    }
    /// [`Self::jacobian`] and [`Self::hessian`] in one call of the problem.
    fn jacobian_and_hessian(
        &mut self,
        x: &[f64],
        rows: &[usize],
        y: &[f64],
        jac: &mut [f64],
        hess: &mut [f64],
    ) -> std::result::Result<(), DomainError> {
        self.counts.jacobian += 1;
        self.counts.hessian += 1;
        let lambda: Vec<f64> = y.iter().zip(&self.sg).map(|(a, b)| a * b).collect();
        let sf = self.sf;
        self.timed(|p| p.jacobian_and_hessian_values(x, jac, sf, &lambda, hess))?;
        jac.iter_mut()
            .zip(rows)
            .for_each(|(v, &r)| *v *= self.sg[r]);
        finite(jac)?;
        finite(hess)
    }
}

fn finite(v: &[f64]) -> std::result::Result<(), DomainError> {
    if v.iter().all(|a| a.is_finite()) {
        Ok(())
    } else {
        Err(DomainError)
    }
}

/// One bounded quantity's barrier data: which bounds are finite.
#[derive(Clone, Copy)]
struct Bounds {
    lower: Option<f64>,
    upper: Option<f64>,
}

/// A search direction in all variables.
#[derive(Clone, Default)]
struct Direction {
    x: Vec<f64>,
    s: Vec<f64>,
    y: Vec<f64>,
    zl: Vec<f64>,
    zu: Vec<f64>,
    vl: Vec<f64>,
    vu: Vec<f64>,
}

/// The exit test of a restoration phase: called with each accepted iterate; true ends it.
type ExitTest<'a> = Box<dyn FnMut(&[f64]) -> bool + 'a>;

/// An accepted trial point of the line search.
struct Trial {
    x: Vec<f64>,
    s: Vec<f64>,
    f: f64,
    g: Vec<f64>,
    /// The primal step length that reached it (also used for y).
    alpha: f64,
    /// Accepted by the Armijo condition on the barrier objective (an "f-type" step; the
    /// filter is not augmented).
    f_type: bool,
}

/// The filter: pairs (θ, φ) that a trial point must improve on.
#[derive(Default)]
struct Filter(Vec<(f64, f64)>);

impl Filter {
    fn acceptable(&self, theta: f64, phi: f64) -> bool {
        self.0.iter().all(|&(t, p)| theta < t || phi < p)
    }
    fn add(&mut self, theta: f64, phi: f64) {
        self.0.retain(|&(t, p)| t < theta || p < phi);
        self.0.push((theta, phi));
    }
}

struct Ipm<'a> {
    prob: Scaled<'a>,
    options: &'a SolveOptions,
    n: usize,
    m: usize,
    xb: Vec<Bounds>,
    fixed: Vec<bool>,
    /// Per constraint: `Some(bounds)` for an inequality (with a slack), `None` for an equality.
    sb: Vec<Option<Bounds>>,
    /// Equality right-hand sides (scaled); unused for inequalities.
    rhs: Vec<f64>,
    jac_rows: Vec<usize>,
    jac_cols: Vec<usize>,
    hess_rows: Vec<usize>,
    hess_cols: Vec<usize>,
    // Iterate.
    x: Vec<f64>,
    s: Vec<f64>,
    y: Vec<f64>,
    zl: Vec<f64>,
    zu: Vec<f64>,
    vl: Vec<f64>,
    vu: Vec<f64>,
    // Functions at the iterate.
    f: f64,
    g: Vec<f64>,
    grad: Vec<f64>,
    jac: Vec<f64>,
    hess: Vec<f64>,
    /// Whether `hess` is W at the current (x, y): evaluated with J after an accepted step.
    hessian_current: bool,
    mu: f64,
    tau: f64,
    delta_w_last: f64,
    kkt: Option<KktSystem>,
    /// Whether two δ_w trials are factorized at once (`factorize`): decided at construction,
    /// true with a core to spare, i.e. outside the rayon pool (a co-design sweep's workers keep
    /// every core busy with whole runs) and with more than one thread in it.
    pair_trials: bool,
    /// A second KKT system with `kkt`'s ordering, for two δ_w trials at once.
    twin: Option<KktSystem>,
    /// Pairs of δ_w trials factorized at once, and how many of them the twin's trial decided.
    paired_trials: usize,
    twin_accepted: usize,
    iterations: usize,
    /// Wall time of this solve's KKT assemblies and factorizations (every inertia trial, two
    /// at once counting once, and the least-squares multiplier estimate's). Their count, and
    /// the solves, are in `kkt`'s and `twin`'s statistics.
    factorization_time: Duration,
    /// The restoration phases' work (their own `other_time` left out: it is part of this
    /// solve's, derived at the end).
    restoration_phases: PhaseTimes,
    /// Iterations inside restoration phases.
    restoration_iterations: usize,
    /// False inside a restoration phase (which has none of its own).
    allow_restoration: bool,
    /// Inside a restoration phase: called with each accepted iterate; true ends the phase.
    exit_test: Option<ExitTest<'a>>,
}

impl<'a> Ipm<'a> {
    fn new(problem: &'a dyn NlpProblem, options: &'a SolveOptions) -> Self {
        let n = problem.num_variables();
        let m = problem.num_constraints();
        let js = problem.jacobian_structure();
        let hs = problem.hessian_structure();
        let hl = hs.len();
        Self {
            prob: Scaled {
                problem,
                sf: 1.0,
                sg: vec![1.0; m],
                counts: EvaluationCounts::default(),
                time: Duration::ZERO,
            },
            options,
            n,
            m,
            xb: Vec::new(),
            fixed: vec![false; n],
            sb: Vec::new(),
            rhs: vec![0.0; m],
            jac: vec![0.0; js.len()],
            jac_rows: js.rows,
            jac_cols: js.cols,
            hess: vec![0.0; hl],
            hessian_current: false,
            hess_rows: hs.rows,
            hess_cols: hs.cols,
            x: vec![0.0; n],
            s: vec![0.0; m],
            y: vec![0.0; m],
            zl: vec![0.0; n],
            zu: vec![0.0; n],
            vl: vec![0.0; m],
            vu: vec![0.0; m],
            f: 0.0,
            g: vec![0.0; m],
            grad: vec![0.0; n],
            mu: MU_INIT,
            tau: TAU_MIN,
            delta_w_last: 0.0,
            kkt: None,
            pair_trials: rayon::current_thread_index().is_none()
                && rayon::current_num_threads() > 1,
            twin: None,
            paired_trials: 0,
            twin_accepted: 0,
            iterations: 0,
            factorization_time: Duration::ZERO,
            restoration_phases: PhaseTimes::default(),
            restoration_iterations: 0,
            allow_restoration: true,
            exit_test: None,
        }
    }

    fn run(
        mut self,
        on_iteration: &mut dyn FnMut(&IterationReport) -> IterationControl,
    ) -> Solution {
        let start = Instant::now();
        let status = self.iterate(on_iteration, start);
        let status = self.acceptable_instead_of(status);
        self.finish(status, start)
    }

    /// IPOPT's `STOP_AT_ACCEPTABLE_POINT`: a solve that fails numerically (no factorization with
    /// the right inertia, no direction, a failed restoration phase) at an iterate that meets the
    /// acceptable tolerances ends `Acceptable` there, not as a failure. Not inside a restoration
    /// phase, whose failure the outer solve handles.
    fn acceptable_instead_of(&self, status: SolveStatus) -> SolveStatus {
        let numerical = matches!(
            status,
            SolveStatus::NumericalError | SolveStatus::RestorationFailed
        );
        if !(numerical && self.allow_restoration && !self.xb.is_empty()) {
            return status;
        }
        let (error, viol, _, compl) = self.errors(0.0);
        if self.within_acceptable_tolerances(error, viol, compl) {
            SolveStatus::Acceptable
        } else {
            status
        }
    }

    /// IPOPT's acceptable point: the scaled KKT error, the violation and the complementarity
    /// (as [`Self::errors`] gives them) within the acceptable tolerances.
    fn within_acceptable_tolerances(&self, error: f64, viol: f64, compl: f64) -> bool {
        error <= ACCEPTABLE_TOL
            && viol <= ACCEPTABLE_VIOLATION
            && compl / self.prob.sf <= ACCEPTABLE_COMPLEMENTARITY
    }

    /// Relaxed bounds, the scaled start point, slacks and multipliers. `Err` ends the solve.
    fn initialize(&mut self) -> std::result::Result<(), SolveStatus> {
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

    /// f and g at x.
    fn evaluate_point(&mut self) -> std::result::Result<(), DomainError> {
        self.f = self.prob.objective(&self.x)?;
        let mut g = std::mem::take(&mut self.g);
        let r = self.prob.constraints(&self.x, &mut g);
        self.g = g;
        r
    }

    /// ∇f and J at x. Every change of x (the start, an accepted step, the return from
    /// restoration) is followed by this, so an iteration's top finds them current and adds only
    /// [`Self::evaluate_hessian`].
    fn evaluate_first_derivatives(&mut self) -> std::result::Result<(), DomainError> {
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
    fn evaluate_derivatives_and_hessian(&mut self) -> std::result::Result<(), DomainError> {
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
    fn evaluate_hessian(&mut self) -> std::result::Result<(), DomainError> {
        let mut hess = std::mem::take(&mut self.hess);
        let r = self.prob.hessian(&self.x, &self.y, &mut hess);
        self.hess = hess;
        r
    }

    /// c = g − s (inequalities) or g − g_eq (equalities), at given g and s.
    fn residual(&self, g: &[f64], s: &[f64], out: &mut [f64]) {
        for i in 0..self.m {
            out[i] = match self.sb[i] {
                Some(_) => g[i] - s[i],
                None => g[i] - self.rhs[i],
            };
        }
    }

    fn complementarity_sum(&self) -> (f64, usize) {
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

    /// IPOPT's least-squares estimate of y at the start (y = 0 if it is large or fails).
    fn least_squares_multipliers(&mut self) {
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

    /// (scaled optimality error at μ, unscaled constraint violation, dual, complementarity).
    fn errors(&self, mu: f64) -> (f64, f64, f64, f64) {
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
    fn barrier(&self, f: f64, x: &[f64], s: &[f64]) -> f64 {
        barrier_value(&self.xb, &self.sb, self.mu, f, x, s)
    }

    /// Gradient of the barrier objective in x and s.
    fn barrier_gradient(&self) -> (Vec<f64>, Vec<f64>) {
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
    fn sigmas(&self) -> (Vec<f64>, Vec<f64>) {
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

    /// Factorizes the KKT matrix with inertia correction; returns the δ_w it needed.
    fn factorize(&mut self, sx: &[f64], ss: &[f64]) -> Option<f64> {
        let (n, m) = (self.n, self.m);
        let correct = |i: Option<super::kkt::Inertia>| {
            i.is_some_and(|i| i.positive == n && i.negative == m && i.zero == 0)
        };
        // Always a small δ_c (IPOPT's `perturb_always_cd`): an exactly zero (2,2) block for
        // the equalities gives zero pivots (with feral's LDLᵀ, ADAM took 47 + 81 iterations
        // and ~8 ms per factorization without it, 40 + 78 and ~7 ms with it).
        let delta_c = DELTA_C_BAR * self.mu.powf(KAPPA_C);
        // After an iteration that needed δ_w, start from δ_w_last/3 instead of trying δ_w = 0
        // first (IPOPT tries 0 every iteration). The LDLᵀ pivots only inside supernodes
        // (`kkt`), so with δ_w = 0 the zero diagonal of the variables that enter linearly gives
        // exact zero pivots and a wrong inertia: on ADAM that trial failed in every such
        // iteration, 49 + 74 iterations either way, 300 factorizations with it and 179 without.
        let mut delta_w = if self.delta_w_last > 0.0 {
            (KAPPA_W_MINUS * self.delta_w_last).max(DELTA_W_MIN)
        } else {
            0.0
        };
        // Pairing (`pair_trials`): the trial δ_w and the one that would follow its failure are
        // factorized at once on twin systems with the same ordering: the same factors and the
        // same choice as one after the other, in the time of one when the first fails (~40 % of
        // ADAM's iterations).
        let (hess, jac, fixed) = (&self.hess, &self.jac, &self.fixed);
        let trial = |k: &mut KktSystem, (primal, dual): (Vec<f64>, Vec<f64>)| {
            k.assemble(hess, jac, &primal, &dual, fixed);
            k.factorize()
        };
        let mut trials = 0;
        while trials < MAX_CORRECTIONS {
            let next = self.next_delta_w(delta_w);
            let kkt = self.kkt.as_mut()?;
            if self.pair_trials && self.twin.is_none() && kkt.is_set_up() {
                self.twin = kkt.twin();
                // A twin without this system's ordering would not give its factors.
                self.pair_trials = self.twin.is_some();
            }
            let pair = self.pair_trials
                && self.twin.is_some()
                && next <= DELTA_W_MAX
                && trials + 2 <= MAX_CORRECTIONS;
            let diagonals = self.diagonals(sx, ss, delta_w, delta_c);
            let next_diagonals = pair.then(|| self.diagonals(sx, ss, next, delta_c));
            let kkt = self.kkt.as_mut()?;
            match (self.twin.as_mut(), next_diagonals) {
                (Some(twin), Some(next_diagonals)) => {
                    let (ra, rb) =
                        rayon::join(|| trial(kkt, diagonals), || trial(twin, next_diagonals));
                    trials += 2;
                    self.paired_trials += 1;
                    if correct(ra) {
                        return Some(self.accept_delta_w(delta_w));
                    }
                    if correct(rb) {
                        // The solves use `kkt`: it takes the twin's factor.
                        std::mem::swap(&mut self.kkt, &mut self.twin);
                        self.twin_accepted += 1;
                        return Some(self.accept_delta_w(next));
                    }
                    delta_w = self.next_delta_w(next);
                }
                _ => {
                    trials += 1;
                    if correct(trial(kkt, diagonals)) {
                        return Some(self.accept_delta_w(delta_w));
                    }
                    delta_w = next;
                }
            }
            if delta_w > DELTA_W_MAX {
                return None;
            }
        }
        None
    }

    /// The δ_w tried after a failed trial at `delta_w` (IPOPT's inertia-correction rule).
    fn next_delta_w(&self, delta_w: f64) -> f64 {
        if delta_w == 0.0 {
            if self.delta_w_last == 0.0 {
                DELTA_W_0
            } else {
                (KAPPA_W_MINUS * self.delta_w_last).max(DELTA_W_MIN)
            }
        } else if self.delta_w_last == 0.0 {
            KAPPA_W_PLUS_BAR * delta_w
        } else {
            KAPPA_W_PLUS * delta_w
        }
    }

    /// Records a successful trial's δ_w and returns it.
    fn accept_delta_w(&mut self, delta_w: f64) -> f64 {
        if delta_w > 0.0 {
            self.delta_w_last = delta_w;
        }
        delta_w
    }

    /// The KKT matrix's diagonals for δ_w and δ_c: Σ_x + δ_w (1 for a fixed variable) and
    /// −δ_c − 1/(Σ_s + δ_w) (the slack eliminated; −δ_c alone for an equality).
    fn diagonals(
        &self,
        sx: &[f64],
        ss: &[f64],
        delta_w: f64,
        delta_c: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let primal = (0..self.n)
            .map(|i| if self.fixed[i] { 1.0 } else { sx[i] + delta_w })
            .collect();
        let dual = (0..self.m)
            .map(|i| {
                -delta_c
                    - if self.sb[i].is_some() {
                        1.0 / (ss[i] + delta_w)
                    } else {
                        0.0
                    }
            })
            .collect();
        (primal, dual)
    }

    /// Solves for the step from the factorized matrix given r_x, r_s and the constraint
    /// residual c (all of the Newton system's right-hand side, sign included below).
    fn direction(
        &mut self,
        rx: &[f64],
        rs: &[f64],
        c: &[f64],
        ss: &[f64],
        delta_w: f64,
    ) -> Option<Direction> {
        let (n, m) = (self.n, self.m);
        let mut rhs = vec![0.0; n + m];
        for i in 0..n {
            rhs[i] = if self.fixed[i] { 0.0 } else { -rx[i] };
        }
        for i in 0..m {
            rhs[n + i] = -c[i]
                - if self.sb[i].is_some() {
                    rs[i] / (ss[i] + delta_w)
                } else {
                    0.0
                };
        }
        let sol = self.kkt.as_mut()?.solve(&rhs, REFINEMENTS)?;
        let mut d = Direction {
            x: sol[..n].to_vec(),
            y: sol[n..].to_vec(),
            s: vec![0.0; m],
            zl: vec![0.0; n],
            zu: vec![0.0; n],
            vl: vec![0.0; m],
            vu: vec![0.0; m],
        };
        for i in 0..m {
            if self.sb[i].is_some() {
                d.s[i] = (d.y[i] - rs[i]) / (ss[i] + delta_w);
            }
        }
        let mu = self.mu;
        for i in 0..n {
            let b = self.xb[i];
            if let Some(l) = b.lower {
                let sl = self.x[i] - l;
                d.zl[i] = mu / sl - self.zl[i] - self.zl[i] / sl * d.x[i];
            }
            if let Some(u) = b.upper {
                let su = u - self.x[i];
                d.zu[i] = mu / su - self.zu[i] + self.zu[i] / su * d.x[i];
            }
        }
        for i in 0..m {
            if let Some(b) = self.sb[i] {
                if let Some(l) = b.lower {
                    let sl = self.s[i] - l;
                    d.vl[i] = mu / sl - self.vl[i] - self.vl[i] / sl * d.s[i];
                }
                if let Some(u) = b.upper {
                    let su = u - self.s[i];
                    d.vu[i] = mu / su - self.vu[i] + self.vu[i] / su * d.s[i];
                }
            }
        }
        Some(d)
    }

    /// Largest α ≤ 1 keeping x + α dx (and s) strictly inside by the fraction τ.
    fn primal_step_limit(&self, dx: &[f64], ds: &[f64]) -> f64 {
        let tau = self.tau;
        let mut alpha = 1.0f64;
        let mut limit = |v: f64, d: f64, b: Bounds| {
            if let Some(l) = b.lower {
                if d < 0.0 {
                    alpha = alpha.min(-tau * (v - l) / d);
                }
            }
            if let Some(u) = b.upper {
                if d > 0.0 {
                    alpha = alpha.min(tau * (u - v) / d);
                }
            }
        };
        for i in 0..self.n {
            limit(self.x[i], dx[i], self.xb[i]);
        }
        for i in 0..self.m {
            if let Some(b) = self.sb[i] {
                limit(self.s[i], ds[i], b);
            }
        }
        alpha
    }

    fn dual_step_limit(&self, d: &Direction) -> f64 {
        let tau = self.tau;
        let mut alpha = 1.0f64;
        let mut limit = |z: f64, dz: f64| {
            if dz < 0.0 && z > 0.0 {
                alpha = alpha.min(-tau * z / dz);
            }
        };
        for i in 0..self.n {
            if self.xb[i].lower.is_some() {
                limit(self.zl[i], d.zl[i]);
            }
            if self.xb[i].upper.is_some() {
                limit(self.zu[i], d.zu[i]);
            }
        }
        for i in 0..self.m {
            if let Some(b) = self.sb[i] {
                if b.lower.is_some() {
                    limit(self.vl[i], d.vl[i]);
                }
                if b.upper.is_some() {
                    limit(self.vu[i], d.vu[i]);
                }
            }
        }
        alpha
    }

    fn iterate(
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

    /// IPOPT's feasibility-restoration phase: minimize the ℓ₁ constraint violation near the
    /// current point ([`super::restoration`]) with this same method until the outer problem
    /// has a point the filter accepts with θ reduced by 10 %, then reset the multipliers
    /// there. `Err` ends the solve: [`SolveStatus::Infeasible`] when the violation cannot be
    /// reduced (a local minimizer of it that is not feasible).
    fn restore(
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

    /// The filter acceptance test: `Some(f_type)` if the trial point is accepted.
    #[allow(clippy::too_many_arguments)]
    fn acceptable(
        &self,
        theta: f64,
        phi: f64,
        dphi: f64,
        theta_t: f64,
        phi_t: f64,
        alpha: f64,
        theta_max: f64,
        theta_min: f64,
        filter: &Filter,
    ) -> Option<bool> {
        if !(theta_t.is_finite() && phi_t.is_finite()) || theta_t > theta_max {
            return None;
        }
        if !filter.acceptable(theta_t, phi_t) {
            return None;
        }
        let switching =
            dphi < 0.0 && alpha * (-dphi).powf(S_PHI) > DELTA_SWITCH * theta.powf(S_THETA);
        if switching && theta <= theta_min {
            return (phi_t <= phi + ETA_PHI * alpha * dphi).then_some(true);
        }
        (theta_t <= (1.0 - GAMMA_THETA) * theta || phi_t <= phi - GAMMA_PHI * theta)
            .then_some(false)
    }

    /// Up to [`MAX_SOC`] second-order corrections of a rejected first trial step.
    #[allow(clippy::too_many_arguments)]
    fn second_order_correction(
        &mut self,
        rx: &[f64],
        rs: &[f64],
        ss: &[f64],
        delta_w: f64,
        c: &[f64],
        c_trial: &[f64],
        alpha: f64,
        theta: f64,
        phi: f64,
        dphi: f64,
        theta_max: f64,
        theta_min: f64,
        filter: &Filter,
    ) -> Option<Trial> {
        let (n, m) = (self.n, self.m);
        let mut c_soc: Vec<f64> = (0..m).map(|i| alpha * c[i] + c_trial[i]).collect();
        let mut theta_old = c_trial.iter().map(|v| v.abs()).sum::<f64>();
        for _ in 0..MAX_SOC {
            let ds = self.direction(rx, rs, &c_soc, ss, delta_w)?;
            let alpha_soc = self.primal_step_limit(&ds.x, &ds.s);
            let x_t: Vec<f64> = (0..n).map(|i| self.x[i] + alpha_soc * ds.x[i]).collect();
            let s_t: Vec<f64> = (0..m).map(|i| self.s[i] + alpha_soc * ds.s[i]).collect();
            let mut g_t = vec![0.0; m];
            let f_t = self.prob.objective(&x_t).ok()?;
            self.prob.constraints(&x_t, &mut g_t).ok()?;
            let mut c_t = vec![0.0; m];
            self.residual(&g_t, &s_t, &mut c_t);
            let theta_t: f64 = c_t.iter().map(|v| v.abs()).sum();
            let phi_t = self.barrier(f_t, &x_t, &s_t);
            if let Some(f_type) = self.acceptable(
                theta, phi, dphi, theta_t, phi_t, alpha_soc, theta_max, theta_min, filter,
            ) {
                return Some(Trial {
                    x: x_t,
                    s: s_t,
                    f: f_t,
                    g: g_t,
                    alpha: alpha_soc,
                    f_type,
                });
            }
            if theta_t > KAPPA_SOC * theta_old {
                return None;
            }
            theta_old = theta_t;
            for i in 0..m {
                c_soc[i] = alpha_soc * c_soc[i] + c_t[i];
            }
        }
        None
    }

    fn finish(mut self, status: SolveStatus, start: Instant) -> Solution {
        let (n, m) = (self.n, self.m);
        let sf = self.prob.sf;
        let mut g = vec![0.0; m];
        let t = Instant::now();
        let ok = self.prob.problem.constraints(&self.x, &mut g).is_ok();
        self.prob.time += t.elapsed();
        let objective = self.f / sf;
        let (mut xl, mut xu) = (vec![0.0; n], vec![0.0; n]);
        self.prob.problem.variable_bounds(&mut xl, &mut xu);
        let (mut gl, mut gu) = (vec![0.0; m], vec![0.0; m]);
        self.prob.problem.constraint_bounds(&mut gl, &mut gu);
        let mut viol = 0.0f64;
        for i in 0..n {
            viol = viol.max(xl[i] - self.x[i]).max(self.x[i] - xu[i]);
        }
        if ok {
            for i in 0..m {
                viol = viol.max(gl[i] - g[i]).max(g[i] - gu[i]);
            }
        } else {
            viol = f64::INFINITY;
        }
        let (_, _, dual_inf, _) = if self.xb.is_empty() {
            (0.0, 0.0, f64::NAN, 0.0)
        } else {
            self.errors(0.0)
        };
        let total = start.elapsed();
        // The work of both KKT systems (a trial the twin decided swapped them).
        let kkt =
            [&self.kkt, &self.twin]
                .into_iter()
                .flatten()
                .fold(KktStats::default(), |mut st, k| {
                    st += k.stats;
                    st
                });
        if self.options.print_level >= 5 && self.kkt.is_some() {
            eprintln!(
                "kkt: {} factorizations {:?} ({} not finite, {} by feral; {} pairs at once, {} decided by the second), {} solves ({} refinement corrections) {:?}; total {:?}, eval {:?}",
                kkt.factorizations,
                kkt.factorization_time,
                kkt.nonfinite,
                kkt.fallbacks,
                self.paired_trials,
                self.twin_accepted,
                kkt.solves,
                kkt.corrections,
                kkt.solve_time,
                total,
                self.prob.time
            );
        }
        let lambda = (0..m).map(|i| self.y[i] * self.prob.sg[i] / sf).collect();
        let solver_time = total.saturating_sub(self.prob.time);
        let mut phases = PhaseTimes {
            factorizations: kkt.factorizations,
            factorization_time: self.factorization_time,
            linear_solves: kkt.solves,
            linear_solve_time: kkt.solve_time,
            other_time: Duration::ZERO,
        };
        phases += self.restoration_phases;
        phases.other_time =
            solver_time.saturating_sub(phases.factorization_time + phases.linear_solve_time);
        Solution {
            status,
            constraint_values: g,
            constraint_multipliers: lambda,
            lower_bound_multipliers: self.zl.iter().map(|z| z / sf).collect(),
            upper_bound_multipliers: self.zu.iter().map(|z| z / sf).collect(),
            statistics: SolveStatistics {
                iterations: self.iterations,
                objective,
                primal_infeasibility: viol.max(0.0),
                dual_infeasibility: dual_inf,
                evaluation_counts: self.prob.counts,
                evaluation_time: self.prob.time,
                solver_time,
                total_time: total,
                restoration_iterations: Some(self.restoration_iterations),
                phases: Some(phases),
            },
            x: std::mem::take(&mut self.x),
        }
    }
}

/// The barrier objective φ_μ = f − μ Σ ln(slack) (+ IPOPT's damping of one-sided bounds) at
/// (x, s), for the bounds `xb` of x and `sb` of the inequality slacks.
fn barrier_value(
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
fn project(v: f64, b: Bounds, push: f64) -> f64 {
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use num_dual::DualNum;

    use crate::nlp::ad::{AdModel, DenseAdProblem};
    use crate::nlp::test_problems::{Hs71, Infeasible};
    use crate::nlp::{
        solve, solve_with_callback, Backend, DomainError, IterationControl, NlpProblem,
        SolveOptions, SolveStatus, SparsityPattern,
    };

    fn native() -> SolveOptions {
        SolveOptions {
            backend: Backend::Native,
            ..SolveOptions::default()
        }
    }

    #[test]
    fn hs71_optimum_and_multipliers_agree_with_ripopt() {
        let problem = DenseAdProblem::new(Hs71::standard());
        let ours = solve(&problem, &native()).unwrap();
        let reference = solve(
            &problem,
            &SolveOptions {
                backend: Backend::Ripopt,
                ..SolveOptions::default()
            },
        )
        .unwrap();
        assert_eq!(ours.status, SolveStatus::Optimal);
        let stats = ours.statistics;
        assert!((stats.objective - 17.014_017_3).abs() < 1e-6, "{stats:?}");
        assert!(stats.primal_infeasibility < 1e-6, "{stats:?}");
        assert_eq!(stats.evaluation_time + stats.solver_time, stats.total_time);
        // Same sign convention and scale as ripopt's (IPOPT's) multipliers: L = f + λᵀg. Both
        // stop at a tolerance of 1e-8 on the scaled KKT error, so they agree to ~1e-6.
        let close = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= 1e-5 * (1.0 + y.abs()))
        };
        assert!(
            close(
                &ours.constraint_multipliers,
                &reference.constraint_multipliers
            ),
            "{:?} vs {:?}",
            ours.constraint_multipliers,
            reference.constraint_multipliers
        );
        assert!(close(
            &ours.lower_bound_multipliers,
            &reference.lower_bound_multipliers
        ));
        assert!(close(
            &ours.upper_bound_multipliers,
            &reference.upper_bound_multipliers
        ));
        assert!(close(&ours.x, &reference.x));
    }

    #[test]
    fn the_gradient_and_jacobian_are_evaluated_once_per_iterate() {
        let problem = DenseAdProblem::new(Hs71::standard());
        let sol = solve(&problem, &native()).unwrap();
        assert_eq!(sol.status, SolveStatus::Optimal);
        let stats = sol.statistics;
        let counts = stats.evaluation_counts;
        // HS71 needs no restoration: the scaling and the start point, then one evaluation per
        // accepted iterate. W is evaluated at the first iteration's top and then with J at
        // each accepted iterate (the last one's is not used: the solve ends there), never
        // again at a top.
        assert!(stats.iterations > 3, "{stats:?}");
        assert_eq!(counts.jacobian, stats.iterations + 2, "{counts:?}");
        assert_eq!(counts.gradient, stats.iterations + 2, "{counts:?}");
        assert_eq!(counts.hessian, stats.iterations + 1, "{counts:?}");
    }

    /// HS71 whose Hessian cannot be evaluated at the point of its `fail_at`-th call (counting
    /// from 1), then or at any later call there.
    struct HessianFailsOnce {
        inner: DenseAdProblem<Hs71>,
        calls: std::cell::Cell<usize>,
        fail_at: usize,
        failing_x: std::cell::RefCell<Option<Vec<f64>>>,
    }

    impl NlpProblem for HessianFailsOnce {
        fn num_variables(&self) -> usize {
            self.inner.num_variables()
        }
        fn num_constraints(&self) -> usize {
            self.inner.num_constraints()
        }
        fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
            self.inner.variable_bounds(lower, upper)
        }
        fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
            self.inner.constraint_bounds(lower, upper)
        }
        fn initial_point(&self, x0: &mut [f64]) {
            self.inner.initial_point(x0)
        }
        fn objective(&self, x: &[f64]) -> Result<f64, DomainError> {
            self.inner.objective(x)
        }
        fn gradient(&self, x: &[f64], g: &mut [f64]) -> Result<(), DomainError> {
            self.inner.gradient(x, g)
        }
        fn constraints(&self, x: &[f64], g: &mut [f64]) -> Result<(), DomainError> {
            self.inner.constraints(x, g)
        }
        fn jacobian_structure(&self) -> SparsityPattern {
            self.inner.jacobian_structure()
        }
        fn jacobian_values(&self, x: &[f64], v: &mut [f64]) -> Result<(), DomainError> {
            self.inner.jacobian_values(x, v)
        }
        fn hessian_structure(&self) -> SparsityPattern {
            self.inner.hessian_structure()
        }
        fn hessian_values(
            &self,
            x: &[f64],
            sigma: f64,
            lambda: &[f64],
            v: &mut [f64],
        ) -> Result<(), DomainError> {
            self.calls.set(self.calls.get() + 1);
            if self.calls.get() == self.fail_at {
                *self.failing_x.borrow_mut() = Some(x.to_vec());
            }
            if self.failing_x.borrow().as_deref() == Some(x) {
                return Err(DomainError);
            }
            self.inner.hessian_values(x, sigma, lambda, v)
        }
    }

    /// W is evaluated with J after every accepted step, so also at the last iterate, where
    /// the solve ends without using it. If it cannot be evaluated there, the solve still
    /// converges to the same point; if it cannot be evaluated at an iterate that needs it,
    /// the solve reports an evaluation error.
    #[test]
    fn a_hessian_the_solve_does_not_need_cannot_fail_it() {
        let reference = solve(&DenseAdProblem::new(Hs71::standard()), &native()).unwrap();
        let last = reference.statistics.evaluation_counts.hessian;
        let failing = |fail_at| HessianFailsOnce {
            inner: DenseAdProblem::new(Hs71::standard()),
            calls: std::cell::Cell::new(0),
            fail_at,
            failing_x: std::cell::RefCell::new(None),
        };
        let sol = solve(&failing(last), &native()).unwrap();
        assert_eq!(sol.status, SolveStatus::Optimal);
        assert_eq!(sol.x, reference.x);
        assert_eq!(sol.statistics.iterations, reference.statistics.iterations);
        let sol = solve(&failing(last - 1), &native()).unwrap();
        assert_eq!(sol.status, SolveStatus::EvaluationError);
    }

    #[test]
    fn a_warm_start_from_the_optimum_converges_at_once() {
        let problem = DenseAdProblem::new(Hs71::standard());
        let cold = solve(&problem, &native()).unwrap();
        let warm = solve(
            &problem,
            &SolveOptions {
                warm_start: Some(cold.warm_start()),
                ..native()
            },
        )
        .unwrap();
        println!(
            "HS71, native: cold {} iterations, warm {}",
            cold.statistics.iterations, warm.statistics.iterations
        );
        assert_eq!(warm.status, SolveStatus::Optimal);
        assert!(
            warm.statistics.iterations <= 3 && cold.statistics.iterations >= 6,
            "warm {} cold {}",
            warm.statistics.iterations,
            cold.statistics.iterations
        );
        assert!((warm.statistics.objective - 17.014_017_3).abs() < 1e-6);
    }

    #[test]
    fn a_fixed_variable_stays_at_its_value() {
        let problem = DenseAdProblem::new(Hs71 {
            lower_bound: 1.0,
            fix_first: true,
        });
        let s = solve(&problem, &native()).unwrap();
        assert_eq!(s.status, SolveStatus::Optimal);
        assert_eq!(s.x[0], 1.0);
        assert!((s.statistics.objective - 17.014_017_3).abs() < 1e-6);
    }

    /// min −‖x‖² on the disc ‖x − c‖² ≤ 1 inside the box [−3, 3]²: a concave objective, so every
    /// iteration needs the inertia correction, with δ_w of the order of the curvature.
    struct Concave;

    impl AdModel for Concave {
        fn num_variables(&self) -> usize {
            2
        }
        fn num_constraints(&self) -> usize {
            1
        }
        fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
            lower.fill(-3.0);
            upper.fill(3.0);
        }
        fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
            lower[0] = f64::NEG_INFINITY;
            upper[0] = 1.0;
        }
        fn initial_point(&self, x0: &mut [f64]) {
            x0.copy_from_slice(&[0.5, 0.2]);
        }
        fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
            -(x[0] * x[0] + x[1] * x[1])
        }
        fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
            g[0] = (x[0] - 1.0).powi(2) + (x[1] - 0.5).powi(2);
        }
    }

    /// Runs the interior point on `problem`, with δ_w trials in pairs if `pair`, and returns its
    /// solution with the number of paired trials and of pairs the twin decided.
    fn run_counting(
        problem: &dyn super::NlpProblem,
        pair: bool,
    ) -> (super::Solution, usize, usize) {
        let options = native();
        let mut ipm = super::Ipm::new(problem, &options);
        ipm.pair_trials = pair;
        let start = std::time::Instant::now();
        let status = ipm.iterate(&mut |_| IterationControl::Continue, start);
        let (pairs, twin) = (ipm.paired_trials, ipm.twin_accepted);
        (ipm.finish(status, start), pairs, twin)
    }

    #[test]
    fn two_inertia_trials_at_once_give_the_sequential_iterates_bit_for_bit() {
        let problem = DenseAdProblem::new(Concave);
        let (paired, pairs, twin) = run_counting(&problem, true);
        let (sequential, seq_pairs, _) = run_counting(&problem, false);
        println!(
            "concave: {} iterations, {pairs} pairs, {twin} decided by the second trial",
            paired.statistics.iterations
        );
        assert_eq!(seq_pairs, 0);
        // The pairing happened, and the second trial of a pair decided some iterations: the
        // twin's factor was used in place of the first system's.
        assert!(pairs > 0 && twin > 0, "{pairs} pairs, {twin} by the twin");
        assert_eq!(paired.status, SolveStatus::Optimal);
        assert_eq!(sequential.status, SolveStatus::Optimal);
        assert_eq!(
            paired.statistics.iterations,
            sequential.statistics.iterations
        );
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&paired.x), bits(&sequential.x));
        assert_eq!(
            bits(&paired.constraint_multipliers),
            bits(&sequential.constraint_multipliers)
        );
        // The farthest point of the disc from the origin: c + c/‖c‖, ‖x‖² = (‖c‖ + 1)².
        let c = (1.25f64).sqrt();
        assert!(
            (paired.statistics.objective + (c + 1.0).powi(2)).abs() < 1e-6,
            "{:?}",
            paired.x
        );
    }

    #[test]
    fn trials_are_paired_outside_the_rayon_pool_only() {
        let problem = DenseAdProblem::new(Concave);
        let options = native();
        let outside = super::Ipm::new(&problem, &options).pair_trials;
        assert_eq!(outside, rayon::current_num_threads() > 1);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        assert!(!pool.install(|| super::Ipm::new(&problem, &options).pair_trials));
    }

    #[test]
    fn an_infeasible_problem_is_reported_infeasible() {
        let s = solve(&DenseAdProblem::new(Infeasible), &native()).unwrap();
        // The restoration phase converges to x = 0, the least violation (x² + 1 ≥ 1 > 0).
        assert_eq!(s.status, SolveStatus::Infeasible);
        assert!(s.x[0].abs() < 1e-3, "{:?}", s.x);
        assert!(s.statistics.primal_infeasibility >= 1.0 - 1e-9);
    }

    #[test]
    fn the_callback_sees_each_iteration_and_can_stop() {
        let problem = DenseAdProblem::new(Hs71::standard());
        let mut seen = Vec::new();
        let full = solve_with_callback(&problem, &native(), &mut |r| {
            seen.push(r.iteration);
            IterationControl::Continue
        })
        .unwrap();
        let expected: Vec<usize> = (0..=full.statistics.iterations).collect();
        assert_eq!(seen, expected);
        let stopped = solve_with_callback(&problem, &native(), &mut |r| {
            if r.iteration >= 2 {
                IterationControl::Stop
            } else {
                IterationControl::Continue
            }
        })
        .unwrap();
        assert_eq!(stopped.status, SolveStatus::UserStop);
        assert_eq!(stopped.statistics.iterations, 2);
    }

    /// Hock–Schittkowski 27 from (−5, −5, −5): the line search gets stuck far from the optimum
    /// (f* = 0.04 at (−1, 1, 0)) and only the restoration phase gets it out. (From the standard
    /// start (2, 2, 2) it needed restoration with feral's LDLᵀ; with faer's it converges in 31
    /// iterations without.)
    struct Hs27;

    impl AdModel for Hs27 {
        fn num_variables(&self) -> usize {
            3
        }
        fn num_constraints(&self) -> usize {
            1
        }
        fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
            lower.fill(f64::NEG_INFINITY);
            upper.fill(f64::INFINITY);
        }
        fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
            lower[0] = 0.0;
            upper[0] = 0.0;
        }
        fn initial_point(&self, x0: &mut [f64]) {
            x0.fill(-5.0);
        }
        fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
            (x[0] - 1.0).powi(2) * 0.01 + (x[1] - x[0] * x[0]).powi(2)
        }
        fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
            g[0] = x[0] + x[2] * x[2] + 1.0;
        }
    }

    #[test]
    fn the_restoration_phase_rescues_a_stuck_line_search() {
        let mut reports = Vec::new();
        let s = solve_with_callback(&DenseAdProblem::new(Hs27), &native(), &mut |r| {
            reports.push(*r);
            IterationControl::Continue
        })
        .unwrap();
        let restoring = reports.iter().filter(|r| r.restoration).count();
        println!(
            "HS27: {:?} in {} iterations ({restoring} in restoration), f = {}",
            s.status, s.statistics.iterations, s.statistics.objective
        );
        assert_eq!(s.status, SolveStatus::Optimal);
        assert!((s.statistics.objective - 0.04).abs() < 1e-8);
        assert!(restoring > 0);
        assert!(reports.windows(2).all(|w| w[1].iteration > w[0].iteration));
        assert_eq!(reports.last().unwrap().iteration, s.statistics.iterations);
        // The statistics name the restoration iterations. Every iteration that steps, outer or
        // restoration, factorizes at least once; the return from each restoration counts one
        // iteration more with no factorization of its own. (A lower bound: it does not tell
        // the restoration's own factorizations from the outer ones.) The phases are disjoint.
        assert_eq!(s.statistics.restoration_iterations, Some(restoring));
        let entries = reports
            .windows(2)
            .filter(|w| !w[0].restoration && w[1].restoration)
            .count();
        let p = s.statistics.phases.unwrap();
        println!("{entries} restoration phase(s), {p:?}");
        assert!(entries > 0);
        assert!(
            p.factorizations + entries >= s.statistics.iterations,
            "{p:?}"
        );
        assert_eq!(
            p.factorization_time + p.linear_solve_time + p.other_time,
            s.statistics.solver_time
        );
    }
}
