//! The treadmill scenarios of issue #29 (`adam bench treadmill`, `tests/treadmill.rs`): each a
//! [`SimWalkOptions`] for a seed, and the figures its acceptance is judged by, measured from the
//! simulator's ground truth ([`SimWalkReport`]) and never past a fall.
//!
//! | scenario | run | figures |
//! |---|---|---|
//! | [`constant_belt`] | belt at a speed for 60 s | falls, trips, max \|position on the belt\| after 10 s ([`max_abs_position_after_m`]), walking speed vs belt after 10 s ([`speed_ratio_after`]) |
//! | [`belt_steps`] | belt 0.20 → 0.30 → 0.20 m/s (ramps of 0.5 m/s²) | steps to get within 0.05 m/s of the belt after each change ([`steps_to_match`]), max \|position\| |
//! | [`push_at_phase`] | belt 0.25 m/s, a 0.2 s push landing at a phase of the step after 3 s, watched to 12 s | ride-through ([`rides_through`]: no trip, no stall, no fall; a stall the controller relaunched from double support is a stall: the run [`walks_on`] and is counted apart, [`outcome`]) |
//! | [`start_restart`] | from Stand; stop → Stand → Walk; belt started after the robot walks | trips, falls |
//!
//! Every run takes seconds of simulation; the bench runs them in parallel.
//!
//! # Start and restart (measured 2026-12-05, the treadmill config, seeds 1–5)
//! `adam run --backend sim --config configs/runtime/adam_treadmill.toml --start stand --belt
//! "0:0,2:0.25" --script 3:walk --duration 20s --seed N` ([`Restart::FromStand`]; add
//! `10:stop,18:walk` and `--duration 26s` for [`Restart::StopAndWalkAgain`]; `--belt
//! "0:0,4:0.25"` for [`Restart::BeltAfterWalk`]). `adam bench treadmill --config
//! configs/runtime/adam_treadmill.toml`, table (d): **5/5, 5/5, 5/5** (before: 2/5, 0/5, 0/5 —
//! the middle one with the old timing, below; `--seeds 6,7,8,9,10`: 5/5 each too). What the controller does: `runtime::control::speed`,
//! "Start and restart"; its tables (a)–(c) and the push bisections are unchanged, figure for
//! figure.
//!
//! **The physics.** A robot standing on a belt at 0.25 m/s is carried back 0.25 m a second;
//! its rear foot leaves the 1.6 m belt when the hip is some 0.65 m behind the centre. From
//! Stand it is carried back while standing (2 → 3 s: 0.19 m), through the launch (1 s in double
//! support: 0.21 m) and through a slow first step: on the slowest gait, which Stand stood in,
//! the first step took 1.3 s for 0.15 m (0.19 m more), and the library speed then climbed
//! 0.02 m/s a step: seeds 1, 3, 4 went off the back at 6.98–8.40 s (hip 0.74–0.78 m behind).
//! Now the launch aims at the gait halfway to the belt's and the first impact jumps to the
//! command's gait: the first impact comes at 4.97 s, 0.52 m behind (seed 1), the walk gets
//! back to the centre by 10 s, and after 10 s |position| ≤ 0.14 m but 0.34 m (seed 4); the
//! deepest point 0.53–0.61 m behind. (With the library down to 0.125 m/s the launch aims 0.4
//! of the way, and the robot stands in the library gait of the runtime gait's step, 0.15 m,
//! not the slowest gait's 0.125 m: `runtime::sim::run`, `runtime::control::speed`.)
//!
//! **Stop → Stand → Walk again: the timing.** The issue does not fix the times; the first
//! scenario (Stop at 8 s, Walk at 11 s) cannot be met on the 1.6 m belt whatever the controller
//! does. At 8 s the start has not yet brought the robot back (0.31 m behind at seed 1 with the
//! start settings below, walking
//! 0.12 m/s over the belt); the braking step lands at 8.6–9.1 s and standing to 11 s carries it
//! 0.5–0.6 m back, the launch 0.25 m more: 1.0–1.1 m from where it stopped, more than the
//! 0.35–0.45 m left behind it (measured: off the back during Stand or the launch in 5 of 5).
//! A stopped robot can stand at most (p_stop + 0.6 m)/b − 1.5 s (launch and first step) on it:
//! 0.9 s from the centre, 2.3 s from 0.35 m ahead. So a Stop on a moving belt first walks
//! ahead (to 0.35 m, at 0.12 m/s over the belt), then slows to a gait the braking step stops,
//! then brakes; that takes 6.2–7.5 s from the centre (Stand at 16.19–17.51 s after a Stop at
//! 10 s, at most 0.48–0.52 m ahead), so the scenario is now Stop at 10 s (the start has
//! settled), Walk at 18 s, 26 s: 5 of 5 go Stop → Stand → Walk and walk on (end 0.37–0.41 m
//! ahead).
//!
//! **BeltAfterWalk, traced (seed 1).** Not the estimate (≤ 5 mrad off: the belt starts while
//! walking, when the accelerometer is not used). The belt's ramp (4.0–4.5 s) yanks the stance
//! foot back by 0.25 m/s during the first step, a forward shove relative to the belt: the steps
//! walk 0.28, 0.49 and 0.41 m/s over the belt (0.149 m in 0.54 s, 0.186 m in 0.38 s, 0.221 m in
//! 0.55 s); the step lever landed them 2–3 cm longer, and the position loop, which saw the robot
//! 0.21 m ahead of where the walk began, dropped the command to 0.17 m/s and the library speed to
//! 0.17 m/s. The step that started at 5.40 s started at phase −0.21 (the lengthened step on a
//! slow gait lands the torso behind its new stance foot), never got over it, and the step
//! timeout tripped at 7.8 s. Now, for 6 impacts after the belt starts, the command is the
//! belt's (the reference follows the estimate) and the lever rests, then the reference glides
//! back at 0.02 m/s: 5 of 5, |position| ≤ 0.38 m (the shove leaves the robot 0.3 m ahead).
//!
//! Tried and not kept (with the settings above unless said; `runtime/examples`' traces, not
//! committed):
//! - the first impact unlimited alone: FromStand 4 of 5 (seed 3 off the back at 6.3 s: its
//!   first step took 1.33 s), BeltAfterWalk 3 of 5; with the launch aiming at the command's own
//!   gait (`launch_gait_fraction = 1`): 5 of 5 but the rear foot chattered in the launch (some
//!   40 repeated touchdowns at seed 1), so halfway (0.4 since the library reaches 0.125 m/s);
//! - without `position_from_start` (the position from each Walk): after 10 s the walk keeps
//!   0.12–0.49 m behind the centre (the belt's travel while standing is lost); with it and no
//!   integral delay: 0.17–0.35 m ahead (the first steps after the launch wind the integral up);
//! - after the belt starts, with the start settings only: 2 of 5 (steps on σ 0.18–0.21 slowed
//!   from 0.29 to 0.13 m/s and stalled); 4 settling impacts and a 0.03 m/s glide with
//!   the lever on, 3 of 5 (a lengthened step bounced); the lever doubled, 0 of 5; lever off and
//!   4 impacts, 4 of 5 (seed 1 slowed on σ 0.19–0.20 and stalled at 14.4 s); 6–8 impacts: 5 of 5;
//! - a Stop's approach by the position loop alone (reference 0.35 m ahead): Stand 6.2–8.4 s
//!   after the Stop (it nears the target exponentially); at 0.18 m/s over the belt: faster by 1 s but
//!   3 of 5 trip after the second Walk (step timeouts 3.4–3.7 s after it, 0.72–0.82 m behind:
//!   they stood at the target from 15.4–16.7 s, too long).
//!
//! The two 1.6 m-belt tests of `runtime/tests/restart_sim.rs` stay ignored: they run the test
//! library with `adam.toml`'s speed settings (none of the above), and the first cannot be met:
//! the belt runs at 0.25 m/s from t = 0, so the robot is carried 0.5 m back during the 2 s Ramp
//! and past the back end during the launch (2.8 s).

