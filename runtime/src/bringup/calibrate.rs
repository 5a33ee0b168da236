//! `adam calibrate`: measure each leg motor's direction and zero offset (and check its gear
//! ratio) with the robot hung on the boom and its legs clamped in the config's two jig poses.
//!
//! Per joint, with the jig angles `q_A`, `q_B` (`calibration.<joint>.jig_rad`), the motor's
//! mean angles `m_A`, `m_B` over `bringup.samples` zero-torque periods, and the configured gear
//! ratio `N`:
//! ```text
//! d  = sign((m_B − m_A) / (q_B − q_A))                  (the direction; ≠ configured: flipped)
//! N̂  = |m_B − m_A| / |q_B − q_A|                        (must be within 5 % of N)
//! o  = ½ [(q_A − d·m_A/N) + (q_B − d·m_B/N)]            (the zero offset)
//! play = |(q_A − d·m_A/N) − (q_B − d·m_B/N)|            (the two poses' disagreement)
//! ```
//! The motors are disabled (damping) while the jig moves between the poses.

use super::preflight::{targets, MotorTarget};
use crate::config::calibration::CalibrationConfig;
use crate::slots::LEG_SLOTS;
use crate::{Result, RuntimeError, Setup};
use core::time::Duration;
use drivers::a1::{Command, Reply};
use drivers::bus::{BusError, MotorBus, MotorSpec};
use std::fmt;

/// Largest relative difference between the measured and the configured gear ratio.
pub const GEAR_RATIO_TOLERANCE: f64 = 0.05;

/// Periods discarded after enabling, before averaging (the encoder's velocity filter and the
/// first replies settle).
const SETTLE_PERIODS: u32 = 5;

/// One of the jig's two poses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JigPose {
    /// Pose A (`jig_rad[0]`).
    A,
    /// Pose B (`jig_rad[1]`).
    B,
}

impl JigPose {
    /// Index into `jig_rad`.
    pub fn index(self) -> usize {
        match self {
            JigPose::A => 0,
            JigPose::B => 1,
        }
    }
}

/// What was measured and decided for one joint.
#[derive(Clone, Debug, PartialEq)]
pub struct JointOutcome {
    /// The motor.
    pub motor: MotorTarget,
    /// The jig's joint angles in pose A and B, rad.
    pub jig_rad: [f64; 2],
    /// The motor's mean angle in pose A and B, rad.
    pub motor_rad: [f64; 2],
    /// Direction in the config before.
    pub direction_before: i8,
    /// Direction measured.
    pub direction: i8,
    /// Gear ratio configured.
    pub gear_ratio: f64,
    /// Gear ratio measured, |m_B − m_A| / |q_B − q_A|.
    pub gear_ratio_measured: f64,
    /// Zero offset in the config before, rad.
    pub zero_offset_before_rad: f64,
    /// Zero offset measured, rad.
    pub zero_offset_rad: f64,
    /// The two poses' disagreement on the offset, rad.
    pub play_rad: f64,
}

impl JointOutcome {
    /// Whether the motor turns the other way than the config said.
    pub fn flipped(&self) -> bool {
        self.direction != self.direction_before
    }
}

/// The calibration measured, and the joints' details.
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrationOutcome {
    /// Per leg slot.
    pub joints: Vec<JointOutcome>,
    /// The config's calibration with the measured directions and offsets.
    pub calibration: CalibrationConfig,
}

impl CalibrationOutcome {
    /// The joints whose motor turns the other way than the config said, by name.
    pub fn flipped(&self) -> Vec<&str> {
        self.joints
            .iter()
            .filter(|j| j.flipped())
            .map(|j| j.motor.joint.as_str())
            .collect()
    }
}

impl fmt::Display for CalibrationOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{:<18} {:>3} {:>3} {:>10} {:>10} {:>9} {:>11} {:>16} {:>9}",
            "joint",
            "bus",
            "id",
            "motor A",
            "motor B",
            "direction",
            "gear ratio",
            "zero offset rad",
            "play deg"
        )?;
        for j in &self.joints {
            let direction = if j.flipped() {
                format!("{} → {}", j.direction_before, j.direction)
            } else {
                j.direction.to_string()
            };
            writeln!(
                f,
                "{:<18} {:>3} {:>3} {:>10.4} {:>10.4} {:>9} {:>5.3}/{:<5.3} {:>7.4} → {:<7.4} {:>8.3}",
                j.motor.joint,
                j.motor.spec.bus,
                j.motor.spec.id.get(),
                j.motor_rad[0],
                j.motor_rad[1],
                direction,
                j.gear_ratio_measured,
                j.gear_ratio,
                j.zero_offset_before_rad,
                j.zero_offset_rad,
                j.play_rad.to_degrees()
            )?;
        }
        let flipped = self.flipped();
        if flipped.is_empty() {
            writeln!(f, "no motor flipped")
        } else {
            writeln!(
                f,
                "FLIPPED (direction changed in the new config): {}",
                flipped.join(", ")
            )
        }
    }
}

