//! The runtime config (`configs/runtime/*.toml`): loop rate, buses, motors, gains, ramp,
//! safety limits, held joint positions, logging and telemetry, and the treadmill's belt speed
//! range ([`TreadmillConfig`]: every belt speed a run asks for is checked against it), and the
//! treadmill speed control's gains ([`SpeedConfig`]), the joint calibration
//! ([`CalibrationConfig`]), the bring-up's pre-flight limits and gains ramp ([`BringupConfig`]),
//! and the torso IMU's mounting and rates ([`ImuConfig`]).
//!
//! Checked data: `deny_unknown_fields` everywhere, a `schema_version`, and [`RuntimeConfig::validate`]
//! rejects NaN/inf, out-of-range values, duplicate motors and bus layouts that
//! [`drivers::timing::validate`] refuses, naming the file, the field and the value.

mod bringup;
pub mod calibration;
mod extends;
mod imu;
mod orbit;
mod speed;

pub use bringup::BringupConfig;
pub use calibration::{CalibrationConfig, JointCalibration};
pub use extends::{extends_chain, MAX_EXTENDS_DEPTH};
pub use imu::{ImuConfig, VN100_BAUD_RATES_BPS};
pub use orbit::OrbitConfig;
pub use speed::{PositionSource, SpeedConfig};

use crate::slots::{SlotLayout, LEG_SLOTS, MAX_HELD, SLOTS};
use crate::{Result, RuntimeError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The schema version this build reads.
pub const RUNTIME_CONFIG_VERSION: u32 = 1;

/// How the phase variable τ is computed at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhaseSource {
    /// τ from the stance-leg angle θ(q) with the gait's θ⁺/θ⁻ (HZD, time-invariant).
    StateBased,
    /// τ = (t − t_step) / T with the gait's step duration.
    TimeBased,
}

/// Loop timing and CAN layout.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoopConfig {
    /// Control rate, Hz.
    pub rate_hz: f64,
    /// CAN bitrate of every bus, bit/s.
    pub bitrate_bps: u32,
    /// Number of CAN buses; `motors[*].bus` indexes them.
    pub bus_count: usize,
    /// Consecutive overruns that trip the safety monitor.
    pub max_overrun_streak: u32,
    /// SCHED_FIFO priority to request (1..=99); 0 = do not ask.
    pub fifo_priority: i32,
    /// Lock memory with `mlockall` (a warning when not permitted).
    pub lock_memory: bool,
}

/// One motor: where it is on the CAN buses and how its shaft maps to the model joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorConfig {
    /// Joint name (URDF name for leg joints, free text for held joints).
    pub joint: String,
    /// Bus index, `0..bus_count`.
    pub bus: usize,
    /// A1 motor id on that bus (1..=127, unique over all buses).
    pub id: u8,
    /// Kept so that configs (and logs) written before `[calibration]` still read: must be 1;
    /// a leg joint's direction is `calibration.<joint>.direction`.
    #[serde(default = "one")]
    pub direction: f64,
    /// Kept like `direction`: must be 0; a leg joint's zero offset is
    /// `calibration.<joint>.zero_offset_rad`.
    #[serde(default)]
    pub offset_rad: f64,
}

impl MotorConfig {
    /// The motor's id and bus as the buses address it; `field` names this motor in the error
    /// (e.g. `leg_motors[2]`) if its id is out of range.
    pub fn spec(&self, field: &str) -> Result<drivers::bus::MotorSpec> {
        let id = drivers::a1::MotorId::new(self.id).ok_or_else(|| RuntimeError::InvalidField {
            origin: "runtime config".into(),
            field: format!("{field}.id"),
            value: self.id.to_string(),
            reason: "must be 1..=127".into(),
        })?;
        Ok(drivers::bus::MotorSpec { bus: self.bus, id })
    }
}

fn one() -> f64 {
    1.0
}

/// A joint outside the planar model, held still at a configured position.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeldJointConfig {
    /// The motor.
    pub motor: MotorConfig,
    /// Held position (motor side), rad.
    pub position_rad: f64,
    /// Stiffness, N·m/rad.
    pub kp_nm_per_rad: f64,
    /// Damping, N·m·s/rad.
    pub kd_nm_s_per_rad: f64,
    /// Largest deviation from `position_rad` before the safety monitor trips, rad.
    pub tolerance_rad: f64,
}