use crate::control::{ControlState, OperatorCommand};
use crate::sim::faults::{Fault, FaultEvent, FaultProfile};
use crate::sim::report::{SimWalkReport, StepRecord};
use crate::sim::run::{SimStart, SimWalkOptions};
use crate::sim::treadmill::BeltProfile;

/// Belt speeds of the constant-belt scenario, m/s.
pub const BELT_SPEEDS_MPS: [f64; 5] = [0.15, 0.20, 0.25, 0.30, 0.35];

/// Push points: phases of the step at which a push lands.
pub const PUSH_PHASES: [f64; 5] = [0.1, 0.3, 0.5, 0.7, 0.9];

/// The pushes of the acceptance: −20 N (backward) and +40 N (forward), 0.2 s each.
pub const PUSH_FORCES_N: [f64; 2] = [-20.0, 40.0];

/// Duration of a push, s.
pub const PUSH_DURATION_S: f64 = 0.2;

/// Belt speed of the push and restart scenarios, m/s.
pub const PUSH_BELT_MPS: f64 = 0.25;

/// When a push scenario arms its push, s (it lands at its phase of the next step).
pub const PUSH_ARM_S: f64 = 3.0;

/// How long after the push arms a push run goes on, s: to 12 s. (It was 4 s until 2026-12-05:
/// too short to see the "no stall" — a +40 N push rode through 25 of 25 runs within
/// 4 s, and none of them walked to 12 s.)
pub const PUSH_WATCH_S: f64 = 9.0;

