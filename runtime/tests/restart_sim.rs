//! Walk → Stop → Stand → Walk again on the simulated robot (issue #29 item 5), seeds 1–5, on the
//! belt at the gait's speed and at 0.25 m/s; and a Walk from Stand on a belt already moving
//! (issue #29 item 6: the launch on an endless belt holds; on the 1.6 m belt, and with the belt
//! started after the robot walks, it does not yet: ignored tests with what was measured).
//!
//! What broke: with the braking step 0.30 m long, Stand after the Stop stood on feet 0.34 m
//! apart with the torso midway; the launch of the second Walk carries the torso to 4 cm behind
//! the front foot, which the straight rear leg allows only 5 cm lower, with the stance knee bent
//! 0.9 rad. Once the rear foot lifted, that knee could not carry the robot: torque saturation
//! (left knee −33.5 N·m against 33 N·m for 50 ticks) 1.1 s after Walk. The braking step is now
//! 0.24 m (`walk.stop_step_length_m`), and a launch ends less far forward (and faster) when the
//! rear leg would make the torso drop more than 3 cm.
//!
//! The free graded-mesh re-plan of the default gait (its 0.1686 m step) walks on from Stand
//! since the launch hands over onto the planned orbit's angular momentum
//! (`the_replanned_gait_walks_on_from_stand`).

use drivers::sim::robot::SimEvent;
use runtime::control::{ControlState, OperatorCommand};
use runtime::rt_loop::{LoopOptions, SimulatedClock};
use runtime::sim::run::{sim_backend, walk, SimStart, SimWalkOptions, SimWalkReport};
use runtime::sim::treadmill::BeltProfile;
use runtime::Setup;

mod common;

/// Walks from the planned state, Stop at 3 s, Walk at 10 s, to 20 s: no trip, no fall, the
/// states in order, and at least 8 steps after the second Walk.
fn walk_stop_walk(seed: u64, belt_speed_mps: Option<f64>) {
    walk_stop_walk_with(&Setup::shipped().expect("setup"), seed, belt_speed_mps);
}

fn walk_stop_walk_with(setup: &Setup, seed: u64, belt_speed_mps: Option<f64>) {
    let end_s = 20.0;
    let mut walk = SimWalkOptions::new(end_s);
    walk.seed = seed;
    walk.belt_speed_mps = belt_speed_mps;
    // Standing 7 s on a moving belt carries the robot 1.2 m back, off a 1.6 m belt (an
    // operator stops the belt when the robot stops); the subject here is the controller's
    // restart: an endless belt.
    walk.belt_length_m = f64::INFINITY;
    let backend = sim_backend(setup, &walk).expect("backend");
    let mut options = LoopOptions::simulation(end_s);
    options.start_walking = true;
    options.script = vec![(3.0, OperatorCommand::Stop), (10.0, OperatorCommand::Walk)];
    let (summary, backend) =
        runtime::run(setup, backend, SimulatedClock::default(), options, None).expect("run");
    let sim = backend.plant();
    let context = format!(
        "seed {seed}, belt {belt_speed_mps:?}: {:?}",
        summary.transitions
    );
    assert_eq!(summary.trip, None, "{context}");
    let fall = sim
        .events()
        .iter()
        .find(|e| matches!(e, SimEvent::Fall { .. } | SimEvent::Fault { .. }));
    assert!(fall.is_none(), "{fall:?} {context}");
    let states: Vec<_> = summary.transitions.iter().map(|t| t.2).collect();
    assert_eq!(
        states,
        [
            ControlState::Walk,
            ControlState::Stop,
            ControlState::Stand,
            ControlState::Walk
        ],
        "{context}"
    );
    // Walking again: steps after the second Walk's launch (1 s).
    let steps = sim
        .events()
        .iter()
        .filter(|e| matches!(e, SimEvent::Touchdown(td) if td.t_s > 11.0))
        .count();
    assert!(
        steps >= 8,
        "{steps} touchdowns after the second Walk, {context}"
    );
}

#[test]
fn walk_after_a_stop_walks_again() {
    for seed in 1..=5 {
        walk_stop_walk(seed, None);
    }
}

