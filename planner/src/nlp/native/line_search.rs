//! The filter line search: the filter, the fraction-to-the-boundary step limits, the
//! acceptance test and the second-order corrections.

use super::bounds::Bounds;
use super::constants::{
    DELTA_SWITCH, ETA_PHI, GAMMA_PHI, GAMMA_THETA, KAPPA_SOC, MAX_SOC, S_PHI, S_THETA,
};
use super::ipm::Ipm;
use super::newton::Direction;

/// An accepted trial point of the line search.
pub(super) struct Trial {
    pub(super) x: Vec<f64>,
    pub(super) s: Vec<f64>,
    pub(super) f: f64,
    pub(super) g: Vec<f64>,
    /// The primal step length that reached it (also used for y).
    pub(super) alpha: f64,
    /// Accepted by the Armijo condition on the barrier objective (an "f-type" step; the
    /// filter is not augmented).
    pub(super) f_type: bool,
}

/// The filter: pairs (θ, φ) that a trial point must improve on.
#[derive(Default)]
pub(super) struct Filter(pub(super) Vec<(f64, f64)>);

impl Filter {
    pub(super) fn acceptable(&self, theta: f64, phi: f64) -> bool {
        self.0.iter().all(|&(t, p)| theta < t || phi < p)
    }
    pub(super) fn add(&mut self, theta: f64, phi: f64) {
        self.0.retain(|&(t, p)| t < theta || p < phi);
        self.0.push((theta, phi));
    }
}

impl Ipm<'_> {
    /// Largest α ≤ 1 keeping x + α dx (and s) strictly inside by the fraction τ.
    pub(super) fn primal_step_limit(&self, dx: &[f64], ds: &[f64]) -> f64 {
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

    pub(super) fn dual_step_limit(&self, d: &Direction) -> f64 {
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

    /// The filter acceptance test: `Some(f_type)` if the trial point is accepted.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn acceptable(
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
    pub(super) fn second_order_correction(
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
}
