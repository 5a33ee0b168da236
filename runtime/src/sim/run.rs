//! The runtime on the simulated ADAM: [`drivers::sim::robot::RobotSim`] as the [`JointPlant`](drivers::sim::plant::JointPlant) behind a
//! [`SimBus`] (every command and reply goes through the A1 CAN codec and the simulated firmware),
//! its torso IMU as the drivers' [`Imu`](drivers::imu::Imu), on a treadmill, under a simulated clock.
//!
//! ```text
//! gait file initial_state (q⁺, q̇⁺) ─▶ RobotSim (belt = gait speed, or a BeltProfile) ─▶ SimBus<RobotSim>
//!   ─▶ FaultySim (faults, the belt profile, pushes at a phase, the truth every 10 ms)
//!   runtime::run(start_walking | script) ─▶ Controller in Walk from tick 0 (or from Stand) ─▶ RunSummary
//!   RobotSim events (touchdowns, fall) + truth + RunSummary ─▶ SimWalkReport (up to any fall)
//! ```
//! `adam demo`, `adam run --backend sim` and the end-to-end tests call [`walk`].
//!
//! # The treadmill
//! The belt is a moving ground of [`SimWalkOptions::belt_length_m`] (1.6 m) with the robot at
//! its centre at the start; its speed is constant ([`SimWalkOptions::belt_speed_mps`], the
//! gait's by default) or follows a [`BeltProfile`] (targets in time, ramped at
//! [`SimWalkOptions::belt_acceleration_mps2`]). A stance foot past either end is a fall
//! (`off the back of the belt`). The report carries the truth: the belt speed and the hip's
//! position on the belt at each step ([`StepRecord`]), every 10 ms ([`TruthSample`]) and at
//! the end or the fall.
//!
//! # Faults and the soak
//! With [`SimWalkOptions::faults`] the backend is a [`FaultySim`]: before each exchange it starts
//! and ends the faults of the profile's seeded schedule ([`crate::sim::faults`]; [`crate::sim::inject`]) at simulated time —
//! wire faults in the [`SimBus`], motor faults in its firmware, pushes, belt steps and IMU
//! faults in the [`RobotSim`] — and a [`FaultClock`] wakes the loop late during overrun faults.
//! Applying a fault allocates nothing (the schedule is built before the loop).
//! [`soak`] walks for a long time under a profile: after each trip it lets the robot settle in
//! Damping for [`SOAK_LINGER_S`], then resets: a fresh controller (Reset) on the robot re-placed
//! in the gait's post-impact state, walking at once, and counts trips by reason.
//!
//! The run starts in the gait's planned post-impact state (the robot already walking at the
//! gait speed, its first stance foot just down), so that every step of the run is on the
//! gait's orbit; or, with [`SimStart::Stand`], standing at rest in the gait's first pose, the
//! controller ramped to Stand by a Start at `t = 0` and walked by the
//! [`SimWalkOptions::script`] (the controller's launch; see `runtime/tests/stand_sim.rs`: its
//! first steps are quicker and converge to the orbit over some 20 steps).
//!
//! With a gait library (speed control) the run starts on the library gait nearest the belt's
//! first speed ([`crate::Setup::starting_near`]); on a belt at rest, on the library gait whose
//! step is nearest the runtime gait's ([`crate::Setup::starting_at_rest`]): the slowest gait
//! of the library down to 0.125 m/s stands on a 0.125 m stance, and from it Stop → Stand →
//! Walk on the 1.6 m belt went off its back in 5 of 5 (`adam bench treadmill --config
//! configs/runtime/adam_treadmill.toml`, table (d)); the 0.15 m stance is the one the
//! 0.15–0.40 m/s library stood on, its runs unchanged figure for figure.

use crate::backend::Backend;
use crate::control::OperatorCommand;
use crate::rt_loop::{LoopOptions, MonotonicClock};
use crate::sim::faults::{Fault, FaultProfile};
pub use crate::sim::hung::joint_bench_backend;
use crate::sim::inject::{FaultClock, FaultySim};
pub use crate::sim::report::{SimWalkReport, StepRecord, TruthSample};
use crate::sim::treadmill::BeltProfile;
use crate::{Result, RuntimeError, Setup};
use drivers::imu::ImuNoise;
use drivers::sim::robot::{
    Boom, LegJoint, RobotSim, RobotSimConfig, DEFAULT_BELT_ACCELERATION_MPS2, DEFAULT_BELT_LENGTH_M,
};
use drivers::sim::{
    bus::{SimBus, SimConfig},
    firmware::{A1Model, SimMotor},
    wire::WireStats,
};
use model::Side;
use std::path::PathBuf;