/// The time after which the constant-belt figures are taken, s.
pub const SETTLE_S: f64 = 10.0;

/// Within this of the belt speed a step matches it, m/s.
pub const MATCH_TOLERANCE_MPS: f64 = 0.05;

/// A run of `duration_s` with seed `seed`.
fn base(duration_s: f64, seed: u64) -> SimWalkOptions {
    let mut o = SimWalkOptions::new(duration_s);
    o.seed = seed;
    o
}

/// The belt at `speed_mps` for `duration_s` (60 s in the acceptance), walking from the start.
pub fn constant_belt(speed_mps: f64, duration_s: f64, seed: u64) -> SimWalkOptions {
    let mut o = base(duration_s, seed);
    o.belt_speed_mps = Some(speed_mps);
    o
}

/// The belt at 0.20 m/s, stepped to 0.30 m/s at `duration_s / 3` and back at `2 duration_s / 3`
/// (each a ramp at the default 0.5 m/s²). Returns the options and the two change times, s.
pub fn belt_steps(duration_s: f64, seed: u64) -> (SimWalkOptions, [f64; 2]) {
    let (t1, t2) = (duration_s / 3.0, 2.0 * duration_s / 3.0);
    let mut o = base(duration_s, seed);
    o.belt_profile = Some(BeltProfile {
        points: vec![(0.0, 0.20), (t1, 0.30), (t2, 0.20)],
    });
    (o, [t1, t2])
}

/// The belt at [`PUSH_BELT_MPS`]; at [`PUSH_ARM_S`] a push of `force_x_n` for
/// [`PUSH_DURATION_S`] waits for the next step and lands at `phase`; the run watches
/// [`PUSH_WATCH_S`] more.
pub fn push_at_phase(force_x_n: f64, phase: f64, seed: u64) -> SimWalkOptions {
    let mut o = base(PUSH_ARM_S + PUSH_WATCH_S, seed);
    o.belt_speed_mps = Some(PUSH_BELT_MPS);
    let mut profile = FaultProfile::none();
    profile.events.push(FaultEvent {
        at_s: PUSH_ARM_S,
        duration_s: PUSH_DURATION_S,
        fault: Fault::PushAtPhase {
            force_x_n,
            force_z_n: 0.0,
            phase,
        },
    });
    o.faults = Some(profile);
    o
}

/// The start and restart cases.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Restart {
    /// From Stand (belt at rest while the controller ramps), the belt ramps to 0.25 m/s at
    /// 2 s, Walk at 3 s; 20 s.
    FromStand,
    /// As [`Restart::FromStand`], then Stop at 10 s (with speed control: walking ahead, then
    /// the braking step, Stand) and Walk again at 18 s on the moving belt; 26 s. (Stop at 8 s
    /// and Walk at 11 s cannot be met on the 1.6 m belt: module docs.)
    StopAndWalkAgain,
    /// From Stand, Walk at 3 s on a belt at rest; the belt ramps to 0.25 m/s from 4 s (on a
    /// belt at rest the robot walks off its front within some 4 s); 20 s.
    BeltAfterWalk,
}

