//! The loop driver: runs the [`Controller`] at a fixed rate on its own thread, against any
//! [`Backend`]: a `MotorBus` and an `Imu` (SimBus, SocketCAN + IMU, replay).
//!
//! One period:
//! ```text
//! exchange(commands of the last tick) → replies ─┐     (one tick of command latency)
//! read_at(t) (the IMU) ──────────────────────────┤
//! operator: script entry due, else ring poll ────┴─▶ Controller::tick ─▶ commands
//!                                                      └─▶ StateSample ─▶ iceoryx2 + log queue
//! the exchange's CAN frames (MotorBus::frames) ─▶ log queue (`/can`)
//! sleep until the absolute deadline t0 + (k+1)·T; late → overrun (streak feeds the safety monitor)
//! ```
//! Time comes from a [`Clock`]: [`MonotonicClock`] (real time, `clock_nanosleep` with an
//! absolute deadline) or [`SimulatedClock`] (time is an argument: sleeping just advances it,
//! so a simulated backend runs as fast as the CPU allows). Before the first tick the thread
//! asks for `mlockall` and SCHED_FIFO when the config says so; refusals are warnings, reported
//! in [`RunSummary::realtime`].

use crate::backend::{Backend, WalkProgress};
use crate::control::{
    CommandMode, ControlState, Controller, JointCommand, OperatorCommand, TickInput, TickOutput,
};
use crate::operator::OperatorReceiver;
use crate::rt_sys;
use crate::safety::Trip;
use crate::slots::{MotorSample, LEG_SLOTS, OUTPUTS, SLOTS};
use crate::telemetry::frames::{BusOp, FrameBatch};
use crate::telemetry::log::{LogContext, LogRecord, LogStats, TickRecord};
use crate::telemetry::sample::{LoopStats, StateSample};
use crate::telemetry::speed_read::SpeedRow;
use crate::{Result, RuntimeError, Setup};
use core::time::Duration;
use drivers::a1::{Command, MotorId, Reply};
use drivers::bus::BusError;
use std::path::PathBuf;

/// Where the loop's time comes from.
pub trait Clock {
    /// Current time, s (any origin).
    fn now_s(&mut self) -> f64;
    /// Block until `now_s() >= deadline_s`.
    fn sleep_until(&mut self, deadline_s: f64);
    /// Whether this is simulated time: the loop then lets a full log queue wait for the writer
    /// instead of dropping records (waiting costs no simulated time). Real time: never.
    fn is_simulated(&self) -> bool {
        false
    }
}

/// Real time: CLOCK_MONOTONIC and absolute-deadline sleeping.
#[derive(Clone, Copy, Debug, Default)]
pub struct MonotonicClock;

impl Clock for MonotonicClock {
    fn now_s(&mut self) -> f64 {
        rt_sys::monotonic_ns() as f64 * 1e-9
    }
    fn sleep_until(&mut self, deadline_s: f64) {
        rt_sys::sleep_until_ns((deadline_s.max(0.0) * 1e9) as u64);
    }
}

/// Simulated time: starts at 0 and jumps to each deadline; never late.
#[derive(Clone, Copy, Debug, Default)]
pub struct SimulatedClock {
    now_s: f64,
}

impl Clock for SimulatedClock {
    fn now_s(&mut self) -> f64 {
        self.now_s
    }
    fn sleep_until(&mut self, deadline_s: f64) {
        self.now_s = self.now_s.max(deadline_s);
    }
    fn is_simulated(&self) -> bool {
        true
    }
}

/// How to run.
#[derive(Clone, Debug)]
pub struct LoopOptions {
    /// Run time, s (controller time).
    pub duration_s: f64,
    /// Drive the held motors too (false when the backend has only the four leg motors).
    pub with_held: bool,
    /// Operator commands at given controller times, s (sorted by time; applied once each).
    pub script: Vec<(f64, OperatorCommand)>,
    /// Write an MCAP log here.
    pub log_path: Option<PathBuf>,
    /// Publish the state sample over iceoryx2 (`telemetry.service_name`).
    pub publish: bool,
    /// Ask for mlockall / SCHED_FIFO as the config says (off for simulation and tests).
    pub realtime: bool,
    /// Begin in Walk at the first tick (see [`Controller::begin_walk_at_step_start`]): only for
    /// a backend that starts in the gait's planned post-impact state.
    pub start_walking: bool,
    /// End the run this long after a safety trip (the soak then restarts on a fresh robot);
    /// `None`: run the whole duration.
    pub stop_after_trip_s: Option<f64>,
    /// Dry run: the whole loop runs, but every motor is sent zero torque (damping with no
    /// gain); the log's commands are what the controller would have sent (`adam run --dry-run`).
    pub dry_run: bool,
}

