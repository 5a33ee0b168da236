//! The runtime on the simulated ADAM: [`drivers::sim::RobotSim`] as the [`JointPlant`] behind a
//! [`SimBus`] (every command and reply goes through the A1 CAN codec and the simulated firmware),
//! its torso IMU as the runtime's [`crate::Imu`], on a treadmill, under a simulated clock.
//!
//! ```text
//! gait file initial_state (q⁺, q̇⁺) ─▶ RobotSim (belt = gait speed) ─▶ SimBus<RobotSim>
//!   runtime::run(start_walking) ─▶ Controller in Walk from tick 0 ─▶ RunSummary
//!   RobotSim events (touchdowns, fall) + RunSummary ─▶ SimWalkReport
//! ```
//! `adam demo`, `adam run --backend sim` and the end-to-end tests call [`walk`].
//!
//! The run starts in the gait's planned post-impact state (the robot already walking at the
//! gait speed, its first stance foot just down), not from standing: Ramp and Stand end in a
//! double-support pose at rest, from which the state-based phase cannot start a step.

use crate::io::Imu;
use crate::rt_loop::{LoopOptions, MonotonicClock, RunSummary, SimulatedClock};
use crate::{Result, RuntimeError, Setup};
use drivers::imu::ImuNoise;
use drivers::sim::{Boom, FallCause, LegJoint, RobotSim, RobotSimConfig, SimEvent};
use drivers::sim_bus::{A1Model, SimBus, SimConfig, SimMotor};
use model::Side;
use std::path::PathBuf;

/// How to run the simulated robot.
#[derive(Clone, Debug)]
pub struct SimWalkOptions {
    /// Simulated run time, s.
    pub duration_s: f64,
    /// Treadmill belt speed, m/s (`None`: the gait's speed, so the robot stays in place).
    pub belt_speed_mps: Option<f64>,
    /// Boom mass added to the torso (`None`: free torso, as the gait was planned).
    pub boom: Option<Boom>,
    /// IMU noise.
    pub imu_noise: ImuNoise,
    /// Seed of the IMU and encoder noise.
    pub seed: u64,
    /// Write an MCAP log here.
    pub log_path: Option<PathBuf>,
    /// Pace the loop by the wall clock at the config's rate (measures loop jitter) instead of
    /// running as fast as the CPU allows under a simulated clock.
    pub real_time: bool,
}

impl SimWalkOptions {
    /// `duration_s` on the treadmill at the gait speed, default IMU noise, seed 1, no log.
    pub fn new(duration_s: f64) -> Self {
        Self {
            duration_s,
            belt_speed_mps: None,
            boom: None,
            imu_noise: ImuNoise::default(),
            seed: 1,
            log_path: None,
            real_time: false,
        }
    }
}

/// What the simulated walk did: the loop's summary and the simulator's ground truth.
#[derive(Clone, Debug)]
pub struct SimWalkReport {
    /// The loop's summary (states, trips, tracking, tick times, log).
    pub summary: RunSummary,
    /// Simulated run time, s.
    pub duration_s: f64,
    /// Belt speed used, m/s.
    pub belt_speed_mps: f64,
    /// Steps: touchdowns of the swing foot (alternating sides).
    pub steps: usize,
    /// Touchdowns of the same foot twice in a row (scuffs, bounces).
    pub repeated_touchdowns: usize,
    /// Mean step length (front foot minus back foot at touchdown), m.
    pub mean_step_length_m: f64,
    /// Mean step duration (between alternating touchdowns, the first from t = 0), s.
    pub mean_step_duration_s: f64,
    /// Mean walking speed over the belt, mean step length / mean step duration, m/s.
    pub speed_mps: f64,
    /// World displacement of the hip over the run (positive: forward, against the belt), m.
    pub drift_m: f64,
    /// Time the run walked: up to the fall, or the whole run, s.
    pub walked_s: f64,
    /// The fall, if any: time, s, and cause.
    pub fall: Option<(f64, FallCause)>,
    /// Time the simulator faulted, s, if it did.
    pub sim_fault_s: Option<f64>,
    /// Friction-cone violations reported by the simulator (μ = 1; the foot stays pinned).
    pub friction_exceeded: usize,
}

/// The runtime's IMU on the simulator's torso IMU (attached with [`RobotSim::attach_imu`]);
/// stamped with the loop time, since the simulator has just stepped to it.
impl Imu for RobotSim {
    fn read_imu(&mut self, t_s: f64) -> Option<crate::ImuSample> {
        let mut s = drivers::imu::ImuSample::default();
        drivers::imu::Imu::read(self, &mut s).ok()?;
        Some(crate::ImuSample {
            t_s,
            gyro_pitch_rad_s: s.gyro_pitch_rad_s,
            accel_x_mps2: s.accel_x_mps2,
            accel_z_mps2: s.accel_z_mps2,
        })
    }
    fn true_pitch_rad(&self) -> Option<f64> {
        Some(self.torso_pitch_rad())
    }
}

