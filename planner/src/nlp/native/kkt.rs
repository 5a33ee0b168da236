//! The condensed primal–dual KKT matrix of the native interior point and its factorization.
//!
//! ```text
//! ⎡ W + Σ_x + δ_w I      Jᵀ  ⎤ ⎡Δx⎤   ⎡r_x⎤
//! ⎣ J                   −D   ⎦ ⎣Δy⎦ = ⎣r_y⎦      D = δ_c (equalities), δ_c + 1/(Σ_s + δ_w) (inequalities)
//! ```
//!
//! The pattern (lower triangle, compressed columns) is fixed at construction; each
//! factorization scatters new values into it.
//!
//! **The factorization** is faer's supernodal LDLᵀ with Bunch–Kaufman pivoting inside each
//! supernode (MIT), on an ordering from feral (MIT): MC64 symmetric matching on the first
//! matrix's values pairs each constraint row with a variable, each pair becomes one vertex of a
//! compressed graph, and METIS nested dissection orders that graph (MUMPS's `ICNTL(12) = 2`).
//! A pair stays adjacent in the ordering, so its 2×2 pivot lies inside one supernode. faer
//! cannot delay a pivot to a parent supernode; the pairing is what makes that unnecessary.
//! Measured on ADAM KKT matrices of one plan (2503 × 2503, see NLP.md): 2.2–3.5 ms per
//! factorization against 7–10 ms for feral's multifrontal LDLᵀ with delayed pivots (AMD), the
//! inertia the same, relative residual ≤ 3e-9 before iterative refinement. faer's own AMD
//! ordering, without the pairing, met 1513 zero pivots on the first matrix.
//!
//! The inertia is counted from D's 1×1 and 2×2 blocks; a pivot below 1e-10 in magnitude (a
//! 2×2 block with |det| ≤ 1e-20) counts as zero, as feral's `zero_tol` did. Where faer's factor
//! is not finite (a zero pivot that pivoting inside the supernode cannot avoid), the
//! factorization fails ([`KktStats::nonfinite`]) and the interior point raises δ_w, as IPOPT
//! does when its linear solver reports a singular matrix. Until December 2026 such a matrix went
//! to feral instead: on ADAM the first 14 matrices of the feasibility solve (δ_w = 0) did, at
//! ~10 ms each; the feasibility solve took 0.73 s, now 0.56–0.63 s (49 iterations for 43). feral's
//! multifrontal LDLᵀ, which delays pivots across supernodes, remains for a pattern whose faer
//! set-up fails (every factorization then goes to it, counted in [`KktStats::fallbacks`]). Both
//! run sequentially, so the same matrix gives the same factor bit for bit.
//!
//! [`KktSystem::twin`] gives a second system with the same pattern and the same ordering, so
//! that the interior point can factorize two δ_w trials at once (one per core) and get the
//! factors it would have got one after the other.

use dyn_stack::{GlobalPodBuffer, PodStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, IntranodeBunchKaufmanRef,
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, Parallelism, Side};
use feral::numeric::factorize::{
    factorize_multifrontal_with_workspace, FactorWorkspace, NumericParams, SparseFactors,
};
use feral::numeric::solve::solve_sparse;
use feral::scaling::ScalingStrategy;
use feral::symbolic::supernode::SupernodeParams;
use feral::symbolic::{
    symbolic_factorize, symbolic_factorize_with_method, OrderingMethod, OrderingPreprocess,
    SymbolicFactorization,
};
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
    /// Iterative-refinement corrections (each one more solve with the factor) among them.
    pub corrections: usize,
    pub solve_time: std::time::Duration,
    /// Factorizations that went to feral (faer's set-up failed for this pattern).
    pub fallbacks: usize,
    /// faer factors that were not finite: failed factorizations.
    pub nonfinite: usize,
}