/// PD gains of the four leg joints, in slot order (left hip, left knee, right hip, right knee).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GainsConfig {
    /// Stiffness per leg slot, N·m/rad.
    pub kp_nm_per_rad: [f64; LEG_SLOTS],
    /// Damping per leg slot, N·m·s/rad.
    pub kd_nm_s_per_rad: [f64; LEG_SLOTS],
    /// Constant feed-forward torque per output (stance hip, stance knee, swing hip, swing
    /// knee) while walking, N·m.
    pub walk_feedforward_nm: [f64; LEG_SLOTS],
    /// Weight of the gait's planned torques (the gait file's `feedforward` table, by phase)
    /// added to the PD commands while walking: 1 = the plan's torques, 0 = PD only. Without
    /// them the PD alone lets the robot lose speed every step (`adam gait check --pd`).
    #[serde(default = "default_plan_feedforward_scale")]
    pub plan_feedforward_scale: f64,
    /// Damping gain in the Idle and Damping states, N·m·s/rad.
    pub damping_kd_nm_s_per_rad: f64,
}

fn default_plan_feedforward_scale() -> f64 {
    1.0
}

/// Idle → Ramp → Stand: the move from the measured pose to the gait's first pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RampConfig {
    /// Shortest ramp duration, s.
    pub min_duration_s: f64,
    /// Highest joint speed of the ramp, rad/s (lengthens the ramp for large moves).
    pub max_speed_rad_s: f64,
}

/// Walking: phase and stance switching.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WalkConfig {
    /// State-based (HZD) or time-based phase.
    pub phase: PhaseSource,
    /// τ at or above which a touchdown may switch the stance leg (1.0 = end of the step).
    pub switch_min_phase: f64,
    /// Swing foot height above the stance foot below which the foot counts as down, m.
    pub touchdown_height_m: f64,
    /// Fastest descent of the swing foot (measured by kinematics) that still counts as "down",
    /// m/s: the foot has landed when it is near the ground and has stopped descending.
    #[serde(default = "default_touchdown_max_descent_mps")]
    pub touchdown_max_descent_mps: f64,
    /// A swing foot this far *below* the stance foot has landed even if it still "descends":
    /// after the impact the old stance foot lifts off, m.
    #[serde(default = "default_touchdown_below_m")]
    pub touchdown_below_m: f64,
    /// An accelerometer sample whose norm differs from g by at least this is the impact of
    /// the swing foot (near the ground, late in the step): switch at once, m/s².
    #[serde(default = "default_touchdown_impact_accel_mps2")]
    pub touchdown_impact_accel_mps2: f64,
    /// τ from which an impact spike (with the swing foot near the ground) switches the stance
    /// leg: a foot that lands a little early must not be ignored.
    #[serde(default = "default_impact_min_phase")]
    pub impact_min_phase: f64,
    /// Latency compensation, s: y^d, ẏ^d and the feed-forward are evaluated at τ + τ̇·lead
    /// (for τ̇ > 0), since a command acts some milliseconds after the sample it was computed
    /// from. The gait is very sensitive to this delay: on the exact model, references 1 ms late
    /// shorten the steady step from 0.96 s to 0.73 s (README).
    #[serde(default)]
    pub reference_lead_s: f64,
    /// Consecutive ticks the touchdown condition must hold.
    pub touchdown_debounce_ticks: u32,
    /// Largest |τ̇| used for ẏ^d, 1/s (guards the velocity reference against gyro spikes).
    pub max_phase_rate_per_s: f64,
    /// Bandwidth of the phase observer, Hz (0: use the measured τ and τ̇ directly). A
    /// critically damped second-order observer tracks the state-based τ (ramps without lag)
    /// but not the torso's fast pitch wobble, which would otherwise feed back through y^d(τ)
    /// into the swing leg and the torso again (runtime::controller docs).
    #[serde(default)]
    pub phase_observer_hz: f64,
    /// Length of a Stop's braking step, m: after Stop, the step under way ends, then one longer
    /// step whose landing leaves the walking speed within what double support absorbs; Stand
    /// then holds the landing pose (runtime::controller docs).
    #[serde(default = "default_stop_step_length_m")]
    pub stop_step_length_m: f64,
}

