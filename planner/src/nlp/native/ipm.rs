//! The interior point's state: the scaled problem, the iterate and its functions, the barrier
//! parameter and the KKT systems; its start ([`Ipm::new`], [`Ipm::run`]) and the [`Solution`]
//! it ends with ([`Ipm::finish`]). The iteration itself is in the sibling modules.

use std::time::{Duration, Instant};

use super::bounds::Bounds;
use super::constants::{
    ACCEPTABLE_COMPLEMENTARITY, ACCEPTABLE_TOL, ACCEPTABLE_VIOLATION, MU_INIT, TAU_MIN,
};
use super::kkt::{KktStats, KktSystem};
use super::scaled::Scaled;
use crate::nlp::interface::{
    EvaluationCounts, IterationControl, IterationReport, NlpProblem, PhaseTimes, Solution,
    SolveOptions, SolveStatistics, SolveStatus,
};

/// The exit test of a restoration phase: called with each accepted iterate; true ends it.
pub(super) type ExitTest<'a> = Box<dyn FnMut(&[f64]) -> bool + 'a>;

pub(super) struct Ipm<'a> {
    pub(super) prob: Scaled<'a>,
    pub(super) options: &'a SolveOptions,
    pub(super) n: usize,
    pub(super) m: usize,
    pub(super) xb: Vec<Bounds>,
    pub(super) fixed: Vec<bool>,
    /// Per constraint: `Some(bounds)` for an inequality (with a slack), `None` for an equality.
    pub(super) sb: Vec<Option<Bounds>>,
    /// Equality right-hand sides (scaled); unused for inequalities.
    pub(super) rhs: Vec<f64>,
    pub(super) jac_rows: Vec<usize>,
    pub(super) jac_cols: Vec<usize>,
    pub(super) hess_rows: Vec<usize>,
    pub(super) hess_cols: Vec<usize>,
    // Iterate.
    pub(super) x: Vec<f64>,
    pub(super) s: Vec<f64>,
    pub(super) y: Vec<f64>,
    pub(super) zl: Vec<f64>,
    pub(super) zu: Vec<f64>,
    pub(super) vl: Vec<f64>,
    pub(super) vu: Vec<f64>,
    // Functions at the iterate.
    pub(super) f: f64,
    pub(super) g: Vec<f64>,
    pub(super) grad: Vec<f64>,
    pub(super) jac: Vec<f64>,
    pub(super) hess: Vec<f64>,
    /// Whether `hess` is W at the current (x, y): evaluated with J after an accepted step.
    pub(super) hessian_current: bool,
    pub(super) mu: f64,
    pub(super) tau: f64,
    pub(super) delta_w_last: f64,
    pub(super) kkt: Option<KktSystem>,
    /// Whether two δ_w trials are factorized at once (`factorize`): decided at construction,
    /// true with a core to spare, i.e. outside the rayon pool (a co-design sweep's workers keep
    /// every core busy with whole runs) and with more than one thread in it.
    pub(super) pair_trials: bool,
    /// A second KKT system with `kkt`'s ordering, for two δ_w trials at once.
    pub(super) twin: Option<KktSystem>,
    /// Pairs of δ_w trials factorized at once, and how many of them the twin's trial decided.
    pub(super) paired_trials: usize,
    pub(super) twin_accepted: usize,
    pub(super) iterations: usize,
    /// Wall time of this solve's KKT assemblies and factorizations (every inertia trial, two
    /// at once counting once, and the least-squares multiplier estimate's). Their count, and
    /// the solves, are in `kkt`'s and `twin`'s statistics.
    pub(super) factorization_time: Duration,
    /// The restoration phases' work (their own `other_time` left out: it is part of this
    /// solve's, derived at the end).
    pub(super) restoration_phases: PhaseTimes,
    /// Iterations inside restoration phases.
    pub(super) restoration_iterations: usize,
    /// False inside a restoration phase (which has none of its own).
    pub(super) allow_restoration: bool,
    /// Inside a restoration phase: called with each accepted iterate; true ends the phase.
    pub(super) exit_test: Option<ExitTest<'a>>,
}

impl<'a> Ipm<'a> {
    pub(super) fn new(problem: &'a dyn NlpProblem, options: &'a SolveOptions) -> Self {
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

    pub(super) fn run(
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
    pub(super) fn acceptable_instead_of(&self, status: SolveStatus) -> SolveStatus {
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
    pub(super) fn within_acceptable_tolerances(&self, error: f64, viol: f64, compl: f64) -> bool {
        error <= ACCEPTABLE_TOL
            && viol <= ACCEPTABLE_VIOLATION
            && compl / self.prob.sf <= ACCEPTABLE_COMPLEMENTARITY
    }

    pub(super) fn finish(mut self, status: SolveStatus, start: Instant) -> Solution {
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
