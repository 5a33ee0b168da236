//! What `adam run` and `adam demo` print beside the runtime's own walk report, in words and
//! units: a fall's cause, the log's counts, a safety trip, and a run on the robot over CAN.
//! (A run on the robot has no report type in `runtime` yet; this one would move there.)

use runtime::rt_loop::{RealtimeStatus, TickTimes, TrackingStats};
use runtime::safety::Trip;
use runtime::RunSummary;
use std::fmt;

/// What the logger wrote, e.g. `60001 records, 420007 MCAP messages, 0 records dropped`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct LogCounts {
    /// Records received from the control thread.
    pub(crate) records: u64,
    /// MCAP messages written (all channels).
    pub(crate) messages: u64,
    /// Records dropped because the queue was full.
    pub(crate) dropped: u64,
}

impl fmt::Display for LogCounts {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} records, {} MCAP messages, {} records dropped",
            self.records, self.messages, self.dropped
        )
    }
}

/// `adam run --backend can`'s report: ticks and time, state changes, tracking, safety, tick
/// and wake-up times, bus and log counts.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RobotRunReport {
    /// Ticks run.
    pub(crate) ticks: u64,
    /// Controller time at the last tick, s.
    pub(crate) end_time_s: f64,
    /// State after the last tick.
    pub(crate) final_state: &'static str,
    /// Every state change: time, s, from, to (at most the first 64).
    pub(crate) transitions: Vec<(f64, &'static str, &'static str)>,
    /// The latched trip at the end.
    pub(crate) trip: Option<Trip>,
    /// Output tracking while walking.
    pub(crate) tracking: TrackingStats,
    /// Tick compute time.
    pub(crate) tick_times: TickTimes,
    /// How late each tick started (loop jitter).
    pub(crate) wake_latency: TickTimes,
    /// Deadlines missed.
    pub(crate) overruns: u64,
    /// Longest overrun streak.
    pub(crate) max_overrun_streak: u32,
    /// Replies missing.
    pub(crate) missing_replies: u64,
    /// Failed exchanges other than a missing reply.
    pub(crate) bus_errors: u64,
    /// Telemetry samples that could not be published.
    pub(crate) publish_failures: u64,
    /// What the logger wrote, if logging.
    pub(crate) log: Option<LogCounts>,
    /// Real-time set-up outcome.
    pub(crate) realtime: RealtimeStatus,
}

impl RobotRunReport {
    /// The report of a run.
    pub(crate) fn of(s: &RunSummary) -> Self {
        Self {
            ticks: s.ticks,
            end_time_s: s.end_time_s,
            final_state: s.final_state.name(),
            transitions: s
                .transitions
                .iter()
                .map(|(t, from, to)| (*t, from.name(), to.name()))
                .collect(),
            trip: s.trip,
            tracking: s.tracking,
            tick_times: s.tick_times,
            wake_latency: s.wake_latency,
            overruns: s.overruns,
            max_overrun_streak: s.max_overrun_streak,
            missing_replies: s.missing_replies,
            bus_errors: s.bus_errors,
            publish_failures: s.publish_failures,
            log: s.log.map(|l| LogCounts {
                records: l.records,
                messages: l.messages,
                dropped: l.dropped,
            }),
            realtime: s.realtime,
        }
    }
}

/// `ok`, `denied (errno N)` or `not asked`.
fn granted(r: Option<Result<(), i32>>) -> String {
    match r {
        None => "not asked".into(),
        Some(Ok(())) => "ok".into(),
        Some(Err(errno)) => format!("denied (errno {errno})"),
    }
}

/// Median, p99 and max of tick times, µs.
fn micros(t: &TickTimes) -> String {
    format!(
        "median {:.1} µs, p99 {:.1} µs, max {:.1} µs",
        t.median_ns as f64 / 1e3,
        t.p99_ns as f64 / 1e3,
        t.max_ns as f64 / 1e3
    )
}

