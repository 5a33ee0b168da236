//! Safety monitor, run every tick while the motors are driven (Ramp, Stand, Walk, Stop).
//!
//! Each check that fails yields a [`Trip`]: a small `Copy` value with the reason and the
//! offending values (no string formatting on the hot path). The controller goes to Damping on
//! the first trip and latches it until an operator `Reset`.
//!
//! # The step timeout: a stall, not a slow step
//! [`ProgressWatch`] trips [`Trip::StepTimeout`] when the walk's phase τ has made no progress
//! (risen [`STALL_MIN_PROGRESS`] above the highest τ of the step so far) for
//! `safety.stall_timeout_s`. A robot held in place, or standing stuck on both feet, stalls;
//! a step slowed by a push, or whose phase runs back for a moment and then passes its highest
//! point again, does not, however long the step lasts. Before, a step lasting three times the
//! gait's duration tripped, progressing or not.

use crate::config::SafetyConfig;
use crate::slots::{MotorSample, SlotLayout, LEG_SLOTS, SLOTS};
use drivers::imu::ImuSample;

/// Why the controller went to Damping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Trip {
    /// Operator emergency stop.
    EStop,
    /// A joint left its position limits (leg joints: model side; held joints: tolerance).
    JointLimit {
        /// Motor slot.
        slot: u8,
        /// Measured position, rad.
        q_rad: f64,
        /// Lower limit, rad.
        lower_rad: f64,
        /// Upper limit, rad.
        upper_rad: f64,
    },
    /// A motor stayed at its torque limit for too long.
    TorqueSaturation {
        /// Motor slot.
        slot: u8,
        /// Measured torque, N·m.
        tau_nm: f64,
        /// Saturation threshold, N·m.
        limit_nm: f64,
        /// Consecutive saturated ticks.
        ticks: u32,
    },
    /// The torso pitched beyond the fall limit.
    Fall {
        /// Estimated pitch, rad.
        pitch_rad: f64,
        /// Limit, rad.
        limit_rad: f64,
    },
    /// A motor is too hot.
    OverTemperature {
        /// Motor slot.
        slot: u8,
        /// Winding temperature, °C.
        temperature_c: f64,
        /// Limit, °C.
        limit_c: f64,
    },
    /// A motor reported fault flags ([`drivers::a1::ErrorFlags`] bits).
    MotorFault {
        /// Motor slot.
        slot: u8,
        /// Fault bits.
        flags: u8,
    },
    /// A motor did not reply for too many consecutive ticks.
    MissingReplies {
        /// Motor slot.
        slot: u8,
        /// Consecutive missing replies.
        consecutive: u32,
    },
    /// No fresh IMU data for too long: no sample, or only samples repeating the last values bit
    /// for bit (a frozen sensor; a live IMU's noise never repeats all three channels).
    ImuStale {
        /// Age of the newest sample, s (infinite if none ever arrived).
        age_s: f64,
        /// Limit, s.
        limit_s: f64,
    },
    /// The IMU sample is not physically plausible.
    ImuImplausible {
        /// Gyro pitch rate, rad/s.
        gyro_rad_s: f64,
        /// Accelerometer norm, m/s².
        accel_norm_mps2: f64,
    },
    /// The loop missed too many deadlines in a row.
    OverrunStreak {
        /// Consecutive overruns.
        streak: u32,
        /// Limit.
        limit: u32,
    },
    /// The walk stalled: its phase made no progress for too long ([`ProgressWatch`]).
    StepTimeout {
        /// Time since the phase last progressed, s.
        elapsed_s: f64,
        /// Limit, s.
        limit_s: f64,
    },
}

