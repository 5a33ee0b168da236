//! The joints the simulated motors drive: the [`JointPlant`] trait (positions and velocities
//! out, torques in) and the simplest plant, [`InertiaDampingPlant`] (independent rigid joints).
//! The whole robot, [`crate::sim::robot::RobotSim`], is a `JointPlant` too.

/// The mechanics the motors drive: joint positions and velocities, torques in.
///
/// Implement this for the robot simulator to put the whole robot behind a [`crate::sim::bus::SimBus`].
pub trait JointPlant {
    /// Number of joints.
    fn joint_count(&self) -> usize;
    /// Joint position \[rad\].
    fn position_rad(&self, joint: usize) -> f64;
    /// Joint velocity \[rad/s\].
    fn velocity_rad_s(&self, joint: usize) -> f64;
    /// Advance by `dt_s` with `torque_nm[j]` applied to joint `j`, held constant.
    /// `torque_nm.len() == joint_count()`; joints without a motor get zero.
    fn step(&mut self, torque_nm: &[f64], dt_s: f64);
}

impl<P: JointPlant + ?Sized> JointPlant for Box<P> {
    fn joint_count(&self) -> usize {
        (**self).joint_count()
    }
    fn position_rad(&self, joint: usize) -> f64 {
        (**self).position_rad(joint)
    }
    fn velocity_rad_s(&self, joint: usize) -> f64 {
        (**self).velocity_rad_s(joint)
    }
    fn step(&mut self, torque_nm: &[f64], dt_s: f64) {
        (**self).step(torque_nm, dt_s)
    }
}

/// One independent joint: `J q̈ = τ + τ_load − b q̇`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidJoint {
    /// Inertia about the joint axis, reflected rotor included \[kg·m²\].
    pub inertia_kg_m2: f64,
    /// Viscous friction \[N·m·s/rad\].
    pub damping_nm_s_per_rad: f64,
    /// Constant external torque, e.g. a gravity load \[N·m\].
    pub load_torque_nm: f64,
}

/// Independent rigid joints, integrated exactly for a torque held over each step.
#[derive(Debug, Clone, PartialEq)]
pub struct InertiaDampingPlant {
    joints: Vec<RigidJoint>,
    q_rad: Vec<f64>,
    dq_rad_s: Vec<f64>,
}

impl InertiaDampingPlant {
    /// Joints at rest at zero; `None` if an inertia is not positive or a damping negative.
    pub fn new(joints: Vec<RigidJoint>) -> Option<Self> {
        let valid = joints.iter().all(|j| {
            j.inertia_kg_m2 > 0.0
                && j.inertia_kg_m2.is_finite()
                && j.damping_nm_s_per_rad >= 0.0
                && j.damping_nm_s_per_rad.is_finite()
                && j.load_torque_nm.is_finite()
        });
        valid.then(|| Self {
            q_rad: vec![0.0; joints.len()],
            dq_rad_s: vec![0.0; joints.len()],
            joints,
        })
    }

    /// Set one joint's state.
    pub fn set_state(&mut self, joint: usize, q_rad: f64, dq_rad_s: f64) {
        self.q_rad[joint] = q_rad;
        self.dq_rad_s[joint] = dq_rad_s;
    }

    /// Change one joint's external load.
    pub fn set_load(&mut self, joint: usize, load_torque_nm: f64) {
        self.joints[joint].load_torque_nm = load_torque_nm;
    }
}

impl JointPlant for InertiaDampingPlant {
    fn joint_count(&self) -> usize {
        self.joints.len()
    }
    fn position_rad(&self, joint: usize) -> f64 {
        self.q_rad[joint]
    }
    fn velocity_rad_s(&self, joint: usize) -> f64 {
        self.dq_rad_s[joint]
    }
    fn step(&mut self, torque_nm: &[f64], dt_s: f64) {
        for (j, joint) in self.joints.iter().enumerate() {
            let u = torque_nm.get(j).copied().unwrap_or(0.0) + joint.load_torque_nm;
            let (q0, v0) = (self.q_rad[j], self.dq_rad_s[j]);
            let rate = joint.damping_nm_s_per_rad / joint.inertia_kg_m2;
            if rate * dt_s > 1e-9 {
                // v(t) = v∞ + (v0 − v∞) e^{−rate t},  v∞ = u / b.
                let v_inf = u / joint.damping_nm_s_per_rad;
                let decay = (-rate * dt_s).exp();
                self.dq_rad_s[j] = v_inf + (v0 - v_inf) * decay;
                self.q_rad[j] = q0 + v_inf * dt_s + (v0 - v_inf) * (1.0 - decay) / rate;
            } else {
                let a = (u - joint.damping_nm_s_per_rad * v0) / joint.inertia_kg_m2;
                self.dq_rad_s[j] = v0 + a * dt_s;
                self.q_rad[j] = q0 + v0 * dt_s + 0.5 * a * dt_s * dt_s;
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn joint(load: f64) -> RigidJoint {
        RigidJoint {
            inertia_kg_m2: 0.05,
            damping_nm_s_per_rad: 0.05,
            load_torque_nm: load,
        }
    }

    #[test]
    fn plant_step_matches_the_analytic_solution() {
        // From rest under constant u: v(t) = u/b (1 − e^{−bt/J}),
        // q(t) = u/b (t − J/b (1 − e^{−bt/J})). One big step vs the formula at t = 0.3 s.
        let mut p = InertiaDampingPlant::new(vec![RigidJoint {
            inertia_kg_m2: 0.2,
            damping_nm_s_per_rad: 0.5,
            load_torque_nm: -1.0,
        }])
        .unwrap();
        p.step(&[3.0], 0.3);
        let (u, b, j, t): (f64, f64, f64, f64) = (2.0, 0.5, 0.2, 0.3);
        let v = u / b * (1.0 - (-b * t / j).exp());
        let q = u / b * (t - j / b * (1.0 - (-b * t / j).exp()));
        assert!((p.velocity_rad_s(0) - v).abs() < 1e-12);
        assert!((p.position_rad(0) - q).abs() < 1e-12);
        // Splitting the step changes nothing (exact discretization), up to rounding.
        let mut p2 = InertiaDampingPlant::new(vec![RigidJoint {
            inertia_kg_m2: 0.2,
            damping_nm_s_per_rad: 0.5,
            load_torque_nm: -1.0,
        }])
        .unwrap();
        for _ in 0..3000 {
            p2.step(&[3.0], 1e-4);
        }
        assert!((p2.position_rad(0) - q).abs() < 1e-9);
        // No damping: constant acceleration.
        let mut p3 = InertiaDampingPlant::new(vec![RigidJoint {
            inertia_kg_m2: 0.5,
            damping_nm_s_per_rad: 0.0,
            load_torque_nm: 0.0,
        }])
        .unwrap();
        p3.step(&[1.0], 2.0);
        assert_eq!((p3.position_rad(0), p3.velocity_rad_s(0)), (4.0, 4.0));
        assert!(InertiaDampingPlant::new(vec![RigidJoint {
            inertia_kg_m2: 0.0,
            ..joint(0.0)
        }])
        .is_none());
    }
}
