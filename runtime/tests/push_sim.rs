//! Pushes on the torso while walking a belt at 0.25 m/s with speed control (issue #29 item 6):
//! 0.2 s long, −20 N (backward) and +40 N (forward), starting at 10/30/50/70/90 % of a step
//! (the step's start and end are the impacts of the same run without the push, which is
//! bit-identical up to the push), seeds 1–5. Ride through = no trip (a step timeout included),
//! no stall relaunch, no fall, and the robot still walking (at least 8 impacts in the 8 s after
//! the push).

use runtime::sim::faults::{Fault, FaultEvent, FaultProfile};
use runtime::sim::run::{walk, SimWalkOptions};
use runtime::Setup;

mod common;

const BELT_MPS: f64 = 0.25;
const PUSH_S: f64 = 0.2;
const AFTER_S: f64 = 8.0;

fn setup() -> Setup {
    common::library_setup().starting_near(BELT_MPS)
}

/// Walks with an optional push (start s, force N); returns (ridden through, impact times, what
/// happened).
fn run(setup: &Setup, seed: u64, end_s: f64, push: Option<(f64, f64)>) -> (bool, Vec<f64>, String) {
    let mut options = SimWalkOptions::new(end_s);
    options.belt_speed_mps = Some(BELT_MPS);
    options.seed = seed;
    if let Some((at_s, force_n)) = push {
        let mut profile = FaultProfile::none();
        profile.events = vec![FaultEvent {
            at_s,
            duration_s: PUSH_S,
            fault: Fault::Push {
                force_x_n: force_n,
                force_z_n: 0.0,
            },
        }];
        options.faults = Some(profile);
    }
    let report = walk(setup, &options).expect("walk");
    // The `/speed` rows of the run (its impacts), from the summary: no log to write and read.
    let impacts: Vec<f64> = report.summary.speed_rows.iter().map(|r| r.t_s).collect();
    assert!(!impacts.is_empty(), "speed control ran");
    let after = push.map_or(0.0, |(at, _)| at + PUSH_S);
    let steps_after = impacts
        .iter()
        .filter(|&&t| t > after && t <= after + AFTER_S)
        .count();
    // A stall relaunch is a stall (off in adam.toml, which this setup runs: never here).
    let relaunches = report.summary.last_sample.recoveries;
    let ok = report.fall.is_none()
        && report.summary.trip.is_none()
        && relaunches == 0
        && steps_after >= 8;
    let what = format!(
        "fall {:?} trip {:?} relaunches {relaunches} impacts in {AFTER_S} s after: {steps_after}",
        report.fall, report.summary.trip
    );
    (ok, impacts, what)
}

/// Pushes landing at five points of a step: how many seeds of 5 ride through, per force and
/// point.
fn ride_through(force_n: f64) -> Vec<(f64, u32)> {
    let setup = setup();
    let points = [0.1, 0.3, 0.5, 0.7, 0.9];
    let mut passed = vec![0u32; points.len()];
    for seed in 1..=5 {
        let (_, impacts, _) = run(&setup, seed, 12.0, None);
        // The first step starting after 8 s.
        let k = impacts
            .iter()
            .position(|&t| t > 8.0)
            .expect("steps after 8 s");
        let (t0, t1) = (impacts[k], impacts[k + 1]);
        for (i, p) in points.iter().enumerate() {
            let at_s = t0 + p * (t1 - t0);
            let (ok, _, what) = run(
                &setup,
                seed,
                at_s + PUSH_S + AFTER_S + 0.5,
                Some((at_s, force_n)),
            );
            eprintln!(
                "{force_n:+} N at {:.0} % (t {at_s:.3} s), seed {seed}: {} {what}",
                p * 100.0,
                if ok { "rides through" } else { "FAILS" }
            );
            passed[i] += u32::from(ok);
        }
    }
    points.iter().copied().zip(passed).collect()
}

/// Asserts that pushes of `force_n` ride through in at least 4 of 5 seeds at every point.
fn assert_rides_through(force_n: f64) {
    let table = ride_through(force_n);
    eprintln!("{force_n:+} N: {table:?}");
    for (point, passed) in table {
        assert!(
            passed >= 4,
            "{force_n:+} N for {PUSH_S} s at {:.0} % of the step: {passed} of 5 seeds ride through",
            point * 100.0
        );
    }
}

