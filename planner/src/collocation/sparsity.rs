//! The structural zeros: each block kind's Jacobian entries and Hessian pairs, found once at
//! set-up by evaluating at a random point, and the global patterns built from them.

use std::collections::HashMap;

use super::blocks::{Block, Kind};
use super::problem::HzdProblem;
use crate::nlp::{DomainError, SparsityPattern};
use model::num_dual::{Dual64, HyperDual64};

/// Structural Jacobian entries (local output, local var) and Hessian pairs (local, local).
type Pattern = (Vec<(usize, usize)>, Vec<(usize, usize)>);

fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64) / ((1u64 << 53) as f64)
}

impl HzdProblem {
    /// A random point used to find structural zeros (deterministic).
    pub(super) fn probe_point(&self) -> Vec<f64> {
        let mut s = 0x5eed_u64;
        let (lo, hi) = self.bounds();
        (0..self.layout.len())
            .map(|i| {
                let r = lcg(&mut s);
                let (a, b) = (lo[i].max(-1.0), hi[i].min(1.0));
                if a < b {
                    a + (b - a) * (0.2 + 0.6 * r)
                } else {
                    a
                }
            })
            .collect()
    }

    pub(super) fn build_patterns(&mut self) {
        let x = self.probe_point();
        let mut cache: HashMap<Kind, Pattern> = HashMap::new();
        let mut hess_index: HashMap<(usize, usize), usize> = HashMap::new();
        let mut hess = SparsityPattern::default();
        let mut slot = |r: usize, c: usize, hess: &mut SparsityPattern| -> usize {
            let key = (r.max(c), r.min(c));
            *hess_index.entry(key).or_insert_with(|| {
                hess.push(key.0, key.1);
                hess.rows.len() - 1
            })
        };
        let blocks = std::mem::take(&mut self.blocks);
        let mut built = Vec::with_capacity(blocks.len());
        for mut blk in blocks {
            let (jac, pairs) = cache
                .entry(blk.kind)
                .or_insert_with(|| self.detect(&blk, &x))
                .clone();
            blk.jac_vars = {
                let mut v: Vec<usize> = jac.iter().map(|&(_, j)| j).collect();
                v.sort_unstable();
                v.dedup();
                v
            };
            for &(r, j) in &jac {
                self.jac_rows.push(blk.row0 + r);
                self.jac_cols.push(blk.vars[j]);
            }
            blk.jac = jac;
            blk.hess_slots = pairs
                .iter()
                .map(|&(a, b)| slot(blk.vars[a], blk.vars[b], &mut hess))
                .collect();
            blk.seeds = pairs.iter().map(|&(a, b)| (a, Some(b))).collect();
            if Self::shares_jacobian_with_hessian(blk.kind) {
                let covered = |j: usize| pairs.iter().any(|&(a, b)| a == j || b == j);
                blk.seeds.extend(
                    blk.jac_vars
                        .iter()
                        .filter(|&&j| !covered(j))
                        .map(|&j| (j, None)),
                );
            }
            built.push(blk);
        }
        self.blocks = built;
        // Objective: T–slack, slack–d; torque–torque, T–torque, torque–d; T–d, d–d.
        let (t, d) = (self.layout.duration(), self.layout.length());
        let lin = self.objective.linear.clone();
        self.obj_slots.t_lin = lin.iter().map(|&(i, _)| slot(t, i, &mut hess)).collect();
        self.obj_slots.lin_d = lin.iter().map(|&(i, _)| slot(i, d, &mut hess)).collect();
        let quad = self.objective.quadratic.clone();
        self.obj_slots.quad = quad.iter().map(|&(j, _)| slot(j, j, &mut hess)).collect();
        self.obj_slots.t_quad = quad.iter().map(|&(j, _)| slot(t, j, &mut hess)).collect();
        self.obj_slots.quad_d = quad.iter().map(|&(j, _)| slot(j, d, &mut hess)).collect();
        self.obj_slots.t_d = slot(t, d, &mut hess);
        self.obj_slots.d_d = slot(d, d, &mut hess);
        let l = &self.layout;
        self.obj_slots.torque = (0..l.points())
            .flat_map(|k| (0..l.nu).map(move |a| l.u(k) + a))
            .map(|i| slot(i, i, &mut hess))
            .collect();
        self.hess_pattern = hess;
    }

    /// Structural Jacobian entries and Hessian pairs of a block at the probe point.
    pub(super) fn detect(&self, blk: &Block, x: &[f64]) -> Pattern {
        let nv = blk.vars.len();
        let z: Vec<f64> = blk.vars.iter().map(|&i| x[i]).collect();
        let mut jac = Vec::new();
        let mut out = vec![Dual64::from(0.0); blk.n_out];
        for j in 0..nv {
            let zd: Vec<Dual64> = z
                .iter()
                .enumerate()
                .map(|(i, &v)| Dual64::new(v, if i == j { 1.0 } else { 0.0 }))
                .collect();
            if self.eval_block(blk.kind, &zd, &mut out).is_err() {
                continue;
            }
            for (r, o) in out.iter().enumerate() {
                if o.eps != 0.0 {
                    jac.push((r, j));
                }
            }
        }
        jac.sort_unstable();
        let mut pairs = Vec::new();
        let mut outh = vec![HyperDual64::from(0.0); blk.n_out];
        for a in 0..nv {
            for b in 0..=a {
                if self.hyper_eval(blk.kind, &z, a, b, &mut outh).is_err() {
                    continue;
                }
                if outh.iter().any(|o| o.eps1eps2 != 0.0) {
                    // Order each pair so the global row index is the larger.
                    pairs.push(if blk.vars[a] >= blk.vars[b] {
                        (a, b)
                    } else {
                        (b, a)
                    });
                }
            }
        }
        (jac, pairs)
    }

    pub(super) fn hyper_eval(
        &self,
        kind: Kind,
        z: &[f64],
        a: usize,
        b: usize,
        out: &mut [HyperDual64],
    ) -> Result<(), DomainError> {
        let zh: Vec<HyperDual64> = z
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                HyperDual64::new(
                    v,
                    if i == a { 1.0 } else { 0.0 },
                    if i == b { 1.0 } else { 0.0 },
                    0.0,
                )
            })
            .collect();
        self.eval_block(kind, &zh, out)
    }
}