/// A trip for a user: the reason, its values and their units, e.g. `joint limit: slot 3 at 1.200 rad,
/// outside [-1.000, 1.000] rad`.
impl std::fmt::Display for Trip {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Trip::EStop => write!(f, "operator e-stop"),
            Trip::JointLimit {
                slot,
                q_rad,
                lower_rad,
                upper_rad,
            } => write!(
                f,
                "joint limit: slot {slot} at {q_rad:.3} rad, outside [{lower_rad:.3}, {upper_rad:.3}] rad"
            ),
            Trip::TorqueSaturation {
                slot,
                tau_nm,
                limit_nm,
                ticks,
            } => write!(
                f,
                "torque saturation: slot {slot} at {tau_nm:.2} N·m (limit {limit_nm:.2} N·m) for {ticks} ticks"
            ),
            Trip::Fall {
                pitch_rad,
                limit_rad,
            } => write!(
                f,
                "fall: pitch {pitch_rad:.3} rad past the limit of {limit_rad:.3} rad"
            ),
            Trip::OverTemperature {
                slot,
                temperature_c,
                limit_c,
            } => write!(
                f,
                "over temperature: slot {slot} at {temperature_c:.1} °C (limit {limit_c:.1} °C)"
            ),
            Trip::MotorFault { slot, flags } => {
                write!(f, "motor fault: slot {slot}, fault flags {flags:#04x}")
            }
            Trip::MissingReplies { slot, consecutive } => write!(
                f,
                "missing replies: slot {slot}, {consecutive} in a row"
            ),
            Trip::ImuStale { age_s, limit_s } if age_s.is_infinite() => write!(
                f,
                "IMU stale: no sample ever arrived (limit {limit_s:.3} s)"
            ),
            Trip::ImuStale { age_s, limit_s } => write!(
                f,
                "IMU stale: newest sample {age_s:.3} s old (limit {limit_s:.3} s)"
            ),
            Trip::ImuImplausible {
                gyro_rad_s,
                accel_norm_mps2,
            } => write!(
                f,
                "IMU implausible: gyro {gyro_rad_s:.3} rad/s, accelerometer norm {accel_norm_mps2:.2} m/s²"
            ),
            Trip::OverrunStreak { streak, limit } => write!(
                f,
                "overrun streak: {streak} deadlines missed in a row (limit {limit})"
            ),
            Trip::StepTimeout { elapsed_s, limit_s } => write!(
                f,
                "step timeout: no phase progress for {elapsed_s:.3} s (limit {limit_s:.3} s)"
            ),
        }
    }
}

impl Trip {
    /// A stable numeric code (telemetry, `StateSample::trip_code`); 0 means no trip.
    pub fn code(&self) -> u32 {
        match self {
            Trip::EStop => 1,
            Trip::JointLimit { .. } => 2,
            Trip::TorqueSaturation { .. } => 3,
            Trip::Fall { .. } => 4,
            Trip::OverTemperature { .. } => 5,
            Trip::MotorFault { .. } => 6,
            Trip::MissingReplies { .. } => 7,
            Trip::ImuStale { .. } => 8,
            Trip::ImuImplausible { .. } => 9,
            Trip::OverrunStreak { .. } => 10,
            Trip::StepTimeout { .. } => 11,
        }
    }

    /// The [`Trip::name`] of a [`Trip::code`] (`None`: 0 or no such code), for readers that
    /// see only the code (the live view, from a `StateSample`).
    pub fn name_of_code(code: u32) -> Option<&'static str> {
        const NAMES: [&str; 11] = [
            "e_stop",
            "joint_limit",
            "torque_saturation",
            "fall",
            "over_temperature",
            "motor_fault",
            "missing_replies",
            "imu_stale",
            "imu_implausible",
            "overrun_streak",
            "step_timeout",
        ];
        code.checked_sub(1)
            .and_then(|i| NAMES.get(i as usize).copied())
    }

    /// Short name of the reason (a `&'static str`, no formatting).
    pub fn name(&self) -> &'static str {
        match self {
            Trip::EStop => "e_stop",
            Trip::JointLimit { .. } => "joint_limit",
            Trip::TorqueSaturation { .. } => "torque_saturation",
            Trip::Fall { .. } => "fall",
            Trip::OverTemperature { .. } => "over_temperature",
            Trip::MotorFault { .. } => "motor_fault",
            Trip::MissingReplies { .. } => "missing_replies",
            Trip::ImuStale { .. } => "imu_stale",
            Trip::ImuImplausible { .. } => "imu_implausible",
            Trip::OverrunStreak { .. } => "overrun_streak",
            Trip::StepTimeout { .. } => "step_timeout",
        }
    }
}

