//! Issue #29's treadmill acceptance on the simulated ADAM (`runtime::sim::scenarios`, the same
//! runs as `adam bench treadmill`), seeds 1–5. The acceptance thresholds run with speed control
//! on (the shipped treadmill config `configs/runtime/adam_treadmill.toml`: the shipped gait
//! library `configs/gaits/adam_library.json` and the gains measured on it)
//! (every one met since 2026-12-07; what was measured: `runtime::control::speed`, "What was
//! measured" and "Where it stands"). Beside them: without speed control leaving the belt is a
//! fall, and a run that falls reports the figures up to the fall, never after it.

use drivers::sim::robot::{BeltEnd, FallCause};
use runtime::control::ControlState;
use runtime::sim::run::{walk, SimWalkReport};
use runtime::sim::scenarios::{
    belt_steps, constant_belt, max_abs_position_after_m, max_abs_position_m, outcome,
    push_at_phase, rides_through, speed_ratio_after, start_restart, steps_to_match, Restart,
    BELT_SPEEDS_MPS, PUSH_PHASES, SETTLE_S,
};
use runtime::Setup;

const SEEDS: [u64; 5] = [1, 2, 3, 4, 5];

fn run(options: &runtime::sim::run::SimWalkOptions) -> SimWalkReport {
    let setup = Setup::shipped().expect("shipped config and gait load");
    walk(&setup, options).expect("the simulated run starts")
}

/// [`run`] with speed control: the shipped treadmill config (`configs/runtime/adam_treadmill.toml`:
/// the shipped gait library and its gains).
fn run_with_speed_control(options: &runtime::sim::run::SimWalkOptions) -> SimWalkReport {
    let root = env!("CARGO_MANIFEST_DIR");
    let setup = Setup::load(
        format!("{root}/configs/runtime/adam_treadmill.toml"),
        format!("{root}/{}", runtime::DEFAULT_GAIT),
    )
    .expect("the treadmill config, its gait library and the shipped gait load");
    walk(&setup, options).expect("the simulated run starts")
}

#[test]
fn walking_slower_than_the_belt_ends_off_the_back_of_the_belt_and_reports_up_to_the_fall() {
    // The shipped gait walks 0.16 m/s; on a belt at 0.30 m/s the robot drifts back 0.14 m/s
    // and its rear stance foot passes the back end (0.8 m behind the centre) after some 5 s.
    let r = run(&constant_belt(0.30, 15.0, 1));
    println!("{r}");
    let (t_s, what) = r.fall.expect("fell off the belt");
    assert_eq!(what, FallCause::OffBelt(BeltEnd::Back));
    assert!((3.0..10.0).contains(&t_s), "fell at {t_s} s");
    assert_eq!(r.walked_s, t_s);
    // Figures up to the fall: the position is the one at the fall, at the back end (the hip
    // is within a step of the foot that left the belt), and the drift matches it.
    assert!(
        (-0.8..-0.6).contains(&r.position_on_belt_m),
        "{}",
        r.position_on_belt_m
    );
    assert!((r.drift_m - r.position_on_belt_m).abs() < 1e-9, "{r}");
    // Nothing measured after it: no step and no truth sample past the fall.
    assert!(r.step_records.iter().all(|s| s.t_s <= t_s));
    assert!(r.trace.iter().all(|s| s.t_s <= t_s));
    assert!(r.trace.last().is_some_and(|s| s.t_s > t_s - 0.02));
    let text = r.to_string();
    assert!(
        text.contains("steps up to the fall")
            && text.contains("position on the belt at the fall")
            && text.contains("off the back of the belt"),
        "{text}"
    );
}