/// The most IMU samples `estimator.encoder_lag_samples` may give: the pitch estimator keeps
/// that many past estimates.
pub const MAX_ENCODER_LAG_SAMPLES: u32 = 3;

/// Torso pitch estimator (see [`crate::estimator`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorConfig {
    /// Gyro white noise, rad/s (per sample).
    pub gyro_noise_rad_s: f64,
    /// Gyro bias random walk, rad/s per √s.
    pub gyro_bias_walk_rad_s_per_sqrt_s: f64,
    /// Accelerometer pitch noise, rad.
    pub accel_pitch_noise_rad: f64,
    /// Skip the accelerometer update when | ‖a‖ − g | exceeds this, m/s².
    pub accel_gate_mps2: f64,
    /// Use the accelerometer while walking too. Off by default: the torso's own
    /// accelerations within a step tilt the measured gravity by tenths of a radian, and through
    /// the bias covariance they drag the bias estimate off; walking uses the gyro and the
    /// kinematic pitch of each touchdown instead.
    #[serde(default)]
    pub accel_while_walking: bool,
    /// Standard deviation of the kinematic pitch measured at each touchdown (both feet on
    /// flat ground), rad.
    #[serde(default = "default_touchdown_pitch_sigma_rad")]
    pub touchdown_pitch_sigma_rad: f64,
    /// How many IMU samples older the joint encoders' sample is than the IMU sample of the same
    /// tick (0 ..= [`MAX_ENCODER_LAG_SAMPLES`]): the legs' pitch is
    /// compared with the estimate of that time. The simulated bus: 1 (its replies sample the
    /// robot at the start of the exchange, its IMU at the end of the period). 0 if absent.
    #[serde(default)]
    pub encoder_lag_samples: u32,
    /// Measure the legs' pitch again at the first tick after a touchdown's impact, with the new
    /// stance foot down and the old one just lifting (each of the two with σ·√2): the landing
    /// foot is still above the ground at the encoders' sample of the impact tick, the old
    /// stance foot already above it at the next, and the two errors have opposite signs. Off if
    /// absent.
    #[serde(default)]
    pub touchdown_after_impact: bool,
    /// A touchdown's legs' pitch further than this from the estimate is set aside, rad (0, the
    /// default: every one is used): a foot still in the air at a fast impact makes the pitch
    /// that levels the feet wrong. After `estimator::MAX_SET_ASIDE` set aside in a row the next
    /// is used whatever it says (`runtime::estimator`, "The touchdown gate").
    #[serde(default)]
    pub touchdown_gate_rad: f64,
}

fn default_max_implausible_imu_samples() -> u32 {
    5
}

fn default_stall_timeout_s() -> f64 {
    1.5
}

fn default_stop_step_length_m() -> f64 {
    0.24
}

fn default_impact_min_phase() -> f64 {
    0.8
}

fn default_touchdown_impact_accel_mps2() -> f64 {
    15.0
}

fn default_touchdown_below_m() -> f64 {
    0.003
}

fn default_touchdown_max_descent_mps() -> f64 {
    0.03
}

fn default_touchdown_pitch_sigma_rad() -> f64 {
    0.01
}

/// Safety limits (see [`crate::safety`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SafetyConfig {
    /// Lower joint limit per leg slot (model side), rad.
    pub joint_lower_rad: [f64; LEG_SLOTS],
    /// Upper joint limit per leg slot (model side), rad.
    pub joint_upper_rad: [f64; LEG_SLOTS],
    /// |τ| at or above which a motor counts as saturated, N·m.
    pub torque_saturation_nm: f64,
    /// Consecutive saturated ticks that trip.
    pub torque_saturation_ticks: u32,
    /// |torso pitch| beyond which the robot is falling, rad.
    pub max_pitch_rad: f64,
    /// Motor winding temperature that trips, °C.
    pub max_temperature_c: f64,
    /// Consecutive missing replies of one motor that trip.
    pub max_missing_replies: u32,
    /// Oldest IMU sample accepted, s.
    pub max_imu_age_s: f64,
    /// Largest plausible |gyro|, rad/s.
    pub max_gyro_rad_s: f64,
    /// Plausible accelerometer norm range, m/s².
    pub accel_norm_range_mps2: [f64; 2],
    /// Consecutive implausible IMU samples that trip (an impact spikes the accelerometer for a
    /// sample or two).
    #[serde(default = "default_max_implausible_imu_samples")]
    pub max_implausible_imu_samples: u32,
    /// A walk (Walk, Stop) whose phase makes no progress for this long has stalled (held, or
    /// stuck on both feet) and trips the step timeout ([`crate::safety::ProgressWatch`]), s. A
    /// slow step that progresses never trips.
    #[serde(default = "default_stall_timeout_s")]
    pub stall_timeout_s: f64,
    /// Replaced by `stall_timeout_s` (the step timeout trips on a stalled phase, not on the
    /// step's duration). Read and ignored, so that configs and the logs of runs from before
    /// still load, replay and plot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_step_duration_factor: Option<f64>,
}

