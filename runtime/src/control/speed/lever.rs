//! The step-length lever: how a step's touchdown pose changes with the step's length, as exact
//! derivatives of the braking step's touchdown family ([`braking_touchdown`]).
//!
//! # The slopes, by the implicit function theorem
//! [`braking_touchdown`] puts the front foot at the origin, the rear foot at (−ℓ, 0) and the
//! torso at pose(ℓ) = (−f·ℓ, z(ℓ), φ) with z(ℓ) = √(z₀² + (d/2)² − ℓ²/4) (f, z₀, d and φ from
//! the gait's first pose), and solves the leg joints q(ℓ) so that each foot is where asked:
//! p_front(pose, q) = 0, p_rear(pose, q) = (−ℓ, 0). Differentiating both in ℓ,
//! J_pose·pose′ + J_leg·q′ = (0, 0) and (−1, 0): each leg's 2 × 2 Jacobian J_leg (hip, knee)
//! gives its q′ from the feet's velocities for a torso "moving" at pose′ =
//! (−f, −ℓ/(4z), 0). The touchdown outputs are the rear leg's joints (their slope is q′ of its
//! slots), and the stance-leg angle's slope is θ̇ along (pose′, q′)
//! ([`model::PlanarModel::stance_leg_angle_rate`]). The unit test checks them against central
//! differences of [`braking_touchdown`].

use super::super::double_support::{slots, solve2, Geometry};
use super::super::gait_table::{side_index, GaitTable};
use super::super::orbit::{add_lean, lean_sign};
use super::super::transitions::{braking_touchdown, first_pose_torso};
use crate::slots::{LEG_SLOTS, OUTPUTS};
use model::robot::MAX_DOF;

/// A step of the lever follows the gait up to this phase, then blends into its longer or
/// shorter touchdown pose (as the braking step does).
pub(in crate::control) const LEVER_BLEND_FROM: f64 = 0.3;

/// The step-length lever: how a step's touchdown pose changes with its length, and this step's
/// length offset. A step `offset_m` longer than the gait's ends with the outputs at
/// y^d(1) + offset·`dy_end_per_m` and the stance leg at θ⁻ + offset·`theta_per_m`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(in crate::control) struct StepLever {
    /// Touchdown offset of each output per metre of extra step length, rad/m.
    pub(in crate::control) dy_end_per_m: [f64; OUTPUTS],
    /// Stance-leg angle at touchdown per metre of extra step length, rad/m.
    pub(in crate::control) theta_per_m: f64,
    /// This step's length offset, m (0: the gait's own step).
    pub(in crate::control) offset_m: f64,
    /// +1 or −1: the hip offset that moves the centre of mass forward at mid-step (0: none
    /// does, no lean).
    pub(in crate::control) lean_sign: f64,
    /// This step's torso lean, rad (+ forward; 0: the gait's own): both hips offset by
    /// `lean_sign`·`lean_rad` for the whole step (a change at an impact blends in with the
    /// references' jump, `runtime::control::speed`).
    pub(in crate::control) lean_rad: f64,
}

impl StepLever {
    /// The slopes of `gait`, whose planned step is `length_m`: the exact derivatives in the
    /// step length of [`braking_touchdown`]'s touchdown pose (module docs). `None` if that pose
    /// is out of reach or a leg is straight (its Jacobian singular).
    pub(in crate::control) fn of(
        geometry: &Geometry,
        gait: &GaitTable,
        length_m: f64,
    ) -> Option<Self> {
        let touchdown = braking_touchdown(geometry, gait, length_m)?;
        let (stand, other) = first_pose_torso(geometry, gait)?;
        // The torso pose of braking_touchdown and its derivative in ℓ.
        let fraction = stand[0] / other[0];
        let half = 0.5 * other[0];
        let z = (stand[1] * stand[1] + half * half - 0.25 * length_m * length_m).sqrt();
        let pose = [-fraction * length_m, z, stand[2]];
        let pose_rate = [-fraction, -0.25 * length_m / z, 0.0];
        // Its joints: the rear leg's are the touchdown outputs (braking_touchdown's dy_end is
        // their offset from y^d(1)); relabeled to the rear foot as stance, they fill all slots.
        let front = gait.first_stance;
        let rear = front.other();
        let mut leg_q = [0.0; LEG_SLOTS];
        for i in 0..OUTPUTS {
            leg_q[gait.out_slot[side_index(rear)][i]] = gait.eval(i, 1.0).0 + touchdown.dy_end[i];
        }
        let (model, dof) = (geometry.model, geometry.dof);
        let mut q = *geometry.q_template;
        q[..3].copy_from_slice(&pose);
        for k in 0..LEG_SLOTS {
            q[geometry.leg_coord[k]] = leg_q[k];
        }
        // Velocities of the two feet (front, rear) for a coordinate rate `dq`.
        let feet = |dq: &[f64; MAX_DOF]| -> Option<[[f64; 2]; 2]> {
            let st = model.body_states(&q[..dof], &dq[..dof]).ok()?;
            Some(
                [front, rear]
                    .map(|side| model.frame_velocity_in(&st, geometry.legs.side(side).foot)),
            )
        };
        let mut dq = [0.0; MAX_DOF];
        dq[..3].copy_from_slice(&pose_rate);
        let from_pose = feet(&dq)?;
        // Each leg: J_leg·q′ = (the foot's rate) − (its velocity from the torso's motion).
        let mut leg_rate = [0.0; LEG_SLOTS];
        for (f, (side, target)) in [(front, [0.0, 0.0]), (rear, [-1.0, 0.0])]
            .into_iter()
            .enumerate()
        {
            let [hip, knee] = slots(side);
            let mut jac = [[0.0; 2]; 2];
            for (col, slot) in [hip, knee].into_iter().enumerate() {
                let mut unit = [0.0; MAX_DOF];
                unit[geometry.leg_coord[slot]] = 1.0;
                let v = feet(&unit)?[f];
                jac[0][col] = v[0];
                jac[1][col] = v[1];
            }
            let rhs = [target[0] - from_pose[f][0], target[1] - from_pose[f][1]];
            let d = solve2(jac, rhs)?;
            leg_rate[hip] = d[0];
            leg_rate[knee] = d[1];
        }
        let mut dy_end_per_m = [0.0; OUTPUTS];
        for (i, d) in dy_end_per_m.iter_mut().enumerate() {
            *d = leg_rate[gait.out_slot[side_index(rear)][i]];
        }
        for k in 0..LEG_SLOTS {
            dq[geometry.leg_coord[k]] = leg_rate[k];
        }
        let (_, theta_per_m) = model
            .stance_leg_angle_rate(&q[..dof], &dq[..dof], geometry.legs, rear)
            .ok()?;
        let lever = Self {
            dy_end_per_m,
            theta_per_m,
            offset_m: 0.0,
            // 0 where the hips do not move the centre of mass: that gait cannot lean (the
            // step lever's slopes do not depend on it).
            lean_sign: lean_sign(geometry, gait).unwrap_or(0.0),
            lean_rad: 0.0,
        };
        let finite =
            lever.dy_end_per_m.iter().all(|d| d.is_finite()) && lever.theta_per_m.is_finite();
        finite.then_some(lever)
    }

