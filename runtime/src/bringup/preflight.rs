//! The pre-flight checks before any gain comes on: every configured motor answers (the scan),
//! then `bringup.samples` control periods of zero-torque exchanges and IMU reads, and the
//! checks of what was heard ([`check`]): no motor fault or heat, every leg joint within
//! `bringup.start_pose_tolerance_rad` of the gait's first pose (held joints within their
//! tolerance), the IMU alive (fresh, advancing, not frozen), still and upright within
//! `bringup.max_start_pitch_rad`, the busiest bus within `bringup.max_bus_load` of the period.
//! Each [`Refusal`] names the motor (joint, bus, id) or the IMU and the value.

use crate::backend::Backend;
use crate::config::RuntimeConfig;
use crate::estimator::{PitchEstimator, GRAVITY_MPS2};
use crate::rt_loop::Clock;
use crate::slots::{SlotLayout, LEG_SLOTS, SLOTS};
use crate::{Result, RuntimeError, Setup};
use core::time::Duration;
use drivers::a1::{Command, ErrorFlags, Reply};
use drivers::bus::{BusError, MotorBus, MotorSpec};
use drivers::imu::ImuSample;
use std::fmt;

/// A configured motor: its slot, joint and place on the buses.
#[derive(Clone, Debug, PartialEq)]
pub struct MotorTarget {
    /// Motor slot (0..4 legs, then held joints).
    pub slot: usize,
    /// Joint name of the config.
    pub joint: String,
    /// Bus and id.
    pub spec: MotorSpec,
}

impl fmt::Display for MotorTarget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} (bus {}, id {})",
            self.joint,
            self.spec.bus,
            self.spec.id.get()
        )
    }
}

/// The driven motors of `config`: the leg motors, and the held ones if `with_held`.
pub fn targets(config: &RuntimeConfig, with_held: bool) -> Result<Vec<MotorTarget>> {
    let mut out = Vec::new();
    for (k, m) in config.leg_motors.iter().enumerate() {
        out.push(MotorTarget {
            slot: k,
            joint: m.joint.clone(),
            spec: m.spec(&format!("leg_motors[{k}]"))?,
        });
    }
    if with_held {
        for (i, h) in config.held.iter().enumerate() {
            out.push(MotorTarget {
                slot: LEG_SLOTS + i,
                joint: h.motor.joint.clone(),
                spec: h.motor.spec(&format!("held[{i}].motor"))?,
            });
        }
    }
    Ok(out)
}

/// What a motor said to the scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Answer {
    /// It enabled and replied to a zero-torque command.
    Reply(Reply),
    /// No reply.
    Silent,
    /// It replied but refused to enable, with these fault flags.
    EnableRefused(ErrorFlags),
}

/// One motor's scan.
#[derive(Clone, Debug, PartialEq)]
pub struct MotorScan {
    /// The motor.
    pub target: MotorTarget,
    /// Its answer.
    pub answer: Answer,
}

/// A zero-torque command: damping with no gain.
fn zero_torque(spec: &MotorSpec) -> Command {
    Command::damping(spec.id, 0.0)
}

/// Ask every motor of `targets`, one at a time (configure it alone, enable, one zero-torque
/// exchange within `budget`, disable), so that one silent motor does not hide the others. The
/// bus must not be active; it is left configured with the last motor. A bus failure other than
/// a silent or refusing motor is an error.
pub fn scan<B: MotorBus>(
    bus: &mut B,
    targets: &[MotorTarget],
    budget: Duration,
) -> Result<Vec<MotorScan>> {
    let mut out = Vec::with_capacity(targets.len());
    for t in targets {
        bus.configure(&[t.spec])?;
        let answer = match bus.activate() {
            Ok(()) => {
                let mut replies = [Reply::zeroed(t.spec.id)];
                let heard = match bus.exchange(&[zero_torque(&t.spec)], &mut replies, budget) {
                    Ok(_) => Answer::Reply(replies[0]),
                    Err(BusError::MissingReply { .. }) => Answer::Silent,
                    Err(e) => {
                        let _ = bus.deactivate();
                        return Err(e.into());
                    }
                };
                bus.deactivate()?;
                heard
            }
            Err(BusError::MissingReply { .. }) => Answer::Silent,
            Err(BusError::EnableRefused { errors, .. }) => Answer::EnableRefused(errors),
            Err(e) => return Err(e.into()),
        };
        out.push(MotorScan {
            target: t.clone(),
            answer,
        });
    }
    Ok(out)
}

/// `adam can scan`'s table: every motor, its answer.
pub struct ScanTable<'a>(pub &'a [MotorScan]);

