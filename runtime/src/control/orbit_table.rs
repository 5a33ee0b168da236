//! The planned orbit's stance-leg angular momentum σ*(θ): how fast the gait means the robot to
//! move at each stance-leg angle.
//!
//! On the gait's zero dynamics (the outputs on their Bézier curves, y = y^d(τ(θ))) the
//! configuration is a function q(θ) of the stance-leg angle alone and q̇ = q'(θ)·θ̇. The angular
//! momentum about the stance foot σ = I(θ)·θ̇ (I(θ): the momentum of q'(θ) at θ̇ = 1) changes
//! only by gravity's moment, σ̇ = m·g·x_c(θ) (x_c: the centre of mass ahead of the foot), so
//! along the step
//!
//! ```text
//! σ*(θ)² = σ⁺² + 2·∫_{θ⁺}^{θ} m·g·x_c(θ')·I(θ') dθ',   T = ∫_{θ⁺}^{θ⁻} I(θ)/σ*(θ) dθ
//! ```
//!
//! σ⁺ is the one that makes the step last the gait's planned duration T: found by bisection, so
//! the table needs only the outputs, θ⁺, θ⁻ and T, and serves a blend of library gaits as well
//! as a planned one (whose `initial_state` gives σ⁺ directly: the unit test compares them).
//! The launch of a walk from Stand ends on σ*(θ) at its hand-over angle
//! (`controller::commands`). Everything here works on fixed-size arrays and never allocates.

use super::double_support::Geometry;
use super::gait_table::{side_index, GaitTable};
use crate::slots::OUTPUTS;
use model::robot::MAX_DOF;

/// Grid points of the table over [θ⁺, θ⁻].
pub const ORBIT_TABLE_POINTS: usize = 41;

/// σ*(θ) on a uniform grid of the stance-leg angle over the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitTable {
    /// First and last grid angle (θ⁺, θ⁻), rad.
    pub theta_range_rad: [f64; 2],
    /// σ*(θ_k) about the stance foot, kg·m²/s.
    pub sigma_kgm2_s: [f64; ORBIT_TABLE_POINTS],
    /// I(θ_k): angular momentum per unit θ̇ on the gait's manifold, kg·m².
    pub inertia_kgm2: [f64; ORBIT_TABLE_POINTS],
}

impl OrbitTable {
    /// The table of `gait` on the robot of `geometry` (its first stance leg; the gait is
    /// symmetric). `None` if the kinematics fail, the phase range is empty or no σ⁺ ≥ 0 gives
    /// the planned step duration (a gait that stalls).
    pub fn of(geometry: &Geometry, gait: &GaitTable) -> Option<Self> {
        let (lo, hi) = (gait.theta_plus_rad, gait.theta_minus_rad);
        if !(lo.is_finite() && hi.is_finite() && hi > lo && gait.step_duration_s > 0.0) {
            return None;
        }
        let n = ORBIT_TABLE_POINTS;
        let h = (hi - lo) / (n - 1) as f64;
        let mass_kg: f64 = geometry
            .model
            .bodies
            .iter()
            .map(|b| b.inertia.mass_kg)
            .sum();
        let weight_n = mass_kg * geometry.model.gravity_mps2;
        let mut inertia = [0.0; ORBIT_TABLE_POINTS];
        // Cumulative ∫ m g x_c I dθ (trapezoid).
        let mut work = [0.0; ORBIT_TABLE_POINTS];
        let mut last = 0.0;
        for k in 0..n {
            let theta = lo + h * k as f64;
            let (i_k, x_c) = manifold_point(geometry, gait, theta)?;
            inertia[k] = i_k;
            let integrand = weight_n * x_c * i_k;
            if k > 0 {
                work[k] = work[k - 1] + 0.5 * h * (last + integrand);
            }
            last = integrand;
        }
        // σ⁺ with T(σ⁺) = the planned duration; T falls as σ⁺ grows.
        let floor2 = work.iter().fold(0.0_f64, |m, w| m.max(-2.0 * w));
        let duration = |sigma_plus: f64| -> f64 {
            let s2 = sigma_plus * sigma_plus;
            let mut t = 0.0;
            for k in 1..n {
                let a = inertia[k - 1] / (s2 + 2.0 * work[k - 1]).max(1e-12).sqrt();
                let b = inertia[k] / (s2 + 2.0 * work[k]).max(1e-12).sqrt();
                t += 0.5 * h * (a + b);
            }
            t
        };
        let mut low = floor2.sqrt();
        let mut high = low + 1.0;
        while duration(high) > gait.step_duration_s {
            high *= 2.0;
            if high > 1e3 {
                return None;
            }
        }
        if duration(low) < gait.step_duration_s {
            return None;
        }
        for _ in 0..80 {
            let mid = 0.5 * (low + high);
            if duration(mid) > gait.step_duration_s {
                low = mid;
            } else {
                high = mid;
            }
        }
        let s2 = high * high;
        let mut sigma_kgm2_s = [0.0; ORBIT_TABLE_POINTS];
        for k in 0..n {
            sigma_kgm2_s[k] = (s2 + 2.0 * work[k]).max(0.0).sqrt();
        }
        Some(Self {
            theta_range_rad: [lo, hi],
            sigma_kgm2_s,
            inertia_kgm2: inertia,
        })
    }

