//! The interior point's constants: IPOPT's defaults, by the names of Wächter & Biegler (2006).

// Algorithm constants (IPOPT's defaults).
pub(super) const MU_INIT: f64 = 0.1;
pub(super) const KAPPA_EPS: f64 = 10.0;
pub(super) const KAPPA_MU: f64 = 0.2;
pub(super) const THETA_MU: f64 = 1.5;
pub(super) const TAU_MIN: f64 = 0.99;
pub(super) const S_MAX: f64 = 100.0;
pub(super) const KAPPA_SIGMA: f64 = 1e10;
pub(super) const BOUND_PUSH: f64 = 1e-2;
pub(super) const BOUND_RELAX: f64 = 1e-8;
pub(super) const KAPPA_D: f64 = 1e-5;
pub(super) const GAMMA_THETA: f64 = 1e-5;
pub(super) const GAMMA_PHI: f64 = 1e-8;
pub(super) const DELTA_SWITCH: f64 = 1.0;
pub(super) const S_THETA: f64 = 1.1;
pub(super) const S_PHI: f64 = 2.3;
pub(super) const ETA_PHI: f64 = 1e-8;
pub(super) const GAMMA_ALPHA: f64 = 0.05;
pub(super) const MAX_SOC: usize = 4;
pub(super) const KAPPA_SOC: f64 = 0.99;
pub(super) const DELTA_W_0: f64 = 1e-4;
pub(super) const DELTA_W_MIN: f64 = 1e-20;
pub(super) const DELTA_W_MAX: f64 = 1e40;
pub(super) const KAPPA_W_MINUS: f64 = 1.0 / 3.0;
pub(super) const KAPPA_W_PLUS: f64 = 8.0;
pub(super) const KAPPA_W_PLUS_BAR: f64 = 100.0;
/// Inertia-correction trials (factorizations) per iteration, at most.
pub(super) const MAX_CORRECTIONS: usize = 60;
pub(super) const DELTA_C_BAR: f64 = 1e-8;
pub(super) const KAPPA_C: f64 = 0.25;
pub(super) const SCALING_MAX_GRADIENT: f64 = 100.0;
pub(super) const ACCEPTABLE_TOL: f64 = 1e-6;
pub(super) const ACCEPTABLE_ITER: usize = 15;
pub(super) const ACCEPTABLE_VIOLATION: f64 = 1e-2;
pub(super) const ACCEPTABLE_COMPLEMENTARITY: f64 = 1e-2;
pub(super) const DUAL_INF_TOL: f64 = 1.0;
pub(super) const COMPL_INF_TOL: f64 = 1e-4;
pub(super) const LS_MULTIPLIER_MAX: f64 = 1e3;
pub(super) const REFINEMENTS: usize = 3;
