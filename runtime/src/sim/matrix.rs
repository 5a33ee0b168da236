//! The treadmill scenarios ([`super::scenarios`]) as independent runs: a [`Run`] names one
//! scenario and seed (serializable, so a sweep plan can list it and a cluster task run it), and
//! [`run`] walks it and keeps the figures the tables of `adam bench treadmill` are made of
//! ([`RunSummary`]). The bench and `adam sweep task` call the same [`run`].
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use runtime::sim::matrix::{run, Run};
//! let setup = runtime::Setup::load("configs/runtime/adam.toml", runtime::DEFAULT_GAIT)?;
//! let summary = run(&setup, &Run::Push { force_x_n: -20.0, phase: 0.3, seed: 1 })?;
//! println!("{}", summary.outcome);
//! # Ok(()) }
//! ```

use super::report::SimWalkReport;
use super::run::{walk, SimWalkOptions};
use super::scenarios::{
    belt_steps, constant_belt, max_abs_position_after_m, max_abs_position_m, outcome,
    push_at_phase, rides_through, speed_ratio_after, start_restart, steps_to_match, walks_on,
    Restart, SETTLE_S,
};
use crate::{Result, Setup};
use serde::{Deserialize, Serialize};

/// One run of the treadmill matrix.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "scenario", rename_all = "snake_case", deny_unknown_fields)]
pub enum Run {
    /// [`constant_belt`]: the belt at `speed_mps` for `duration_s`.
    ConstantBelt {
        /// Belt speed, m/s.
        speed_mps: f64,
        /// Length of the run, s.
        duration_s: f64,
        /// Seed of the simulation's noise.
        seed: u64,
    },
    /// [`belt_steps`]: 0.20 → 0.30 → 0.20 m/s over `duration_s`.
    BeltSteps {
        /// Length of the run, s.
        duration_s: f64,
        /// Seed.
        seed: u64,
    },
    /// [`push_at_phase`]: a push of `force_x_n` landing at `phase` of a step.
    Push {
        /// Push force along x, N.
        force_x_n: f64,
        /// Phase of the step it lands at, 0–1.
        phase: f64,
        /// Seed.
        seed: u64,
    },
    /// [`start_restart`]: a start-and-restart case.
    Restart {
        /// The case.
        case: Restart,
        /// Seed.
        seed: u64,
    },
}

impl Run {
    /// The options of the simulated walk.
    pub fn options(&self) -> SimWalkOptions {
        match *self {
            Run::ConstantBelt {
                speed_mps,
                duration_s,
                seed,
            } => constant_belt(speed_mps, duration_s, seed),
            Run::BeltSteps { duration_s, seed } => belt_steps(duration_s, seed).0,
            Run::Push {
                force_x_n,
                phase,
                seed,
            } => push_at_phase(force_x_n, phase, seed),
            Run::Restart { case, seed } => start_restart(case, seed),
        }
    }

    /// The figures of `report`, a walk of this run.
    pub fn summarize(&self, report: &SimWalkReport) -> RunSummary {
        let steps_to_match = match *self {
            Run::BeltSteps { duration_s, seed } => {
                let [t1, t2] = belt_steps(duration_s, seed).1;
                Some([
                    steps_to_match(&report.step_records, t1, t2),
                    steps_to_match(&report.step_records, t2, duration_s),
                ])
            }
            _ => None,
        };
        RunSummary {
            outcome: outcome(report),
            fell: report.fall.is_some(),
            tripped: report.summary.trip.is_some(),
            rides_through: rides_through(report),
            walks_on: walks_on(report),
            max_abs_position_m: max_abs_position_m(report),
            max_abs_position_after_settle_m: max_abs_position_after_m(report, SETTLE_S),
            speed_ratio_after_settle: speed_ratio_after(&report.step_records, SETTLE_S),
            steps_to_match,
            recoveries: report.summary.last_sample.recoveries,
            catches: report.summary.last_sample.catches,
        }
    }
}

/// What the tables need of one run (from the simulator's ground truth, never past a fall).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSummary {
    /// What ended it in a few words, `ok` if it rode through ([`outcome`]).
    pub outcome: String,
    /// Whether it fell.
    pub fell: bool,
    /// Whether the safety monitor tripped.
    pub tripped: bool,
    /// No trip, no stall, no fall, still walking at the end ([`rides_through`]; a stall
    /// relaunched from double support is a stall).
    pub rides_through: bool,
    /// No trip, no fall, still walking at the end, a stall relaunch or not ([`walks_on`]).
    #[serde(default)]
    pub walks_on: bool,
    /// The largest |position on the belt| of the run, m.
    pub max_abs_position_m: f64,
    /// The largest |position on the belt| after [`SETTLE_S`], m (`None`: ended before).
    pub max_abs_position_after_settle_m: Option<f64>,
    /// Walking speed over belt speed of the steps after [`SETTLE_S`] ([`speed_ratio_after`]).
    pub speed_ratio_after_settle: Option<f64>,
    /// Belt steps only: steps to match the belt after the step up and after the step down
    /// ([`steps_to_match`]; `None` inside: never).
    pub steps_to_match: Option<[Option<usize>; 2]>,
    /// Stalled steps the controller relaunched from double support (`speed.stall_relaunch_s`).
    #[serde(default)]
    pub recoveries: u32,
    /// Steps caught after a step back (`speed.step_back_catch_m`): ridden through.
    #[serde(default)]
    pub catches: u32,
}

/// Walks `run` on the simulated robot of `setup` and summarizes it.
pub fn run(setup: &Setup, run: &Run) -> Result<RunSummary> {
    Ok(run.summarize(&walk(setup, &run.options())?))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn runs_round_trip_through_json_and_name_their_scenario() {
        let runs = [
            Run::ConstantBelt {
                speed_mps: 0.2,
                duration_s: 20.0,
                seed: 3,
            },
            Run::BeltSteps {
                duration_s: 30.0,
                seed: 1,
            },
            Run::Push {
                force_x_n: -20.0,
                phase: 0.3,
                seed: 2,
            },
            Run::Restart {
                case: Restart::StopAndWalkAgain,
                seed: 5,
            },
        ];
        for r in runs {
            let text = serde_json::to_string(&r).unwrap();
            assert_eq!(serde_json::from_str::<Run>(&text).unwrap(), r);
        }
        let text = serde_json::to_string(&runs[2]).unwrap();
        assert_eq!(
            text,
            r#"{"scenario":"push","force_x_n":-20.0,"phase":0.3,"seed":2}"#
        );
        assert!(serde_json::from_str::<Run>(r#"{"scenario":"push","force_x_n":1.0}"#).is_err());
        // The options are the scenarios' own.
        assert_eq!(runs[0].options().belt_speed_mps, Some(0.2));
        assert_eq!(runs[3].options().seed, 5);
    }
}
