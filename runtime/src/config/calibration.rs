//! The `[calibration]` section: how each leg motor's shaft maps to its model joint (zero offset,
//! direction, gear ratio), and the two jig poses `adam calibrate` measures them in.
//!
//! ```text
//! joint angle q = direction · m / gear_ratio + zero_offset_rad      (m: the A1's output angle)
//! joint rate  q̇ = direction · ṁ / gear_ratio
//! joint torque τ = direction · gear_ratio · τ_m                     (power τ·q̇ = τ_m·ṁ)
//! gains        kp_m = kp / gear_ratio²,  kd_m = kd / gear_ratio²
//! ```
//! The runtime applies it in one place, [`crate::slots::SlotLayout`] (allocation-free
//! arithmetic), where motor readings become joint angles and joint commands become motor
//! commands. `gear_ratio` is a transmission *between* the A1's output shaft and the joint (a belt
//! or linkage); the A1's own 9.1:1 gearbox is inside the motor, whose reported angles are
//! already at its output, so a joint driven directly by an A1 has `gear_ratio = 1`.
//!
//! # Checks
//! Per joint: `direction` is 1 or −1; `gear_ratio` in [[`MIN_GEAR_RATIO`], [`MAX_GEAR_RATIO`]];
//! `zero_offset_rad` finite and within ±2π; the two jig angles finite and at least
//! [`MIN_JIG_SPAN_RAD`] apart (one pose cannot tell the direction: see `adam calibrate`).
//! Against the robot ([`CalibrationConfig::check_against`], when the URDF is known): the jig
//! angles inside the joint's URDF limits (a jig past a limit is not a pose of this robot, and a
//! calibration measured in it would shift every command past the limit), and the joint's whole
//! URDF range reachable by the A1's position field (±12.5 rad at the output): otherwise a
//! command inside the limits would be clamped by the codec to another angle.

use crate::{Result, RuntimeError};
use serde::{Deserialize, Serialize};

/// Smallest gear ratio accepted (output turns of the A1 per joint turn).
pub const MIN_GEAR_RATIO: f64 = 0.1;
/// Largest gear ratio accepted.
pub const MAX_GEAR_RATIO: f64 = 10.0;
/// Smallest difference between a joint's two jig angles, rad: below it the measured direction
/// and gear ratio would drown in the jig's own play.
pub const MIN_JIG_SPAN_RAD: f64 = 0.2;

/// One leg joint's calibration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointCalibration {
    /// The joint angle when the motor reads zero, rad (model side).
    #[serde(default)]
    pub zero_offset_rad: f64,
    /// +1 when the motor's positive sense is the joint's, −1 when mounted the other way.
    #[serde(default = "plus_one")]
    pub direction: i8,
    /// Motor output turns per joint turn of the transmission between them (1: direct drive).
    #[serde(default = "unit_ratio")]
    pub gear_ratio: f64,
    /// The joint angle in jig pose A and in jig pose B, rad (model side), where
    /// `adam calibrate` measures.
    #[serde(default = "default_jig")]
    pub jig_rad: [f64; 2],
}

fn plus_one() -> i8 {
    1
}

fn unit_ratio() -> f64 {
    1.0
}

fn default_jig() -> [f64; 2] {
    [0.2, 1.0]
}

impl Default for JointCalibration {
    fn default() -> Self {
        Self {
            zero_offset_rad: 0.0,
            direction: 1,
            gear_ratio: 1.0,
            jig_rad: default_jig(),
        }
    }
}

impl JointCalibration {
    /// The direction as a factor (±1.0).
    pub fn direction_factor(&self) -> f64 {
        f64::from(self.direction)
    }

    /// The joint angle of motor angle `motor_rad`, rad.
    pub fn joint_rad(&self, motor_rad: f64) -> f64 {
        self.direction_factor() * motor_rad / self.gear_ratio + self.zero_offset_rad
    }

    /// The motor angle of joint angle `joint_rad`, rad.
    pub fn motor_rad(&self, joint_rad: f64) -> f64 {
        (joint_rad - self.zero_offset_rad) * self.gear_ratio * self.direction_factor()
    }
}

