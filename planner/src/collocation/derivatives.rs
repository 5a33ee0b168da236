//! The derivative sweeps over the blocks: Jacobians from `Dual` and Lagrangian Hessians from
//! `HyperDual` numbers, four seeds per evaluation, spread over the rayon pool, and the
//! Hessian's assembly in block order.

use super::blocks::{Block, Kind};
use super::cost::FEASIBILITY_TORQUE_WEIGHT;
use super::problem::HzdProblem;
use super::residuals::Scratch;
use crate::nlp::lanes::Lanes;
use crate::nlp::DomainError;
use model::num_dual::{Dual, HyperDual};
use model::Real;

/// Seeds (Jacobian columns or Hessian pairs) differentiated together in one block evaluation
/// ([`Lanes`]): bit for bit the one-seed-per-evaluation results, with the kinematics and the
/// bookkeeping of an evaluation shared by this many seeds.
const SEED_LANES: usize = 4;

/// Per-worker buffers of a derivative sweep over the blocks: the block scratch, the seeded
/// local variables, the block outputs and a dense Jacobian.
pub(super) struct SweepWork<S> {
    pub(super) scratch: Scratch<S>,
    pub(super) z: Vec<S>,
    pub(super) out: Vec<S>,
    pub(super) dense: Vec<f64>,
}

impl<S: Real> SweepWork<S> {
    pub(super) fn new() -> Self {
        Self {
            scratch: Scratch::new(),
            z: Vec::new(),
            out: Vec::new(),
            dense: Vec::new(),
        }
    }

    /// Zeroed outputs (`n_out`) and dense Jacobian (`n_out` × `nv`) for a block's sweep.
    pub(super) fn prepare(&mut self, n_out: usize, nv: usize) {
        self.dense.clear();
        self.dense.resize(n_out * nv, 0.0);
        self.out.clear();
        self.out.resize(n_out, S::zero());
    }
}

/// Fills `z` with a block's local variables at `x` (global indices `vars`) as four-lane
/// hyper-dual numbers: lane l has ε₁ on local variable a and ε₂ on b for the l-th seed
/// (a, Some(b)), or ε₁ alone for (a, None) (at most [`SEED_LANES`] seeds).
fn seed_hyper_duals(
    x: &[f64],
    vars: &[usize],
    seeds: impl Iterator<Item = (usize, Option<usize>)> + Clone,
    z: &mut Vec<HyperDual<Lanes<SEED_LANES>>>,
) {
    z.clear();
    z.extend(vars.iter().enumerate().map(|(i, &g)| {
        let (mut eps1, mut eps2) = ([0.0; SEED_LANES], [0.0; SEED_LANES]);
        for (l, (a, b)) in seeds.clone().enumerate() {
            if i == a {
                eps1[l] = 1.0;
            }
            if b == Some(i) {
                eps2[l] = 1.0;
            }
        }
        HyperDual::new(
            Lanes::splat(x[g]),
            Lanes(eps1),
            Lanes(eps2),
            Lanes::splat(0.0),
        )
    }));
}

impl HzdProblem {
    /// Whether a block kind's Jacobian is read off its Hessian passes
    /// ([`Self::block_hyper_sweep`]): the kinds with Hessian pairs whose evaluation
    /// divides no dual number by another. num-dual's `Dual` and `HyperDual` apply the same
    /// first-order rules to sums, products, scalars and functions (the same products, added
    /// in either order), so a hyper-dual pass's ε₁ and ε₂ parts are the `Dual` sweep's
    /// Jacobian columns bit for bit; their quotient rules round differently (the stance-leg
    /// angle's rate, `atan2`, the impact map's elimination), so those kinds keep their own
    /// sweep. The test `merged_jacobian_and_hessian_are_the_separate_sweeps_bits` compares the
    /// merged values with the separate sweeps' bits; it fails with `PhaseLift` or `Impact`
    /// added here.
    pub(super) fn shares_jacobian_with_hessian(kind: Kind) -> bool {
        matches!(
            kind,
            Kind::Dynamics
                | Kind::OutputDynamics(_)
                | Kind::OutputStart(_)
                | Kind::Interval(_)
                | Kind::Power(_)
                | Kind::SwingHeight
                | Kind::SwingEnd
        )
    }

