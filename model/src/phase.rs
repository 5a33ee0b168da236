//! The phase variable τ that parametrizes the desired outputs.
//!
//! State-based (the HZD choice, time-invariant): θ(q) is the angle of the stance leg, the line
//! from the stance foot to the stance hip, measured from the vertical, positive when the hip is
//! ahead of the foot (+x): `θ = atan2(x_hip − x_foot, z_hip − z_foot)`. It grows monotonically over
//! a forward step, from θ⁺ just after impact to θ⁻ just before the next, and
//! `τ(q) = (θ(q) − θ⁺) / (θ⁻ − θ⁺)` runs from 0 to 1.
//! Time-based: `τ = t / T` with T the step duration.

use crate::kinematics::BodyStates;
use crate::robot::{Legs, PlanarModel, Side};
use crate::{Real, Result};

impl PlanarModel {
    /// Stance-leg angle θ from computed body states, rad. Never allocates.
    pub fn stance_leg_angle_in<S: Real>(&self, st: &BodyStates<S>, legs: &Legs, stance: Side) -> S {
        let leg = legs.side(stance);
        let hip = st.pose[self.joints[leg.hip].body].xz_m;
        let foot = self.frame_position_in(st, leg.foot);
        (hip[0] - foot[0]).atan2(hip[1] - foot[1])
    }

    /// Stance-leg angle θ(q), rad. Never allocates.
    pub fn stance_leg_angle<S: Real>(&self, q: &[S], legs: &Legs, stance: Side) -> Result<S> {
        let mut st = BodyStates::zeroed();
        self.body_poses_into(q, &mut st)?;
        Ok(self.stance_leg_angle_in(&st, legs, stance))
    }

    /// θ(q) and its rate θ̇ = (∂θ/∂q) q̇, rad and rad/s. Never allocates.
    pub fn stance_leg_angle_rate<S: Real>(
        &self,
        q: &[S],
        dq: &[S],
        legs: &Legs,
        stance: Side,
    ) -> Result<(S, S)> {
        let mut st = BodyStates::zeroed();
        self.body_states_into(q, dq, &mut st)?;
        let leg = legs.side(stance);
        let hip_body = self.joints[leg.hip].body;
        let hip = st.pose[hip_body].xz_m;
        let foot = self.frame_position_in(&st, leg.foot);
        let vh = st.vel_xz[hip_body];
        let vf = self.frame_velocity_in(&st, leg.foot);
        let (dx, dz) = (hip[0] - foot[0], hip[1] - foot[1]);
        let (vx, vz) = (vh[0] - vf[0], vh[1] - vf[1]);
        // d/dt atan2(dx, dz) = (dz·vx − dx·vz) / (dx² + dz²)
        let rate = (dz * vx - dx * vz) / (dx * dx + dz * dz);
        Ok((dx.atan2(dz), rate))
    }
}

/// θ, θ̇ and θ̈ of the stance-leg angle along (q, q̇, q̈), rad, rad/s, rad/s².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngleDerivatives<S> {
    /// θ, rad.
    pub theta: S,
    /// θ̇, rad/s.
    pub rate: S,
    /// θ̈, rad/s².
    pub accel: S,
}

impl PlanarModel {
    /// θ, θ̇ and θ̈ of the stance-leg angle, for the planner's output dynamics. Never allocates.
    pub fn stance_leg_angle_derivatives<S: Real>(
        &self,
        q: &[S],
        dq: &[S],
        ddq: &[S],
        legs: &Legs,
        stance: Side,
    ) -> Result<AngleDerivatives<S>> {
        let mut st = BodyStates::zeroed();
        self.body_states_into(q, dq, &mut st)?;
        self.stance_leg_angle_derivatives_in(&st, ddq, legs, stance)
    }

    /// [`Self::stance_leg_angle_derivatives`] from body states already computed at (q, q̇) by
    /// [`Self::body_states_into`]. Only hip-to-foot differences enter, so states computed with
    /// any base position and base linear velocity (and q̈ with any base linear acceleration)
    /// give the same angle and derivatives up to rounding. Never allocates.
    pub fn stance_leg_angle_derivatives_in<S: Real>(
        &self,
        st: &BodyStates<S>,
        ddq: &[S],
        legs: &Legs,
        stance: Side,
    ) -> Result<AngleDerivatives<S>> {
        if ddq.len() != self.dof() {
            return Err(crate::ModelError::Dimension {
                what: "ddq",
                expected: self.dof(),
                found: ddq.len(),
            });
        }
        let leg = legs.side(stance);
        let hip_body = self.joints[leg.hip].body;
        let foot = self.frame_position_in(st, leg.foot);
        let hip = st.pose[hip_body].xz_m;
        let acc = |body: usize, p: [S; 2], bias: [S; 2]| {
            let mut a = bias;
            self.point_jacobian_into(st, body, p, |r, c, v| a[r] += v * ddq[c]);
            a
        };
        let a_hip = acc(hip_body, hip, st.bias_acc_xz[hip_body]);
        let a_foot = acc(
            self.frames[leg.foot].body,
            foot,
            self.frame_bias_acceleration_in(st, leg.foot),
        );
        let v_hip = st.vel_xz[hip_body];
        let v_foot = self.frame_velocity_in(st, leg.foot);
        let r = [hip[0] - foot[0], hip[1] - foot[1]];
        let v = [v_hip[0] - v_foot[0], v_hip[1] - v_foot[1]];
        let a = [a_hip[0] - a_foot[0], a_hip[1] - a_foot[1]];
        let rho2 = r[0] * r[0] + r[1] * r[1];
        let rate = (r[1] * v[0] - r[0] * v[1]) / rho2;
        let accel =
            (r[1] * a[0] - r[0] * a[1]) / rho2 - rate * (r[0] * v[0] + r[1] * v[1]) * 2.0 / rho2;
        Ok(AngleDerivatives {
            theta: r[0].atan2(r[1]),
            rate,
            accel,
        })
    }

    /// Height of the swing foot above the ground (z = 0), z_nsf(q), m. Never allocates.
    pub fn swing_foot_height<S: Real>(&self, q: &[S], legs: &Legs, swing: Side) -> Result<S> {
        let mut st = BodyStates::zeroed();
        self.body_poses_into(q, &mut st)?;
        Ok(self.frame_position_in(&st, legs.side(swing).foot)[1])
    }
}

/// State-based phase τ = (θ − θ⁺) / (θ⁻ − θ⁺).
#[inline]
pub fn state_phase<S: Real>(theta_rad: S, theta_plus_rad: f64, theta_minus_rad: f64) -> S {
    (theta_rad - theta_plus_rad) / (theta_minus_rad - theta_plus_rad)
}

/// Time-based phase τ = t / T.
#[inline]
pub fn time_phase<S: Real>(t_s: S, step_duration_s: f64) -> S {
    t_s / step_duration_s
}