#[test]
fn a_torso_fall_reports_the_drift_at_the_fall_not_where_the_body_lies_later() {
    // A 400 N backward shove for 0.3 s throws the robot down; the run goes on 3 s after it.
    let mut o = constant_belt(0.167, 6.0, 1);
    o.belt_length_m = f64::INFINITY;
    let mut profile = runtime::sim::faults::FaultProfile::none();
    profile
        .events
        .push(runtime::sim::treadmill::parse_push("1.5:-400:0.3", "t").expect("a push"));
    o.faults = Some(profile);
    let r = run(&o);
    println!("{r}");
    let (t_s, _) = r.fall.expect("the shove throws it down");
    assert!(t_s < 3.0, "{t_s}");
    // The drift and the position are at the fall: the last truth sample is within 10 ms of it
    // and agrees with them to the motion of those 10 ms (at its speed, 10 % margin, + 1 mm).
    let last = r.trace.last().expect("truth up to the fall");
    assert!(t_s - last.t_s <= 0.0105, "{} s vs {t_s} s", last.t_s);
    let moved_m = (last.position_on_belt_m - r.position_on_belt_m).abs();
    assert!(
        moved_m <= 1.1 * last.base_velocity_mps.abs() * 0.01 + 1e-3,
        "{moved_m} m at {} m/s",
        last.base_velocity_mps
    );
    assert!((r.drift_m - r.position_on_belt_m).abs() < 1e-9, "{r}");
    assert!(r.walked_s == t_s && r.summary.end_time_s > t_s + 2.0);
}

#[test]
fn the_belt_profile_ramps_at_the_set_acceleration_in_the_truth() {
    let (o, [t1, t2]) = belt_steps(12.0, 1);
    let r = run(&o);
    for s in &r.trace {
        let expected = if s.t_s <= t1 {
            0.20
        } else if s.t_s <= t2 {
            (0.20 + 0.5 * (s.t_s - t1)).min(0.30)
        } else {
            (0.30 - 0.5 * (s.t_s - t2)).max(0.20)
        };
        // The profile acts at the loop's ticks (1 ms): within 1 ms of ramp, 5e-4 m/s.
        assert!(
            (s.belt_speed_mps - expected).abs() < 6e-4,
            "{} s: {} vs {expected}",
            s.t_s,
            s.belt_speed_mps
        );
        if r.fall.is_some() {
            break;
        }
    }
}

/// The shipped library is one continuous family over 0.125–0.40 m/s: its step length never
/// shrinks with speed and neighbouring gaits differ by at most 0.03 m in step length and 0.1 s
/// in duration (speed control interpolates neighbours; planned with Table I's steps up to
/// 0.35 m it jumped from 0.20 m / 0.67 s to 0.26 m / 0.79 s between 0.300 and 0.325 m/s, and
/// the gaits in between stalled on a 0.35 m/s belt).
#[test]
fn the_shipped_library_is_one_continuous_family() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/configs/gaits/adam_library.json"
    );
    let library = model::library::GaitLibrary::load(path).expect("the shipped library loads");
    let speeds: Vec<f64> = library.entries.iter().map(|e| e.speed_mps).collect();
    assert!(
        speeds.first().is_some_and(|&v| v <= 0.15 + 1e-9)
            && speeds.last().is_some_and(|&v| v >= 0.35 - 1e-9),
        "{speeds:?}"
    );
    for w in library.entries.windows(2) {
        let (a, b) = (&w[0].gait, &w[1].gait);
        let what = format!("{} → {} m/s", w[0].speed_mps, w[1].speed_mps);
        assert!(
            b.step_length_m >= a.step_length_m - 1e-6,
            "{what}: step {} → {} m",
            a.step_length_m,
            b.step_length_m
        );
        assert!(
            b.step_length_m - a.step_length_m <= 0.03,
            "{what}: step {} → {} m",
            a.step_length_m,
            b.step_length_m
        );
        assert!(
            (b.step_duration_s - a.step_duration_s).abs() <= 0.1,
            "{what}: duration {} → {} s",
            a.step_duration_s,
            b.step_duration_s
        );
    }
}