/// The mean angle of each motor of `specs` over `samples` zero-torque periods (after
/// [`SETTLE_PERIODS`]), enabling and disabling the motors around it.
fn mean_angles<B: MotorBus>(
    bus: &mut B,
    targets: &[MotorTarget],
    samples: u32,
    budget: Duration,
) -> Result<Vec<f64>> {
    let specs: Vec<MotorSpec> = targets.iter().map(|t| t.spec).collect();
    let commands: Vec<Command> = specs.iter().map(|s| Command::damping(s.id, 0.0)).collect();
    let mut replies: Vec<Reply> = specs.iter().map(|s| Reply::zeroed(s.id)).collect();
    let mut sum = vec![0.0; specs.len()];
    let mut count = vec![0u32; specs.len()];
    bus.configure(&specs)?;
    bus.activate()?;
    for k in 0..SETTLE_PERIODS + samples {
        for r in replies.iter_mut() {
            r.q_rad = f64::NAN;
        }
        match bus.exchange(&commands, &mut replies, budget) {
            Ok(_) | Err(BusError::MissingReply { .. }) => {}
            Err(e) => {
                let _ = bus.deactivate();
                return Err(e.into());
            }
        }
        if k < SETTLE_PERIODS {
            continue;
        }
        for (i, r) in replies.iter().enumerate() {
            if r.q_rad.is_finite() {
                sum[i] += r.q_rad;
                count[i] += 1;
            }
        }
    }
    bus.deactivate()?;
    let mut silent = Vec::new();
    for (i, t) in targets.iter().enumerate() {
        if count[i] * 2 < samples {
            silent.push(format!(
                "\n  - motor {t}: {} replies in {samples} periods",
                count[i]
            ));
        }
    }
    if !silent.is_empty() {
        return Err(RuntimeError::Calibration {
            problems: silent.concat(),
        });
    }
    Ok(sum
        .iter()
        .zip(&count)
        .map(|(s, &n)| s / f64::from(n))
        .collect())
}

/// The calibration from the motors' angles in the two poses (leg slot order); errors name
/// every joint whose motor did not follow the jig as its gear ratio says.
pub fn solve(
    setup: &Setup,
    motors: &[MotorTarget],
    pose_a: &[f64],
    pose_b: &[f64],
) -> Result<CalibrationOutcome> {
    let before = &setup.config.calibration;
    let mut calibration = before.clone();
    let mut joints = Vec::with_capacity(LEG_SLOTS);
    let mut problems = String::new();
    for (k, ((_, c), new)) in before
        .joints()
        .into_iter()
        .zip(calibration.joints_mut())
        .enumerate()
    {
        let [qa, qb] = c.jig_rad;
        let (ma, mb) = (pose_a[k], pose_b[k]);
        let ratio = (mb - ma) / (qb - qa);
        let direction: i8 = if ratio < 0.0 { -1 } else { 1 };
        let d = f64::from(direction);
        let n = c.gear_ratio;
        let oa = qa - d * ma / n;
        let ob = qb - d * mb / n;
        let measured = ratio.abs();
        if !super::preflight::at_most((measured / n - 1.0).abs(), GEAR_RATIO_TOLERANCE) {
            problems.push_str(&format!(
                "\n  - {}: the motor moved {:.4} rad for the jig's {:.4} rad (gear ratio {:.3}, \
                 configured {n}): a motor on another joint, a slipping transmission, the jig \
                 not moved, or a wrong calibration.{}.gear_ratio",
                motors[k],
                (mb - ma).abs(),
                (qb - qa).abs(),
                measured,
                motors[k].joint
            ));
        }
        new.direction = direction;
        new.zero_offset_rad = 0.5 * (oa + ob);
        joints.push(JointOutcome {
            motor: motors[k].clone(),
            jig_rad: c.jig_rad,
            motor_rad: [ma, mb],
            direction_before: c.direction,
            direction,
            gear_ratio: n,
            gear_ratio_measured: measured,
            zero_offset_before_rad: c.zero_offset_rad,
            zero_offset_rad: new.zero_offset_rad,
            play_rad: (oa - ob).abs(),
        });
    }
    if !problems.is_empty() {
        return Err(RuntimeError::Calibration { problems });
    }
    calibration.validate("the measured calibration")?;
    calibration.check_against(&setup.model, "the measured calibration")?;
    Ok(CalibrationOutcome {
        joints,
        calibration,
    })
}

/// Calibrate the leg motors of `setup` on `bus` (not active): `place(pose, bus)` puts the legs
/// in the jig pose (the simulator sets the joints; on the robot the operator clamps the jig
/// and confirms), the motors are read at zero torque, then [`solve`].
pub fn calibrate<B: MotorBus>(
    setup: &Setup,
    bus: &mut B,
    mut place: impl FnMut(JigPose, &mut B) -> Result<()>,
) -> Result<CalibrationOutcome> {
    let motors = targets(&setup.config, false)?;
    let budget = Duration::from_secs_f64(setup.config.period_s());
    let samples = setup.config.bringup.samples;
    place(JigPose::A, bus)?;
    let a = mean_angles(bus, &motors, samples, budget)?;
    place(JigPose::B, bus)?;
    let b = mean_angles(bus, &motors, samples, budget)?;
    solve(setup, &motors, &a, &b)
}