/// Per-tick inputs of the monitor besides the motor samples.
#[derive(Clone, Copy, Debug)]
pub struct SafetyInput<'a> {
    /// Controller time, s.
    pub t_s: f64,
    /// Motor samples by slot (model-side angles for leg slots, motor side for held slots).
    pub motors: &'a [MotorSample; SLOTS],
    /// Model-side leg joint angles, rad.
    pub leg_q_rad: &'a [f64; LEG_SLOTS],
    /// IMU sample of this tick, if any.
    pub imu: Option<&'a ImuSample>,
    /// Estimated torso pitch, rad.
    pub pitch_rad: f64,
    /// Consecutive overruns reported by the loop driver.
    pub overrun_streak: u32,
}

/// The stateful monitor: counters for persistent conditions.
#[derive(Clone, Debug)]
pub struct SafetyMonitor {
    limits: SafetyConfig,
    max_overrun_streak: u32,
    layout: SlotLayout,
    saturated_ticks: [u32; SLOTS],
    missing: [u32; SLOTS],
    last_imu_t_s: f64,
    /// Bits of the last plausible sample's (gyro, accel x, accel z).
    last_imu_bits: Option<[u64; 3]>,
    implausible_imu: u32,
}

impl SafetyMonitor {
    /// A monitor with these limits for the motors of `layout`.
    pub fn new(limits: SafetyConfig, max_overrun_streak: u32, layout: SlotLayout) -> Self {
        Self {
            limits,
            max_overrun_streak,
            layout,
            saturated_ticks: [0; SLOTS],
            missing: [0; SLOTS],
            last_imu_t_s: f64::NEG_INFINITY,
            last_imu_bits: None,
            implausible_imu: 0,
        }
    }

    /// Forget persistent counters (after a reset), keeping the IMU age.
    pub fn reset_counters(&mut self) {
        self.saturated_ticks = [0; SLOTS];
        self.missing = [0; SLOTS];
    }

    /// Whether the gyro of an IMU sample is usable (finite, within the limit). The controller
    /// integrates only those; an accelerometer beyond its range is a real impact, not a glitch.
    pub fn gyro_plausible(&self, imu: &ImuSample) -> bool {
        imu.gyro_pitch_rad_s.is_finite()
            && imu.gyro_pitch_rad_s.abs() <= self.limits.max_gyro_rad_s
            && imu.accel_x_mps2.is_finite()
            && imu.accel_z_mps2.is_finite()
    }

    /// Whether an IMU sample is physically plausible (finite, |gyro| and ‖accel‖ within the
    /// limits).
    pub fn imu_plausible(&self, imu: &ImuSample) -> bool {
        let l = &self.limits;
        let norm = imu.accel_x_mps2.hypot(imu.accel_z_mps2);
        imu.gyro_pitch_rad_s.is_finite()
            && imu.gyro_pitch_rad_s.abs() <= l.max_gyro_rad_s
            && norm.is_finite()
            && norm >= l.accel_norm_range_mps2[0]
            && norm <= l.accel_norm_range_mps2[1]
    }