    /// σ*(θ) about the stance foot, kg·m²/s: linear interpolation inside the step; outside it
    /// the nearest end's value (a launch hands over just before θ⁺ at most a little).
    pub fn sigma_at(&self, theta_rad: f64) -> f64 {
        let [lo, hi] = self.theta_range_rad;
        let u = ((theta_rad - lo) / (hi - lo)).clamp(0.0, 1.0) * (ORBIT_TABLE_POINTS - 1) as f64;
        let k = (u.floor() as usize).min(ORBIT_TABLE_POINTS - 2);
        let w = u - k as f64;
        self.sigma_kgm2_s[k] * (1.0 - w) + self.sigma_kgm2_s[k + 1] * w
    }
}

/// On the gait's manifold at stance-leg angle `theta_rad`: I(θ) (angular momentum about the
/// stance foot per unit θ̇, kg·m²) and the centre of mass ahead of the stance foot, m.
pub(super) fn manifold_point(
    geometry: &Geometry,
    gait: &GaitTable,
    theta_rad: f64,
) -> Option<(f64, f64)> {
    let model = geometry.model;
    let stance = gait.first_stance;
    let span = gait.theta_minus_rad - gait.theta_plus_rad;
    let tau = (theta_rad - gait.theta_plus_rad) / span;
    let mut q = *geometry.q_template;
    let mut dq = [0.0; MAX_DOF];
    q[0] = 0.0;
    q[1] = 0.0;
    for i in 0..OUTPUTS {
        let slot = gait.out_slot[side_index(stance)][i];
        let (y, dy_dtau) = gait.eval(i, tau);
        q[geometry.leg_coord[slot]] = y;
        dq[geometry.leg_coord[slot]] = dy_dtau / span;
    }
    let dof = geometry.dof;
    // The pitch that puts the stance leg at θ: a rigid rotation of the whole robot turns θ by
    // the same angle (one way or the other: the slope is ±1, measured).
    let theta_of = |q: &[f64; MAX_DOF]| {
        model
            .stance_leg_angle(&q[..dof], geometry.legs, stance)
            .ok()
    };
    q[2] = 0.0;
    let t0 = theta_of(&q)?;
    q[2] = 0.1;
    let slope = (theta_of(&q)? - t0) / 0.1;
    if slope.abs().partial_cmp(&0.5) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    q[2] = (theta_rad - t0) / slope;
    // θ̇ = slope·φ̇ + (∂θ/∂joints)·q̇_joints = 1: the pitch rate that makes it so.
    let (_, joint_rate) = model
        .stance_leg_angle_rate(&q[..dof], &dq[..dof], geometry.legs, stance)
        .ok()?;
    dq[2] = (1.0 - joint_rate) / slope;
    // The stance foot still: the whole robot translates so that its velocity vanishes.
    let (inertia, foot) = geometry.pinned_momentum(stance, &q, &dq)?;
    let com = model.center_of_mass(&q[..dof]).ok()?;
    Some((inertia, com[0] - foot[0]))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::control::double_support::GeometryParts;
    use crate::Setup;

    fn table_of(setup: &Setup) -> (OrbitTable, GaitTable, f64) {
        let model = &setup.model;
        let q0 = setup.gait.initial_state.clone().unwrap().q;
        let parts = GeometryParts::new(model, &q0);
        let (g, legs) = (parts.geometry(model), &parts.legs);
        let gait = GaitTable::new(&setup.gait, model, legs).unwrap();
        let table = OrbitTable::of(&g, &gait).unwrap();
        // The planned post-impact state's σ about its stance foot.
        let s = setup.gait.initial_state.clone().unwrap();
        let st = model.body_poses(&s.q).unwrap();
        let foot = model.frame_position_in(&st, legs.side(setup.gait.stance_leg).foot);
        let sigma_plus = model.angular_momentum_about(&s.q, &s.dq, foot).unwrap();
        (table, gait, sigma_plus)
    }

    /// The shipped gait and the graded-mesh re-plan of it (a test fixture).
    fn setups() -> [(&'static str, Setup); 2] {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let replan = Setup::load(
            root.join("configs/runtime/adam.toml"),
            root.join("runtime/tests/fixtures/adam_codesign_graded.json"),
        )
        .unwrap();
        [("shipped", Setup::shipped().unwrap()), ("re-plan", replan)]
    }

    /// σ⁺ found from the planned step duration alone equals the planned post-impact state's
    /// angular momentum about the stance foot (an independent figure: the gait file's
    /// `initial_state`), within 0.5 % (measured 0.03-0.04 %); and the orbit slows over the top
    /// (σ* smallest mid-step, 40 % of σ⁺), as an inverted pendulum does.
    #[test]
    fn the_table_starts_at_the_planned_post_impact_momentum() {
        for (name, setup) in setups() {
            let (table, gait, sigma_plus) = table_of(&setup);
            let s = &table.sigma_kgm2_s;
            assert!(
                (s[0] - sigma_plus).abs() < 0.005 * sigma_plus,
                "{name}: σ⁺ {} from the duration, {sigma_plus} planned",
                s[0]
            );
            assert_eq!(
                table.theta_range_rad,
                [gait.theta_plus_rad, gait.theta_minus_rad]
            );
            let (k_min, s_min) =
                s.iter().enumerate().fold(
                    (0, f64::INFINITY),
                    |m, (k, &v)| if v < m.1 { (k, v) } else { m },
                );
            assert!(
                k_min > ORBIT_TABLE_POINTS / 4 && k_min < 3 * ORBIT_TABLE_POINTS / 4,
                "{name}: {s:?}"
            );
            assert!(s_min > 0.2 * s[0] && s_min < 0.6 * s[0], "{name}: {s:?}");
            // Interpolation: exact at the grid points, between neighbours in between.
            let [lo, hi] = table.theta_range_rad;
            let h = (hi - lo) / (ORBIT_TABLE_POINTS - 1) as f64;
            assert!((table.sigma_at(lo + 7.0 * h) - s[7]).abs() < 1e-9);
            let mid = table.sigma_at(lo + 7.5 * h);
            assert!(mid >= s[7].min(s[8]) && mid <= s[7].max(s[8]));
            assert_eq!(table.sigma_at(lo - 1.0), s[0]);
        }
    }
}
