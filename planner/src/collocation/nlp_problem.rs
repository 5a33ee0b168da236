//! [`HzdProblem`] as an [`NlpProblem`]: bounds, start point, f, ∇f, g and the sparse
//! derivatives the solver asks for.

use super::cost::FEASIBILITY_TORQUE_WEIGHT;
use super::derivatives::SweepWork;
use super::problem::HzdProblem;
use crate::nlp::{DomainError, NlpProblem, SparsityPattern};

impl NlpProblem for HzdProblem {
    fn num_variables(&self) -> usize {
        self.layout.len()
    }

    fn num_constraints(&self) -> usize {
        self.lower_g.len()
    }

    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        let (lo, hi) = self.bounds();
        lower.copy_from_slice(&lo);
        upper.copy_from_slice(&hi);
    }

    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.lower_g);
        upper.copy_from_slice(&self.upper_g);
    }

    fn initial_point(&self, x0: &mut [f64]) {
        x0.copy_from_slice(&self.initial);
    }

    fn objective(&self, x: &[f64]) -> Result<f64, DomainError> {
        Ok(if self.with_cost {
            self.cost(x)
        } else {
            FEASIBILITY_TORQUE_WEIGHT * self.torque_vars().map(|i| x[i] * x[i]).sum::<f64>()
        })
    }

    fn gradient(&self, x: &[f64], gradient: &mut [f64]) -> Result<(), DomainError> {
        gradient.fill(0.0);
        if !self.with_cost {
            for i in self.torque_vars() {
                gradient[i] = 2.0 * FEASIBILITY_TORQUE_WEIGHT * x[i];
            }
            return Ok(());
        }
        self.cost_gradient(x, gradient);
        Ok(())
    }

    fn constraints(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        // Blocks own consecutive rows in block order, so each writes its own run.
        self.for_each_block(
            values,
            |blk| blk.n_out,
            |work: &mut SweepWork<f64>, blk, out| {
                let SweepWork { scratch, z, .. } = work;
                z.clear();
                z.extend(blk.vars.iter().map(|&i| x[i]));
                self.eval_block_in(blk.kind, z, out, scratch)
            },
        )
    }

    fn jacobian_structure(&self) -> SparsityPattern {
        SparsityPattern {
            rows: self.jac_rows.clone(),
            cols: self.jac_cols.clone(),
        }
    }

    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        // Each block fills its own run of entries, in block order.
        self.for_each_block(
            values,
            |blk| blk.jac.len(),
            |work, blk, run| self.block_jacobian(x, blk, work, run),
        )
    }

    fn hessian_structure(&self) -> SparsityPattern {
        self.hess_pattern.clone()
    }

    fn hessian_values(
        &self,
        x: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        let mut parts = self.hessian_parts();
        self.for_each_block(
            &mut parts,
            |blk| blk.hess_slots.len(),
            |work, blk, run| self.block_hessian(x, multipliers, blk, work, run),
        )?;
        self.assemble_hessian(x, objective_factor, multipliers, &parts, values);
        Ok(())
    }

    fn jacobian_and_hessian_values(
        &self,
        x: &[f64],
        jacobian: &mut [f64],
        objective_factor: f64,
        multipliers: &[f64],
        hessian: &mut [f64],
    ) -> Result<(), DomainError> {
        let mut parts = self.hessian_parts();
        let runs: Vec<_> = self
            .runs(jacobian, |blk| blk.jac.len())
            .into_iter()
            .zip(self.runs(&mut parts, |blk| blk.hess_slots.len()))
            .collect();
        self.for_each_run(
            runs,
            || (SweepWork::new(), SweepWork::new()),
            |(jac_work, hess_work), blk, (jac, hess)| {
                if Self::shares_jacobian_with_hessian(blk.kind) && !blk.inactive(multipliers) {
                    self.block_hyper_sweep(x, multipliers, blk, hess_work, hess, Some(jac))
                } else {
                    self.block_jacobian(x, blk, jac_work, jac)?;
                    self.block_hessian(x, multipliers, blk, hess_work, hess)
                }
            },
        )?;
        self.assemble_hessian(x, objective_factor, multipliers, &parts, hessian);
        Ok(())
    }
}