impl Restart {
    /// Every case, in the table's order.
    pub const ALL: [Restart; 3] = [
        Restart::FromStand,
        Restart::StopAndWalkAgain,
        Restart::BeltAfterWalk,
    ];

    /// The case in words.
    pub fn name(self) -> &'static str {
        match self {
            Restart::FromStand => "Stand → Walk on the belt at 0.25",
            Restart::StopAndWalkAgain => "Walk → stop → Stand → Walk at 0.25",
            Restart::BeltAfterWalk => "Walk, then the belt starts (→ 0.25)",
        }
    }
}

/// The run of a start-and-restart case.
pub fn start_restart(case: Restart, seed: u64) -> SimWalkOptions {
    let duration_s = match case {
        Restart::StopAndWalkAgain => 26.0,
        _ => 20.0,
    };
    let mut o = base(duration_s, seed);
    o.start = SimStart::Stand;
    let (belt, script) = match case {
        Restart::FromStand => (
            vec![(0.0, 0.0), (2.0, PUSH_BELT_MPS)],
            vec![(3.0, OperatorCommand::Walk)],
        ),
        Restart::StopAndWalkAgain => (
            vec![(0.0, 0.0), (2.0, PUSH_BELT_MPS)],
            vec![
                (3.0, OperatorCommand::Walk),
                (10.0, OperatorCommand::Stop),
                (18.0, OperatorCommand::Walk),
            ],
        ),
        Restart::BeltAfterWalk => (
            vec![(0.0, 0.0), (4.0, PUSH_BELT_MPS)],
            vec![(3.0, OperatorCommand::Walk)],
        ),
    };
    o.belt_profile = Some(BeltProfile { points: belt });
    o.script = script;
    o
}

/// The largest |position on the belt| from `after_s` on (up to any fall), m; `None` if the
/// run ended (or fell) before.
pub fn max_abs_position_after_m(r: &SimWalkReport, after_s: f64) -> Option<f64> {
    r.trace
        .iter()
        .filter(|s| s.t_s >= after_s)
        .map(|s| s.position_on_belt_m.abs())
        .reduce(f64::max)
}

/// The largest |position on the belt| of the whole run (up to any fall), m.
pub fn max_abs_position_m(r: &SimWalkReport) -> f64 {
    max_abs_position_after_m(r, 0.0).unwrap_or(r.position_on_belt_m.abs())
}

/// Mean walking speed over the belt of the steps after `after_s` (sum of lengths over sum of
/// durations) divided by the mean belt speed at their touchdowns; `None` without such steps.
pub fn speed_ratio_after(steps: &[StepRecord], after_s: f64) -> Option<f64> {
    let steps: Vec<_> = steps.iter().filter(|s| s.t_s >= after_s).collect();
    if steps.is_empty() {
        return None;
    }
    let length: f64 = steps.iter().map(|s| s.length_m).sum();
    let duration: f64 = steps.iter().map(|s| s.duration_s).sum();
    let belt: f64 = steps.iter().map(|s| s.belt_speed_mps).sum::<f64>() / steps.len() as f64;
    Some(length / duration / belt)
}

/// Steps after the belt change at `from_s` until the walk matches the belt: the count (from 1)
/// of the first step from which every step up to `until_s` (or the run's end) has a speed
/// within [`MATCH_TOLERANCE_MPS`] of the belt at its touchdown; `None` if it never does (or
/// no step follows).
pub fn steps_to_match(steps: &[StepRecord], from_s: f64, until_s: f64) -> Option<usize> {
    let steps: Vec<_> = steps
        .iter()
        .filter(|s| s.t_s > from_s && s.t_s <= until_s)
        .collect();
    let matched = |s: &StepRecord| (s.speed_mps() - s.belt_speed_mps).abs() <= MATCH_TOLERANCE_MPS;
    let last_unmatched = steps.iter().rposition(|s| !matched(s));
    match last_unmatched {
        None if steps.is_empty() => None,
        None => Some(1),
        Some(k) if k + 1 < steps.len() => Some(k + 2),
        Some(_) => None,
    }
}