#[test]
fn walk_after_a_stop_walks_again_on_a_belt_at_a_quarter_metre_per_second() {
    for seed in 1..=5 {
        walk_stop_walk(seed, Some(0.25));
    }
}

/// The free graded-mesh re-plan of the default gait
/// (`runtime/tests/fixtures/adam_codesign_graded.json`: `adam plan --robot
/// configs/robots/adam_codesign.urdf`, 0.1686 m in 0.9000 s, orbit +0.28 %; its URDF path
/// pointed at `configs/robots/`) with a braking step of `stop_m`.
fn replanned(stop_m: f64) -> Setup {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut setup = Setup::load(
        root.join("configs/runtime/adam.toml"),
        root.join("runtime/tests/fixtures/adam_codesign_graded.json"),
    )
    .expect("the re-planned gait");
    setup.config.walk.stop_step_length_m = stop_m;
    setup
}

/// The re-planned default gait restarts after a Stop once its braking step is 0.20 m (seeds 1–5;
/// measured 10 of 10 seeds for 0.20–0.22 m, 9 of 10 at 0.23 m): a shorter braking step leaves
/// the feet nearer the gait's own stance width (0.20–0.24 m apart after Stand's rocking), so the
/// launch needs less crouch. With the shipped 0.24 m it restarts in none of seeds 1–5 (the feet
/// 0.26–0.30 m apart; `runtime::control::double_support`).
#[test]
fn the_replanned_gait_walks_again_after_a_stop_with_a_shorter_braking_step() {
    let setup = replanned(0.20);
    for seed in 1..=5 {
        walk_stop_walk_with(&setup, seed, Some(0.0));
    }
}

/// The re-planned gait walks on from Stand, on its planned orbit from the first steps: the launch
/// hands over once the robot's angular momentum about the stance foot reaches the orbit's
/// σ*(θ) (`runtime::control::orbit_table`), so from the third step after the hand-over every
/// step lasts the planned 0.90 s within 25 % (measured 0.87-1.19 s). Before (a fixed 0.20 m/s
/// launch end speed) the first steps took 0.44-0.60 s, each slower than the last, and seeds 3-5
/// overshot into a stall (step timeout; `runtime::control::double_support`).
#[test]
fn the_replanned_gait_walks_on_from_stand() {
    let setup = replanned(0.20);
    let planned_s = setup.gait.step_duration_s;
    for seed in 1..=5 {
        // 20 s: at the planned 0.90 s a step, 15 s leave room for 13 steps at most.
        let r = walk_from_stand_until(&setup, seed, f64::INFINITY, None, 20.0);
        let context = format!("re-planned gait, seed {seed}");
        assert_walks_on(&r, &context);
        // The launch ends by 3.1 s (Walk at 2.1 s, 1 s at most).
        let durations: Vec<f64> = r
            .step_records
            .iter()
            .filter(|s| s.t_s > 3.1)
            .map(|s| s.duration_s)
            .collect();
        for d in &durations[3..] {
            assert!(
                (d - planned_s).abs() < 0.25 * planned_s,
                "{context}: steps {durations:.2?} s, planned {planned_s:.2} s"
            );
        }
    }
}

/// From Stand (the Ramp from t = 0 reaches it at 2 s), Walk at 2.1 s on a belt of `length_m`
/// moving at 0.25 m/s from the start (or following `profile`), to 15 s.
fn walk_from_stand(
    setup: &Setup,
    seed: u64,
    length_m: f64,
    profile: Option<&str>,
) -> SimWalkReport {
    walk_from_stand_until(setup, seed, length_m, profile, 15.0)
}

/// [`walk_from_stand`] to `end_s`.
fn walk_from_stand_until(
    setup: &Setup,
    seed: u64,
    length_m: f64,
    profile: Option<&str>,
    end_s: f64,
) -> SimWalkReport {
    let mut options = SimWalkOptions::new(end_s);
    options.seed = seed;
    options.start = SimStart::Stand;
    options.belt_length_m = length_m;
    match profile {
        Some(p) => options.belt_profile = Some(BeltProfile::parse(p, "test").expect("profile")),
        None => options.belt_speed_mps = Some(0.25),
    }
    options.script = vec![(2.1, OperatorCommand::Walk)];
    walk(setup, &options).expect("walk")
}