impl fmt::Display for ScanTable<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{:<22} {:>3} {:>4}  {:<8} {:>12} {:>9} {:>8}  errors",
            "motor", "bus", "id", "answer", "position rad", "rate rad/s", "temp °C"
        )?;
        for s in self.0 {
            let t = &s.target;
            match s.answer {
                Answer::Reply(r) => writeln!(
                    f,
                    "{:<22} {:>3} {:>4}  {:<8} {:>12.4} {:>9.3} {:>8.1}  {}",
                    t.joint,
                    t.spec.bus,
                    t.spec.id.get(),
                    "ok",
                    r.q_rad,
                    r.dq_rad_s,
                    r.temperature_c,
                    r.errors
                )?,
                Answer::Silent => writeln!(
                    f,
                    "{:<22} {:>3} {:>4}  {:<8} {:>12} {:>9} {:>8}  -",
                    t.joint,
                    t.spec.bus,
                    t.spec.id.get(),
                    "SILENT",
                    "-",
                    "-",
                    "-"
                )?,
                Answer::EnableRefused(e) => writeln!(
                    f,
                    "{:<22} {:>3} {:>4}  {:<8} {:>12} {:>9} {:>8}  {e}",
                    t.joint,
                    t.spec.bus,
                    t.spec.id.get(),
                    "REFUSED",
                    "-",
                    "-",
                    "-"
                )?,
            }
        }
        let silent: Vec<String> = self
            .0
            .iter()
            .filter(|s| s.answer == Answer::Silent)
            .map(|s| s.target.to_string())
            .collect();
        if silent.is_empty() {
            writeln!(f, "{} of {} motors answered", self.0.len(), self.0.len())
        } else {
            writeln!(
                f,
                "{} of {} motors answered; missing: {}",
                self.0.len() - silent.len(),
                self.0.len(),
                silent.join(", ")
            )
        }
    }
}

/// What the listening periods heard.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Heard {
    /// Control periods listened.
    pub samples: u32,
    /// Per driven slot: the last reply (`None`: never heard while listening) and the replies
    /// counted.
    pub motors: Vec<(MotorTarget, Option<Reply>, u32)>,
    /// IMU samples that were fresh (a sample with an advancing time stamp).
    pub imu_fresh: u32,
    /// Whether every fresh IMU sample was bit for bit the first one (a frozen IMU).
    pub imu_frozen: bool,
    /// Mean accelerometer pitch over the fresh samples, rad (NaN without any).
    pub imu_pitch_rad: f64,
    /// Mean accelerometer norm over the fresh samples, m/s² (NaN without any).
    pub imu_accel_norm_mps2: f64,
    /// Bus time of the busiest bus per exchange: median and largest, s (0 without exchanges).
    pub bus_time_median_s: f64,
    /// Largest bus time, s.
    pub bus_time_max_s: f64,
    /// A bus failure while listening, if any (as text).
    pub bus_failure: Option<String>,
}