impl std::ops::AddAssign for KktStats {
    /// Adds the work of another system (a twin's) to this one's.
    fn add_assign(&mut self, other: Self) {
        self.factorizations += other.factorizations;
        self.factorization_time += other.factorization_time;
        self.solves += other.solves;
        self.corrections += other.corrections;
        self.solve_time += other.solve_time;
        self.fallbacks += other.fallbacks;
        self.nonfinite += other.nonfinite;
    }
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
    /// faer's factorization, set up at the first factorization (the ordering needs values).
    faer: Option<FaerLdlt>,
    /// Whether that set-up was tried (a failed one is not repeated: every factorization then
    /// goes to feral).
    faer_tried: bool,
    /// feral's symbolic analysis, set up at the first fallback.
    symbolic: Option<SymbolicFactorization>,
    workspace: FactorWorkspace,
    params: NumericParams,
    /// feral's factor, when the last factorization fell back to it.
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
        let mut params = NumericParams::default();
        // Keep the factor when a pivot is (near) zero and report it in the inertia; the
        // correction loop then regularizes and refactorizes.
        params.bk.on_zero_pivot = ZeroPivotAction::ForceAccept;
        params.scaling = ScalingStrategy::Identity;
        params.bk.zero_tol = ZERO_PIVOT;
        params.bk.zero_tol_2x2 = ZERO_PIVOT * ZERO_PIVOT;
        Ok(Self {
            n,
            m,
            matrix,
            hess_slots,
            jac_slots,
            diag_slots,
            hess_vars: hess.0.iter().copied().zip(hess.1.iter().copied()).collect(),
            jac_vars: jac.1.to_vec(),
            faer: None,
            faer_tried: false,
            symbolic: None,
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
        self.factors = None;
        if !self.faer_tried {
            self.faer_tried = true;
            self.faer = FaerLdlt::new(&self.matrix);
        }
        match self.faer.as_mut() {
            Some(faer) => {
                let inertia = faer.factorize(&self.matrix);
                if inertia.is_none() {
                    self.stats.nonfinite += 1;
                }
                inertia
            }
            None => {
                self.stats.fallbacks += 1;
                self.factorize_feral()
            }
        }
    }

    /// Whether the first factorization has set up the ordering (faer's, or feral's fallback).
    pub fn is_set_up(&self) -> bool {
        self.faer_tried
    }

    /// A second system with this one's pattern and, once this one's faer set-up is done, the
    /// same ordering and symbolic analysis: the same matrix then gives both the same factor,
    /// bit for bit. Its statistics start at zero. `None` if that analysis fails (the twin would
    /// not give this system's factors).
    pub fn twin(&self) -> Option<Self> {
        let faer = match &self.faer {
            Some(f) => Some(FaerLdlt::with_ordering(&self.matrix, f.perm.clone())?),
            None => None,
        };
        Some(Self {
            n: self.n,
            m: self.m,
            matrix: CscMatrix {
                n: self.matrix.n,
                col_ptr: self.matrix.col_ptr.clone(),
                row_idx: self.matrix.row_idx.clone(),
                values: vec![0.0; self.matrix.values.len()],
            },
            hess_slots: self.hess_slots.clone(),
            jac_slots: self.jac_slots.clone(),
            diag_slots: self.diag_slots.clone(),
            hess_vars: self.hess_vars.clone(),
            jac_vars: self.jac_vars.clone(),
            faer_tried: self.faer_tried,
            faer,
            symbolic: None,
            workspace: FactorWorkspace::new(),
            params: self.params.clone(),
            factors: None,
            stats: KktStats::default(),
        })
    }

    /// feral's multifrontal LDLᵀ with delayed pivots: its sequential driver, whose sums run in
    /// one fixed order (the plan must be deterministic).
    fn factorize_feral(&mut self) -> Option<Inertia> {
        if self.symbolic.is_none() {
            self.symbolic = symbolic_factorize(&self.matrix, &SupernodeParams::default()).ok();
        }
        match factorize_multifrontal_with_workspace(
            &self.matrix,
            self.symbolic.as_ref()?,
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
            Err(_) => None,
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

    /// One solve with the last factorization, feral's if it fell back, else faer's.
    fn solve_once(&mut self, rhs: &[f64]) -> Option<Vec<f64>> {
        match &self.factors {
            Some(factors) => solve_sparse(factors, rhs).ok(),
            None => self.faer.as_mut()?.solve(rhs),
        }
    }

    fn solve_inner(&mut self, rhs: &[f64], refinements: usize) -> Option<Vec<f64>> {
        let mut sol = self.solve_once(rhs)?;
        let scale = rhs.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        let mut residual = vec![0.0; rhs.len()];
        for _ in 0..refinements {
            self.multiply(&sol, &mut residual);
            let mut worst = 0.0f64;
            for (r, b) in residual.iter_mut().zip(rhs) {
                *r = b - *r;
                worst = worst.max(r.abs());
            }
            if worst <= REFINEMENT_TOLERANCE * scale {
                break;
            }
            self.stats.corrections += 1;
            let correction = self.solve_once(&residual)?;
            for (s, d) in sol.iter_mut().zip(&correction) {
                *s += d;
            }
        }
        sol.iter().all(|v| v.is_finite()).then_some(sol)
    }
}

/// faer's supernodal intranode Bunch–Kaufman LDLᵀ on feral's matching-compressed METIS
/// ordering (module docs), with its buffers.
struct FaerLdlt {
    /// The fill-reducing ordering (new position k holds old index `perm[k]`).
    perm: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    subdiag: Vec<f64>,
    /// Bunch–Kaufman's pivot permutation of the last factorization.
    pivots_fwd: Vec<usize>,
    pivots_inv: Vec<usize>,
    factor_mem: GlobalPodBuffer,
    solve_mem: GlobalPodBuffer,
    /// Whether `l_values` holds a finite factor of the last matrix.
    factored: bool,
}

/// Iterative refinement stops once the residual's largest entry is at most this times
/// max(1, the right-hand side's largest): IPOPT's `residual_ratio_max` (it also adds ‖K‖‖x‖ to
/// the denominator, which makes its test looser). Until December 2026 the bound was 1e-14, and
/// 104 of one ADAM plan's 240 residual checks led to a correction that changed nothing the
/// interior point could see (the median first residual was 3.7e-14 of the right-hand side).
const REFINEMENT_TOLERANCE: f64 = 1e-10;

/// Magnitude below which a 1×1 pivot counts as zero (its square for a 2×2 block's determinant),
/// the same for faer's inertia count and feral's `zero_tol`.
const ZERO_PIVOT: f64 = 1e-10;

impl FaerLdlt {
    /// The ordering and symbolic analysis for `matrix`'s pattern, the matching from its values;
    /// `None` if either fails (the caller then uses feral).
    fn new(matrix: &CscMatrix) -> Option<Self> {
        let params = SupernodeParams {
            preprocess: OrderingPreprocess::LdltCompress,
            ..SupernodeParams::default()
        };
        let perm = symbolic_factorize_with_method(matrix, &params, OrderingMethod::MetisND)
            .ok()?
            .perm;
        Self::with_ordering(matrix, perm)
    }

    /// The symbolic analysis of `matrix`'s pattern for the ordering `perm`; `None` if it fails.
    fn with_ordering(matrix: &CscMatrix, perm: Vec<usize>) -> Option<Self> {
        let n = matrix.n;
        let mut perm_inv = vec![0; n];
        for (k, &old) in perm.iter().enumerate() {
            perm_inv[old] = k;
        }
        let symbolic = factorize_symbolic_cholesky(
            pattern(matrix),
            Side::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&perm, &perm_inv, n)),
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .ok()?;
        let factor_mem = GlobalPodBuffer::try_new(
            symbolic
                .factorize_numeric_intranode_bunch_kaufman_req::<f64>(false, Parallelism::None)
                .ok()?,
        )
        .ok()?;
        let solve_mem =
            GlobalPodBuffer::try_new(symbolic.solve_in_place_req::<f64>(1).ok()?).ok()?;
        Some(Self {
            perm,
            l_values: vec![0.0; symbolic.len_values()],
            subdiag: vec![0.0; n],
            pivots_fwd: vec![0; n],
            pivots_inv: vec![0; n],
            symbolic,
            factor_mem,
            solve_mem,
            factored: false,
        })
    }

    /// Factorizes `matrix` (the pattern given to [`FaerLdlt::new`]); its inertia, or `None` if
    /// the factor is not finite.
    fn factorize(&mut self, matrix: &CscMatrix) -> Option<Inertia> {
        self.factored = false;
        self.symbolic
            .factorize_numeric_intranode_bunch_kaufman::<f64>(
                &mut self.l_values,
                &mut self.subdiag,
                &mut self.pivots_fwd,
                &mut self.pivots_inv,
                SparseColMatRef::new(pattern(matrix), &matrix.values[..]),
                Side::Lower,
                Default::default(),
                Parallelism::None,
                PodStack::new(&mut self.factor_mem),
            );
        let SymbolicCholeskyRaw::Supernodal(supernodes) = self.symbolic.raw() else {
            return None;
        };
        let mut inertia = Inertia {
            positive: 0,
            negative: 0,
            zero: 0,
        };
        // D is block diagonal: each supernode's diagonal, with a 2×2 block wherever subdiag
        // is non-zero. Its blocks' eigenvalue signs are the matrix's (Sylvester).
        let begin = supernodes.supernode_begin();
        let end = supernodes.supernode_end();
        let values_at = supernodes.col_ptrs_for_values();
        for s in 0..supernodes.n_supernodes() {
            let size = end[s] - begin[s];
            let rows = (values_at[s + 1] - values_at[s]) / size;
            let d = |j: usize| self.l_values[values_at[s] + j * rows + j];
            let mut j = 0;
            while j < size {
                let off = self.subdiag[begin[s] + j];
                if off == 0.0 {
                    let d = d(j);
                    if !d.is_finite() {
                        return None;
                    }
                    match d {
                        d if d.abs() <= ZERO_PIVOT => inertia.zero += 1,
                        d if d > 0.0 => inertia.positive += 1,
                        _ => inertia.negative += 1,
                    }
                    j += 1;
                } else {
                    let (a, b) = (d(j), d(j + 1));
                    let det = a * b - off * off;
                    if !det.is_finite() {
                        return None;
                    }
                    if det.abs() <= ZERO_PIVOT * ZERO_PIVOT {
                        inertia.zero += 2;
                    } else if det < 0.0 {
                        inertia.positive += 1;
                        inertia.negative += 1;
                    } else if a + b > 0.0 {
                        inertia.positive += 2;
                    } else {
                        inertia.negative += 2;
                    }
                    j += 2;
                }
            }
        }
        self.factored = true;
        Some(inertia)
    }

    /// Solves with the last factorization; `None` if there is none.
    fn solve(&mut self, rhs: &[f64]) -> Option<Vec<f64>> {
        if !self.factored {
            return None;
        }
        let n = rhs.len();
        let ldlt = IntranodeBunchKaufmanRef::<'_, usize, f64>::new(
            &self.symbolic,
            &self.l_values,
            &self.subdiag,
            PermRef::new_checked(&self.pivots_fwd, &self.pivots_inv, n),
        );
        let mut x = Mat::<f64>::from_fn(n, 1, |i, _| rhs[i]);
        ldlt.solve_in_place_with_conj(
            Conj::No,
            x.as_mut(),
            Parallelism::None,
            PodStack::new(&mut self.solve_mem),
        );
        Some((0..n).map(|i| x.read(i, 0)).collect())
    }
}

/// faer's view of the KKT pattern.
fn pattern(matrix: &CscMatrix) -> SymbolicSparseColMatRef<'_, usize> {
    SymbolicSparseColMatRef::new_checked(matrix.n, matrix.n, &matrix.col_ptr, None, &matrix.row_idx)
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

