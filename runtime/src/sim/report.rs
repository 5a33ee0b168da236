//! What a simulated walk did ([`SimWalkReport`]): the loop's summary and the simulator's
//! ground truth — steps ([`StepRecord`]), the treadmill (belt speed, position on the belt, a
//! [`TruthSample`] every 10 ms), the fall — each figure taken up to a fall, never after it.

use crate::rt_loop::RunSummary;
pub use crate::sim::inject::TruthSample;
use drivers::sim::robot::{FallCause, RobotSim, SimEvent};
use drivers::sim::wire::WireStats;
use model::Side;

/// One step of a simulated walk: the touchdown that ended it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepRecord {
    /// Touchdown time, s.
    pub t_s: f64,
    /// The foot that touched down.
    pub side: Side,
    /// Step length (front foot minus back foot at touchdown), m.
    pub length_m: f64,
    /// Since the step before (the first: since the start), s.
    pub duration_s: f64,
    /// Belt speed at touchdown, m/s.
    pub belt_speed_mps: f64,
    /// The hip's position on the belt at touchdown, forward of its centre, m.
    pub position_on_belt_m: f64,
}

impl StepRecord {
    /// The step's speed over the belt, length / duration, m/s.
    pub fn speed_mps(&self) -> f64 {
        self.length_m / self.duration_s
    }
}

/// What the simulated walk did: the loop's summary and the simulator's ground truth.
#[derive(Clone, Debug)]
pub struct SimWalkReport {
    /// The loop's summary (states, trips, tracking, tick times, log).
    pub summary: RunSummary,
    /// Simulated run time, s.
    pub duration_s: f64,
    /// Belt speed at the start, m/s.
    pub belt_speed_mps: f64,
    /// Belt speed at the end of the run (or at the fall), m/s.
    pub belt_speed_end_mps: f64,
    /// The belt's length, m (infinite: endless).
    pub belt_length_m: f64,
    /// The hip's position on the belt, forward of its centre, at the end of the run or at the
    /// fall, m.
    pub position_on_belt_m: f64,
    /// Every step before any fall, from the simulator's touchdowns.
    pub step_records: Vec<StepRecord>,
    /// The treadmill's ground truth every 10 ms (up to the end of the run).
    pub trace: Vec<TruthSample>,
    /// Steps: touchdowns of the swing foot (alternating sides).
    pub steps: usize,
    /// Touchdowns of the same foot twice in a row (scuffs, bounces).
    pub repeated_touchdowns: usize,
    /// Mean step length (front foot minus back foot at touchdown), m.
    pub mean_step_length_m: f64,
    /// Mean step duration (between alternating touchdowns, the first from t = 0), s.
    pub mean_step_duration_s: f64,
    /// Mean walking speed over the belt, mean step length / mean step duration (steps before
    /// any fall), m/s.
    pub speed_mps: f64,
    /// World displacement of the hip over the run, up to the fall if it fell (positive:
    /// forward, against the belt), m. Where in a step the run ends moves it by centimetres;
    /// see `landing_drift_m`.
    pub drift_m: f64,
    /// World displacement of the landing foot: the last step's touchdown point minus the
    /// stance foot at the start (both at touchdown, the same gait phase), m; 0 without steps.
    pub landing_drift_m: f64,
    /// Time the run walked: up to the fall, or the whole run, s.
    pub walked_s: f64,
    /// The fall, if any: time, s, and cause.
    pub fall: Option<(f64, FallCause)>,
    /// Time the simulator faulted, s, if it did.
    pub sim_fault_s: Option<f64>,
    /// Friction-cone violations reported by the simulator (μ = 1; the foot stays pinned).
    pub friction_exceeded: usize,
    /// Distance walked over the belt: the sum of the step lengths before any fall, m.
    pub distance_m: f64,
    /// Faults started from the profile's schedule.
    pub faults_started: u64,
    /// What the simulated CAN wire did.
    pub wire: WireStats,
    /// The pre-flight checks, when the run made them ([`crate::bringup::preflight()`]).
    pub preflight: Option<crate::bringup::PreflightReport>,
}