/// Why the pre-flight refuses: each names the motor (joint, bus, id) or the IMU, and the value.
#[derive(Clone, Debug, PartialEq)]
pub enum Refusal {
    /// No reply to the scan.
    MotorSilent(MotorTarget),
    /// Replied to the scan but refused to enable.
    EnableRefused(MotorTarget, ErrorFlags),
    /// Answered the scan, then missed replies while listening.
    MotorDropping {
        /// The motor.
        motor: MotorTarget,
        /// Replies heard.
        heard: u32,
        /// Periods listened.
        samples: u32,
    },
    /// Reports fault flags.
    MotorFault(MotorTarget, ErrorFlags),
    /// Too hot.
    MotorHot {
        /// The motor.
        motor: MotorTarget,
        /// Its winding temperature, °C.
        temperature_c: f64,
        /// The safety limit, °C.
        limit_c: f64,
    },
    /// A joint far from where Start will take it.
    JointOffStart {
        /// The motor.
        motor: MotorTarget,
        /// Its joint angle (leg: model side, through the calibration; held: motor side), rad.
        q_rad: f64,
        /// The start pose's angle, rad.
        start_rad: f64,
        /// The tolerance, rad.
        tolerance_rad: f64,
    },
    /// Too few fresh IMU samples.
    ImuDead {
        /// Fresh samples.
        fresh: u32,
        /// Periods listened.
        samples: u32,
    },
    /// Every IMU sample identical.
    ImuFrozen {
        /// Fresh samples, all identical.
        fresh: u32,
    },
    /// The IMU's pitch is not that of an upright robot.
    ImuPitch {
        /// Mean accelerometer pitch, rad.
        pitch_rad: f64,
        /// `bringup.max_start_pitch_rad`.
        limit_rad: f64,
    },
    /// The IMU does not read gravity alone.
    ImuNotStill {
        /// Mean accelerometer norm, m/s².
        accel_norm_mps2: f64,
        /// `bringup.max_still_accel_error_mps2`.
        limit_mps2: f64,
    },
    /// The busiest bus takes too much of the period.
    BusLoad {
        /// Its largest measured bus time per exchange, µs.
        measured_us: f64,
        /// The control period, µs.
        period_us: f64,
        /// `bringup.max_bus_load`.
        limit: f64,
    },
    /// The bus failed while listening.
    Bus(String),
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::MotorSilent(m) => write!(f, "motor {m}: no reply"),
            Refusal::EnableRefused(m, e) => {
                write!(f, "motor {m}: replied but refused to enable (faults: {e})")
            }
            Refusal::MotorDropping {
                motor,
                heard,
                samples,
            } => write!(
                f,
                "motor {motor}: {heard} replies in {samples} periods (fewer than 90 %)"
            ),
            Refusal::MotorFault(m, e) => write!(f, "motor {m}: fault flags {e}"),
            Refusal::MotorHot {
                motor,
                temperature_c,
                limit_c,
            } => write!(
                f,
                "motor {motor}: {temperature_c:.1} °C, at or above the safety limit {limit_c:.1} °C"
            ),
            Refusal::JointOffStart {
                motor,
                q_rad,
                start_rad,
                tolerance_rad,
            } => write!(
                f,
                "motor {motor}: joint at {q_rad:.4} rad, {:.4} rad from the start pose's \
                 {start_rad:.4} rad (tolerance {tolerance_rad} rad): move the leg, or check \
                 its [calibration] (adam calibrate)",
                (q_rad - start_rad).abs()
            ),
            Refusal::ImuDead { fresh, samples } => write!(
                f,
                "IMU: {fresh} fresh samples in {samples} periods: dead or disconnected"
            ),
            Refusal::ImuFrozen { fresh } => {
                write!(f, "IMU: all {fresh} samples identical: frozen output")
            }
            Refusal::ImuPitch {
                pitch_rad,
                limit_rad,
            } => write!(
                f,
                "IMU: pitch {pitch_rad:.4} rad, beyond ±{limit_rad} rad of upright \
                 (bringup.max_start_pitch_rad): the robot tilted, or the IMU mounted wrong"
            ),
            Refusal::ImuNotStill {
                accel_norm_mps2,
                limit_mps2,
            } => write!(
                f,
                "IMU: |a| = {accel_norm_mps2:.3} m/s², more than {limit_mps2} m/s² from g: \
                 the robot is moving or the accelerometer is off"
            ),
            Refusal::BusLoad {
                measured_us,
                period_us,
                limit,
            } => write!(
                f,
                "bus load: the busiest bus took {measured_us:.0} µs of the {period_us:.0} µs \
                 period ({:.0} %, limit {:.0} %): another node on the bus or a wrong bitrate",
                100.0 * measured_us / period_us,
                100.0 * limit
            ),
            Refusal::Bus(e) => write!(f, "bus: {e}"),
        }
    }
}

/// `x ≤ limit`, false for NaN: a value that is not a number never passes a check.
pub(super) fn at_most(x: f64, limit: f64) -> bool {
    x <= limit
}

/// `x < limit`, false for NaN.
fn below(x: f64, limit: f64) -> bool {
    x < limit
}