/// The `[calibration]` section: one table per leg joint, named by its URDF joint
/// (`[calibration.left_knee_pitch]`); an absent table is the identity (offset 0, direction 1,
/// gear ratio 1).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationConfig {
    /// Left hip pitch (leg slot 0).
    #[serde(default)]
    pub left_hip_pitch: JointCalibration,
    /// Left knee pitch (leg slot 1).
    #[serde(default)]
    pub left_knee_pitch: JointCalibration,
    /// Right hip pitch (leg slot 2).
    #[serde(default)]
    pub right_hip_pitch: JointCalibration,
    /// Right knee pitch (leg slot 3).
    #[serde(default)]
    pub right_knee_pitch: JointCalibration,
}

impl CalibrationConfig {
    /// The joints in leg slot order, with their URDF names.
    pub fn joints(&self) -> [(&'static str, &JointCalibration); 4] {
        [
            ("left_hip_pitch", &self.left_hip_pitch),
            ("left_knee_pitch", &self.left_knee_pitch),
            ("right_hip_pitch", &self.right_hip_pitch),
            ("right_knee_pitch", &self.right_knee_pitch),
        ]
    }

    /// The joints in leg slot order, mutable.
    pub fn joints_mut(&mut self) -> [&mut JointCalibration; 4] {
        [
            &mut self.left_hip_pitch,
            &mut self.left_knee_pitch,
            &mut self.right_hip_pitch,
            &mut self.right_knee_pitch,
        ]
    }

    /// Checked ranges; errors name `origin`, the field (`calibration.<joint>.<field>`) and the
    /// value.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let bad = |field: String, value: String, reason: &str| RuntimeError::InvalidField {
            origin: origin.to_string(),
            field,
            value,
            reason: reason.to_string(),
        };
        for (name, j) in self.joints() {
            let field = |f: &str| format!("calibration.{name}.{f}");
            if j.direction != 1 && j.direction != -1 {
                return Err(bad(
                    field("direction"),
                    j.direction.to_string(),
                    "must be 1 or -1",
                ));
            }
            if !(j.gear_ratio.is_finite()
                && (MIN_GEAR_RATIO..=MAX_GEAR_RATIO).contains(&j.gear_ratio))
            {
                return Err(bad(
                    field("gear_ratio"),
                    j.gear_ratio.to_string(),
                    &format!(
                        "must be in [{MIN_GEAR_RATIO}, {MAX_GEAR_RATIO}] (motor output turns per \
                         joint turn; 1 = the A1 drives the joint directly)"
                    ),
                ));
            }
            if !(j.zero_offset_rad.is_finite() && j.zero_offset_rad.abs() <= core::f64::consts::TAU)
            {
                return Err(bad(
                    field("zero_offset_rad"),
                    j.zero_offset_rad.to_string(),
                    "must be finite and within ±2π rad",
                ));
            }
            let [a, b] = j.jig_rad;
            if !(a.is_finite() && b.is_finite()) {
                return Err(bad(
                    field("jig_rad"),
                    format!("[{a}, {b}]"),
                    "must be finite (the joint angle in jig pose A and B, rad)",
                ));
            }
            if (b - a).abs() < MIN_JIG_SPAN_RAD {
                return Err(bad(
                    field("jig_rad"),
                    format!("[{a}, {b}]"),
                    &format!(
                        "the two jig angles must be at least {MIN_JIG_SPAN_RAD} rad apart: one \
                         pose cannot tell a flipped motor from an offset one"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Checks against the robot: each jig angle inside the joint's URDF limits, and the joint's
    /// URDF range inside what the A1's position field can command (±12.5 rad at the output).
    /// Errors name `origin`, the field, the value and the limits.
    pub fn check_against(&self, model: &model::PlanarModel, origin: &str) -> Result<()> {
        let q_range = drivers::a1::codec::Q_RANGE_RAD;
        for (name, j) in self.joints() {
            let joint = &model.joints[model.require_joint(name)?];
            let (lower, upper) = (joint.lower, joint.upper);
            let bad = |field: &str, value: String, reason: String| RuntimeError::InvalidField {
                origin: origin.to_string(),
                field: format!("calibration.{name}.{field}"),
                value,
                reason,
            };
            for (pose, q) in ["A", "B"].iter().zip(j.jig_rad) {
                if !(lower..=upper).contains(&q) {
                    return Err(bad(
                        "jig_rad",
                        format!("[{}, {}]", j.jig_rad[0], j.jig_rad[1]),
                        format!(
                            "jig pose {pose} puts {name} at {q} rad, past its URDF limits \
                             [{lower}, {upper}] rad"
                        ),
                    ));
                }
            }
            let (m_lower, m_upper) = (j.motor_rad(lower), j.motor_rad(upper));
            let worst = m_lower.abs().max(m_upper.abs());
            if worst > q_range {
                return Err(bad(
                    "zero_offset_rad",
                    j.zero_offset_rad.to_string(),
                    format!(
                        "with direction {} and gear ratio {}, the URDF limits [{lower}, {upper}] \
                         rad of {name} need motor angles [{m_lower:.3}, {m_upper:.3}] rad, past \
                         the A1's ±{q_range} rad position field: a command inside the limits \
                         would be clamped to another joint angle",
                        j.direction, j.gear_ratio
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The section as TOML text (`[calibration.<joint>]` tables), for a config written by
    /// `adam calibrate`.
    pub fn to_toml_section(&self) -> String {
        let mut text = String::from(
            "# Joint calibration (runtime::config::calibration): joint angle = direction · motor angle /\n\
             # gear_ratio + zero_offset_rad; jig_rad = the joint's angle in jig pose A and B (adam calibrate).\n",
        );
        for (name, j) in self.joints() {
            text.push_str(&format!(
                "[calibration.{name}]\nzero_offset_rad = {:?}\ndirection = {}\ngear_ratio = {:?}\njig_rad = [{:?}, {:?}]\n\n",
                j.zero_offset_rad, j.direction, j.gear_ratio, j.jig_rad[0], j.jig_rad[1]
            ));
        }
        text
    }
}

/// `text` (a runtime config) with its `[calibration]` tables replaced by `calibration`'s: every
/// table header `[calibration]` or `[calibration.…]` and its lines are dropped, the rest is
/// kept as written (comments included, except those right above a calibration table), and the
/// new section is appended.
pub fn replace_section(text: &str, calibration: &CalibrationConfig) -> String {
    let mut out: Vec<&str> = Vec::new();
    let mut inside = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with('[') {
            let header = t.trim_start_matches('[').trim_start();
            inside = header.starts_with("calibration")
                && header["calibration".len()..]
                    .trim_start()
                    .starts_with(['.', ']']);
            if inside {
                // The comment block that introduces the table goes with it.
                while out.last().is_some_and(|l| l.trim_start().starts_with('#')) {
                    out.pop();
                }
            }
        }
        if !inside {
            out.push(line);
        }
    }
    while out.last().is_some_and(|l| l.trim().is_empty()) {
        out.pop();
    }
    let mut out = out.join("\n");
    out.push_str("\n\n");
    out.push_str(&calibration.to_toml_section());
    out
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn joint(offset: f64, direction: i8, ratio: f64) -> JointCalibration {
        JointCalibration {
            zero_offset_rad: offset,
            direction,
            gear_ratio: ratio,
            jig_rad: [0.2, 1.0],
        }
    }

    #[test]
    fn motor_and_joint_angles_invert_each_other() {
        for j in [joint(0.3, -1, 2.5), joint(-1.0, 1, 0.5), joint(0.0, 1, 1.0)] {
            for q in [-1.2, 0.0, 0.4, 2.1] {
                let back = j.joint_rad(j.motor_rad(q));
                assert!((back - q).abs() < 1e-12, "{j:?} {q} {back}");
            }
        }
        // Direct drive, no offset: the identity, bit for bit.
        let j = JointCalibration::default();
        assert_eq!(j.joint_rad(0.123_456_789), 0.123_456_789);
    }

    #[test]
    fn replacing_the_section_keeps_the_rest_and_parses_back() {
        let shipped = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../configs/runtime/adam.toml"
        ))
        .unwrap();
        let c = CalibrationConfig {
            left_knee_pitch: joint(0.25, -1, 1.0),
            ..CalibrationConfig::default()
        };
        let text = replace_section(&shipped, &c);
        let twice = replace_section(&text, &c);
        assert_eq!(text, twice, "replacing is idempotent");
        let parsed = crate::config::RuntimeConfig::from_toml(&text, "new.toml").unwrap();
        assert_eq!(parsed.calibration, c);
        assert!(text.contains("[gains]") && text.contains("[speed]"));
    }
}
