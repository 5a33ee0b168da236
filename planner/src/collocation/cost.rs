//! The objectives: the costs of `[cost]` (mechanical and electrical cost of transport, torque
//! squared per distance, their weighted sum), the feasibility stage's torque regularizer, and
//! the start of the power slacks on the central path.
//!
//! # Costs
//! Every cost is a Simpson sum over the 2N + 1 points (weights c_k, ∫ f dt ≈ T/(6N) Σ c_k f_k)
//! of per-actuator terms with the joint weights w_a, divided by the step length d:
//!
//! | kind | Φ | units |
//! |---|---|---|
//! | `mechanical` | Σ_a w_a ∫ \|u_a q̇_a\| dt / (m g d), with \|u q̇\| = p + n | 1 |
//! | `electrical` | Σ_a w_a ∫ [ρ_a u_a² + max(u_a q̇_a, 0)] dt / (m g d), ρ_a = R_a / (N_a k_t,a)², max(u q̇, 0) = p | 1 |
//! | `torque_squared` | Σ_a w_a ∫ u_a² dt / d | N²·m·s |
//! | `weighted` | λ_m Φ_mech + λ_e Φ_elec + λ_τ Φ_τ² | 1 |
//!
//! (m the robot's mass, g gravity; p, n ≥ 0 the power slacks with p − n = u q̇, so at the
//! optimum p = max(u q̇, 0) and n = max(−u q̇, 0): the electrical cost pays for positive
//! mechanical power only, no regeneration, plus the copper loss i² R of the current
//! i = u / (N k_t); N, k_t and R come from the robot's transmissions, [`model::JointDrive`].)
//!
//! With the torque variable x_u = u / `TORQUE_SCALE`, every cost has the form
//! Φ = (T/d) · S(x), S = Σ_i a_i x_i + Σ_j b_j x_j²: linear in the slacks, quadratic in the
//! torques. Its exact derivatives, by hand: ∂Φ/∂x_i = (T/d) a_i, ∂Φ/∂x_j = 2 (T/d) b_j x_j,
//! ∂Φ/∂T = S/d, ∂Φ/∂d = −T S/d²; the Hessian's non-zeros are (x_j, x_j) 2 b_j T/d,
//! (T, x_i) a_i/d, (x_i, d) −T a_i/d², (T, x_j) 2 b_j x_j/d, (x_j, d) −2 T b_j x_j/d²,
//! (T, d) −S/d² and (d, d) 2 T S/d³. The tests check them against finite differences for each
//! kind.

use super::layout::TORQUE_SCALE;
use super::problem::{HzdProblem, ObjectiveTerms};
use crate::config::CostMix;

/// Weight of the feasibility stage's torque regularizer Σ_k Σ_a (u_ka / 10 N·m)²: small enough
/// not to shape the gait, large enough to give the interior point a bounded, strictly convex
/// objective in the torques (a zero objective left the first solve wandering for minutes).
pub const FEASIBILITY_TORQUE_WEIGHT: f64 = 1e-4;