/// The checks of what the pre-flight heard, against `config`; `start_pose` is the motor-side
/// pose of every slot Start ramps to ([`crate::control::Controller::first_pose`]).
pub fn check(
    config: &RuntimeConfig,
    layout: &SlotLayout,
    start_pose: &[f64; SLOTS],
    scan: &[MotorScan],
    heard: Option<&Heard>,
) -> Vec<Refusal> {
    let b = &config.bringup;
    let mut out = Vec::new();
    for s in scan {
        match s.answer {
            Answer::Silent => out.push(Refusal::MotorSilent(s.target.clone())),
            Answer::EnableRefused(e) => out.push(Refusal::EnableRefused(s.target.clone(), e)),
            Answer::Reply(_) => {}
        }
    }
    let Some(h) = heard else {
        return out;
    };
    if let Some(e) = &h.bus_failure {
        out.push(Refusal::Bus(e.clone()));
    }
    for (t, reply, count) in &h.motors {
        if u64::from(*count) * 10 < u64::from(h.samples) * 9 {
            out.push(Refusal::MotorDropping {
                motor: t.clone(),
                heard: *count,
                samples: h.samples,
            });
        }
        let Some(r) = reply else { continue };
        if !r.errors.is_empty() {
            out.push(Refusal::MotorFault(t.clone(), r.errors));
        }
        if !below(r.temperature_c, config.safety.max_temperature_c) {
            out.push(Refusal::MotorHot {
                motor: t.clone(),
                temperature_c: r.temperature_c,
                limit_c: config.safety.max_temperature_c,
            });
        }
        let (q, start, tolerance) = if t.slot < LEG_SLOTS {
            (
                layout.model_rad(t.slot, r.q_rad),
                layout.model_rad(t.slot, start_pose[t.slot]),
                b.start_pose_tolerance_rad,
            )
        } else {
            (
                r.q_rad,
                layout.held_center_rad[t.slot],
                layout.held_tolerance_rad[t.slot],
            )
        };
        if !at_most((q - start).abs(), tolerance) {
            out.push(Refusal::JointOffStart {
                motor: t.clone(),
                q_rad: q,
                start_rad: start,
                tolerance_rad: tolerance,
            });
        }
    }
    let min_fresh = (b.min_imu_fraction * f64::from(h.samples)).ceil() as u32;
    if h.imu_fresh < min_fresh.max(1) {
        out.push(Refusal::ImuDead {
            fresh: h.imu_fresh,
            samples: h.samples,
        });
    } else if h.imu_frozen {
        out.push(Refusal::ImuFrozen { fresh: h.imu_fresh });
    } else {
        if !at_most(h.imu_pitch_rad.abs(), b.max_start_pitch_rad) {
            out.push(Refusal::ImuPitch {
                pitch_rad: h.imu_pitch_rad,
                limit_rad: b.max_start_pitch_rad,
            });
        }
        if !at_most(
            (h.imu_accel_norm_mps2 - GRAVITY_MPS2).abs(),
            b.max_still_accel_error_mps2,
        ) {
            out.push(Refusal::ImuNotStill {
                accel_norm_mps2: h.imu_accel_norm_mps2,
                limit_mps2: b.max_still_accel_error_mps2,
            });
        }
    }
    let period_s = config.period_s();
    if h.bus_time_max_s > b.max_bus_load * period_s {
        out.push(Refusal::BusLoad {
            measured_us: h.bus_time_max_s * 1e6,
            period_us: period_s * 1e6,
            limit: b.max_bus_load,
        });
    }
    out
}

/// Listen `samples` periods to `targets` (all of which answered the scan) and the IMU, every
/// motor at zero torque, paced by `clock` at the config's rate. The bus is activated and left
/// deactivated (configured).
fn listen<B: Backend, C: Clock>(
    config: &RuntimeConfig,
    backend: &mut B,
    clock: &mut C,
    targets: &[MotorTarget],
) -> Result<Heard> {
    let samples = config.bringup.samples;
    let period_s = config.period_s();
    let specs: Vec<MotorSpec> = targets.iter().map(|t| t.spec).collect();
    let commands: Vec<Command> = specs.iter().map(zero_torque).collect();
    let mut replies: Vec<Reply> = specs.iter().map(|s| Reply::zeroed(s.id)).collect();
    let mut heard = Heard {
        samples,
        motors: targets.iter().map(|t| (t.clone(), None, 0)).collect(),
        ..Heard::default()
    };
    let mut bus_times = Vec::with_capacity(samples as usize);
    let mut imu: Vec<ImuSample> = Vec::with_capacity(samples as usize);
    backend.configure(&specs)?;
    backend.activate()?;
    let budget = Duration::from_secs_f64(period_s);
    let t0 = clock.now_s();
    for k in 0..samples {
        for r in replies.iter_mut() {
            r.q_rad = f64::NAN;
        }
        match backend.exchange(&commands, &mut replies, budget) {
            Ok(report) => bus_times.push(report.bus_time.as_secs_f64()),
            Err(BusError::MissingReply { .. }) => {}
            Err(e) => {
                heard.bus_failure = Some(e.to_string());
                break;
            }
        }
        for (i, r) in replies.iter().enumerate() {
            if r.q_rad.is_finite() {
                heard.motors[i].1 = Some(*r);
                heard.motors[i].2 += 1;
            }
        }
        let t = clock.now_s() - t0;
        if let Some(s) = backend.read_at(t) {
            let advancing = imu.last().is_none_or(|last| s.t_s > last.t_s);
            if advancing && s.t_s.is_finite() {
                imu.push(s);
            }
        }
        clock.sleep_until(t0 + f64::from(k + 1) * period_s);
    }
    backend.deactivate()?;
    heard.imu_fresh = imu.len() as u32;
    heard.imu_frozen = imu.len() > 1
        && imu.iter().all(|s| {
            (s.gyro_pitch_rad_s, s.accel_x_mps2, s.accel_z_mps2)
                == (
                    imu[0].gyro_pitch_rad_s,
                    imu[0].accel_x_mps2,
                    imu[0].accel_z_mps2,
                )
        });
    let n = imu.len() as f64;
    heard.imu_pitch_rad = imu
        .iter()
        .map(|s| PitchEstimator::accel_pitch_rad(s.accel_x_mps2, s.accel_z_mps2))
        .sum::<f64>()
        / n;
    heard.imu_accel_norm_mps2 = imu
        .iter()
        .map(|s| s.accel_x_mps2.hypot(s.accel_z_mps2))
        .sum::<f64>()
        / n;
    bus_times.sort_by(f64::total_cmp);
    heard.bus_time_median_s = bus_times.get(bus_times.len() / 2).copied().unwrap_or(0.0);
    heard.bus_time_max_s = bus_times.last().copied().unwrap_or(0.0);
    Ok(heard)
}