/// The largest pushes that ride through today (of −5, −7.5, −10, −20 N and +5, +7.5, +10, +20,
/// +40 N tried; seeds riding through at 10/30/50/70/90 %): −5 N [4, 5, 4, 5, 4], +7.5 N
/// [5, 5, 5, 4, 5]. With the step timeout on a stalled phase (`safety.stall_timeout_s`, 1.5 s
/// without progress) the larger ones fail exactly as with the old one (a step longer than 3
/// gait steps), every failure a `step_timeout` (a genuine stall: the robot stands on one or
/// both feet, carried back by the belt): −7.5 N [1, 5, 1, 5, 0], −10 N [0, 3, 2, 5, 0],
/// +10 N [3, 4, 4, 4, 4], +20 N [0, 0, 1, 1, 0]. The largest push that rides through in at
/// least 4 of 5 seeds, per point: backward −5, −7.5, −5, −10, −5 N; forward +7.5, +10, +10,
/// +10, +10 N. With the step lever and the shipped gains (2026-12-05): −5 N [5, 5, 5, 5, 5],
/// +7.5 N [4, 5, 4, 5, 4] (seed 1 stalls at 10, 50 and 90 %); with σ following the belt speed
/// (`speed.command_share = 0`) +7.5 N at 90 % rode through in 3 of 5.
#[test]
fn small_backward_pushes_ride_through_at_five_points_of_a_step() {
    assert_rides_through(-5.0);
}

/// The forward half of the small pushes above (a test of its own, so the two run side by side).
#[test]
fn small_forward_pushes_ride_through_at_five_points_of_a_step() {
    assert_rides_through(7.5);
}

/// The issue's acceptance: −20 N and +40 N. Not met: measured [0, 0, 1, 0, 0] and
/// [0, 0, 0, 0, 0] of 5 seeds with the old step timeout; with the stall-based one, seeds 1–2
/// ride through 1 of 10 (−20 N) and 0 of 10 (+40 N). A backward push early in a step stops the
/// torso short of the stance foot: the swing foot comes down behind it and the robot stands
/// in double support until the step timeout trips; a forward one quickens the steps, then
/// the walk slows into the same stall within 2–5 steps.
#[test]
#[ignore = "issue #29 item 6 with adam.toml (one gait, no speed control): -20 N / +40 N for 0.2 s do not ride through; the treadmill config meets them (tests/treadmill.rs)"]
fn issue_pushes_ride_through_at_five_points_of_a_step() {
    assert_rides_through(-20.0);
    assert_rides_through(40.0);
}

/// The shipped treadmill config (`configs/runtime/adam_treadmill.toml`: the shipped gait library,
/// speed control, the stall relaunch after 1 s) with the relaunch after `relaunch_s` (0: off).
fn treadmill_setup(relaunch_s: f64) -> Setup {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let mut setup = Setup::load(
        format!("{root}/configs/runtime/adam_treadmill.toml"),
        format!("{root}/{}", runtime::DEFAULT_GAIT),
    )
    .expect("the treadmill config and its library load");
    setup.config.speed.stall_relaunch_s = relaunch_s;
    setup
}

/// The step-back catch end to end (`runtime::control::recovery`, "The step-back catch"; the
/// same push as the next test: −20 N at 90 % of a step, seed 1, 9 s): with the shipped
/// treadmill config the phase runs back, the swing foot is set down behind at once and the
/// robot is carried forward from double support. It rides through (no trip, no fall, no stall
/// relaunch) with at least one catch counted; without the catch the same run stalls. Measured:
/// one catch; the longest time between the simulator's touchdowns 0.992 s (printed).
#[test]
fn a_backward_push_that_runs_a_step_back_is_caught_at_once_and_rides_through() {
    use runtime::sim::scenarios::{push_at_phase, rides_through, PUSH_ARM_S};
    let mut options = push_at_phase(-20.0, 0.9, 1);
    options.duration_s = PUSH_ARM_S + 9.0;
    let setup = treadmill_setup(1.0);
    assert!(
        setup.config.speed.step_back_catch_m > 0.0,
        "the shipped config catches"
    );
    let on = walk(&setup, &options).expect("walk");
    println!("{on}");
    assert!(rides_through(&on), "{on}");
    assert!(on.summary.last_sample.catches >= 1, "{on}");
    assert_eq!(on.summary.last_sample.recoveries, 0, "{on}");
    // The same run without the catch stalls and relaunches (the relaunch waits 1 s at rest).
    let mut off = setup.clone();
    off.config.speed.step_back_catch_m = 0.0;
    let off = walk(&off, &options).expect("walk");
    assert!(!rides_through(&off), "{off}");
    assert_eq!(off.summary.last_sample.recoveries, 1, "{off}");
    // The catch walks on at once: its longest time between touchdowns is at least half a second
    // shorter than the relaunch's (measured 0.992 s against 1.897 s; the relaunch's 1 s wait
    // makes the difference).
    let longest_gap_s = |r: &runtime::sim::run::SimWalkReport| {
        r.step_records
            .windows(2)
            .map(|w| w[1].t_s - w[0].t_s)
            .fold(0.0_f64, f64::max)
    };
    let (gap_on, gap_off) = (longest_gap_s(&on), longest_gap_s(&off));
    assert!(gap_on + 0.5 < gap_off, "{gap_on:.3} s vs {gap_off:.3} s");
}