/// The simulated robot behind a `SimBus`, in the gait's planned post-impact state, its leg
/// motors on the buses and ids of the runtime config.
pub fn sim_backend(setup: &Setup, options: &SimWalkOptions) -> Result<SimBus<RobotSim>> {
    let origin = "simulated backend";
    let invalid = |field: &str, value: String, reason: &str| RuntimeError::InvalidField {
        origin: origin.into(),
        field: field.into(),
        value,
        reason: reason.into(),
    };
    if !(options.duration_s.is_finite() && options.duration_s > 0.0) {
        return Err(invalid(
            "duration_s",
            options.duration_s.to_string(),
            "must be positive and finite",
        ));
    }
    let belt_speed_mps = options.belt_speed_mps.unwrap_or(setup.gait.speed_mps);
    let state = setup
        .gait
        .initial_state
        .as_ref()
        .ok_or_else(|| RuntimeError::Gait {
            reason: "the gait file has no initial_state to start the simulation in".into(),
        })?;
    let config = RobotSimConfig {
        belt_speed_mps,
        boom: options.boom,
        ..RobotSimConfig::default()
    };
    let mut sim = RobotSim::new(&setup.model, config).map_err(|e| sim_error(&e))?;
    sim.set_state_single_stance(&state.q, &state.dq, setup.gait.stance_leg)
        .map_err(|e| sim_error(&e))?;
    sim.attach_imu(options.imu_noise, options.seed);
    let mut motors = Vec::with_capacity(setup.config.leg_motors.len());
    for (k, m) in setup.config.leg_motors.iter().enumerate() {
        // The simulated motors are mounted like the model joints: no sign flip, no offset.
        if m.direction != 1.0 || m.offset_rad != 0.0 {
            return Err(invalid(
                &format!("leg_motors[{k}].direction/offset_rad"),
                format!("{} / {}", m.direction, m.offset_rad),
                "the simulated robot has direction 1 and offset 0",
            ));
        }
        let side = if m.joint.starts_with("left_") {
            Side::Left
        } else {
            Side::Right
        };
        let which = if m.joint.ends_with("knee_pitch") {
            LegJoint::Knee
        } else {
            LegJoint::Hip
        };
        let id = drivers::a1::MotorId::new(m.id).ok_or_else(|| {
            invalid(
                &format!("leg_motors[{k}].id"),
                m.id.to_string(),
                "must be 1..=127",
            )
        })?;
        motors.push(SimMotor {
            spec: drivers::bus::MotorSpec { bus: m.bus, id },
            joint: sim.joint_index(side, which),
        });
    }
    let bus_config = SimConfig {
        control_rate_hz: setup.config.loop_.rate_hz,
        bitrate_bps: setup.config.loop_.bitrate_bps,
        bus_count: setup.config.loop_.bus_count,
        motors,
        model: A1Model::default(),
        seed: options.seed,
    };
    SimBus::new(bus_config, sim).map_err(|e| RuntimeError::Gait {
        reason: format!("simulated bus: {e}"),
    })
}

fn sim_error(e: &drivers::sim::RobotSimError) -> RuntimeError {
    RuntimeError::Gait {
        reason: format!("simulator: {e}"),
    }
}

/// Walk the gait on the simulated treadmill for `options.duration_s` (simulated time, as fast
/// as the CPU allows) and measure the walk from the simulator's ground truth.
pub fn walk(setup: &Setup, options: &SimWalkOptions) -> Result<SimWalkReport> {
    walk_with_operator(setup, options, None)
}