/// What the pre-flight saw and decided.
#[derive(Clone, Debug, PartialEq)]
pub struct PreflightReport {
    /// The scan, one row per driven motor.
    pub scan: Vec<MotorScan>,
    /// The listening periods (`None` when a motor was silent: nothing was enabled together).
    pub heard: Option<Heard>,
    /// The start pose's joint angle per leg slot, rad (model side).
    pub start_rad: [f64; LEG_SLOTS],
    /// The control period, s.
    pub period_s: f64,
    /// Why it refuses (empty: passed).
    pub refusals: Vec<Refusal>,
}

impl PreflightReport {
    /// Whether every check passed.
    pub fn passed(&self) -> bool {
        self.refusals.is_empty()
    }

    /// `Ok` if every check passed; otherwise the error listing every refusal.
    pub fn refuse(&self) -> Result<()> {
        if self.passed() {
            return Ok(());
        }
        Err(RuntimeError::Preflight {
            refusals: self.refusals.iter().map(|r| format!("\n  - {r}")).collect(),
        })
    }
}

impl fmt::Display for PreflightReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "pre-flight (every motor at zero torque):")?;
        write!(f, "{}", ScanTable(&self.scan))?;
        if let Some(h) = &self.heard {
            writeln!(
                f,
                "listened {} periods: IMU {} fresh samples, pitch {:.4} rad, |a| {:.3} m/s²; \
                 busiest bus {:.0} µs median, {:.0} µs max per exchange of the {:.0} µs period",
                h.samples,
                h.imu_fresh,
                h.imu_pitch_rad,
                h.imu_accel_norm_mps2,
                h.bus_time_median_s * 1e6,
                h.bus_time_max_s * 1e6,
                self.period_s * 1e6
            )?;
        }
        if self.passed() {
            writeln!(f, "pre-flight: passed")
        } else {
            writeln!(f, "pre-flight: REFUSED")?;
            for r in &self.refusals {
                writeln!(f, "  - {r}")?;
            }
            Ok(())
        }
    }
}

/// The pre-flight of `setup` on `backend` (not active): [`scan`] every driven motor, then
/// listen `bringup.samples` periods at zero torque (paced by `clock`), then [`check`]. A
/// refusal is in the report ([`PreflightReport::refuse`] turns it into the error); an error is
/// a bus that could not be driven at all.
pub fn preflight<B: Backend, C: Clock>(
    setup: &Setup,
    backend: &mut B,
    clock: &mut C,
    with_held: bool,
) -> Result<PreflightReport> {
    let config = &setup.config;
    let controller = setup.controller(with_held)?;
    let layout = *controller.layout();
    let start_pose = controller.first_pose();
    let targets = targets(config, with_held)?;
    let budget = Duration::from_secs_f64(config.period_s());
    let scanned = scan(backend, &targets, budget)?;
    let all_answered = scanned.iter().all(|s| matches!(s.answer, Answer::Reply(_)));
    let heard = if all_answered {
        Some(listen(config, backend, clock, &targets)?)
    } else {
        None
    };
    let refusals = check(config, &layout, &start_pose, &scanned, heard.as_ref());
    let mut start_rad = [0.0; LEG_SLOTS];
    for (k, s) in start_rad.iter_mut().enumerate() {
        *s = layout.model_rad(k, start_pose[k]);
    }
    Ok(PreflightReport {
        scan: scanned,
        heard,
        start_rad,
        period_s: config.period_s(),
        refusals,
    })
}