/// How to run the simulated robot.
#[derive(Clone, Debug)]
pub struct SimWalkOptions {
    /// Simulated run time, s.
    pub duration_s: f64,
    /// Treadmill belt speed, m/s (`None`: the gait's speed, so the robot stays in place).
    pub belt_speed_mps: Option<f64>,
    /// The belt's speed profile (replaces `belt_speed_mps`; [`BeltProfile`]).
    pub belt_profile: Option<BeltProfile>,
    /// The belt's ramp acceleration, m/s² (default 0.5).
    pub belt_acceleration_mps2: f64,
    /// The belt's length, m (default 1.6; infinite: endless). The robot starts at its centre;
    /// past either end it has fallen.
    pub belt_length_m: f64,
    /// How the run starts: walking in the gait's post-impact state, or standing.
    pub start: SimStart,
    /// Operator commands at simulated times, s (sorted by time).
    pub script: Vec<(f64, OperatorCommand)>,
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
    /// Faults to inject (`None`: none). Overrun faults need the simulated clock.
    pub faults: Option<FaultProfile>,
    /// Publish every tick's state sample over iceoryx2 (`telemetry.service_name`): for the
    /// live view (`adam live`) and any other subscriber.
    pub publish: bool,
    /// End the run this long after a safety trip (`None`: run the whole duration).
    pub stop_after_trip_s: Option<f64>,
    /// How each leg motor sits on its joint, in leg slot order (default: as the model's joint,
    /// what the identity calibration expects); a robot to calibrate (`adam calibrate`).
    pub encoder_mounts: [drivers::sim::firmware::EncoderMount; crate::slots::LEG_SLOTS],
    /// Run the pre-flight checks before the loop, on the robot hung on the boom
    /// ([`crate::sim::hung::preflight_hung`]): for a run that starts from Idle
    /// (`SimStart::Stand`); its report lands in the run's report.
    pub preflight: bool,
}

impl SimWalkOptions {
    /// `duration_s` on the treadmill at the gait speed, default IMU noise, seed 1, no log.
    pub fn new(duration_s: f64) -> Self {
        Self {
            duration_s,
            belt_speed_mps: None,
            belt_profile: None,
            belt_acceleration_mps2: DEFAULT_BELT_ACCELERATION_MPS2,
            belt_length_m: DEFAULT_BELT_LENGTH_M,
            start: SimStart::Walk,
            script: Vec::new(),
            boom: None,
            imu_noise: ImuNoise::default(),
            seed: 1,
            log_path: None,
            real_time: false,
            faults: None,
            publish: false,
            stop_after_trip_s: None,
            encoder_mounts: Default::default(),
            preflight: false,
        }
    }
}

/// How a simulated run starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimStart {
    /// In Walk from the first tick, the robot in the gait's planned post-impact state.
    Walk,
    /// Standing on both feet in the gait's first pose at rest; the operator's Start at
    /// `t = 0` ramps the controller to Stand (2 s), and a scripted `walk` starts the walk.
    Stand,
}