    /// Uniform numbers in [−1, 1) from a 64-bit linear congruential generator: deterministic
    /// test data.
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    /// Lower-triangle triplets of an n × n Hessian with bandwidth 2: entry (i, j), j ≥ i − 2,
    /// is `value(i, j)` (row by row), or structurally absent where that is `None`.
    fn banded_hessian(
        n: usize,
        mut value: impl FnMut(usize, usize) -> Option<f64>,
    ) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (mut hr, mut hc, mut hv) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..n {
            for j in i.saturating_sub(2)..=i {
                if let Some(v) = value(i, j) {
                    hr.push(i);
                    hc.push(j);
                    hv.push(v);
                }
            }
        }
        (hr, hc, hv)
    }

    /// Triplets of an m × n banded Jacobian: row r has 3 entries from column r n / m on, entry
    /// (r, c) `value(c)`.
    fn banded_jacobian(
        n: usize,
        m: usize,
        mut value: impl FnMut(usize) -> f64,
    ) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (mut jr, mut jc, mut jv) = (Vec::new(), Vec::new(), Vec::new());
        for r in 0..m {
            let first = (r * n) / m;
            for c in first..(first + 3).min(n) {
                jr.push(r);
                jc.push(c);
                jv.push(value(c));
            }
        }
        (jr, jc, jv)
    }

    type Triplets<'a> = (&'a [usize], &'a [usize], &'a [f64]);

    /// The dense symmetric `[W + diag(primal), Jᵀ; J, diag(dual)]` of (n, m) = `size`, W from
    /// its lower-triangle triplets.
    fn dense_kkt(
        size: (usize, usize),
        w: Triplets<'_>,
        j: Triplets<'_>,
        primal: &[f64],
        dual: &[f64],
    ) -> nalgebra::DMatrix<f64> {
        let (n, m) = size;
        let mut dense = nalgebra::DMatrix::<f64>::zeros(n + m, n + m);
        for ((&r, &c), &v) in w.0.iter().zip(w.1).zip(w.2) {
            dense[(r, c)] += v;
            if r != c {
                dense[(c, r)] += v;
            }
        }
        for ((&r, &c), &v) in j.0.iter().zip(j.1).zip(j.2) {
            dense[(n + r, c)] += v;
            dense[(c, n + r)] += v;
        }
        for (i, d) in primal.iter().enumerate() {
            dense[(i, i)] += d;
        }
        for (i, d) in dual.iter().enumerate() {
            dense[(n + i, n + i)] += d;
        }
        dense
    }

    /// (positive, negative) eigenvalue counts of `dense`, which must have none within 1e-12
    /// of zero.
    fn eigen_signs(dense: &nalgebra::DMatrix<f64>) -> (usize, usize) {
        let eigen = nalgebra::SymmetricEigen::new(dense.clone()).eigenvalues;
        assert!(eigen.iter().all(|e| e.abs() > 1e-12), "{eigen}");
        (
            eigen.iter().filter(|&&e| e > 0.0).count(),
            eigen.iter().filter(|&&e| e < 0.0).count(),
        )
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

    /// A collocation-like KKT matrix: a banded indefinite W in which every third variable enters
    /// linearly (zero diagonal, so it needs a 2×2 pivot with a constraint row), a banded J and
    /// a small δ_c. faer's factorization (the default path) and feral's (the fallback) must
    /// report the inertia of a dense eigen-decomposition and solve to machine precision.
    #[test]
    fn faer_and_the_feral_fallback_agree_with_a_dense_eigendecomposition() {
        let (n, m) = (45_usize, 27_usize);
        let mut next = uniform(12_345);
        let (hr, hc, hv) = banded_hessian(n, |i, j| {
            // The linear variables: no curvature.
            let linear = i % 3 == 2 && (i == j || j % 3 == 2);
            (!linear).then(|| if i == j { 3.0 * next() } else { next() })
        });
        let (jr, jc, jv) = banded_jacobian(n, m, |c| next() + if c % 3 == 2 { 2.0 } else { 0.0 });
        let dual = vec![-1e-9; m];
        let masked = vec![false; n];
        let dense = dense_kkt(
            (n, m),
            (&hr, &hc, &hv),
            (&jr, &jc, &jv),
            &vec![0.0; n],
            &dual,
        );
        let truth = eigen_signs(&dense);
        let rhs: Vec<f64> = (0..n + m).map(|_| next()).collect();
        let mut k = KktSystem::new(n, m, (&hr, &hc), (&jr, &jc)).unwrap();
        k.assemble(&hv, &jv, &vec![0.0; n], &dual, &masked);
        let faer = k.factorize().unwrap();
        assert_eq!(k.stats.fallbacks, 0, "faer factorized it");
        let x_faer = k.solve(&rhs, 3).unwrap();
        let feral = k.factorize_feral().unwrap();
        let x_feral = k.solve(&rhs, 3).unwrap();
        for (name, inertia, x) in [("faer", faer, x_faer), ("feral", feral, x_feral)] {
            assert_eq!(
                (inertia.positive, inertia.negative, inertia.zero),
                (truth.0, truth.1, 0),
                "{name}"
            );
            let x = nalgebra::DVector::from_vec(x);
            let residual = &dense * &x - nalgebra::DVector::from_vec(rhs.clone());
            // Backward error relative to ‖K‖ ‖x‖ (max norms): a few ulps after refinement.
            let scale = dense.amax() * x.amax();
            assert!(
                residual.amax() <= 1e-13 * scale,
                "{name}: residual {} of {scale}",
                residual.amax()
            );
        }
    }

    /// Iterative refinement corrects a solve until the residual is at most
    /// [`REFINEMENT_TOLERANCE`] of the right-hand side, and no further. A KKT matrix with
    /// curvatures from 1e-10 to 1e10 (barrier terms of variables near and far from their
    /// bounds) leaves the unrefined solve a residual of 1.3e-7; one correction takes it to
    /// 1.6e-12, and the refinement stops there although more were allowed.
    #[test]
    fn refinement_corrects_a_badly_scaled_solve_to_the_tolerance_and_stops() {
        let (n, m) = (60_usize, 36_usize);
        let mut next = uniform(777);
        let (hr, hc, hv) = banded_hessian(n, |i, j| {
            let scale = 10f64.powi(((i * 7) % 21) as i32 - 10);
            Some(if i == j {
                scale * (2.0 + next())
            } else {
                next()
            })
        });
        let (jr, jc, jv) = banded_jacobian(n, m, |_| next());
        let dual = vec![-1e-8; m];
        let dense = dense_kkt(
            (n, m),
            (&hr, &hc, &hv),
            (&jr, &jc, &jv),
            &vec![0.0; n],
            &dual,
        );
        let rhs: Vec<f64> = (0..n + m).map(|_| next()).collect();
        let scale = rhs.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        let residual_of = |x: &[f64]| {
            let x = nalgebra::DVector::from_column_slice(x);
            (&dense * &x - nalgebra::DVector::from_column_slice(&rhs)).amax()
        };
        let mut k = KktSystem::new(n, m, (&hr, &hc), (&jr, &jc)).unwrap();
        k.assemble(&hv, &jv, &vec![0.0; n], &dual, &vec![false; n]);
        k.factorize().unwrap();
        let unrefined = residual_of(&k.solve(&rhs, 0).unwrap());
        assert_eq!(k.stats.corrections, 0);
        let refined = residual_of(&k.solve(&rhs, 5).unwrap());
        let corrections = k.stats.corrections;
        assert!(unrefined > REFINEMENT_TOLERANCE * scale, "{unrefined:e}");
        assert!(refined <= REFINEMENT_TOLERANCE * scale, "{refined:e}");
        assert!((1..3).contains(&corrections), "{corrections} corrections");
    }

    /// A KKT matrix whose linear variables have no curvature and whose (2,2) block is exactly
    /// zero (δ_w = δ_c = 0): faer's pivoting inside supernodes meets a zero pivot and its factor
    /// is not finite. That is a failed factorization (the interior point then raises δ_w), not a
    /// detour through feral; with δ_w = 1 and δ_c = 1e-8 the same pattern factorizes, with the
    /// inertia of a dense eigendecomposition.
    #[test]
    fn a_factor_faer_cannot_finish_fails_and_a_perturbed_one_succeeds() {
        let (n, m) = (45_usize, 27_usize);
        let mut next = uniform(2);
        let (hr, hc, hv) = banded_hessian(n, |i, j| {
            Some(if i % 3 == 2 {
                0.0 // a linear variable: no curvature
            } else if i == j {
                3.0 * next()
            } else {
                next()
            })
        });
        let (jr, jc, jv) = banded_jacobian(n, m, |_| next());
        let masked = vec![false; n];
        let mut k = KktSystem::new(n, m, (&hr, &hc), (&jr, &jc)).unwrap();
        // The ordering comes from the first matrix, as in a solve: the least-squares one.
        k.assemble(
            &vec![0.0; hv.len()],
            &jv,
            &vec![1.0; n],
            &vec![-1.0; m],
            &masked,
        );
        assert!(k.factorize().is_some());
        k.assemble(&hv, &jv, &vec![0.0; n], &vec![0.0; m], &masked);
        assert_eq!(k.factorize(), None);
        assert_eq!((k.stats.nonfinite, k.stats.fallbacks), (1, 0));
        let (delta_w, delta_c) = (1.0, 1e-8);
        k.assemble(&hv, &jv, &vec![delta_w; n], &vec![-delta_c; m], &masked);
        let inertia = k.factorize().unwrap();
        let dense = dense_kkt(
            (n, m),
            (&hr, &hc, &hv),
            (&jr, &jc, &jv),
            &vec![delta_w; n],
            &vec![-delta_c; m],
        );
        let (positive, negative) = eigen_signs(&dense);
        assert_eq!(
            (inertia.positive, inertia.negative, inertia.zero),
            (positive, negative, 0)
        );
        assert_eq!((k.stats.nonfinite, k.stats.fallbacks), (1, 0));
    }
}
