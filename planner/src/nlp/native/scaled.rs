//! The problem in the solver's scaling, counting its evaluations and timing them.

use std::time::{Duration, Instant};

use crate::nlp::interface::{DomainError, EvaluationCounts, NlpProblem};

/// The problem in the solver's scaling, with evaluation counts and time.
pub(super) struct Scaled<'a> {
    pub(super) problem: &'a dyn NlpProblem,
    pub(super) sf: f64,
    pub(super) sg: Vec<f64>,
    pub(super) counts: EvaluationCounts,
    pub(super) time: Duration,
}

impl Scaled<'_> {
    pub(super) fn timed<T>(&mut self, f: impl FnOnce(&dyn NlpProblem) -> T) -> T {
        let t = Instant::now();
        let out = f(self.problem);
        self.time += t.elapsed();
        out
    }
    pub(super) fn objective(&mut self, x: &[f64]) -> std::result::Result<f64, DomainError> {
        self.counts.objective += 1;
        let v = self.timed(|p| p.objective(x))?;
        if v.is_finite() {
            Ok(self.sf * v)
        } else {
            Err(DomainError)
        }
    }
    pub(super) fn gradient(
        &mut self,
        x: &[f64],
        out: &mut [f64],
    ) -> std::result::Result<(), DomainError> {
        self.counts.gradient += 1;
        self.timed(|p| p.gradient(x, out))?;
        let sf = self.sf;
        out.iter_mut().for_each(|v| *v *= sf);
        finite(out)
    }
    pub(super) fn constraints(
        &mut self,
        x: &[f64],
        out: &mut [f64],
    ) -> std::result::Result<(), DomainError> {
        self.counts.constraints += 1;
        self.timed(|p| p.constraints(x, out))?;
        out.iter_mut().zip(&self.sg).for_each(|(v, s)| *v *= s);
        finite(out)
    }
    pub(super) fn jacobian(
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
    pub(super) fn hessian(
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
    pub(super) fn jacobian_and_hessian(
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
