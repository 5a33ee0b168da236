//! The Newton step: the KKT matrix factorized with inertia correction (δ_w, δ_c; two trials
//! at once on twin systems) and the search direction solved from it.

use super::constants::{
    DELTA_C_BAR, DELTA_W_0, DELTA_W_MAX, DELTA_W_MIN, KAPPA_C, KAPPA_W_MINUS, KAPPA_W_PLUS,
    KAPPA_W_PLUS_BAR, MAX_CORRECTIONS, REFINEMENTS,
};
use super::ipm::Ipm;
use super::kkt::KktSystem;

/// A search direction in all variables.
#[derive(Clone, Default)]
pub(super) struct Direction {
    pub(super) x: Vec<f64>,
    pub(super) s: Vec<f64>,
    pub(super) y: Vec<f64>,
    pub(super) zl: Vec<f64>,
    pub(super) zu: Vec<f64>,
    pub(super) vl: Vec<f64>,
    pub(super) vu: Vec<f64>,
}

impl Ipm<'_> {
    /// Factorizes the KKT matrix with inertia correction; returns the δ_w it needed.
    pub(super) fn factorize(&mut self, sx: &[f64], ss: &[f64]) -> Option<f64> {
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
    pub(super) fn next_delta_w(&self, delta_w: f64) -> f64 {
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
    pub(super) fn accept_delta_w(&mut self, delta_w: f64) -> f64 {
        if delta_w > 0.0 {
            self.delta_w_last = delta_w;
        }
        delta_w
    }

    /// The KKT matrix's diagonals for δ_w and δ_c: Σ_x + δ_w (1 for a fixed variable) and
    /// −δ_c − 1/(Σ_s + δ_w) (the slack eliminated; −δ_c alone for an equality).
    pub(super) fn diagonals(
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
    pub(super) fn direction(
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
}