    /// Update the counters with this tick and, if `armed`, return the first trip.
    ///
    /// Counters always run (so a condition that began while idle counts), but only an armed
    /// monitor trips.
    // `!(x <= limit)` on purpose: a NaN reading must trip, not pass.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn check(&mut self, input: &SafetyInput<'_>, armed: bool) -> Option<Trip> {
        let l = &self.limits;
        let mut trip = None;
        let mut first = |t: Trip| {
            if trip.is_none() {
                trip = Some(t);
            }
        };
        if input.overrun_streak >= self.max_overrun_streak {
            first(Trip::OverrunStreak {
                streak: input.overrun_streak,
                limit: self.max_overrun_streak,
            });
        }
        // IMU: plausibility of this sample, then age.
        if let Some(imu) = input.imu {
            let norm = imu.accel_x_mps2.hypot(imu.accel_z_mps2);
            let plausible = self.imu_plausible(imu);
            if plausible {
                // A sample repeating the last one bit for bit is not fresh data.
                let bits = [
                    imu.gyro_pitch_rad_s.to_bits(),
                    imu.accel_x_mps2.to_bits(),
                    imu.accel_z_mps2.to_bits(),
                ];
                if self.last_imu_bits != Some(bits) {
                    self.last_imu_t_s = self.last_imu_t_s.max(imu.t_s);
                    self.last_imu_bits = Some(bits);
                }
                self.implausible_imu = 0;
            } else {
                self.implausible_imu = self.implausible_imu.saturating_add(1);
            }
            // A foot impact is a millisecond spike of the accelerometer; only a run of
            // implausible samples is a fault.
            if !plausible && self.implausible_imu >= l.max_implausible_imu_samples {
                first(Trip::ImuImplausible {
                    gyro_rad_s: imu.gyro_pitch_rad_s,
                    accel_norm_mps2: norm,
                });
            }
        }
        let age_s = input.t_s - self.last_imu_t_s;
        if !(age_s <= l.max_imu_age_s) {
            first(Trip::ImuStale {
                age_s,
                limit_s: l.max_imu_age_s,
            });
        }
        if !(input.pitch_rad.abs() <= l.max_pitch_rad) {
            first(Trip::Fall {
                pitch_rad: input.pitch_rad,
                limit_rad: l.max_pitch_rad,
            });
        }
        for slot in 0..SLOTS {
            if !self.layout.present[slot] {
                continue;
            }
            let m = &input.motors[slot];
            let s = slot as u8;
            if !m.fresh {
                self.missing[slot] = self.missing[slot].saturating_add(1);
                if self.missing[slot] >= l.max_missing_replies {
                    first(Trip::MissingReplies {
                        slot: s,
                        consecutive: self.missing[slot],
                    });
                }
                continue; // stale values: nothing else to check
            }
            self.missing[slot] = 0;
            if m.errors != 0 {
                first(Trip::MotorFault {
                    slot: s,
                    flags: m.errors,
                });
            }
            if !(m.temperature_c <= l.max_temperature_c) {
                first(Trip::OverTemperature {
                    slot: s,
                    temperature_c: m.temperature_c,
                    limit_c: l.max_temperature_c,
                });
            }
            if m.tau_nm.abs() >= l.torque_saturation_nm {
                self.saturated_ticks[slot] = self.saturated_ticks[slot].saturating_add(1);
                if self.saturated_ticks[slot] >= l.torque_saturation_ticks {
                    first(Trip::TorqueSaturation {
                        slot: s,
                        tau_nm: m.tau_nm,
                        limit_nm: l.torque_saturation_nm,
                        ticks: self.saturated_ticks[slot],
                    });
                }
            } else {
                self.saturated_ticks[slot] = 0;
            }
            let (q, lower, upper) = if slot < LEG_SLOTS {
                (
                    input.leg_q_rad[slot],
                    l.joint_lower_rad[slot],
                    l.joint_upper_rad[slot],
                )
            } else {
                let c = self.layout.held_center_rad[slot];
                let w = self.layout.held_tolerance_rad[slot];
                (m.q_rad, c - w, c + w)
            };
            if !(q >= lower && q <= upper) {
                first(Trip::JointLimit {
                    slot: s,
                    q_rad: q,
                    lower_rad: lower,
                    upper_rad: upper,
                });
            }
        }
        if armed {
            trip
        } else {
            None
        }
    }
}

/// Phase progress that counts for the [`ProgressWatch`]: τ this far above the highest τ of the
/// step so far (a normal step covers it in about 10 ms).
pub const STALL_MIN_PROGRESS: f64 = 0.01;