impl LoopOptions {
    /// A simulation run of `duration_s`: leg motors only, no log, no publishing, no RT set-up.
    pub fn simulation(duration_s: f64) -> Self {
        Self {
            duration_s,
            with_held: false,
            script: Vec::new(),
            log_path: None,
            publish: false,
            realtime: false,
            start_walking: false,
            stop_after_trip_s: None,
            dry_run: false,
        }
    }
}

/// What the real-time set-up achieved (`Err(errno)`: refused; `None`: not asked).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RealtimeStatus {
    /// `mlockall`.
    pub memory_locked: Option<core::result::Result<(), i32>>,
    /// SCHED_FIFO.
    pub fifo: Option<core::result::Result<(), i32>>,
}

/// Tick compute time statistics, ns (100 ns resolution).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TickTimes {
    /// Median.
    pub median_ns: u64,
    /// 99th percentile.
    pub p99_ns: u64,
    /// Maximum.
    pub max_ns: u64,
}

/// Output tracking over the ticks spent in Walk: `y^d − y^a` per output (stance hip, stance
/// knee, swing hip, swing knee).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrackingStats {
    /// Ticks that ended in Walk.
    pub walk_ticks: u64,
    /// Σ (y^d − y^a)² per output, rad².
    pub sum_sq_rad2: [f64; OUTPUTS],
    /// max |y^d − y^a| per output, rad.
    pub max_abs_rad: [f64; OUTPUTS],
    /// Walk ticks with a ground-truth pitch (simulation), and Σ (θ̂ − θ)², rad².
    pub pitch_truth_ticks: u64,
    /// Σ (estimated − true pitch)² over those ticks, rad².
    pub pitch_sum_sq_rad2: f64,
    /// max |estimated − true pitch|, rad.
    pub pitch_max_abs_rad: f64,
}

/// `tracking RMS: hip … knee … (stance hip …, …) over N walk ticks`, in degrees, or `tracking
/// RMS: no walk ticks`.
impl std::fmt::Display for TrackingStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.walk_ticks == 0 {
            return f.write_str("tracking RMS: no walk ticks");
        }
        write!(
            f,
            "tracking RMS: hip {:.3}° knee {:.3}° (stance hip {:.3}°, stance knee {:.3}°, swing hip {:.3}°, swing knee {:.3}°) over {} walk ticks",
            self.hip_rms_deg(),
            self.knee_rms_deg(),
            self.rms_rad(0).to_degrees(),
            self.rms_rad(1).to_degrees(),
            self.rms_rad(2).to_degrees(),
            self.rms_rad(3).to_degrees(),
            self.walk_ticks
        )
    }
}

impl TrackingStats {
    fn add(&mut self, status: &crate::control::Status) {
        self.walk_ticks += 1;
        for i in 0..OUTPUTS {
            let e = status.y_des_rad[i] - status.y_act_rad[i];
            self.sum_sq_rad2[i] += e * e;
            self.max_abs_rad[i] = self.max_abs_rad[i].max(e.abs());
        }
    }

    fn add_pitch(&mut self, estimate_rad: f64, truth_rad: f64) {
        let e = estimate_rad - truth_rad;
        self.pitch_truth_ticks += 1;
        self.pitch_sum_sq_rad2 += e * e;
        self.pitch_max_abs_rad = self.pitch_max_abs_rad.max(e.abs());
    }

    /// RMS of the pitch estimate's error against the ground truth while walking, rad (`None`
    /// without ground truth, i.e. on hardware).
    pub fn pitch_rms_rad(&self) -> Option<f64> {
        (self.pitch_truth_ticks > 0)
            .then(|| (self.pitch_sum_sq_rad2 / self.pitch_truth_ticks as f64).sqrt())
    }

    /// RMS error of output `i` over the Walk ticks, rad (NaN without Walk ticks).
    pub fn rms_rad(&self, i: usize) -> f64 {
        (self.sum_sq_rad2[i] / self.walk_ticks as f64).sqrt()
    }

