//! The objectives: the cost of transport (power slacks, Simpson's rule), the feasibility
//! stage's torque regularizer, and the start of the power slacks on the central path.

use super::layout::TORQUE_SCALE;
use super::problem::HzdProblem;

/// Weight of the feasibility stage's torque regularizer Σ_k Σ_a (u_ka / 10 N·m)²: small enough
/// not to shape the gait, large enough to give the interior point a bounded, strictly convex
/// objective in the torques (a zero objective left the first solve wandering for minutes).
pub const FEASIBILITY_TORQUE_WEIGHT: f64 = 1e-4;

impl HzdProblem {
    pub(super) fn torque_vars(&self) -> impl Iterator<Item = usize> + '_ {
        let l = &self.layout;
        (0..l.points()).flat_map(move |k| (0..l.nu).map(move |a| l.u(k) + a))
    }

    /// Σ_k c_k Σ_a w_a (p + n): the Simpson sum of the absolute power.
    pub(super) fn power_sum(&self, x: &[f64]) -> f64 {
        self.slack_weights.iter().map(|&(i, w)| w * x[i]).sum()
    }

    /// K = 1 / (6 N M g): Φ = K T S / d.
    pub(super) fn cost_factor(&self) -> f64 {
        1.0 / (6.0
            * self.layout.intervals as f64
            * self.total_mass_kg
            * self.biped.model.gravity_mps2)
    }

    /// Moves the start point's power slacks onto the central path of the barrier parameter
    /// `mu_init` for this problem's cost, and makes `mu_init` the solve's initial barrier
    /// parameter ([`Self::initial_barrier`]).
    ///
    /// p = max(u q̇, 0) + δ and n = max(−u q̇, 0) + δ, so p − n = u q̇ holds, with
    /// δ = μ₀ / (∂Φ/∂p) the distance from the bound at which the barrier's push μ₀/δ equals the
    /// cost's pull (1 W where an actuator's weight is zero; the solver's bound push keeps a p or n
    /// that ends above its bound inside). Nothing else moves. (When the
    /// feasibility problem still had the slacks, with no cost on them, its barrier left them near
    /// the middle of their bounds, hundreds of watts where |u q̇| is below one: started there, the
    /// cost stage began at a cost of transport of ~100 and spent most of its iterations bringing
    /// them down.)
    pub fn centre_power_slacks(&mut self, mu_init: f64) {
        let l = &self.layout;
        let (t, d) = (self.initial[l.duration()], self.initial[l.length()]);
        let pull = self.cost_factor() * t / d;
        for k in 0..l.points() {
            for (a, &c) in self.biped.actuators.iter().enumerate() {
                let power = TORQUE_SCALE * self.initial[l.u(k) + a] * self.initial[l.dq(k) + c];
                let w = l.simpson_weight(k) * self.config.cost.weights[a];
                let delta = if pull * w > 0.0 {
                    mu_init / (pull * w)
                } else {
                    1.0
                };
                self.initial[l.p(k) + a] = power.max(0.0) + delta;
                self.initial[l.n(k) + a] = (-power).max(0.0) + delta;
            }
        }
        self.initial_barrier = Some(mu_init);
    }

    /// The mechanical cost of transport at x (whether or not it is the objective).
    pub fn cost_of_transport(&self, x: &[f64]) -> f64 {
        self.cost_factor() * x[self.layout.duration()] * self.power_sum(x) / x[self.layout.length()]
    }
}