/// The step timeout ([`Trip::StepTimeout`]): watches a walk's phase τ and trips when it has not
/// risen [`STALL_MIN_PROGRESS`] above its highest value of the step for longer than the limit.
/// The controller restarts it at each impact (and at the end of a launch) and disarms it
/// outside Walk and Stop. A phase that is not finite never progresses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressWatch {
    limit_s: f64,
    armed: bool,
    /// Highest phase of the step that counted as progress.
    best_phase: f64,
    /// When the phase last progressed, s.
    since_t_s: f64,
}

impl ProgressWatch {
    /// A disarmed watch that trips after `limit_s` without progress.
    pub fn new(limit_s: f64) -> Self {
        Self {
            limit_s,
            armed: false,
            best_phase: f64::NEG_INFINITY,
            since_t_s: 0.0,
        }
    }

    /// Arms the watch at the start of a step (or of the walk): `phase` at `t_s` is its start.
    pub fn restart(&mut self, t_s: f64, phase: f64) {
        self.armed = true;
        self.best_phase = if phase.is_finite() {
            phase
        } else {
            f64::NEG_INFINITY
        };
        self.since_t_s = t_s;
    }

    /// Stops watching (the robot is not walking, or a launch moves it on a timed plan).
    pub fn disarm(&mut self) {
        self.armed = false;
    }

    /// The limit: no progress for longer than this trips, s.
    pub fn limit_s(&self) -> f64 {
        self.limit_s
    }