/// Belt 0.15–0.35 m/s for 60 s, seeds 1–5: no fall, no trip; after 10 s within ±0.10 m of the
/// centre and within 2 % of the belt's speed in every run (issue #29, item 6 (a)).
///
/// Measured (2026-12-06, the treadmill config with a step lean of at most 7 mrad): walked/belt
/// 100.0 / 100.2 / 99.7 / 99.8 / 99.8 % (mean) and |position| after 10 s at most 0.079 / 0.082 /
/// 0.093 / 0.059 / 0.065 m at 0.15 / 0.20 / 0.25 / 0.30 / 0.35 m/s (seeds 6–10, not tested:
/// 0.139 / 0.093 / 0.132 / 0.087 / 0.081 m; seeds 11–20: 0.138 / 0.088 / 0.131 / 0.073 /
/// 0.071 m). With at most 6 mrad the 0.25 m/s belt strayed 0.1004 m in seed 2, and this test
/// was ignored; on 2026-12-05's config 0.124 / 0.170 / 0.262 / 0.123 / 0.111 m (before the
/// library's steps were capped at 0.22 m every seed tripped the step timeout at 0.35 m/s).
#[test]
fn walks_every_belt_speed_for_60_s_in_the_middle_at_the_belt_speed() {
    for v in BELT_SPEEDS_MPS {
        for seed in SEEDS {
            let r = run_with_speed_control(&constant_belt(v, 60.0, seed));
            assert!(rides_through(&r), "{v} m/s seed {seed}: {}", outcome(&r));
            let p = max_abs_position_after_m(&r, SETTLE_S).expect("walked past 10 s");
            assert!(p <= 0.10, "{v} m/s seed {seed}: |position| {p} m");
            let ratio = speed_ratio_after(&r.step_records, SETTLE_S).expect("steps");
            assert!((ratio - 1.0).abs() <= 0.02, "{v} m/s seed {seed}: {ratio}");
        }
    }
}

/// Belt 0.20 → 0.30 → 0.20 m/s: within 0.05 m/s of the belt in ≤ 8 steps after each change.
/// Measured (2026-12-06, treadmill config, seeds 1-5): up 1, 1, 1, 1, 3 and down 1, 1, 1, 1, 1
/// steps (seeds 6-10, not tested: up 1, 1, 1, 3, 3, down 9, 1, 2, 17, 1; no stall; with a step
/// lean of at most 6 mrad down 3, 1, 1, 1, 1 and 9, 1, 2, 1, 1; 2026-12-05's config: down 5, 7,
/// 16, never, 1).
#[test]
fn follows_a_belt_step_up_and_back_within_8_steps() {
    for seed in SEEDS {
        let (o, [t1, t2]) = belt_steps(60.0, seed);
        let r = run_with_speed_control(&o);
        assert!(rides_through(&r), "seed {seed}: {}", outcome(&r));
        for (from, until) in [(t1, t2), (t2, 60.0)] {
            let n = steps_to_match(&r.step_records, from, until);
            assert!(
                n.is_some_and(|n| n <= 8),
                "seed {seed} from {from} s: {n:?}"
            );
        }
    }
}

/// Belt 0.20 → 0.30 → 0.20 m/s: within ±0.15 m of the centre throughout. Measured (2026-12-06,
/// treadmill config, seeds 1-5): 0.100, 0.075, 0.098, 0.113, 0.094 m (seeds 6-10, not tested:
/// 0.251, 0.101, 0.070, 0.260, 0.119 m; with a step lean of at most 6 mrad 0.129, 0.075, 0.098,
/// 0.090, 0.094 and 0.241, 0.099, 0.070, 0.083, 0.121 m; 2026-12-05's config, seeds 1-5: 0.244,
/// 0.129, 0.314, 0.200, 0.170 m).
#[test]
fn stays_within_15_cm_of_the_centre_through_a_belt_step() {
    for seed in SEEDS {
        let (o, _) = belt_steps(60.0, seed);
        let r = run_with_speed_control(&o);
        assert!(rides_through(&r), "seed {seed}: {}", outcome(&r));
        let p = max_abs_position_m(&r);
        assert!(p <= 0.15, "seed {seed}: |position| {p} m");
    }
}