/// [`walk`] with operator commands (keyboard, iceoryx2) arriving through `operator`.
pub fn walk_with_operator(
    setup: &Setup,
    options: &SimWalkOptions,
    operator: Option<crate::operator::OperatorReceiver>,
) -> Result<SimWalkReport> {
    let backend = sim_backend(setup, options)?;
    let belt_speed_mps = backend.plant().config().belt_speed_mps;
    let x0_m = backend.plant().base_position_m()[0];
    let mut loop_options = LoopOptions::simulation(options.duration_s);
    loop_options.start_walking = true;
    loop_options.log_path = options.log_path.clone();
    // A wall-clock run asks for mlockall and SCHED_FIFO like the robot run (a warning if denied).
    loop_options.realtime = options.real_time;
    let (summary, backend) = if options.real_time {
        crate::run(setup, backend, MonotonicClock, loop_options, operator)?
    } else {
        crate::run(
            setup,
            backend,
            SimulatedClock::default(),
            loop_options,
            operator,
        )?
    };
    let sim = backend.plant();
    let mut report = SimWalkReport {
        duration_s: options.duration_s,
        belt_speed_mps,
        steps: 0,
        repeated_touchdowns: 0,
        mean_step_length_m: f64::NAN,
        mean_step_duration_s: f64::NAN,
        speed_mps: f64::NAN,
        drift_m: sim.base_position_m()[0] - x0_m,
        walked_s: sim.time_s(),
        fall: None,
        sim_fault_s: None,
        friction_exceeded: 0,
        summary,
    };
    // The initial state is just after a touchdown of the gait's stance foot.
    let mut last_side = setup.gait.stance_leg;
    let mut last_t_s = 0.0;
    let (mut length_sum_m, mut duration_sum_s) = (0.0, 0.0);
    for event in sim.events() {
        match *event {
            SimEvent::Touchdown(td) if report.fall.is_none() => {
                if td.side == last_side {
                    report.repeated_touchdowns += 1;
                    continue;
                }
                report.steps += 1;
                length_sum_m += td.step_length_m;
                duration_sum_s += td.t_s - last_t_s;
                last_side = td.side;
                last_t_s = td.t_s;
            }
            SimEvent::Fall { t_s, what } if report.fall.is_none() => {
                report.fall = Some((t_s, what));
                report.walked_s = t_s;
            }
            SimEvent::Fault { t_s } => report.sim_fault_s = Some(t_s),
            SimEvent::FrictionExceeded { .. } => report.friction_exceeded += 1,
            _ => {}
        }
    }
    if report.steps > 0 {
        let n = report.steps as f64;
        report.mean_step_length_m = length_sum_m / n;
        report.mean_step_duration_s = duration_sum_s / n;
        report.speed_mps = length_sum_m / duration_sum_s;
    }
    Ok(report)
}

fn granted(r: Option<core::result::Result<(), i32>>) -> String {
    match r {
        None => "not asked".into(),
        Some(Ok(())) => "ok".into(),
        Some(Err(errno)) => format!("denied (errno {errno})"),
    }
}

impl std::fmt::Display for SimWalkReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.summary;
        writeln!(
            f,
            "walked {:.2} s of {:.2} s on the treadmill at {:.3} m/s; final state {}",
            self.walked_s,
            self.duration_s,
            self.belt_speed_mps,
            s.final_state.name()
        )?;
        writeln!(
            f,
            "steps {} | mean step length {:.4} m | mean step duration {:.4} s | speed {:.4} m/s | drift {:+.3} m",
            self.steps,
            self.mean_step_length_m,
            self.mean_step_duration_s,
            self.speed_mps,
            self.drift_m
        )?;
        let t = &s.tracking;
        writeln!(
            f,
            "tracking RMS: hip {:.3}° knee {:.3}° (stance hip {:.3}°, stance knee {:.3}°, swing hip {:.3}°, swing knee {:.3}°) over {} walk ticks",
            t.hip_rms_deg(),
            t.knee_rms_deg(),
            t.rms_rad(0).to_degrees(),
            t.rms_rad(1).to_degrees(),
            t.rms_rad(2).to_degrees(),
            t.rms_rad(3).to_degrees(),
            t.walk_ticks
        )?;
        let trip = s
            .trip
            .map_or_else(|| "none".to_string(), |t| format!("{t:?}"));
        let fall = self
            .fall
            .map_or_else(|| "none".to_string(), |(t, w)| format!("{w:?} at {t:.3} s"));
        if let Some(rms) = t.pitch_rms_rad() {
            writeln!(
                f,
                "pitch estimate vs ground truth: RMS {:.3}°, max {:.3}° (bias estimate {:+.4} rad/s)",
                rms.to_degrees(),
                t.pitch_max_abs_rad.to_degrees(),
                s.last_sample.gyro_bias_rad_s
            )?;
        }
        writeln!(
            f,
            "safety trips: {trip} | falls: {fall} | repeated touchdowns {} | friction warnings {}",
            self.repeated_touchdowns, self.friction_exceeded
        )?;
        write!(
            f,
            "tick compute time: median {:.1} µs, p99 {:.1} µs, max {:.1} µs | missing replies {} | bus errors {}",
            s.tick_times.median_ns as f64 / 1e3,
            s.tick_times.p99_ns as f64 / 1e3,
            s.tick_times.max_ns as f64 / 1e3,
            s.missing_replies,
            s.bus_errors
        )?;
        if s.wake_latency.max_ns > 0 {
            write!(
                f,
                "\nloop wake-up latency (jitter): median {:.1} µs, p99 {:.1} µs, max {:.1} µs | overruns {} (longest streak {}) | mlockall {} SCHED_FIFO {}",
                s.wake_latency.median_ns as f64 / 1e3,
                s.wake_latency.p99_ns as f64 / 1e3,
                s.wake_latency.max_ns as f64 / 1e3,
                s.overruns,
                s.max_overrun_streak,
                granted(s.realtime.memory_locked),
                granted(s.realtime.fifo),
            )?;
        }
        Ok(())
    }
}