/// MCAP logging and zero-copy telemetry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TelemetryConfig {
    /// Capacity of the tick → logger queue, samples (drops are counted when full).
    pub log_queue_capacity: usize,
    /// Log every n-th tick (1 = every tick).
    pub log_every_n_ticks: u32,
    /// zstd chunk compression for MCAP.
    pub log_zstd: bool,
    /// iceoryx2 service name of the per-tick state sample; empty = do not publish.
    pub service_name: String,
}

/// The treadmill the robot walks on (the simulated one, and the lab's).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TreadmillConfig {
    /// Belt speeds the treadmill can run, [lowest, highest], m/s: every belt speed a run asks
    /// for (`adam run --belt`, the gait's speed, a fault profile's belt step) must lie inside.
    pub belt_speed_range_mps: [f64; 2],
}

/// The belt speed range of a config without a `[treadmill]` section, m/s.
pub const DEFAULT_BELT_SPEED_RANGE_MPS: [f64; 2] = [0.0, 0.5];

impl Default for TreadmillConfig {
    fn default() -> Self {
        Self {
            belt_speed_range_mps: DEFAULT_BELT_SPEED_RANGE_MPS,
        }
    }
}

impl TreadmillConfig {
    /// Checks a belt speed asked for by `what` (e.g. `--belt` or a gait file) against
    /// [`Self::belt_speed_range_mps`]; the error names `what`, the value and the range.
    pub fn check_belt_speed(&self, what: &str, speed_mps: f64) -> Result<()> {
        let [lo, hi] = self.belt_speed_range_mps;
        if speed_mps.is_finite() && lo <= speed_mps && speed_mps <= hi {
            Ok(())
        } else {
            Err(RuntimeError::BeltSpeed {
                what: what.to_string(),
                speed_mps,
                range_mps: self.belt_speed_range_mps,
            })
        }
    }
}

/// The runtime config.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RuntimeConfig {
    /// Must equal [`RUNTIME_CONFIG_VERSION`].
    pub schema_version: u32,
    /// Loop rate and buses.
    #[serde(rename = "loop")]
    pub loop_: LoopConfig,
    /// The four leg motors, in slot order: left hip, left knee, right hip, right knee. Their
    /// `joint` must be the URDF joint names `left_hip_pitch`, `left_knee_pitch`, ...
    pub leg_motors: [MotorConfig; LEG_SLOTS],
    /// Up to ten held joints (hip yaw/roll, arms); may be absent in simulation.
    #[serde(default)]
    pub held: Vec<HeldJointConfig>,
    /// PD gains.
    pub gains: GainsConfig,
    /// Ramp to the first pose.
    pub ramp: RampConfig,
    /// Walking.
    pub walk: WalkConfig,
    /// Torso pitch estimator.
    pub estimator: EstimatorConfig,
    /// Safety monitor.
    pub safety: SafetyConfig,
    /// Logging and telemetry.
    pub telemetry: TelemetryConfig,
    /// The treadmill (absent: [`DEFAULT_BELT_SPEED_RANGE_MPS`]).
    #[serde(default)]
    pub treadmill: TreadmillConfig,
    /// Speed control on the treadmill (absent: [`SpeedConfig::default`]).
    #[serde(default)]
    pub speed: SpeedConfig,
    /// The within-step orbit lever (absent: [`OrbitConfig::default`], on).
    #[serde(default)]
    pub orbit: OrbitConfig,
    /// How each leg motor maps to its joint (absent: the identity).
    #[serde(default)]
    pub calibration: CalibrationConfig,
    /// Pre-flight limits and the gains ramp (absent: [`BringupConfig::default`]).
    #[serde(default)]
    pub bringup: BringupConfig,
    /// The torso IMU on the robot (absent: [`ImuConfig::default`]).
    #[serde(default)]
    pub imu: ImuConfig,
}