/// −20 N for 0.2 s at the five points of the step rides through (no trip, no stall, no fall,
/// 12 s) in at least 4 of 5 seeds, most after a step-back catch (`runtime::control::recovery`,
/// "The step-back catch"): measured 2026-12-06, seeds 1–5, 4, 5, 4, 5, 5 of 5 at 10/30/50/70/90
/// % (18 of the 23 after one step back; without the catch 0, 0, 0, 5, 0).
#[test]
fn backward_pushes_ride_through_at_every_point_of_the_step() {
    for phase in PUSH_PHASES {
        let ok = SEEDS
            .iter()
            .filter(|&&seed| {
                rides_through(&run_with_speed_control(&push_at_phase(-20.0, phase, seed)))
            })
            .count();
        assert!(ok >= 4, "-20 N at {phase}: {ok} of 5");
    }
}

/// +40 N for 0.2 s at the five points of the step rides through (no trip, no stall, no fall,
/// 12 s) in at least 4 of 5 seeds: measured 2026-12-07, seeds 1–5, 5 of 5 at every point (7
/// of the 25 after a step back or more; seeds 6–10 5, 5, 5, 4, 5). It needs the touchdown gate
/// (`runtime::estimator`, "The touchdown gate"), no disturbance settle and the step lever at
/// most 2 cm (`runtime::control::speed`, "Forward pushes"): before, 0, 4, 5, 5, 0.
#[test]
fn forward_pushes_ride_through_at_every_point_of_the_step() {
    for phase in PUSH_PHASES {
        let ok = SEEDS
            .iter()
            .filter(|&&seed| {
                rides_through(&run_with_speed_control(&push_at_phase(40.0, phase, seed)))
            })
            .count();
        assert!(ok >= 4, "+40 N at {phase}: {ok} of 5");
    }
}

/// A simulated robot that starts on a belt at rest with the shipped library stands in the
/// library gait of the runtime gait's step (0.15 m, the 0.15 m/s gait), not in the slowest
/// gait's 0.125 m stance: from that, Stop → Stand → Walk on the 1.6 m belt went off its back in
/// 5 of 5 seeds (`runtime::sim::run`).
#[test]
fn a_robot_starting_on_a_belt_at_rest_stands_in_the_runtime_gaits_stance() {
    let root = env!("CARGO_MANIFEST_DIR");
    let setup = Setup::load(
        format!("{root}/configs/runtime/adam_treadmill.toml"),
        format!("{root}/{}", runtime::DEFAULT_GAIT),
    )
    .expect("the treadmill config, its gait library and the shipped gait load");
    let slowest = setup.library_gait_nearest(0.0).expect("a library");
    assert!(slowest.step_length_m < 0.13, "{}", slowest.step_length_m);
    let step_m = setup.gait.step_length_m;
    let at_rest = setup.clone().starting_at_rest();
    assert!((at_rest.gait.step_length_m - step_m).abs() < 1e-6);
    assert!((at_rest.gait.speed_mps - 0.15).abs() < 1e-9);
}

/// From Stand, restart after a stop, and the belt started after the walk: no trip or fall, and
/// the restart goes through Stand (Stop → Stand → Walk). How: `runtime::control::speed`,
/// "Start and restart"; the scenarios and what was measured: `runtime::sim::scenarios`.
#[test]
fn starts_and_restarts_on_the_moving_belt() {
    for case in Restart::ALL {
        for seed in SEEDS {
            let r = run_with_speed_control(&start_restart(case, seed));
            assert!(
                rides_through(&r),
                "{} seed {seed}: {}",
                case.name(),
                outcome(&r)
            );
            if case == Restart::StopAndWalkAgain {
                let states: Vec<_> = r.summary.transitions.iter().map(|t| t.2).collect();
                assert!(
                    states.ends_with(&[
                        ControlState::Walk,
                        ControlState::Stop,
                        ControlState::Stand,
                        ControlState::Walk
                    ]),
                    "seed {seed}: {:?}",
                    r.summary.transitions
                );
            }
        }
    }
}