    /// `f(work, block, values)` for every block with its own run of `values` (`len(block)`
    /// entries each, in block order): on the rayon pool when called outside it (one plan: both
    /// cores evaluate), sequentially inside it (a co-design sweep already keeps every core busy
    /// with whole runs). Each worker reuses one [`SweepWork`], so a sweep allocates and zeroes
    /// its dual-number buffers a few times, not once per block. Results do not depend on the
    /// schedule: each block writes only its own run.
    pub(super) fn for_each_block<S: Real + Send>(
        &self,
        values: &mut [f64],
        len: impl Fn(&Block) -> usize,
        f: impl Fn(&mut SweepWork<S>, &Block, &mut [f64]) -> Result<(), DomainError> + Sync + Send,
    ) -> Result<(), DomainError> {
        self.for_each_run(self.runs(values, len), SweepWork::new, f)
    }

    /// Each block with its own run of `values` (`len(block)` entries each, in block order).
    pub(super) fn runs<'v>(
        &self,
        values: &'v mut [f64],
        len: impl Fn(&Block) -> usize,
    ) -> Vec<&'v mut [f64]> {
        let mut runs = Vec::with_capacity(self.blocks.len());
        let mut rest = values;
        for blk in &self.blocks {
            let (run, tail) = rest.split_at_mut(len(blk));
            runs.push(run);
            rest = tail;
        }
        runs
    }

    /// `f(work, block, run)` for every block and its run (see [`Self::for_each_block`]), with
    /// per-worker buffers from `init`.
    pub(super) fn for_each_run<W: Send, R: Send>(
        &self,
        runs: Vec<R>,
        init: impl Fn() -> W + Sync + Send,
        f: impl Fn(&mut W, &Block, R) -> Result<(), DomainError> + Sync + Send,
    ) -> Result<(), DomainError> {
        use rayon::prelude::*;
        let runs: Vec<(&Block, R)> = self.blocks.iter().zip(runs).collect();
        if rayon::current_thread_index().is_some() {
            let mut work = init();
            runs.into_iter()
                .try_for_each(|(blk, run)| f(&mut work, blk, run))
        } else {
            runs.into_par_iter()
                .try_for_each_init(init, |work, (blk, run)| f(work, blk, run))
        }
    }

    /// A block's structural Jacobian entries, in [`Block::jac`] order, into `values`. Lane l of
    /// one evaluation is the `Dual64` sweep of the chunk's column l.
    pub(super) fn block_jacobian(
        &self,
        x: &[f64],
        blk: &Block,
        work: &mut SweepWork<Dual<Lanes<SEED_LANES>>>,
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        let nv = blk.vars.len();
        work.prepare(blk.n_out, nv);
        let SweepWork {
            scratch,
            z,
            out,
            dense,
        } = work;
        for chunk in blk.jac_vars.chunks(SEED_LANES) {
            z.clear();
            z.extend(blk.vars.iter().enumerate().map(|(i, &g)| {
                let mut eps = [0.0; SEED_LANES];
                for (l, &j) in chunk.iter().enumerate() {
                    if i == j {
                        eps[l] = 1.0;
                    }
                }
                Dual::new(Lanes::splat(x[g]), Lanes(eps))
            }));
            self.eval_block_in(blk.kind, z, out, scratch)?;
            for (l, &j) in chunk.iter().enumerate() {
                for (r, o) in out.iter().enumerate() {
                    dense[r * nv + j] = o.eps.0[l];
                }
            }
        }
        for (v, &(r, j)) in values.iter_mut().zip(&blk.jac) {
            *v = dense[r * nv + j];
        }
        Ok(())
    }

    /// A block's contribution Σ_r μ_r ∂²c_r to each of its Hessian pairs, in
    /// [`Block::pairs`] order, into `hess`; with `jac`, also its Jacobian entries
    /// ([`Block::jac`] order) read off the same passes, over all of [`Block::seeds`] (for an
    /// active block of a kind that [`Self::shares_jacobian_with_hessian`]). Lane l of one
    /// evaluation is the `HyperDual64` evaluation of the chunk's seed l: its ε₁ (and ε₂) parts
    /// are the Jacobian columns of its variables as a `Dual64` sweep gives them, its ε₁ε₂
    /// part the pair's second derivatives; a Jacobian-only seed has no ε₂ and adds no
    /// Hessian entry.
    pub(super) fn block_hyper_sweep(
        &self,
        x: &[f64],
        multipliers: &[f64],
        blk: &Block,
        work: &mut SweepWork<HyperDual<Lanes<SEED_LANES>>>,
        hess: &mut [f64],
        jac: Option<&mut [f64]>,
    ) -> Result<(), DomainError> {
        let nv = blk.vars.len();
        let mu = &multipliers[blk.row0..blk.row0 + blk.n_out];
        let seeds = if jac.is_some() {
            &blk.seeds[..]
        } else {
            blk.pairs()
        };
        work.prepare(blk.n_out, if jac.is_some() { nv } else { 0 });
        let SweepWork {
            scratch,
            z,
            out,
            dense,
        } = work;
        let mut at = 0;
        for chunk in seeds.chunks(SEED_LANES) {
            seed_hyper_duals(x, &blk.vars, chunk.iter().copied(), z);
            self.eval_block_in(blk.kind, z, out, scratch)?;
            for (l, &(a, b)) in chunk.iter().enumerate() {
                if jac.is_some() {
                    for (r, o) in out.iter().enumerate() {
                        dense[r * nv + a] = o.eps1.0[l];
                        if let Some(b) = b {
                            dense[r * nv + b] = o.eps2.0[l];
                        }
                    }
                }
                if b.is_some() {
                    hess[at] = out
                        .iter()
                        .zip(mu)
                        .map(|(o, m)| o.eps1eps2.0[l] * m)
                        .sum::<f64>();
                    at += 1;
                }
            }
        }
        if let Some(jac) = jac {
            for (v, &(r, j)) in jac.iter_mut().zip(&blk.jac) {
                *v = dense[r * nv + j];
            }
        }
        Ok(())
    }

    /// A block's Hessian contribution ([`Self::block_hyper_sweep`] without the Jacobian),
    /// left alone when its multipliers are all zero.
    pub(super) fn block_hessian(
        &self,
        x: &[f64],
        multipliers: &[f64],
        blk: &Block,
        work: &mut SweepWork<HyperDual<Lanes<SEED_LANES>>>,
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        if blk.inactive(multipliers) {
            return Ok(());
        }
        self.block_hyper_sweep(x, multipliers, blk, work, values, None)
    }

    /// Zeroed room for every block's Hessian contribution, in block order.
    pub(super) fn hessian_parts(&self) -> Vec<f64> {
        vec![0.0; self.blocks.iter().map(|b| b.hess_slots.len()).sum()]
    }

    /// The Lagrangian Hessian from the blocks' contributions `parts` (each block's run in
    /// block order, as [`Self::block_hessian`] writes them) and the objective's.
    pub(super) fn assemble_hessian(
        &self,
        x: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        parts: &[f64],
        values: &mut [f64],
    ) {
        values.fill(0.0);
        // Blocks share Hessian slots: their contributions are added in block order, as a
        // sequential loop would, whatever order they were computed in.
        let mut at = 0;
        for blk in &self.blocks {
            let run = &parts[at..at + blk.hess_slots.len()];
            at += blk.hess_slots.len();
            // Skipped, not added as zeros: +0.0 would turn a −0.0 entry into +0.0.
            if blk.inactive(multipliers) {
                continue;
            }
            for (&slot, value) in blk.hess_slots.iter().zip(run) {
                values[slot] += value;
            }
        }
        if !self.with_cost {
            for &slot in &self.obj_slots.torque {
                values[slot] += 2.0 * FEASIBILITY_TORQUE_WEIGHT * objective_factor;
            }
        }
        if self.with_cost && objective_factor != 0.0 {
            self.add_cost_hessian(x, objective_factor, values);
        }
    }
}
