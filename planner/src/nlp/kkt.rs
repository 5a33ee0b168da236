//! The condensed primal–dual KKT matrix of the native interior point and its factorization.
//!
//! ```text
//! ⎡ W + Σ_x + δ_w I      Jᵀ  ⎤ ⎡Δx⎤   ⎡r_x⎤
//! ⎣ J                   −D   ⎦ ⎣Δy⎦ = ⎣r_y⎦      D = δ_c (equalities), δ_c + 1/(Σ_s + δ_w) (inequalities)
//! ```
//!
//! The pattern (lower triangle, compressed columns) is fixed at construction; each
//! factorization scatters new values into it. The factorization is feral's multifrontal
//! LDLᵀ with Bunch–Kaufman pivoting and delayed pivots (MIT licence), which reports the
//! inertia the interior point's correction loop needs. Its symbolic analysis (ordering,
//! supernodes) runs once per solve.

use feral::numeric::factorize::{
    factorize_multifrontal_with_workspace, FactorWorkspace, NumericParams, SparseFactors,
};
use feral::numeric::solve::solve_sparse;
use feral::scaling::ScalingStrategy;
use feral::symbolic::supernode::SupernodeParams;
use feral::symbolic::{symbolic_factorize, SymbolicFactorization};
use feral::{CscMatrix, ZeroPivotAction};

/// Eigenvalue signs of a factorized matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Inertia {
    pub positive: usize,
    pub negative: usize,
    pub zero: usize,
}

/// What a [`KktSystem`] has done: factorizations and solves, and the wall time in each.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct KktStats {
    pub factorizations: usize,
    pub factorization_time: std::time::Duration,
    pub solves: usize,
    pub solve_time: std::time::Duration,
}

/// The KKT matrix of one solve: fixed pattern, fresh values per factorization.
pub(crate) struct KktSystem {
    n: usize,
    m: usize,
    matrix: CscMatrix,
    /// Slot in `matrix.values` of every Hessian entry (in the problem's order).
    hess_slots: Vec<usize>,
    /// Slot of every Jacobian entry.
    jac_slots: Vec<usize>,
    /// Slot of each diagonal entry, 0..n+m.
    diag_slots: Vec<usize>,
    /// The two variables of every Hessian entry.
    hess_vars: Vec<(usize, usize)>,
    /// The variable (column) of every Jacobian entry.
    jac_vars: Vec<usize>,
    symbolic: SymbolicFactorization,
    workspace: FactorWorkspace,
    params: NumericParams,
    factors: Option<SparseFactors>,
    /// Work done so far (printed by the interior point at print level 5).
    pub stats: KktStats,
}

