//! The `[bringup]` section: what the pre-flight checks accept before any gain comes on
//! ([`crate::bringup::preflight()`]), and how fast the gains come on after Start.

use crate::{Result, RuntimeError};
use serde::{Deserialize, Serialize};

/// Pre-flight limits and the gains ramp.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BringupConfig {
    /// Control periods the pre-flight listens to the motors and the IMU with zero torque.
    #[serde(default = "default_samples")]
    pub samples: u32,
    /// Largest distance of each leg joint from the gait's first pose (the pose Start ramps
    /// to), rad, model side.
    #[serde(default = "default_start_pose_tolerance_rad")]
    pub start_pose_tolerance_rad: f64,
    /// Largest |torso pitch| the IMU's accelerometer may read before Start, rad (the robot
    /// hangs upright on the boom).
    #[serde(default = "default_max_start_pitch_rad")]
    pub max_start_pitch_rad: f64,
    /// Largest | ‖a‖ − g | of the IMU's accelerometer at rest, m/s² (a still robot reads
    /// gravity alone).
    #[serde(default = "default_max_still_accel_error_mps2")]
    pub max_still_accel_error_mps2: f64,
    /// Fewest fresh IMU samples, as a fraction of `samples`, for the IMU to count as alive.
    #[serde(default = "default_min_imu_fraction")]
    pub min_imu_fraction: f64,
    /// Largest share of the control period the busiest bus may take per exchange, measured
    /// during the pre-flight (the timing model, `drivers::timing`, bounds our own traffic; more
    /// means another node on the bus or a wrong bitrate).
    #[serde(default = "default_max_bus_load")]
    pub max_bus_load: f64,
    /// The gains (kp, kd of every driven motor) ramp from 0 to their configured values over
    /// this time after Start, s (0: at once).
    #[serde(default)]
    pub gains_ramp_s: f64,
}

fn default_max_bus_load() -> f64 {
    0.9
}

fn default_samples() -> u32 {
    50
}

fn default_start_pose_tolerance_rad() -> f64 {
    0.35
}

fn default_max_start_pitch_rad() -> f64 {
    0.25
}

fn default_max_still_accel_error_mps2() -> f64 {
    1.5
}

fn default_min_imu_fraction() -> f64 {
    0.8
}

impl Default for BringupConfig {
    fn default() -> Self {
        Self {
            samples: default_samples(),
            start_pose_tolerance_rad: default_start_pose_tolerance_rad(),
            max_start_pitch_rad: default_max_start_pitch_rad(),
            max_still_accel_error_mps2: default_max_still_accel_error_mps2(),
            min_imu_fraction: default_min_imu_fraction(),
            max_bus_load: default_max_bus_load(),
            gains_ramp_s: 0.0,
        }
    }
}

impl BringupConfig {
    /// Checked ranges; errors name `origin`, the field (`bringup.<field>`) and the value.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let bad = |field: &str, value: String, reason: &str| RuntimeError::InvalidField {
            origin: origin.to_string(),
            field: format!("bringup.{field}"),
            value,
            reason: reason.to_string(),
        };
        if !(1..=10_000).contains(&self.samples) {
            return Err(bad(
                "samples",
                self.samples.to_string(),
                "must be in 1..=10000 control periods",
            ));
        }
        for (field, v, hi) in [
            (
                "start_pose_tolerance_rad",
                self.start_pose_tolerance_rad,
                core::f64::consts::PI,
            ),
            (
                "max_start_pitch_rad",
                self.max_start_pitch_rad,
                core::f64::consts::FRAC_PI_2,
            ),
            (
                "max_still_accel_error_mps2",
                self.max_still_accel_error_mps2,
                9.81,
            ),
            ("min_imu_fraction", self.min_imu_fraction, 1.0),
            ("max_bus_load", self.max_bus_load, 1.0),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= hi) {
                return Err(bad(field, v.to_string(), &format!("must be in (0, {hi}]")));
            }
        }
        if !(self.gains_ramp_s.is_finite() && (0.0..=10.0).contains(&self.gains_ramp_s)) {
            return Err(bad(
                "gains_ramp_s",
                self.gains_ramp_s.to_string(),
                "must be in [0, 10] s",
            ));
        }
        Ok(())
    }
}