/// The URDF joint of each leg slot.
pub const LEG_JOINT_NAMES: [&str; LEG_SLOTS] = [
    "left_hip_pitch",
    "left_knee_pitch",
    "right_hip_pitch",
    "right_knee_pitch",
];

impl RuntimeConfig {
    /// Reads and validates a runtime config; errors name the file and the field. A config may
    /// be written as the changes to another: `extends = "base.toml"` (config::extends: tables
    /// merge key by key, other values replace the base's; errors name the file and its chain).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let merged = extends::read_merged(path)?;
        let mut origin = path.display().to_string();
        // A file on its own is read from its text, so that its errors' line numbers are its
        // own; a merged chain has no one text, and its errors name the key instead.
        let config = if merged.chain.is_empty() {
            Self::from_toml(&merged.text, &origin)?
        } else {
            let names: Vec<String> = merged
                .chain
                .iter()
                .map(|p| {
                    p.file_name()
                        .unwrap_or(p.as_os_str())
                        .to_string_lossy()
                        .into_owned()
                })
                .collect();
            origin = format!("{origin} (extends {})", names.join(" → "));
            Self::from_value(merged.value, &origin)?
        };
        for ignored in config.ignored_settings() {
            eprintln!("warning: {origin}: {ignored}");
        }
        Ok(config)
    }

    /// The settings this build reads and ignores (kept so that older configs and the logs of
    /// older runs still load), each with what replaced it; [`RuntimeConfig::load`] prints them
    /// as warnings.
    pub fn ignored_settings(&self) -> Vec<String> {
        let mut ignored = Vec::new();
        if let Some(factor) = self.safety.max_step_duration_factor {
            ignored.push(format!(
                "safety.max_step_duration_factor = {factor} is ignored: the step timeout trips \
                 a stalled phase after safety.stall_timeout_s = {} s, not a slow step; \
                 remove it",
                self.safety.stall_timeout_s
            ));
        }
        ignored
    }

    /// Parses and validates TOML; `origin` names the source in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self> {
        let raw: toml::Value = toml::from_str(text).map_err(|e| RuntimeError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        Self::check_header(&raw, origin)?;
        // From the text, not the value: its errors carry the line and column.
        let config: Self = toml::from_str(text).map_err(|e| RuntimeError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        config.validate(origin)?;
        Ok(config)
    }

    /// [`Self::from_toml`] from TOML already parsed (a merged `extends` chain).
    fn from_value(raw: toml::Value, origin: &str) -> Result<Self> {
        Self::check_header(&raw, origin)?;
        let config: Self = raw
            .try_into()
            .map_err(|e: toml::de::Error| RuntimeError::Parse {
                origin: origin.to_string(),
                message: e.to_string(),
            })?;
        config.validate(origin)?;
        Ok(config)
    }

    /// No `extends` (only a file's loader finds its base) and this build's schema version.
    fn check_header(raw: &toml::Value, origin: &str) -> Result<()> {
        if let Some(v) = raw.get("extends") {
            return Err(RuntimeError::InvalidField {
                origin: origin.to_string(),
                field: "extends".into(),
                value: v.to_string(),
                reason: "only a config read from its file can extend another \
                         (RuntimeConfig::load: the base is found next to it)"
                    .into(),
            });
        }
        let version = raw.get("schema_version").and_then(|v| v.as_integer());
        if version != Some(i64::from(RUNTIME_CONFIG_VERSION)) {
            return Err(RuntimeError::InvalidField {
                origin: origin.to_string(),
                field: "schema_version".into(),
                value: match raw.get("schema_version") {
                    Some(v) => v.to_string(),
                    None => "(missing)".into(),
                },
                reason: format!("this build reads runtime schema version {RUNTIME_CONFIG_VERSION}"),
            });
        }
        Ok(())
    }

    /// The config as TOML text (for the log attachment).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Control period, s.
    pub fn period_s(&self) -> f64 {
        1.0 / self.loop_.rate_hz
    }

    /// Rejects NaN/inf, out-of-range values, duplicate ids and overloaded buses.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let bad = |field: &str, value: String, reason: &str| RuntimeError::InvalidField {
            origin: origin.to_string(),
            field: field.to_string(),
            value,
            reason: reason.to_string(),
        };
        let finite = |field: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(bad(field, v.to_string(), "must be finite"))
            }
        };
        let positive = |field: &str, v: f64| {
            finite(field, v)?;
            if v > 0.0 {
                Ok(())
            } else {
                Err(bad(field, v.to_string(), "must be positive"))
            }
        };
        let non_negative = |field: &str, v: f64| {
            finite(field, v)?;
            if v >= 0.0 {
                Ok(())
            } else {
                Err(bad(field, v.to_string(), "must not be negative"))
            }
        };
        if self.schema_version != RUNTIME_CONFIG_VERSION {
            return Err(bad(
                "schema_version",
                self.schema_version.to_string(),
                "unknown schema version",
            ));
        }
        let l = &self.loop_;
        positive("loop.rate_hz", l.rate_hz)?;
        if l.bus_count == 0 || l.bus_count > drivers::sim::bus::MAX_BUSES {
            return Err(bad(
                "loop.bus_count",
                l.bus_count.to_string(),
                "must be in 1..=8",
            ));
        }
        if !(0..=99).contains(&l.fifo_priority) {
            return Err(bad(
                "loop.fifo_priority",
                l.fifo_priority.to_string(),
                "must be 0 (off) or 1..=99",
            ));
        }
        if l.max_overrun_streak == 0 {
            return Err(bad("loop.max_overrun_streak", "0".into(), "must be ≥ 1"));
        }
        if self.held.len() > MAX_HELD {
            return Err(bad(
                "held",
                format!("{} entries", self.held.len()),
                "at most 10 held joints",
            ));
        }
        // Motors: ids unique, buses exist, names of the leg joints, per-bus load.
        let motors: Vec<(String, &MotorConfig)> = self
            .leg_motors
            .iter()
            .enumerate()
            .map(|(i, m)| (format!("leg_motors[{i}]"), m))
            .chain(
                self.held
                    .iter()
                    .enumerate()
                    .map(|(i, h)| (format!("held[{i}].motor"), &h.motor)),
            )
            .collect();
        for (i, (field, m)) in motors.iter().enumerate() {
            if m.id == 0 || m.id > drivers::a1::codec::MAX_MOTOR_ID {
                return Err(bad(
                    &format!("{field}.id"),
                    m.id.to_string(),
                    "must be 1..=127",
                ));
            }
            if m.bus >= l.bus_count {
                return Err(bad(
                    &format!("{field}.bus"),
                    m.bus.to_string(),
                    &format!("loop.bus_count is {}", l.bus_count),
                ));
            }
            if motors[..i].iter().any(|(_, o)| o.id == m.id) {
                return Err(bad(&format!("{field}.id"), m.id.to_string(), "used twice"));
            }
            if m.direction != 1.0 || m.offset_rad != 0.0 {
                return Err(bad(
                    &format!("{field}.direction/offset_rad"),
                    format!("{} / {}", m.direction, m.offset_rad),
                    "a motor's direction and offset live in [calibration.<joint>] \
                     (direction, zero_offset_rad); leave these out",
                ));
            }
        }
        for (i, (m, name)) in self.leg_motors.iter().zip(LEG_JOINT_NAMES).enumerate() {
            if m.joint != name {
                return Err(bad(
                    &format!("leg_motors[{i}].joint"),
                    format!("\"{}\"", m.joint),
                    &format!("slot {i} is {name}"),
                ));
            }
        }
        for bus in 0..l.bus_count {
            let count = motors.iter().filter(|(_, m)| m.bus == bus).count();
            if count > 0 {
                drivers::timing::validate(l.rate_hz, count, l.bitrate_bps).map_err(|e| {
                    bad(
                        "loop.rate_hz",
                        l.rate_hz.to_string(),
                        &format!("bus {bus} carries {count} motors: {e}"),
                    )
                })?;
            }
        }
        for (i, h) in self.held.iter().enumerate() {
            finite(&format!("held[{i}].position_rad"), h.position_rad)?;
            non_negative(&format!("held[{i}].kp_nm_per_rad"), h.kp_nm_per_rad)?;
            non_negative(&format!("held[{i}].kd_nm_s_per_rad"), h.kd_nm_s_per_rad)?;
            positive(&format!("held[{i}].tolerance_rad"), h.tolerance_rad)?;
        }
        let g = &self.gains;
        for k in 0..LEG_SLOTS {
            let kp = g.kp_nm_per_rad[k];
            let kd = g.kd_nm_s_per_rad[k];
            non_negative(&format!("gains.kp_nm_per_rad[{k}]"), kp)?;
            non_negative(&format!("gains.kd_nm_s_per_rad[{k}]"), kd)?;
            if kp > drivers::a1::codec::KP_MAX_NM_PER_RAD {
                return Err(bad(
                    &format!("gains.kp_nm_per_rad[{k}]"),
                    kp.to_string(),
                    "above the A1 maximum 500",
                ));
            }
            if kd > drivers::a1::codec::KD_MAX_NM_S_PER_RAD {
                return Err(bad(
                    &format!("gains.kd_nm_s_per_rad[{k}]"),
                    kd.to_string(),
                    "above the A1 maximum 10",
                ));
            }
            finite(
                &format!("gains.walk_feedforward_nm[{k}]"),
                g.walk_feedforward_nm[k],
            )?;
        }
        non_negative("gains.plan_feedforward_scale", g.plan_feedforward_scale)?;
        if g.plan_feedforward_scale > 2.0 {
            return Err(bad(
                "gains.plan_feedforward_scale",
                g.plan_feedforward_scale.to_string(),
                "must be in [0, 2] (1 = the planned torques)",
            ));
        }
        non_negative("gains.damping_kd_nm_s_per_rad", g.damping_kd_nm_s_per_rad)?;
        non_negative("ramp.min_duration_s", self.ramp.min_duration_s)?;
        positive("ramp.max_speed_rad_s", self.ramp.max_speed_rad_s)?;
        let w = &self.walk;
        positive("walk.switch_min_phase", w.switch_min_phase)?;
        non_negative("walk.touchdown_height_m", w.touchdown_height_m)?;
        non_negative("walk.touchdown_below_m", w.touchdown_below_m)?;
        non_negative("walk.impact_min_phase", w.impact_min_phase)?;
        non_negative("walk.reference_lead_s", w.reference_lead_s)?;
        positive("walk.stop_step_length_m", w.stop_step_length_m)?;
        if w.reference_lead_s > 0.02 {
            return Err(bad(
                "walk.reference_lead_s",
                w.reference_lead_s.to_string(),
                "must be at most 0.02 s (a few control periods)",
            ));
        }
        positive(
            "walk.touchdown_impact_accel_mps2",
            w.touchdown_impact_accel_mps2,
        )?;
        positive(
            "walk.touchdown_max_descent_mps",
            w.touchdown_max_descent_mps,
        )?;
        positive("walk.max_phase_rate_per_s", w.max_phase_rate_per_s)?;
        non_negative("walk.phase_observer_hz", w.phase_observer_hz)?;
        if w.touchdown_debounce_ticks == 0 {
            return Err(bad(
                "walk.touchdown_debounce_ticks",
                "0".into(),
                "must be ≥ 1",
            ));
        }
        let e = &self.estimator;
        positive("estimator.gyro_noise_rad_s", e.gyro_noise_rad_s)?;
        non_negative(
            "estimator.gyro_bias_walk_rad_s_per_sqrt_s",
            e.gyro_bias_walk_rad_s_per_sqrt_s,
        )?;
        positive("estimator.accel_pitch_noise_rad", e.accel_pitch_noise_rad)?;
        positive("estimator.accel_gate_mps2", e.accel_gate_mps2)?;
        positive(
            "estimator.touchdown_pitch_sigma_rad",
            e.touchdown_pitch_sigma_rad,
        )?;
        non_negative("estimator.touchdown_gate_rad", e.touchdown_gate_rad)?;
        if e.encoder_lag_samples > MAX_ENCODER_LAG_SAMPLES {
            return Err(bad(
                "estimator.encoder_lag_samples",
                e.encoder_lag_samples.to_string(),
                "must be at most 3 (IMU samples)",
            ));
        }
        self.speed.validate(origin)?;
        self.orbit.validate(origin)?;
        self.calibration.validate(origin)?;
        self.bringup.validate(origin)?;
        self.imu.validate(origin)?;
        let [lo, hi] = self.treadmill.belt_speed_range_mps;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(bad(
                "treadmill.belt_speed_range_mps",
                format!("[{lo}, {hi}]"),
                "must be [lowest, highest] m/s, finite, lowest ≤ highest",
            ));
        }
        let s = &self.safety;
        for k in 0..LEG_SLOTS {
            finite(
                &format!("safety.joint_lower_rad[{k}]"),
                s.joint_lower_rad[k],
            )?;
            finite(
                &format!("safety.joint_upper_rad[{k}]"),
                s.joint_upper_rad[k],
            )?;
            if s.joint_lower_rad[k] >= s.joint_upper_rad[k] {
                return Err(bad(
                    &format!("safety.joint_upper_rad[{k}]"),
                    s.joint_upper_rad[k].to_string(),
                    "must exceed joint_lower_rad",
                ));
            }
        }
        positive("safety.torque_saturation_nm", s.torque_saturation_nm)?;
        positive("safety.max_pitch_rad", s.max_pitch_rad)?;
        positive("safety.max_temperature_c", s.max_temperature_c)?;
        positive("safety.max_imu_age_s", s.max_imu_age_s)?;
        positive("safety.max_gyro_rad_s", s.max_gyro_rad_s)?;
        positive("safety.stall_timeout_s", s.stall_timeout_s)?;
        // The stall relaunch (0: off) must come before the step timeout, the last resort.
        if self.speed.stall_relaunch_s > 0.0 && self.speed.stall_relaunch_s >= s.stall_timeout_s {
            return Err(bad(
                "speed.stall_relaunch_s",
                self.speed.stall_relaunch_s.to_string(),
                "must be shorter than safety.stall_timeout_s (the step timeout is the last resort)",
            ));
        }
        if s.torque_saturation_ticks == 0 {
            return Err(bad(
                "safety.torque_saturation_ticks",
                "0".into(),
                "must be ≥ 1",
            ));
        }
        if s.max_missing_replies == 0 {
            return Err(bad("safety.max_missing_replies", "0".into(), "must be ≥ 1"));
        }
        let [lo, hi] = s.accel_norm_range_mps2;
        non_negative("safety.accel_norm_range_mps2[0]", lo)?;
        positive("safety.accel_norm_range_mps2[1]", hi)?;
        if lo >= hi {
            return Err(bad(
                "safety.accel_norm_range_mps2",
                format!("[{lo}, {hi}]"),
                "must be an increasing range",
            ));
        }
        let t = &self.telemetry;
        if t.log_queue_capacity < 16 {
            return Err(bad(
                "telemetry.log_queue_capacity",
                t.log_queue_capacity.to_string(),
                "must be ≥ 16",
            ));
        }
        if t.log_every_n_ticks == 0 {
            return Err(bad(
                "telemetry.log_every_n_ticks",
                "0".into(),
                "must be ≥ 1",
            ));
        }
        Ok(())
    }
}