    /// RMS error of the hips (stance and swing together), deg.
    pub fn hip_rms_deg(&self) -> f64 {
        self.pair_rms_rad(0, 2).to_degrees()
    }

    /// RMS error of the knees (stance and swing together), deg.
    pub fn knee_rms_deg(&self) -> f64 {
        self.pair_rms_rad(1, 3).to_degrees()
    }

    fn pair_rms_rad(&self, a: usize, b: usize) -> f64 {
        ((self.sum_sq_rad2[a] + self.sum_sq_rad2[b]) / (2 * self.walk_ticks) as f64).sqrt()
    }
}

/// The most `/speed` rows a [`RunSummary`] keeps: some 40 minutes of steps.
pub const MAX_SUMMARY_SPEED_ROWS: usize = 4096;

/// What a run did.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// Ticks run.
    pub ticks: u64,
    /// Controller time at the last tick, s.
    pub end_time_s: f64,
    /// Deadlines missed.
    pub overruns: u64,
    /// Longest overrun streak.
    pub max_overrun_streak: u32,
    /// Exchanges that failed (bus errors other than a missing reply).
    pub bus_errors: u64,
    /// Replies missing.
    pub missing_replies: u64,
    /// State after the last tick.
    pub final_state: ControlState,
    /// Latched trip at the end.
    pub trip: Option<Trip>,
    /// Every state change (time, from, to) — at most the first 64.
    pub transitions: Vec<(f64, ControlState, ControlState)>,
    /// Every speed-control update, the `/speed` rows as a log holds them (read back by
    /// [`crate::telemetry::speed_read::read_speed`]), whether the run logs or not: at most the
    /// first [`MAX_SUMMARY_SPEED_ROWS`] (room made before the loop, so the tick never allocates).
    pub speed_rows: Vec<SpeedRow>,
    /// Speed-control updates past [`MAX_SUMMARY_SPEED_ROWS`], left out of `speed_rows` (a run
    /// that relies on every row can check this is 0).
    pub speed_rows_dropped: u64,
    /// The last state sample.
    pub last_sample: StateSample,
    /// Controller tick compute time.
    pub tick_times: TickTimes,
    /// How late each tick started against its absolute deadline (loop jitter; zero under a
    /// simulated clock).
    pub wake_latency: TickTimes,
    /// Output tracking while walking.
    pub tracking: TrackingStats,
    /// Log statistics, if logging.
    pub log: Option<LogStats>,
    /// Telemetry samples that could not be published.
    pub publish_failures: u64,
    /// Real-time set-up outcome.
    pub realtime: RealtimeStatus,
}

/// A compute-time histogram with 100 ns bins up to 2 ms (allocated once, before the loop).
struct Histogram {
    bins: Vec<u64>,
    max_ns: u64,
    count: u64,
}

impl Histogram {
    fn new() -> Self {
        Self {
            bins: vec![0; 20_001],
            max_ns: 0,
            count: 0,
        }
    }
    fn add(&mut self, ns: u64) {
        let bin = ((ns / 100) as usize).min(self.bins.len() - 1);
        self.bins[bin] += 1;
        self.max_ns = self.max_ns.max(ns);
        self.count += 1;
    }
    fn quantile_ns(&self, q: f64) -> u64 {
        let target = ((self.count as f64) * q).ceil().max(1.0) as u64;
        let mut seen = 0;
        for (bin, &n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= target {
                // Upper edge of the bin, capped by the true maximum.
                return ((bin as u64 + 1) * 100).min(self.max_ns);
            }
        }
        self.max_ns
    }
    fn times(&self) -> TickTimes {
        TickTimes {
            median_ns: self.quantile_ns(0.5),
            p99_ns: self.quantile_ns(0.99),
            max_ns: self.max_ns,
        }
    }
}

fn to_a1(motor: MotorId, c: &JointCommand) -> Command {
    match c.mode {
        CommandMode::Damping => Command::damping(motor, c.kd_nm_s_per_rad),
        CommandMode::Pd => Command::pd(
            motor,
            c.q_des_rad,
            c.dq_des_rad_s,
            c.kp_nm_per_rad,
            c.kd_nm_s_per_rad,
            c.tau_ff_nm,
        ),
    }
}