    /// Offset of output `i` at this step's touchdown, rad.
    pub(in crate::control) fn dy_end(&self, i: usize) -> f64 {
        self.offset_m * self.dy_end_per_m[i]
    }

    /// Leans the outputs `y` by this step's lean (the same all through the step).
    pub(in crate::control) fn add_lean(&self, y: &mut [f64; OUTPUTS]) {
        add_lean(y, self.lean_sign, self.lean_rad);
    }

    /// No longer step, no lean: the gait's own step.
    pub(in crate::control) fn rest(&mut self) {
        self.offset_m = 0.0;
        self.lean_rad = 0.0;
    }

    /// Offset of the stance-leg angle at this step's touchdown, rad.
    pub(in crate::control) fn theta_offset_rad(&self) -> f64 {
        self.offset_m * self.theta_per_m
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::config::LEG_JOINT_NAMES;
    use crate::Setup;

    /// The slopes match central differences of the touchdown family (h = 1e-4 m: truncation
    /// O(h²) ≈ 1e-8 of the second derivative's scale, Newton's 1e-10 m tolerance over 2h ≈
    /// 1e-6) for the shipped gait and each of the shipped library's gaits.
    #[test]
    fn the_slopes_match_central_differences_of_the_touchdown_pose() {
        let setup = Setup::shipped().unwrap();
        let model = &setup.model;
        let legs = model.legs().unwrap();
        let mut q_template = [0.0; MAX_DOF];
        q_template[..model.dof()].copy_from_slice(&setup.gait.initial_state.clone().unwrap().q);
        let mut leg_coord = [0; LEG_SLOTS];
        for (k, name) in LEG_JOINT_NAMES.iter().enumerate() {
            leg_coord[k] = model.joints[model.require_joint(name).unwrap()].coordinate;
        }
        let geometry = Geometry {
            model,
            legs: &legs,
            dof: model.dof(),
            q_template: &q_template,
            leg_coord: &leg_coord,
        };
        let library_path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../configs/gaits/adam_library.json"
        );
        let library = model::library::GaitLibrary::load(library_path).unwrap();
        let mut gaits = vec![setup.gait.clone()];
        gaits.extend(library.entries.iter().map(|e| e.gait.clone()));
        let h = 1e-4;
        for gait in &gaits {
            let table = GaitTable::new(gait, model, &legs).unwrap();
            for length_m in [gait.step_length_m, gait.step_length_m + 0.03] {
                let lever = StepLever::of(&geometry, &table, length_m).unwrap();
                let long = braking_touchdown(&geometry, &table, length_m + h).unwrap();
                let short = braking_touchdown(&geometry, &table, length_m - h).unwrap();
                let what = format!("{} m/s gait, step {length_m} m", gait.speed_mps);
                for i in 0..OUTPUTS {
                    let fd = (long.dy_end[i] - short.dy_end[i]) / (2.0 * h);
                    let exact = lever.dy_end_per_m[i];
                    assert!(
                        (exact - fd).abs() <= 1e-4 * (1.0 + fd.abs()),
                        "{what}: output {i}: exact {exact} rad/m, differences {fd} rad/m"
                    );
                }
                let fd = (long.theta_rad - short.theta_rad) / (2.0 * h);
                assert!(
                    (lever.theta_per_m - fd).abs() <= 1e-4 * (1.0 + fd.abs()),
                    "{what}: θ: exact {} rad/m, differences {fd} rad/m",
                    lever.theta_per_m
                );
                // The lever moves the touchdown: a longer step opens the legs.
                assert!(lever.dy_end_per_m.iter().any(|d| d.abs() > 0.1), "{what}");
            }
        }
    }
}