// Here, beside the config it reads, so that `crate::slots` stays a leaf.
impl SlotLayout {
    /// The layout of a config; `with_held` = whether the held motors are driven.
    pub fn new(config: &RuntimeConfig, with_held: bool) -> Self {
        let mut l = Self {
            present: [false; SLOTS],
            direction: [1.0; LEG_SLOTS],
            offset_rad: [0.0; LEG_SLOTS],
            gear_ratio: [1.0; LEG_SLOTS],
            held_center_rad: [0.0; SLOTS],
            held_tolerance_rad: [0.0; SLOTS],
            held_kp: [0.0; SLOTS],
            held_kd: [0.0; SLOTS],
        };
        for (k, (_, c)) in config.calibration.joints().into_iter().enumerate() {
            l.present[k] = true;
            l.direction[k] = c.direction_factor();
            l.offset_rad[k] = c.zero_offset_rad;
            l.gear_ratio[k] = c.gear_ratio;
        }
        for (i, h) in config.held.iter().enumerate().take(MAX_HELD) {
            let s = LEG_SLOTS + i;
            l.present[s] = with_held;
            l.held_center_rad[s] = h.position_rad;
            l.held_tolerance_rad[s] = h.tolerance_rad;
            l.held_kp[s] = h.kp_nm_per_rad;
            l.held_kd[s] = h.kd_nm_s_per_rad;
        }
        l
    }
}

#[cfg(test)]
mod tests;