/// The touchdown gate end to end (`runtime::estimator`, "The touchdown gate"): +40 N at 10 %
/// of a step (seed 1, 12 s, the shipped treadmill config) lands the pushed step with the foot
/// still in the air. With the gate the pitch estimate stays within 0.3° of the simulator's
/// truth all run (measured RMS 0.057°, max 0.152°) and the run rides through; without it the
/// estimate runs more than 1° off (measured RMS 1.245°, max 2.244°) and the robot falls.
#[test]
fn a_fast_impacts_wrong_touchdown_pitch_is_set_aside_and_the_estimate_stays_true() {
    use runtime::sim::scenarios::{push_at_phase, rides_through};
    let options = push_at_phase(40.0, 0.1, 1);
    let gated = treadmill_setup(1.0);
    assert!(
        gated.config.estimator.touchdown_gate_rad > 0.0,
        "the shipped config gates"
    );
    let on = walk(&gated, &options).expect("walk");
    let pitch = &on.summary.tracking;
    let rms = pitch.pitch_rms_rad().expect("the simulator's truth");
    assert!(
        rms < 0.1_f64.to_radians() && pitch.pitch_max_abs_rad < 0.3_f64.to_radians(),
        "RMS {rms} rad, max {} rad\n{on}",
        pitch.pitch_max_abs_rad
    );
    assert!(rides_through(&on), "{on}");
    let mut ungated = gated.clone();
    ungated.config.estimator.touchdown_gate_rad = 0.0;
    let off = walk(&ungated, &options).expect("walk");
    assert!(
        off.summary.tracking.pitch_max_abs_rad > 1.0_f64.to_radians(),
        "{off}"
    );
    assert!(!rides_through(&off), "{off}");
}

/// The stall relaunch end to end, the step-back catch off (`runtime::control::recovery`; issue
/// #29's push at 90 % of a
/// step, its 0.2 s lasting into the next step, `runtime::sim::scenarios::push_at_phase`, seed 1,
/// the run 9 s long): −20 N stops the torso short of the next stance foot. Without the relaunch
/// the robot stands on both feet until the step timeout trips; with it, the controller
/// relaunches once from double support and the walk goes on: no trip, no fall, and at least 6
/// forward steps (simulator truth) in the last 5 s. The relaunched step stalled, so the run
/// walks on but does not ride through (issue #29's "no stall").
#[test]
fn a_backward_push_that_stalls_a_step_relaunches_from_double_support_and_walks_on() {
    use runtime::sim::scenarios::{push_at_phase, rides_through, walks_on, PUSH_ARM_S};
    let mut options = push_at_phase(-20.0, 0.9, 1);
    options.duration_s = PUSH_ARM_S + 9.0;
    // The step-back catch off: the stall relaunch alone.
    let without_catch = |relaunch_s| {
        let mut setup = treadmill_setup(relaunch_s);
        setup.config.speed.step_back_catch_m = 0.0;
        setup
    };
    let off = walk(&without_catch(0.0), &options).expect("walk");
    assert_eq!(
        off.summary.trip.map(|t| t.name()),
        Some("step_timeout"),
        "{off}"
    );
    assert_eq!(off.summary.last_sample.recoveries, 0);
    let on = walk(&without_catch(1.0), &options).expect("walk");
    println!("{on}");
    assert!(on.summary.trip.is_none() && on.fall.is_none(), "{on}");
    assert_eq!(on.summary.last_sample.recoveries, 1, "{on}");
    assert!(walks_on(&on) && !rides_through(&on), "{on}");
    let from_s = options.duration_s - 5.0;
    let forward = on
        .step_records
        .iter()
        .filter(|s| s.t_s > from_s && s.length_m > 0.1)
        .count();
    assert!(forward >= 6, "{forward} forward steps after {from_s} s");
}