fn assert_walks_on(r: &SimWalkReport, context: &str) {
    assert_eq!(r.summary.trip, None, "{context}");
    assert!(r.fall.is_none(), "{:?} {context}", r.fall);
    assert_eq!(r.summary.final_state, ControlState::Walk, "{context}");
    // The launch (1 s), then at least 12 steps in the 11.9 s left.
    assert!(r.steps >= 12, "{} steps, {context}", r.steps);
}

/// The launch from Stand onto a belt already at 0.25 m/s, with and without speed control
/// (the gait library), seeds 1–5, on an endless belt (the subject is the controller's
/// launch; on the 1.6 m belt see the ignored test below). Measured: 14–17 steps, no trip.
#[test]
fn walk_from_stand_on_a_moving_belt_walks() {
    for (name, setup) in [
        ("one gait", Setup::shipped().expect("setup")),
        ("library", common::library_setup()),
    ] {
        for seed in 1..=5 {
            let r = walk_from_stand(&setup, seed, f64::INFINITY, None);
            assert_walks_on(&r, &format!("{name}, seed {seed}"));
        }
    }
}

/// Issue #29 item 6 on the 1.6 m belt. Not met: the belt carries the standing robot 0.5 m back
/// during the 2 s Ramp and the launch's 1 s in double support takes it past the back end at
/// 2.8–2.9 s (hip 0.69–0.73 m behind the centre), seeds 1–5 with and without the library. The
/// launch would have to step sooner (or the robot stand further forward) on a moving belt.
/// The pitch estimate is not the cause here (the belt does not ramp under the standing robot):
/// unchanged by the legs' pitch in Stand (`runtime::sim::scenarios`). The belt moves from t = 0,
/// so the robot is 0.5 m back before Walk, some 0.15 m from losing its rear foot, and the 1 s
/// launch alone is carried 0.25 m: it would have to step within 0.6 s of Walk;
/// the 1.6 m-belt start of issue #29 with the belt started once the robot stands passes with
/// the treadmill config (`tests/treadmill.rs::starts_and_restarts_on_the_moving_belt`).
#[test]
#[ignore = "issue #29 item 6: Walk from Stand on a 1.6 m belt already at 0.25 m/s goes off its back (measured 5 of 5 seeds; re-checked 2026-12-05 with the legs' pitch in Stand: seed 1 off the back at 2.80 s, in the launch)"]
fn walk_from_stand_on_the_moving_belt_stays_on_it() {
    for seed in 1..=5 {
        let r = walk_from_stand(&common::library_setup(), seed, 1.6, None);
        assert_walks_on(&r, &format!("seed {seed}"));
    }
}

/// Issue #29 item 6: the belt started after the robot walks (`--belt "0:0,5:0.25"`, 0.5 m/s²),
/// with speed control. Not met: the robot walks the still belt at the library's slowest gait
/// (0.15 m/s), then after the belt starts it stalls: the step timeout trips at 8.4–10.3 s,
/// seeds 1–5 (hip 0.16–0.75 m behind the centre). This runs the test library with `adam.toml`'s
/// speed settings; with the treadmill config's start settings (`runtime::control::speed`, "Start
/// and restart") the shipped library rides it out (`tests/treadmill.rs`), not re-tried here.
#[test]
#[ignore = "issue #29 item 6: with the belt started after the walk, the walk stalls (step timeout, 5 of 5 seeds; re-checked 2026-12-05 with the legs' pitch in Stand: seed 1 still trips the step timeout)"]
fn walk_on_a_belt_started_after_the_walk() {
    for seed in 1..=5 {
        let r = walk_from_stand(&common::library_setup(), seed, 1.6, Some("0:0,5:0.25"));
        assert_walks_on(&r, &format!("seed {seed}"));
    }
}
