//! The simulated robot's configuration ([`RobotSimConfig`], the optional [`Boom`]), its checks,
//! and the standing pose the simulation starts from.

use super::{Result, RobotSimError};
use model::{ModelError, PlanarModel, Side};

/// Mass properties the boom adds to the torso.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boom {
    /// Added mass \[kg\].
    pub mass_kg: f64,
    /// Where that mass acts, in the torso frame (x, z) \[m\].
    pub com_xz_m: [f64; 2],
    /// Added pitch inertia about that point \[kg·m²\].
    pub inertia_yy_kgm2: f64,
}

/// Configuration of a [`RobotSim`](super::RobotSim).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotSimConfig {
    /// Integration rate \[Hz\]; `JointPlant::step(dt)` takes `round(dt · rate)` equal steps.
    pub rate_hz: f64,
    /// Treadmill belt speed at the start, positive when the belt surface moves backwards
    /// \[m/s\] (later changes: [`RobotSim::set_belt_target_speed`](super::RobotSim::set_belt_target_speed),
    /// [`RobotSim::set_belt_speed`](super::RobotSim::set_belt_speed)).
    pub belt_speed_mps: f64,
    /// Length of the belt \[m\]: the robot starts at its centre and a stance foot beyond either
    /// end is a fall ([`FallCause::OffBelt`](super::FallCause::OffBelt)); `f64::INFINITY`: an
    /// endless belt.
    pub belt_length_m: f64,
    /// Acceleration of the belt's ramps toward a new target speed \[m/s²\].
    pub belt_acceleration_mps2: f64,
    /// The boom's added mass, or `None` (default: the paper did not model it).
    pub boom: Option<Boom>,
    /// Friction coefficient μ for the friction report.
    pub friction_coefficient: f64,
    /// Torso pitch beyond which the robot has fallen \[rad\].
    pub fall_pitch_limit_rad: f64,
    /// Hip height of the initial standing pose \[m\] (`None`: 92 % of the leg length).
    pub stand_hip_height_m: Option<f64>,
    /// Horizontal distance of each foot from the hip in the initial standing pose \[m\].
    pub stand_half_stance_m: f64,
    /// Integration steps that share one evaluation of `D`, `H`, the factor of `D` and the contact
    /// operator (see the robot module docs, "Multi-rate dynamics"): 1 re-evaluates them every step
    /// (the exact path); the default 10 evaluates them once per millisecond at 10 kHz.
    pub dynamics_refresh_substeps: u32,
}

/// The belt's length by default \[m\].
pub const DEFAULT_BELT_LENGTH_M: f64 = 1.6;

/// The belt's ramp acceleration by default \[m/s²\].
pub const DEFAULT_BELT_ACCELERATION_MPS2: f64 = 0.5;

impl Default for RobotSimConfig {
    fn default() -> Self {
        Self {
            rate_hz: 10_000.0,
            belt_speed_mps: 0.0,
            belt_length_m: DEFAULT_BELT_LENGTH_M,
            belt_acceleration_mps2: DEFAULT_BELT_ACCELERATION_MPS2,
            boom: None,
            friction_coefficient: 1.0,
            fall_pitch_limit_rad: 1.0,
            stand_hip_height_m: None,
            stand_half_stance_m: 0.08,
            dynamics_refresh_substeps: 10,
        }
    }
}