impl SimWalkReport {
    /// The figures of a run from the simulator's events: steps (alternating touchdowns,
    /// the first after the start at `t = 0` of the foot `first_stance`), the fall, friction
    /// warnings, faults; `x0_m` and `stance_x0_m` the hip's and the stance foot's world x at
    /// the start. Nothing after a fall is counted: the drift and position are taken at it.
    #[allow(clippy::too_many_arguments)]
    pub fn measure(
        summary: RunSummary,
        sim: &RobotSim,
        duration_s: f64,
        belt_speed_mps: f64,
        first_stance: Side,
        x0_m: f64,
        stance_x0_m: f64,
        faults_started: u64,
        wire: WireStats,
        trace: Vec<TruthSample>,
    ) -> Self {
        let fall = sim.fall_record();
        let mut report = SimWalkReport {
            duration_s,
            belt_speed_mps,
            belt_speed_end_mps: sim.belt_speed_mps(),
            belt_length_m: sim.belt_length_m(),
            position_on_belt_m: fall.map_or(sim.position_on_belt_m(), |f| f.position_on_belt_m),
            step_records: Vec::new(),
            trace,
            steps: 0,
            repeated_touchdowns: 0,
            mean_step_length_m: f64::NAN,
            mean_step_duration_s: f64::NAN,
            speed_mps: f64::NAN,
            drift_m: fall.map_or(sim.base_position_m()[0], |f| f.base_x_m) - x0_m,
            landing_drift_m: 0.0,
            walked_s: sim.time_s(),
            fall: None,
            sim_fault_s: None,
            friction_exceeded: 0,
            distance_m: 0.0,
            faults_started,
            wire,
            summary,
            preflight: None,
        };
        if let Some(f) = fall {
            report.trace.retain(|s| s.t_s <= f.t_s);
        }
        let mut last_side = first_stance;
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
                    report.landing_drift_m = td.foot_x_m - stance_x0_m;
                    length_sum_m += td.step_length_m;
                    duration_sum_s += td.t_s - last_t_s;
                    report.step_records.push(StepRecord {
                        t_s: td.t_s,
                        side: td.side,
                        length_m: td.step_length_m,
                        duration_s: td.t_s - last_t_s,
                        belt_speed_mps: td.belt_speed_mps,
                        position_on_belt_m: td.position_on_belt_m,
                    });
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
        report.distance_m = length_sum_m;
        if report.steps > 0 {
            let n = report.steps as f64;
            report.mean_step_length_m = length_sum_m / n;
            report.mean_step_duration_s = duration_sum_s / n;
            report.speed_mps = length_sum_m / duration_sum_s;
        }
        report
    }

    /// Time of the first transition into Damping, s (the trip's effect), if any.
    pub fn damping_at_s(&self) -> Option<f64> {
        self.summary
            .transitions
            .iter()
            .find(|(_, _, to)| *to == crate::control::ControlState::Damping)
            .map(|(t, _, _)| *t)
    }
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
        if let Some(p) = &self.preflight {
            write!(f, "{p}")?;
        }
        let belt = if self.belt_speed_end_mps == self.belt_speed_mps {
            format!("{:.3} m/s", self.belt_speed_mps)
        } else {
            format!(
                "{:.3} → {:.3} m/s",
                self.belt_speed_mps, self.belt_speed_end_mps
            )
        };
        writeln!(
            f,
            "walked {:.2} s of {:.2} s on the treadmill at {belt}; final state {}",
            self.walked_s,
            self.duration_s,
            s.final_state.name()
        )?;
        // After a fall, every figure is the one up to it (never where the body lies later).
        let (upto, at) = if self.fall.is_some() {
            (" up to the fall", "at the fall")
        } else {
            ("", "at the end")
        };
        writeln!(
            f,
            "steps{upto} {} | mean step length {:.4} m | mean step duration {:.4} s | speed {:.4} m/s | drift {:+.3} m",
            self.steps,
            self.mean_step_length_m,
            self.mean_step_duration_s,
            self.speed_mps,
            self.drift_m
        )?;
        let length = if self.belt_length_m.is_finite() {
            format!("belt {:.2} m", self.belt_length_m)
        } else {
            "endless belt".to_string()
        };
        writeln!(
            f,
            "position on the belt {at} {:+.3} m (+ forward of its centre; {length})",
            self.position_on_belt_m
        )?;
        let t = &s.tracking;
        writeln!(f, "{t}")?;
        let trip = s.trip.map_or_else(|| "none".to_string(), |t| t.to_string());
        let fall = self
            .fall
            .map_or_else(|| "none".to_string(), |(t, w)| format!("{w} at {t:.3} s"));
        if let Some(rms) = t.pitch_rms_rad() {
            writeln!(
                f,
                "pitch estimate vs ground truth: RMS {:.3}°, max {:.3}° (bias estimate {:+.4} rad/s)",
                rms.to_degrees(),
                t.pitch_max_abs_rad.to_degrees(),
                s.last_sample.gyro_bias_rad_s
            )?;
        }
        if self.faults_started > 0 || self.wire != WireStats::default() {
            let w = &self.wire;
            writeln!(
                f,
                "faults injected {} | CAN frames lost {}, corrupted {}, replies delayed {} ({} past the period)",
                self.faults_started, w.lost, w.corrupted, w.delayed, w.delayed_late
            )?;
        }
        writeln!(
            f,
            "safety trips: {trip} | falls: {fall} | repeated touchdowns {} | friction warnings {}",
            self.repeated_touchdowns, self.friction_exceeded
        )?;
        if s.last_sample.catches > 0 {
            writeln!(
                f,
                "steps caught after a step back (the phase ran back): {}",
                s.last_sample.catches
            )?;
        }
        if s.last_sample.recoveries > 0 {
            writeln!(
                f,
                "stalled steps relaunched from double support: {}",
                s.last_sample.recoveries
            )?;
        }
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