/// Queue a bus operation's frames for the log (`/can`): no allocation, never blocks.
fn push_frames(
    tx: &mut crate::telemetry::log::LogProducer,
    op: BusOp,
    t_s: f64,
    tick: Option<u64>,
    frames: &[drivers::frame_log::LoggedFrame],
) {
    for batch in FrameBatch::batches(op, t_s, tick, frames) {
        tx.push(LogRecord::Frames(batch));
    }
}

/// Run the loop on its own thread (`adam-rt`) and wait for it. Returns the summary and the
/// backend (deactivated: every motor in damping).
///
/// The backend is configured with the driven motors of the config (legs, plus held motors
/// if `options.with_held`) and activated before the first tick.
pub fn run<B, C>(
    setup: &Setup,
    backend: B,
    clock: C,
    options: LoopOptions,
    operator: Option<OperatorReceiver>,
) -> Result<(RunSummary, B)>
where
    B: Backend + Send + 'static,
    C: Clock + Send + 'static,
{
    let controller = setup.controller(options.with_held)?;
    let config = setup.config.clone();
    let log_context = LogContext::new(setup, controller.layout());
    std::thread::Builder::new()
        .name("adam-rt".into())
        .spawn(move || {
            run_on_this_thread(
                controller,
                &config,
                log_context,
                backend,
                clock,
                options,
                operator,
            )
        })
        .map_err(|e| RuntimeError::Thread {
            name: "adam-rt",
            message: e.to_string(),
        })?
        .join()
        .map_err(|_| RuntimeError::Thread {
            name: "adam-rt",
            message: "the control thread panicked".into(),
        })?
}