impl KktSystem {
    /// The pattern of `[W, Jᵀ; J, −D]` for Hessian entries `(hess_rows, hess_cols)` (lower
    /// triangle of the n × n block) and Jacobian entries `(jac_rows, jac_cols)` (m × n).
    pub fn new(
        n: usize,
        m: usize,
        hess: (&[usize], &[usize]),
        jac: (&[usize], &[usize]),
    ) -> Result<Self, String> {
        let dim = n + m;
        // (col, row) of every entry, lower triangle: row ≥ col.
        let mut entries: Vec<(usize, usize)> = Vec::with_capacity(hess.0.len() + jac.0.len() + dim);
        for (&r, &c) in hess.0.iter().zip(hess.1) {
            entries.push((r.min(c), r.max(c)));
        }
        for (&r, &c) in jac.0.iter().zip(jac.1) {
            entries.push((c, n + r));
        }
        for i in 0..dim {
            entries.push((i, i));
        }
        let mut unique = entries.clone();
        unique.sort_unstable();
        unique.dedup();
        let mut col_ptr = vec![0usize; dim + 1];
        for &(c, _) in &unique {
            col_ptr[c + 1] += 1;
        }
        for c in 0..dim {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx: Vec<usize> = unique.iter().map(|&(_, r)| r).collect();
        let slot_of = |e: (usize, usize)| -> usize {
            unique
                .binary_search(&e)
                .expect("every entry is in the unique pattern")
        };
        let hl = hess.0.len();
        let jl = jac.0.len();
        let hess_slots = entries[..hl].iter().map(|&e| slot_of(e)).collect();
        let jac_slots = entries[hl..hl + jl].iter().map(|&e| slot_of(e)).collect();
        let diag_slots = entries[hl + jl..].iter().map(|&e| slot_of(e)).collect();
        let matrix = CscMatrix {
            n: dim,
            col_ptr,
            row_idx,
            values: vec![0.0; unique.len()],
        };
        let symbolic = symbolic_factorize(&matrix, &SupernodeParams::default())
            .map_err(|e| format!("symbolic analysis of the KKT matrix: {e:?}"))?;
        let mut params = NumericParams::default();
        // Keep the factor when a pivot is (near) zero and report it in the inertia; the
        // correction loop then regularizes and refactorizes.
        params.bk.on_zero_pivot = ZeroPivotAction::ForceAccept;
        params.scaling = ScalingStrategy::Identity;
        params.bk.zero_tol = 1e-10;
        params.bk.zero_tol_2x2 = 1e-20;
        Ok(Self {
            n,
            m,
            matrix,
            hess_slots,
            jac_slots,
            diag_slots,
            hess_vars: hess.0.iter().copied().zip(hess.1.iter().copied()).collect(),
            jac_vars: jac.1.to_vec(),
            symbolic,
            workspace: FactorWorkspace::new(),
            params,
            factors: None,
            stats: Default::default(),
        })
    }

    /// Writes the values: Hessian entries, `primal_diagonal` (Σ_x + δ_w, length n), Jacobian
    /// entries and `dual_diagonal` (−D, length m). `masked[j]` drops variable j's Hessian and
    /// Jacobian entries (a fixed variable's row and column become the identity's).
    pub fn assemble(
        &mut self,
        hess_values: &[f64],
        jac_values: &[f64],
        primal_diagonal: &[f64],
        dual_diagonal: &[f64],
        masked: &[bool],
    ) {
        let v = &mut self.matrix.values;
        v.fill(0.0);
        for ((&slot, &h), &(a, b)) in self.hess_slots.iter().zip(hess_values).zip(&self.hess_vars) {
            if !masked[a] && !masked[b] {
                v[slot] += h;
            }
        }
        for ((&slot, &a), &j) in self.jac_slots.iter().zip(jac_values).zip(&self.jac_vars) {
            if !masked[j] {
                v[slot] += a;
            }
        }
        for i in 0..self.n {
            v[self.diag_slots[i]] += primal_diagonal[i];
        }
        for i in 0..self.m {
            v[self.diag_slots[self.n + i]] += dual_diagonal[i];
        }
    }

    /// Factorizes the assembled matrix; `None` when the factorization failed outright.
    pub fn factorize(&mut self) -> Option<Inertia> {
        let t = std::time::Instant::now();
        let r = self.factorize_inner();
        self.stats.factorizations += 1;
        self.stats.factorization_time += t.elapsed();
        r
    }

    fn factorize_inner(&mut self) -> Option<Inertia> {
        // The sequential driver: its sums run in one fixed order, so the same matrix gives the
        // same factor bit for bit (the plan must be deterministic); the parallel one was no
        // faster on 2 cores.
        match factorize_multifrontal_with_workspace(
            &self.matrix,
            &self.symbolic,
            &self.params,
            &mut self.workspace,
        ) {
            Ok((factors, inertia)) => {
                self.factors = Some(factors);
                Some(Inertia {
                    positive: inertia.positive,
                    negative: inertia.negative,
                    zero: inertia.zero,
                })
            }
            Err(_) => {
                self.factors = None;
                None
            }
        }
    }

    /// y = K x for the assembled matrix (symmetric, lower triangle stored).
    fn multiply(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        let a = &self.matrix;
        for c in 0..a.n {
            for k in a.col_ptr[c]..a.col_ptr[c + 1] {
                let r = a.row_idx[k];
                let v = a.values[k];
                y[r] += v * x[c];
                if r != c {
                    y[c] += v * x[r];
                }
            }
        }
    }

    /// Solves K sol = rhs with the last factorization and up to `refinements` steps of
    /// iterative refinement; `None` if there is no factorization or the solve fails.
    pub fn solve(&mut self, rhs: &[f64], refinements: usize) -> Option<Vec<f64>> {
        let t = std::time::Instant::now();
        let r = self.solve_inner(rhs, refinements);
        self.stats.solves += 1;
        self.stats.solve_time += t.elapsed();
        r
    }

    fn solve_inner(&self, rhs: &[f64], refinements: usize) -> Option<Vec<f64>> {
        let factors = self.factors.as_ref()?;
        let mut sol = solve_sparse(factors, rhs).ok()?;
        let scale = rhs.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        let mut residual = vec![0.0; rhs.len()];
        for _ in 0..refinements {
            self.multiply(&sol, &mut residual);
            let mut worst = 0.0f64;
            for (r, b) in residual.iter_mut().zip(rhs) {
                *r = b - *r;
                worst = worst.max(r.abs());
            }
            if worst <= 1e-14 * scale {
                break;
            }
            let correction = solve_sparse(factors, &residual).ok()?;
            for (s, d) in sol.iter_mut().zip(&correction) {
                *s += d;
            }
        }
        sol.iter().all(|v| v.is_finite()).then_some(sol)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// [W, Jᵀ; J, −D] with W = diag(w0, w1), J = [1 1], D = d; returns (inertia, K x = b solved).
    fn small(w: [f64; 2], d: f64) -> (Inertia, Vec<f64>) {
        let mut k = KktSystem::new(2, 1, (&[0, 1], &[0, 1]), (&[0, 0], &[0, 1])).unwrap();
        k.assemble(&w, &[1.0, 1.0], &[0.0, 0.0], &[-d], &[false, false]);
        let inertia = k.factorize().unwrap();
        let x = k.solve(&[1.0, 2.0, 3.0], 2).unwrap();
        (inertia, x)
    }

    #[test]
    fn the_inertia_counts_the_kkt_matrix_eigenvalue_signs() {
        // W positive definite: n positive, m negative.
        let (i, _) = small([2.0, 3.0], 0.0);
        assert_eq!((i.positive, i.negative, i.zero), (2, 1, 0));
        // W indefinite, but positive on the null space of J = [1 1] (w0 + w1 > 0): still (2, 1).
        let (i, _) = small([-1.0, 3.0], 0.0);
        assert_eq!((i.positive, i.negative), (2, 1));
        // Negative curvature on the null space (w0 + w1 < 0): one positive eigenvalue short.
        let (i, _) = small([-3.0, 1.0], 0.0);
        assert_eq!((i.positive, i.negative), (1, 2));
    }

    #[test]
    fn solves_match_the_dense_solution() {
        // [2 0 1; 0 3 1; 1 1 -0.5] x = [1 2 3]: solved by hand elimination.
        let (_, x) = small([2.0, 3.0], 0.5);
        let k = [[2.0, 0.0, 1.0], [0.0, 3.0, 1.0], [1.0, 1.0, -0.5]];
        for (r, row) in k.iter().enumerate() {
            let lhs: f64 = row.iter().zip(&x).map(|(a, b)| a * b).sum();
            assert!((lhs - [1.0, 2.0, 3.0][r]).abs() < 1e-13, "row {r}: {lhs}");
        }
    }
}