/// The simulated robot behind its bus: the drivers' IMU on the simulator's torso (attached
/// with [`RobotSim::attach_imu`]), stamped with the loop time since the simulator has just
/// stepped to it; and the true torso pitch.
impl Backend for SimBus<RobotSim> {
    fn true_pitch_rad(&self) -> Option<f64> {
        Some(self.plant().torso_pitch_rad())
    }
    /// The hip's position on the belt, forward of its centre (where the robot starts).
    fn true_belt_position_m(&self) -> Option<f64> {
        Some(self.plant().position_on_belt_m())
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
    let belt_speed_mps = match &options.belt_profile {
        Some(profile) => {
            profile.validate("belt profile")?;
            profile.initial_speed_mps()
        }
        None => options.belt_speed_mps.unwrap_or(setup.gait.speed_mps),
    };
    let state = setup
        .gait
        .initial_state
        .as_ref()
        .ok_or_else(|| RuntimeError::Gait {
            reason: "the gait file has no initial_state to start the simulation in".into(),
        })?;
    let config = RobotSimConfig {
        belt_speed_mps,
        belt_length_m: options.belt_length_m,
        belt_acceleration_mps2: options.belt_acceleration_mps2,
        boom: options.boom,
        ..RobotSimConfig::default()
    };
    let mut sim = RobotSim::new(&setup.model, config).map_err(|e| sim_error(&e))?;
    match options.start {
        SimStart::Walk => sim.set_state_single_stance(&state.q, &state.dq, setup.gait.stance_leg),
        SimStart::Stand => sim.set_state(&state.q, &vec![0.0; state.q.len()]),
    }
    .map_err(|e| sim_error(&e))?;
    sim.attach_imu(options.imu_noise, options.seed);
    let mut motors = Vec::with_capacity(setup.config.leg_motors.len());
    for (k, m) in setup.config.leg_motors.iter().enumerate() {
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
        motors.push(SimMotor {
            spec: m.spec(&format!("leg_motors[{k}]"))?,
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
    let mut bus = SimBus::new(bus_config, sim).map_err(|e| RuntimeError::Gait {
        reason: format!("simulated bus: {e}"),
    })?;
    crate::sim::hung::mount_sim_motors(&mut bus, setup, &options.encoder_mounts)?;
    Ok(bus)
}

fn sim_error(e: &drivers::sim::robot::RobotSimError) -> RuntimeError {
    RuntimeError::Gait {
        reason: format!("simulator: {e}"),
    }
}

/// How often a run records the treadmill's ground truth ([`SimWalkReport::trace`]), s.
pub const TRUTH_PERIOD_S: f64 = 0.01;

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
    // With speed control, start on the library gait nearest the belt's first speed; on a belt
    // at rest, on the one whose step is nearest the runtime gait's (its stance).
    let first_belt_mps = match &options.belt_profile {
        Some(profile) => Some(profile.initial_speed_mps()),
        None => options.belt_speed_mps,
    };
    let near;
    let setup = match first_belt_mps {
        Some(v) if !setup.library.is_empty() => {
            near = if v > 0.0 {
                setup.clone().starting_near(v)
            } else {
                setup.clone().starting_at_rest()
            };
            &near
        }
        _ => setup,
    };
    let bus = sim_backend(setup, options)?;
    let preflight = if options.preflight {
        let pitch_rad = bus.plant().torso_pitch_rad();
        let report =
            crate::sim::hung::preflight_hung(setup, &bus, pitch_rad, &options.encoder_mounts)?;
        report.refuse()?;
        Some(report)
    } else {
        None
    };
    let belt_speed_mps = bus.plant().belt_speed_mps();
    let x0_m = bus.plant().base_position_m()[0];
    let stance_x0_m = bus.plant().foot_position_m(setup.gait.stance_leg)[0];
    let period_s = 1.0 / setup.config.loop_.rate_hz;
    let none = FaultProfile::none();
    let profile = options.faults.as_ref().unwrap_or(&none);
    profile.validate("fault profile")?;
    let schedule = profile.schedule(options.duration_s, period_s, options.seed);
    if options.real_time
        && schedule
            .iter()
            .any(|f| matches!(f.fault, Fault::Overrun { .. }))
    {
        return Err(RuntimeError::InvalidField {
            origin: "fault profile".into(),
            field: "events/random: overrun".into(),
            value: "real_time = true".into(),
            reason: "overrun faults need the simulated clock".into(),
        });
    }
    let clock = FaultClock::new(&schedule);
    let belt_points = options
        .belt_profile
        .as_ref()
        .map_or(&[][..], |p| p.points.as_slice());
    let belt_commands = if setup.library.is_empty() {
        Vec::new()
    } else {
        belt_script(belt_speed_mps, &schedule, belt_points)
    };
    let backend = FaultySim::new(setup, bus, profile, schedule)?
        .with_belt_profile(belt_points)
        .with_truth_trace(options.duration_s, TRUTH_PERIOD_S);
    let mut loop_options = LoopOptions::simulation(options.duration_s);
    loop_options.start_walking = options.start == SimStart::Walk;
    if options.start == SimStart::Stand {
        loop_options.script.push((0.0, OperatorCommand::Start));
    }
    loop_options.script.extend_from_slice(&options.script);
    loop_options.script.extend(belt_commands);
    loop_options.script.sort_by(|a, b| a.0.total_cmp(&b.0));
    loop_options.log_path = options.log_path.clone();
    loop_options.stop_after_trip_s = options.stop_after_trip_s;
    loop_options.publish = options.publish;

    // A wall-clock run asks for mlockall and SCHED_FIFO like the robot run (a warning if denied).
    loop_options.realtime = options.real_time;
    let (summary, mut backend) = if options.real_time {
        crate::run(setup, backend, MonotonicClock, loop_options, operator)?
    } else {
        crate::run(setup, backend, clock, loop_options, operator)?
    };
    let trace = std::mem::take(&mut backend.trace);
    let faults_started = backend.started;
    let wire = backend.bus.wire_stats();
    let mut report = SimWalkReport::measure(
        summary,
        backend.bus.plant(),
        options.duration_s,
        belt_speed_mps,
        setup.gait.stance_leg,
        x0_m,
        stance_x0_m,
        faults_started,
        wire,
        trace,
    );
    report.preflight = preflight;
    Ok(report)
}

/// The belt's speed as an operator tells it to speed control: at the start, at every pair of
/// the belt profile (`--belt t:v,…`: the speed the belt ramps to), and at the start and end of
/// every belt step of the fault schedule (operator commands, so the log replays).
fn belt_script(
    belt_speed_mps: f64,
    schedule: &[crate::sim::faults::ScheduledFault],
    belt_points: &[(f64, f64)],
) -> Vec<(f64, crate::control::OperatorCommand)> {
    use crate::control::OperatorCommand;
    let mut script = vec![(
        0.0,
        OperatorCommand::Belt {
            speed_mps: belt_speed_mps,
        },
    )];
    for &(t_s, speed_mps) in belt_points {
        script.push((t_s, OperatorCommand::Belt { speed_mps }));
    }
    for f in schedule {
        if let Fault::BeltSpeed { speed_mps } = f.fault {
            script.push((f.start_s, OperatorCommand::Belt { speed_mps }));
            script.push((
                f.end_s,
                OperatorCommand::Belt {
                    speed_mps: belt_speed_mps,
                },
            ));
        }
    }
    script.sort_by(|a, b| a.0.total_cmp(&b.0));
    script
}

/// How long the soak lets the robot lie in Damping after a trip before it resets, s.
pub const SOAK_LINGER_S: f64 = 0.5;

/// How to soak.
#[derive(Clone, Debug)]
pub struct SoakOptions {
    /// Simulated time to walk, s.
    pub duration_s: f64,
    /// Faults to inject.
    pub profile: FaultProfile,
    /// Seed of the first episode (episode `k` uses `seed + k`).
    pub seed: u64,
    /// Keep each episode's MCAP log here as `episode-NNN.mcap` (`None`: a temporary file,
    /// removed at the end; the log still runs, so its drops are measured).
    pub log_dir: Option<PathBuf>,
}

/// What the soak saw.
#[derive(Clone, Debug, Default)]
pub struct SoakReport {
    /// Walks started (1 + resets).
    pub episodes: u64,
    /// Ticks run.
    pub ticks: u64,
    /// Simulated time, s.
    pub sim_time_s: f64,
    /// Deadlines missed.
    pub overruns: u64,
    /// Trips by reason ([`crate::safety::Trip::name`]), in order of first occurrence.
    pub trips: Vec<(&'static str, u64)>,
    /// Simulator falls with no safety trip before them.
    pub falls_without_trip: u64,
    /// Log records dropped (queue full).
    pub log_drops: u64,
    /// MCAP messages written.
    pub log_messages: u64,
    /// Worst controller tick compute time, ns.
    pub worst_tick_ns: u64,
    /// Distance walked over the belt (sum of step lengths), m.
    pub distance_m: f64,
    /// Steps walked.
    pub steps: u64,
    /// Faults injected from the schedule.
    pub faults: u64,
    /// Replies missing.
    pub missing_replies: u64,
    /// What the wire did.
    pub wire: WireStats,
}

impl SoakReport {
    /// Trips of one reason.
    pub fn trips_of(&self, reason: &str) -> u64 {
        self.trips
            .iter()
            .find(|(r, _)| *r == reason)
            .map_or(0, |(_, n)| *n)
    }

    fn add(&mut self, report: &SimWalkReport, period_s: f64) {
        let s = &report.summary;
        self.episodes += 1;
        self.ticks += s.ticks;
        self.sim_time_s += s.ticks as f64 * period_s;
        self.overruns += s.overruns;
        if let Some(trip) = s.trip {
            match self.trips.iter_mut().find(|(r, _)| *r == trip.name()) {
                Some((_, n)) => *n += 1,
                None => self.trips.push((trip.name(), 1)),
            }
        } else if report.fall.is_some() {
            self.falls_without_trip += 1;
        }
        if let Some(log) = &s.log {
            self.log_drops += log.dropped;
            self.log_messages += log.messages;
        }
        self.worst_tick_ns = self.worst_tick_ns.max(s.tick_times.max_ns);
        self.distance_m += report.distance_m;
        self.steps += report.steps as u64;
        self.faults += report.faults_started;
        self.missing_replies += s.missing_replies;
        self.wire += report.wire;
    }
}

impl std::fmt::Display for SoakReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let row = |f: &mut std::fmt::Formatter<'_>, k: &str, v: String| writeln!(f, "{k:<28} {v}");
        row(f, "simulated time", format!("{:.1} s", self.sim_time_s))?;
        row(f, "ticks", self.ticks.to_string())?;
        row(f, "overruns", self.overruns.to_string())?;
        row(f, "episodes (walk starts)", self.episodes.to_string())?;
        row(f, "faults injected", self.faults.to_string())?;
        let total: u64 = self.trips.iter().map(|(_, n)| n).sum();
        row(f, "trips", total.to_string())?;
        for (reason, n) in &self.trips {
            row(f, &format!("  {reason}"), n.to_string())?;
        }
        row(
            f,
            "falls without a trip",
            self.falls_without_trip.to_string(),
        )?;
        row(
            f,
            "CAN frames lost/corrupted",
            format!("{} / {}", self.wire.lost, self.wire.corrupted),
        )?;
        row(f, "replies missing", self.missing_replies.to_string())?;
        row(
            f,
            "log drops",
            format!("{} of {} messages", self.log_drops, self.log_messages),
        )?;
        row(
            f,
            "worst tick compute time",
            format!("{:.1} µs", self.worst_tick_ns as f64 / 1e3),
        )?;
        row(
            f,
            "distance walked",
            format!("{:.2} m in {} steps", self.distance_m, self.steps),
        )?;
        Ok(())
    }
}

/// Walk `options.duration_s` of simulated time under random faults; after each trip, reset
/// and walk again on a freshly placed robot. `progress` sees the report after each episode.
pub fn soak(
    setup: &Setup,
    options: &SoakOptions,
    mut progress: impl FnMut(&SoakReport),
) -> Result<SoakReport> {
    if !(options.duration_s.is_finite() && options.duration_s > 0.0) {
        return Err(RuntimeError::InvalidField {
            origin: "soak".into(),
            field: "minutes".into(),
            value: (options.duration_s / 60.0).to_string(),
            reason: "must be positive and finite".into(),
        });
    }
    options.profile.validate("fault profile")?;
    let period_s = 1.0 / setup.config.loop_.rate_hz;
    let temp_log = std::env::temp_dir().join(format!("adam-soak-{}.mcap", std::process::id()));
    if let Some(dir) = &options.log_dir {
        std::fs::create_dir_all(dir).map_err(|error| RuntimeError::Io {
            path: dir.clone(),
            error,
        })?;
    }
    let mut report = SoakReport::default();
    // Less than one tick left: done.
    while options.duration_s - report.sim_time_s >= period_s {
        let episode = report.episodes;
        let mut walk_options = SimWalkOptions::new(options.duration_s - report.sim_time_s);
        walk_options.seed = options.seed.wrapping_add(episode);
        walk_options.faults = Some(options.profile.clone());
        walk_options.stop_after_trip_s = Some(SOAK_LINGER_S);
        // The soak's subject is the faults: an endless belt (the belt's ends are the
        // treadmill bench's, `adam bench treadmill`).
        walk_options.belt_length_m = f64::INFINITY;
        walk_options.log_path = Some(match &options.log_dir {
            Some(dir) => dir.join(format!("episode-{episode:03}.mcap")),
            None => temp_log.clone(),
        });
        let walked = walk(setup, &walk_options)?;
        report.add(&walked, period_s);
        progress(&report);
    }
    if options.log_dir.is_none() {
        let _ = std::fs::remove_file(&temp_log);
    }
    Ok(report)
}