/// The loop itself, on the calling thread (what [`run`] spawns).
#[allow(clippy::too_many_arguments)]
pub fn run_on_this_thread<B: Backend, C: Clock>(
    mut controller: Controller,
    config: &crate::config::RuntimeConfig,
    mut log_context: LogContext,
    mut backend: B,
    mut clock: C,
    options: LoopOptions,
    mut operator: Option<OperatorReceiver>,
) -> Result<(RunSummary, B)> {
    let rate_hz = config.loop_.rate_hz;
    let period_s = 1.0 / rate_hz;
    let layout = *controller.layout();
    // Motors: the driven slots, validated against the bus timing.
    let mut specs = Vec::new();
    let mut slot_of = Vec::new();
    let mut ids = Vec::new();
    for slot in 0..SLOTS {
        if !layout.present[slot] {
            continue;
        }
        let m = if slot < LEG_SLOTS {
            &config.leg_motors[slot]
        } else {
            &config.held[slot - LEG_SLOTS].motor
        };
        let spec = m.spec(&format!("motor of slot {slot}"))?;
        specs.push(spec);
        slot_of.push(slot);
        ids.push(spec.id);
    }
    for bus in 0..config.loop_.bus_count {
        let count = specs.iter().filter(|s| s.bus == bus).count();
        if count > 0 {
            drivers::timing::validate(rate_hz, count, config.loop_.bitrate_bps)?;
        }
    }
    let mut realtime = RealtimeStatus::default();
    if options.realtime {
        if config.loop_.lock_memory {
            let r = rt_sys::lock_memory();
            if let Err(errno) = r {
                eprintln!(
                    "warning: mlockall refused (errno {errno}); running without locked memory"
                );
            }
            realtime.memory_locked = Some(r);
        }
        if config.loop_.fifo_priority > 0 {
            let r = rt_sys::set_fifo(config.loop_.fifo_priority);
            if let Err(errno) = r {
                eprintln!(
                    "warning: SCHED_FIFO refused (errno {errno}); running at normal priority"
                );
            }
            realtime.fifo = Some(r);
        }
    }
    #[cfg(feature = "iceoryx2")]
    let mut publisher = if options.publish && !config.telemetry.service_name.is_empty() {
        Some(crate::telemetry::sample::Publisher::new(
            &config.telemetry.service_name,
        )?)
    } else {
        None
    };
    log_context
        .metadata
        .insert("start_walking".into(), options.start_walking.to_string());
    if options.dry_run {
        log_context.metadata.insert("dry_run".into(), "true".into());
    }
    let (mut log_tx, logger) = match &options.log_path {
        Some(path) => {
            let (mut tx, logger) = crate::telemetry::log::start(
                path,
                log_context,
                config.telemetry.log_queue_capacity,
            )?;
            tx.wait_when_full(clock.is_simulated());
            (Some(tx), Some(logger))
        }
        None => (None, None),
    };
    backend.configure(&specs)?;
    let activated = backend.activate();
    if let Some(tx) = log_tx.as_mut() {
        push_frames(tx, BusOp::Activate, 0.0, None, backend.frames());
    }
    activated?;

    let budget = Duration::from_secs_f64(period_s);
    let damp = Command::damping(ids[0], config.gains.damping_kd_nm_s_per_rad);
    let mut commands: Vec<Command> = ids
        .iter()
        .map(|&id| Command { motor: id, ..damp })
        .collect();
    let mut replies: Vec<Reply> = ids.iter().map(|&id| Reply::zeroed(id)).collect();
    let mut input = TickInput::default();
    let mut out = TickOutput::default();
    let mut sample = StateSample::default();
    let mut histogram = Histogram::new();
    let mut wake_histogram = Histogram::new();
    let mut transitions = Vec::with_capacity(64);
    let mut speed_rows = Vec::with_capacity(MAX_SUMMARY_SPEED_ROWS);
    let mut speed_rows_dropped = 0_u64;
    let mut script = options.script.iter().peekable();
    let ticks = (options.duration_s * rate_hz).round().max(0.0) as u64;
    let (mut overruns, mut streak, mut max_streak) = (0u64, 0u32, 0u32);
    let (mut bus_errors, mut missing) = (0u64, 0u64);
    let log_every = u64::from(config.telemetry.log_every_n_ticks);
    let mut tracking = TrackingStats::default();
    if options.start_walking && controller.begin_walk_at_step_start(0.0, &mut out.status) {
        transitions.push((0.0, ControlState::Idle, ControlState::Walk));
        if let Some(tx) = log_tx.as_mut() {
            tx.push(LogRecord::Transition {
                t_s: 0.0,
                from: ControlState::Idle,
                to: ControlState::Walk,
            });
        }
    }
    let t0 = clock.now_s();
    let mut deadline = t0;
    let mut ran = 0u64;
    let mut tripped_at_s: Option<f64> = None;

    for tick in 0..ticks {
        let t = clock.now_s() - t0;
        // Wake-up jitter: how late this tick starts against its absolute deadline.
        let late_s = (t0 + t) - deadline;
        wake_histogram.add((late_s.max(0.0) * 1e9) as u64);
        // Exchange: a NaN position marks "no reply written".
        for r in replies.iter_mut() {
            r.q_rad = f64::NAN;
        }
        let result = backend.exchange(&commands, &mut replies, budget);
        if let Some(tx) = log_tx.as_mut() {
            push_frames(tx, BusOp::Exchange, t, Some(tick), backend.frames());
        }
        let replies_valid = match result {
            Ok(_) | Err(BusError::MissingReply { .. }) => true,
            Err(_) => {
                bus_errors += 1;
                false
            }
        };
        for (i, r) in replies.iter().enumerate() {
            let slot = slot_of[i];
            if replies_valid && r.q_rad.is_finite() {
                input.motors[slot] = MotorSample {
                    fresh: true,
                    q_rad: r.q_rad,
                    dq_rad_s: r.dq_rad_s,
                    tau_nm: r.tau_nm,
                    temperature_c: r.temperature_c,
                    errors: r.errors.0,
                };
            } else {
                input.motors[slot].fresh = false;
                missing += 1;
            }
        }
        input.t_s = t;
        input.imu = backend.read_at(t);
        input.operator = match script.peek() {
            Some(&&(at, cmd)) if at <= t => {
                script.next();
                Some(cmd)
            }
            _ => operator.as_mut().and_then(|o| o.poll()),
        };
        input.overrun_streak = streak;
        let c0 = rt_sys::monotonic_ns();
        controller.tick(&input, &mut out);
        let compute_ns = rt_sys::monotonic_ns().saturating_sub(c0);
        histogram.add(compute_ns);
        backend.observe(&WalkProgress {
            walking: out.status.state == ControlState::Walk,
            steps: out.status.steps,
            phase: out.status.phase,
        });
        for (i, cmd) in commands.iter_mut().enumerate() {
            *cmd = if options.dry_run {
                Command::damping(ids[i], 0.0)
            } else {
                to_a1(ids[i], &out.commands[slot_of[i]])
            };
        }
        sample.fill(
            &input,
            &out,
            LoopStats {
                tick,
                overruns,
                tick_compute_ns: compute_ns,
            },
        );
        sample.true_pitch_rad = backend.true_pitch_rad().unwrap_or(f64::NAN);
        // Asked once per tick: the sample, the summary's row and the log all take this value.
        let true_position_m = backend.true_belt_position_m();
        sample.true_belt_position_m = true_position_m.unwrap_or(f64::NAN);
        #[cfg(feature = "iceoryx2")]
        if let Some(p) = publisher.as_mut() {
            p.publish(&sample);
        }
        let status = &out.status;
        if status.state == ControlState::Walk {
            tracking.add(status);
            if let Some(truth) = backend.true_pitch_rad() {
                tracking.add_pitch(status.pitch_rad, truth);
            }
        }
        if let Some((from, to)) = status.transition {
            if transitions.len() < transitions.capacity() {
                transitions.push((t, from, to));
            }
        }
        if status.speed_update {
            if speed_rows.len() < speed_rows.capacity() {
                speed_rows.push(SpeedRow::from_update(t, &status.speed, true_position_m));
            } else {
                speed_rows_dropped += 1;
            }
        }
        if let Some(tx) = log_tx.as_mut() {
            tx.push(LogRecord::Tick(TickRecord {
                tick,
                input,
                commands: out.commands,
                state: status.state,
            }));
            if let Some((from, to)) = status.transition {
                tx.push(LogRecord::Transition { t_s: t, from, to });
            }
            if status.speed_update {
                tx.push(LogRecord::Speed {
                    t_s: t,
                    speed: status.speed,
                    true_position_m,
                });
            }
            if let (true, Some(trip)) = (status.new_trip, status.trip) {
                tx.push(LogRecord::Trip { t_s: t, tick, trip });
            }
            if tick % log_every == 0 {
                tx.push(LogRecord::Sample(sample));
            }
        }
        ran = tick + 1;
        if status.new_trip {
            tripped_at_s = Some(t);
        }
        if let (Some(linger_s), Some(at_s)) = (options.stop_after_trip_s, tripped_at_s) {
            if t - at_s >= linger_s {
                break;
            }
        }
        // Absolute deadlines; when more than a period late, re-anchor instead of bursting.
        deadline += period_s;
        let now = clock.now_s();
        if now > deadline {
            overruns += 1;
            streak += 1;
            max_streak = max_streak.max(streak);
            if now > deadline + period_s {
                deadline = now;
            }
        } else {
            streak = 0;
        }
        clock.sleep_until(deadline);
    }
    let deactivated = backend.deactivate();
    if let Some(tx) = log_tx.as_mut() {
        push_frames(tx, BusOp::Deactivate, input.t_s, None, backend.frames());
    }
    let log = match logger {
        Some(l) => Some(l.finish()?),
        None => None,
    };
    deactivated?;
    #[cfg(feature = "iceoryx2")]
    let publish_failures = publisher.as_ref().map_or(0, |p| p.failures());
    #[cfg(not(feature = "iceoryx2"))]
    let publish_failures = 0;
    let summary = RunSummary {
        ticks: ran,
        end_time_s: input.t_s,
        overruns,
        max_overrun_streak: max_streak,
        bus_errors,
        missing_replies: missing,
        final_state: out.status.state,
        trip: out.status.trip,
        transitions,
        speed_rows,
        speed_rows_dropped,
        last_sample: sample,
        tick_times: histogram.times(),
        wake_latency: wake_histogram.times(),
        tracking,
        log,
        publish_failures,
        realtime,
    };
    Ok((summary, backend))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn simulated_clock_jumps_to_deadlines_and_never_goes_back() {
        let mut c = SimulatedClock::default();
        c.sleep_until(0.5);
        assert_eq!(c.now_s(), 0.5);
        c.sleep_until(0.2);
        assert_eq!(c.now_s(), 0.5);
    }

    #[test]
    fn histogram_quantiles_bracket_the_data() {
        let mut h = Histogram::new();
        for k in 1..=1000u64 {
            h.add(k * 1000 - 500); // 0.5 µs … 999.5 µs
        }
        let t = h.times();
        assert!((499_500..=499_600).contains(&t.median_ns), "{t:?}");
        assert!((989_500..=989_600).contains(&t.p99_ns), "{t:?}");
        assert_eq!(t.max_ns, 999_500);
    }
}
