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
        let st = self.body_poses(q)?;
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
        let st = self.body_states(q, dq)?;
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