/// Issue #29's "ride through": no trip, no stall, no fall, still walking at the end. A step
/// that stalled (1 s without phase progress) and was relaunched from double support
/// (`speed.stall_relaunch_s`) stalled: such a run [`walks_on`] but does not ride through. A
/// step caught after a step back (`speed.step_back_catch_m`: the phase ran back, the swing
/// foot was set down behind at once and the robot carried forward from double support) did
/// not stall, and [`outcome`] says how many there were.
pub fn rides_through(r: &SimWalkReport) -> bool {
    walks_on(r) && r.summary.last_sample.recoveries == 0
}

/// No trip (a step timeout is a stall), no fall, still walking at the end, with or without a
/// stall relaunch ([`outcome`] and the run's summary count the relaunches).
pub fn walks_on(r: &SimWalkReport) -> bool {
    r.fall.is_none()
        && r.summary.trip.is_none()
        && r.sim_fault_s.is_none()
        && r.summary.final_state == ControlState::Walk
}

/// What ended a run that did not walk on, in a few words (`fall: off the back of the
/// belt`, `trip: step_timeout`); `ok` if it rode through (`ok, n steps back` with step-back
/// catches), `ok after a relaunch` (or `after n relaunches`) if it walked on after a stalled
/// step was relaunched from double support.
pub fn outcome(r: &SimWalkReport) -> String {
    match (r.summary.trip, r.fall) {
        (Some(t), _) => format!("trip: {}", t.name()),
        (None, Some((_, what))) => format!("fall: {what}"),
        (None, None) if r.summary.final_state != ControlState::Walk => {
            format!("ended in {}", r.summary.final_state.name())
        }
        (None, None) => match (
            r.summary.last_sample.recoveries,
            r.summary.last_sample.catches,
        ) {
            (0, 0) => "ok".into(),
            (0, 1) => "ok, 1 step back".into(),
            (0, n) => format!("ok, {n} steps back"),
            (1, _) => "ok after a relaunch".into(),
            (n, _) => format!("ok after {n} relaunches"),
        },
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn step(t_s: f64, speed_mps: f64, belt_speed_mps: f64) -> StepRecord {
        StepRecord {
            t_s,
            side: model::Side::Left,
            length_m: 0.15,
            duration_s: 0.15 / speed_mps,
            belt_speed_mps,
            position_on_belt_m: 0.0,
        }
    }

    #[test]
    fn steps_to_match_counts_to_the_first_step_that_stays_within_the_tolerance() {
        // The belt steps to 0.30 at 10 s: steps at 0.20, 0.24, 0.27 (in), 0.22 (out), 0.29,
        // 0.30 (in): matched from the 5th step on.
        let steps = [
            step(9.0, 0.2, 0.2),
            step(11.0, 0.2, 0.3),
            step(12.0, 0.24, 0.3),
            step(13.0, 0.27, 0.3),
            step(14.0, 0.22, 0.3),
            step(15.0, 0.29, 0.3),
            step(16.0, 0.30, 0.3),
            step(21.0, 0.1, 0.2),
        ];
        assert_eq!(steps_to_match(&steps, 10.0, 20.0), Some(5));
        assert_eq!(steps_to_match(&steps, 14.5, 20.0), Some(1));
        // The last step out of tolerance: never matched.
        assert_eq!(steps_to_match(&steps, 10.0, 30.0), None);
        assert_eq!(steps_to_match(&steps, 30.0, 40.0), None);
        // Speed over belt after 10 s: 0.15 m steps; lengths over durations, over the mean belt.
        let r = speed_ratio_after(&steps[1..3], 10.0).unwrap();
        let v = 0.3 / (0.15 / 0.2 + 0.15 / 0.24);
        assert!((r - v / 0.3).abs() < 1e-12, "{r}");
        assert_eq!(speed_ratio_after(&steps, 100.0), None);
    }

    #[test]
    fn scenario_runs_validate() {
        let (o, t) = belt_steps(60.0, 1);
        o.belt_profile.as_ref().unwrap().validate("t").unwrap();
        assert_eq!(t, [20.0, 40.0]);
        for case in Restart::ALL {
            let o = start_restart(case, 2);
            o.belt_profile.as_ref().unwrap().validate("t").unwrap();
            assert_eq!(o.start, SimStart::Stand);
        }
        push_at_phase(-20.0, 0.3, 1)
            .faults
            .unwrap()
            .validate("t")
            .unwrap();
    }
}