    /// Whether the watch is armed.
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// Feeds the phase at `t_s`; the trip if it has not progressed for longer than the limit.
    pub fn check(&mut self, t_s: f64, phase: f64) -> Option<Trip> {
        if !self.armed {
            return None;
        }
        if phase.is_finite() && phase >= self.best_phase + STALL_MIN_PROGRESS {
            self.best_phase = phase;
            self.since_t_s = t_s;
        }
        let stalled_s = t_s - self.since_t_s;
        (stalled_s > self.limit_s).then_some(Trip::StepTimeout {
            elapsed_s: stalled_s,
            limit_s: self.limit_s,
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    /// Feeds `phase(t)` at 1 kHz for `seconds`; when it tripped, if it did.
    fn watch(seconds: f64, phase: impl Fn(f64) -> f64) -> Option<(f64, Trip)> {
        let mut w = ProgressWatch::new(1.5);
        w.restart(0.0, phase(0.0));
        for k in 1..=(seconds * 1e3) as u32 {
            let t = f64::from(k) * 1e-3;
            if let Some(trip) = w.check(t, phase(t)) {
                return Some((t, trip));
            }
        }
        None
    }

    #[test]
    fn a_held_walk_trips_the_step_timeout_and_a_slow_one_does_not() {
        // Held: the phase stops at 0.4 from 0.3 s on: trips 1.5 s later.
        let (t, trip) = watch(10.0, |t| 1.25 * t.min(0.3) + 0.01 * (50.0 * t).sin()).unwrap();
        assert!((t - 1.8).abs() < 0.05, "{t} {trip}");
        assert_eq!(trip.name(), "step_timeout");
        // A step slowed twentyfold (τ̇ = 0.06/s: 17 s long) never trips.
        assert_eq!(watch(16.0, |t| 0.06 * t), None);
        // Running back for 0.8 s after a push and past its highest point again 1.2 s after it
        // stopped progressing: rides through. Running back for good: trips.
        let back_and_on = |t: f64| {
            if t < 0.5 {
                t
            } else if t < 1.3 {
                0.5 - 0.5 * (t - 0.5)
            } else {
                0.1 + (t - 1.3)
            }
        };
        assert_eq!(watch(3.0, back_and_on), None);
        let (t, _) = watch(5.0, |t| if t < 0.5 { t } else { 1.0 - t }).unwrap();
        assert!((t - 2.0).abs() < 0.02, "{t}");
        // A phase that is not finite never progresses.
        let (t, _) = watch(5.0, |t| if t < 1.0 { t } else { f64::NAN }).unwrap();
        assert!((t - 2.5).abs() < 0.02, "{t}");
        // Disarmed: never.
        let mut w = ProgressWatch::new(0.1);
        w.restart(0.0, 0.0);
        w.disarm();
        assert_eq!(w.check(10.0, 0.0), None);
    }

    #[test]
    fn trips_name_the_reason_the_values_and_their_units() {
        let text = |t: Trip| t.to_string();
        assert_eq!(text(Trip::EStop), "operator e-stop");
        assert_eq!(
            text(Trip::JointLimit {
                slot: 3,
                q_rad: 1.2,
                lower_rad: -1.0,
                upper_rad: 1.0
            }),
            "joint limit: slot 3 at 1.200 rad, outside [-1.000, 1.000] rad"
        );
        assert_eq!(
            text(Trip::MotorFault { slot: 1, flags: 5 }),
            "motor fault: slot 1, fault flags 0x05"
        );
        assert_eq!(
            text(Trip::ImuStale {
                age_s: f64::INFINITY,
                limit_s: 0.05
            }),
            "IMU stale: no sample ever arrived (limit 0.050 s)"
        );
        assert_eq!(
            text(Trip::OverTemperature {
                slot: 0,
                temperature_c: 91.26,
                limit_c: 90.0
            }),
            "over temperature: slot 0 at 91.3 °C (limit 90.0 °C)"
        );
    }

    use super::*;
    use crate::slots::SlotLayout;

    /// Feeds `n` ticks at 1 kHz with healthy motors and the IMU sample `imu(k)`; the first trip.
    fn run(n: u32, imu: impl Fn(u32) -> ImuSample) -> Option<(u32, Trip)> {
        let setup = crate::Setup::shipped().unwrap();
        let layout = SlotLayout::new(&setup.config, false);
        let mut monitor = SafetyMonitor::new(setup.config.safety.clone(), 20, layout);
        let mut motors = [MotorSample::default(); SLOTS];
        for m in motors.iter_mut() {
            m.fresh = true;
            m.temperature_c = 30.0;
        }
        let leg_q_rad = [0.0, 0.3, 0.0, 0.3];
        for k in 0..n {
            let sample = imu(k);
            let input = SafetyInput {
                t_s: f64::from(k) * 1e-3,
                motors: &motors,
                leg_q_rad: &leg_q_rad,
                imu: Some(&sample),
                pitch_rad: 0.0,
                overrun_streak: 0,
            };
            if let Some(trip) = monitor.check(&input, true) {
                return Some((k, trip));
            }
        }
        None
    }

    fn sample(k: u32, gyro_rad_s: f64) -> ImuSample {
        ImuSample {
            t_s: f64::from(k) * 1e-3,
            gyro_pitch_rad_s: gyro_rad_s,
            accel_x_mps2: 0.0,
            accel_z_mps2: 9.81,
        }
    }

    #[test]
    fn a_frozen_imu_is_stale_after_the_age_limit_and_a_live_one_never() {
        // Live: values change every sample (the smallest change counts).
        assert_eq!(
            run(2000, |k| sample(
                k,
                crate::backend::test_dither_rad_s(f64::from(k) * 1e-3)
            )),
            None
        );
        let live = |k: u32| crate::backend::test_dither_rad_s(f64::from(k) * 1e-3);
        // Frozen from tick 100 on (value and time stamp): the last fresh sample is at 100 ms;
        // stale once older than the 20 ms limit, at 121 ms.
        let (k, trip) = run(2000, |k| {
            if k < 100 {
                sample(k, live(k))
            } else {
                sample(100, 0.01)
            }
        })
        .unwrap();
        assert!(matches!(trip, Trip::ImuStale { .. }), "{trip:?}");
        assert_eq!(k, 121, "{trip:?}");
        // Only the values count: fresh time stamps do not make repeated values fresh.
        let (k, trip) = run(2000, |k| sample(k, if k < 100 { live(k) } else { 0.01 })).unwrap();
        assert!(matches!(trip, Trip::ImuStale { .. }), "{trip:?}");
        assert_eq!(k, 121);
    }
}