impl HzdProblem {
    pub(super) fn torque_vars(&self) -> impl Iterator<Item = usize> + '_ {
        let l = &self.layout;
        (0..l.points()).flat_map(move |k| (0..l.nu).map(move |a| l.u(k) + a))
    }

    /// K = 1 / (6 N M g): Φ = K T S / d.
    pub(super) fn cost_factor(&self) -> f64 {
        1.0 / (6.0
            * self.layout.intervals as f64
            * self.total_mass_kg
            * self.biped.model.gravity_mps2)
    }

    /// The coefficients (a_p, a_n) of actuator `a`'s power slacks p and n at point `k` in
    /// S (Φ = (T/d) S): K c_k w_a (λ_m + λ_e) and K c_k w_a λ_m.
    fn slack_coefficients(&self, mix: &CostMix, k: usize, a: usize) -> (f64, f64) {
        let w = self.cost_factor() * self.layout.simpson_weight(k) * self.config.cost.weights[a];
        (w * (mix.mechanical + mix.electrical), w * mix.mechanical)
    }

    /// The cost's terms for this problem's layout and `[cost]` (none without power slacks).
    pub(super) fn objective_terms(&self) -> ObjectiveTerms {
        let l = &self.layout;
        let mix = self.config.cost.mix();
        let mut terms = ObjectiveTerms::default();
        if !l.slacks {
            return terms;
        }
        let per_second = 1.0 / (6.0 * l.intervals as f64);
        for k in 0..l.points() {
            for a in 0..l.nu {
                let (ap, an) = self.slack_coefficients(&mix, k, a);
                for (i, c) in [(l.p(k) + a, ap), (l.n(k) + a, an)] {
                    if c != 0.0 {
                        terms.linear.push((i, c));
                    }
                }
                let w = l.simpson_weight(k) * self.config.cost.weights[a];
                let copper = self.copper_loss_w_per_nm2.get(a).copied().unwrap_or(0.0);
                let b = w
                    * TORQUE_SCALE
                    * TORQUE_SCALE
                    * (mix.electrical * self.cost_factor() * copper
                        + mix.torque_squared * per_second);
                if b != 0.0 {
                    terms.quadratic.push((l.u(k) + a, b));
                }
            }
        }
        terms
    }

    /// S(x) = Σ a_i x_i + Σ b_j x_j² (Φ = (T/d) S).
    pub(super) fn objective_sum(&self, x: &[f64]) -> f64 {
        let t = &self.objective;
        t.linear.iter().map(|&(i, a)| a * x[i]).sum::<f64>()
            + t.quadratic
                .iter()
                .map(|&(j, b)| b * x[j] * x[j])
                .sum::<f64>()
    }

    /// The configured cost Φ at x (`[cost]`; the mechanical cost of transport by default).
    pub fn cost(&self, x: &[f64]) -> f64 {
        x[self.layout.duration()] * self.objective_sum(x) / x[self.layout.length()]
    }

    /// The gradient of [`Self::cost`] into `gradient` (zeroed by the caller).
    pub(super) fn cost_gradient(&self, x: &[f64], gradient: &mut [f64]) {
        let (t_i, d_i) = (self.layout.duration(), self.layout.length());
        let (t, d) = (x[t_i], x[d_i]);
        for &(i, a) in &self.objective.linear {
            gradient[i] += t * a / d;
        }
        for &(j, b) in &self.objective.quadratic {
            gradient[j] += 2.0 * t * b * x[j] / d;
        }
        let s = self.objective_sum(x);
        gradient[t_i] += s / d;
        gradient[d_i] += -t * s / (d * d);
    }

    /// Adds `factor` × the Hessian of [`Self::cost`] into the Hessian `values` at the slots of
    /// `build_patterns`.
    pub(super) fn add_cost_hessian(&self, x: &[f64], factor: f64, values: &mut [f64]) {
        let (t, d) = (x[self.layout.duration()], x[self.layout.length()]);
        let slots = &self.obj_slots;
        for (n, &(_, a)) in self.objective.linear.iter().enumerate() {
            values[slots.t_lin[n]] += factor * a / d;
            values[slots.lin_d[n]] += -factor * t * a / (d * d);
        }
        for (n, &(j, b)) in self.objective.quadratic.iter().enumerate() {
            values[slots.quad[n]] += factor * 2.0 * b * t / d;
            values[slots.t_quad[n]] += factor * 2.0 * b * x[j] / d;
            values[slots.quad_d[n]] += -factor * 2.0 * t * b * x[j] / (d * d);
        }
        let s = self.objective_sum(x);
        values[slots.t_d] += -factor * s / (d * d);
        values[slots.d_d] += 2.0 * factor * t * s / (d * d * d);
    }

    /// Moves the start point's power slacks onto the central path of the barrier parameter
    /// `mu_init` for this problem's cost, and makes `mu_init` the solve's initial barrier
    /// parameter ([`Self::initial_barrier`]).
    ///
    /// p = max(u q̇, 0) + δ and n = max(−u q̇, 0) + δ, so p − n = u q̇ holds, with
    /// δ = μ₀ / (∂Φ/∂p) the distance from the bound at which the barrier's push μ₀/δ equals the
    /// cost's pull (the larger of p's and n's; 1 W where neither carries cost, as with the torque
    /// squared: the solver's bound push keeps a p or n that ends above its bound inside). Nothing
    /// else moves. (When the feasibility problem still had the slacks, with no cost on them, its
    /// barrier left them near the middle of their bounds, hundreds of watts where |u q̇| is below
    /// one: started there, the cost stage began at a cost of transport of ~100 and spent most of
    /// its iterations bringing them down.)
    pub fn centre_power_slacks(&mut self, mu_init: f64) {
        let l = &self.layout;
        let mix = self.config.cost.mix();
        let (t, d) = (self.initial[l.duration()], self.initial[l.length()]);
        for k in 0..l.points() {
            for (a, &c) in self.biped.actuators.iter().enumerate() {
                let power = TORQUE_SCALE * self.initial[l.u(k) + a] * self.initial[l.dq(k) + c];
                let (ap, an) = self.slack_coefficients(&mix, k, a);
                let pull = t / d * ap.max(an);
                let delta = if pull > 0.0 { mu_init / pull } else { 1.0 };
                self.initial[l.p(k) + a] = power.max(0.0) + delta;
                self.initial[l.n(k) + a] = (-power).max(0.0) + delta;
            }
        }
        self.initial_barrier = Some(mu_init);
    }

    /// The mechanical cost of transport at x (whether or not it is the objective), from the
    /// torques and rates themselves: K (T/d) Σ_k c_k Σ_a w_a |u_ka q̇_ka|. (Not from the power
    /// slacks: where the objective gives them no cost they need not sit on |u q̇|.)
    pub fn cost_of_transport(&self, x: &[f64]) -> f64 {
        self.power_costs(x, None).0
    }

    /// The electrical cost of transport at x (whether or not it is the objective):
    /// K (T/d) Σ_k c_k Σ_a w_a [ρ_a u_ka² + max(u_ka q̇_ka, 0)], or `None` when the robot lacks
    /// an actuator's constants.
    pub fn electrical_cost_of_transport(&self, x: &[f64]) -> Option<f64> {
        let rho = &self.copper_loss_w_per_nm2;
        (rho.len() == self.layout.nu).then(|| self.power_costs(x, Some(rho)).1)
    }

    /// (mechanical, electrical) costs of transport at x; the electrical one is 0 without `rho`.
    fn power_costs(&self, x: &[f64], rho: Option<&[f64]>) -> (f64, f64) {
        let l = &self.layout;
        let (mut mech, mut elec) = (0.0, 0.0);
        for k in 0..l.points() {
            for (a, &c) in self.biped.actuators.iter().enumerate() {
                let w = l.simpson_weight(k) * self.config.cost.weights[a];
                let u = TORQUE_SCALE * x[l.u(k) + a];
                let power = u * x[l.dq(k) + c];
                mech += w * power.abs();
                if let Some(rho) = rho {
                    elec += w * (rho[a] * u * u + power.max(0.0));
                }
            }
        }
        let f = self.cost_factor() * x[l.duration()] / x[l.length()];
        (f * mech, f * elec)
    }
}