impl fmt::Display for RobotRunReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "ran {} ticks, {:.3} s; final state {}",
            self.ticks, self.end_time_s, self.final_state
        )?;
        if self.transitions.is_empty() {
            writeln!(f, "state changes: none")?;
        } else {
            let changes: Vec<String> = self
                .transitions
                .iter()
                .map(|(t, from, to)| format!("{from} → {to} at {t:.3} s"))
                .collect();
            writeln!(f, "state changes: {}", changes.join(", "))?;
        }
        writeln!(f, "{}", self.tracking)?;
        match self.trip {
            Some(trip) => writeln!(f, "safety trip: {}", trip)?,
            None => writeln!(f, "safety trips: none")?,
        }
        writeln!(
            f,
            "tick compute time: {} | missing replies {} | bus errors {}",
            micros(&self.tick_times),
            self.missing_replies,
            self.bus_errors
        )?;
        writeln!(
            f,
            "loop wake-up latency (jitter): {} | overruns {} (longest streak {}) | mlockall {} SCHED_FIFO {}",
            micros(&self.wake_latency),
            self.overruns,
            self.max_overrun_streak,
            granted(self.realtime.memory_locked),
            granted(self.realtime.fifo)
        )?;
        write!(
            f,
            "telemetry samples not published {}",
            self.publish_failures
        )?;
        if let Some(log) = &self.log {
            write!(f, "\nlog: {log}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_counts_read_as_numbers_with_their_names() {
        let counts = LogCounts {
            records: 60001,
            messages: 180001,
            dropped: 0,
        };
        assert_eq!(
            counts.to_string(),
            "60001 records, 180001 MCAP messages, 0 records dropped"
        );
    }

    fn report() -> RobotRunReport {
        RobotRunReport {
            ticks: 1500,
            end_time_s: 1.5,
            final_state: "damping",
            transitions: vec![(0.0, "idle", "ramp"), (1.2, "ramp", "damping")],
            trip: Some(Trip::Fall {
                pitch_rad: 0.7,
                limit_rad: 0.6,
            }),
            tracking: TrackingStats::default(),
            tick_times: TickTimes {
                median_ns: 1000,
                p99_ns: 4700,
                max_ns: 12_300,
            },
            wake_latency: TickTimes {
                median_ns: 20_000,
                p99_ns: 50_000,
                max_ns: 80_000,
            },
            overruns: 2,
            max_overrun_streak: 1,
            missing_replies: 4,
            bus_errors: 0,
            publish_failures: 0,
            log: None,
            realtime: RealtimeStatus {
                memory_locked: Some(Ok(())),
                fifo: Some(Err(1)),
            },
        }
    }

    #[test]
    fn a_run_on_the_robot_reports_states_trip_and_times_without_debug_forms() {
        let text = report().to_string();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines,
            [
                "ran 1500 ticks, 1.500 s; final state damping",
                "state changes: idle → ramp at 0.000 s, ramp → damping at 1.200 s",
                "tracking RMS: no walk ticks",
                "safety trip: fall: pitch 0.700 rad past the limit of 0.600 rad",
                "tick compute time: median 1.0 µs, p99 4.7 µs, max 12.3 µs | missing replies 4 \
                 | bus errors 0",
                "loop wake-up latency (jitter): median 20.0 µs, p99 50.0 µs, max 80.0 µs | \
                 overruns 2 (longest streak 1) | mlockall ok SCHED_FIFO denied (errno 1)",
                "telemetry samples not published 0",
            ]
        );
        let mut with_log = report();
        with_log.trip = None;
        with_log.log = Some(LogCounts {
            records: 10,
            messages: 30,
            dropped: 1,
        });
        let text = with_log.to_string();
        assert!(text.contains("\nsafety trips: none\n"), "{text}");
        assert!(
            text.ends_with("\nlog: 10 records, 30 MCAP messages, 1 records dropped"),
            "{text}"
        );
    }
}