pub(super) fn validate(c: &RobotSimConfig) -> Result<()> {
    let bad = |field, value, reason| {
        Err(RobotSimError::Config {
            field,
            value,
            reason,
        })
    };
    if !(c.rate_hz.is_finite() && c.rate_hz > 0.0) {
        return bad("rate_hz", c.rate_hz, "must be positive and finite");
    }
    if !c.belt_speed_mps.is_finite() {
        return bad("belt_speed_mps", c.belt_speed_mps, "must be finite");
    }
    if c.belt_length_m.is_nan() || c.belt_length_m <= 0.0 {
        return bad(
            "belt_length_m",
            c.belt_length_m,
            "must be positive (infinite: an endless belt)",
        );
    }
    if !(c.belt_acceleration_mps2.is_finite() && c.belt_acceleration_mps2 > 0.0) {
        return bad(
            "belt_acceleration_mps2",
            c.belt_acceleration_mps2,
            "must be positive and finite",
        );
    }
    if c.friction_coefficient.is_nan() || c.friction_coefficient < 0.0 {
        return bad(
            "friction_coefficient",
            c.friction_coefficient,
            "must be ≥ 0",
        );
    }
    if c.fall_pitch_limit_rad.is_nan() || c.fall_pitch_limit_rad <= 0.0 {
        return bad(
            "fall_pitch_limit_rad",
            c.fall_pitch_limit_rad,
            "must be positive",
        );
    }
    if c.dynamics_refresh_substeps == 0 {
        return bad(
            "dynamics_refresh_substeps",
            f64::from(c.dynamics_refresh_substeps),
            "must be ≥ 1",
        );
    }
    if !(c.stand_half_stance_m.is_finite() && c.stand_half_stance_m >= 0.0) {
        return bad(
            "stand_half_stance_m",
            c.stand_half_stance_m,
            "must be ≥ 0 and finite",
        );
    }
    if let Some(h) = c.stand_hip_height_m {
        if !(h.is_finite() && h > 0.0) {
            return bad("stand_hip_height_m", h, "must be positive and finite");
        }
    }
    if let Some(b) = c.boom {
        for (field, value) in [
            ("boom.mass_kg", b.mass_kg),
            ("boom.inertia_yy_kgm2", b.inertia_yy_kgm2),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return bad(field, value, "must be ≥ 0 and finite");
            }
        }
        for value in b.com_xz_m {
            if !value.is_finite() {
                return bad("boom.com_xz_m", value, "must be finite");
            }
        }
    }
    Ok(())
}

/// A standing pose: torso upright, hip axis at `hip_height_m` above the ground (`None`: 92 % of
/// the leg length), the left foot `half_stance_m` ahead of the hip and the right foot as far
/// behind, both on the ground, knees flexed. Solved by Newton's method on the model's own
/// kinematics, so it holds for any design.
pub fn standing_pose(
    model: &PlanarModel,
    hip_height_m: Option<f64>,
    half_stance_m: f64,
) -> Result<Vec<f64>> {
    let legs = model.legs()?;
    let mut q = model.nominal_pose()?;
    q[0] = 0.0;
    q[1] = 0.0;
    q[2] = 0.0;
    let (thigh, shin) = model.leg_lengths(&q, Side::Left)?;
    let height = hip_height_m.unwrap_or(0.92 * (thigh + shin));
    q[1] = height;
    for (side, dx) in [(Side::Left, half_stance_m), (Side::Right, -half_stance_m)] {
        let leg = legs.side(side);
        let (ch, ck) = (
            model.joints[leg.hip].coordinate,
            model.joints[leg.knee].coordinate,
        );
        q[ch] = -0.4;
        q[ck] = 0.8;
        let target = [dx, 0.0];
        for _ in 0..50 {
            let p = model.frame_position(&q, leg.foot)?;
            let e = [p[0] - target[0], p[1] - target[1]];
            if e[0].abs().max(e[1].abs()) < 1e-12 {
                break;
            }
            let eps = 1e-7;
            let mut jac = [[0.0; 2]; 2];
            for (col, &c) in [ch, ck].iter().enumerate() {
                let mut qp = q.clone();
                qp[c] += eps;
                let pp = model.frame_position(&qp, leg.foot)?;
                jac[0][col] = (pp[0] - p[0]) / eps;
                jac[1][col] = (pp[1] - p[1]) / eps;
            }
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            if det.abs() < 1e-12 {
                return Err(ModelError::Singular {
                    what: "standing pose inverse kinematics",
                }
                .into());
            }
            q[ch] -= (jac[1][1] * e[0] - jac[0][1] * e[1]) / det;
            q[ck] -= (-jac[1][0] * e[0] + jac[0][0] * e[1]) / det;
        }
        let p = model.frame_position(&q, leg.foot)?;
        if (p[0] - target[0]).abs() > 1e-9 || p[1].abs() > 1e-9 {
            return Err(RobotSimError::Config {
                field: "stand_hip_height_m",
                value: height,
                reason: "the feet cannot reach the ground at this height and stance",
            });
        }
    }
    Ok(q)
}
