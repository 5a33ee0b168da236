//! Replay tests without hardware: the MCAP fixtures under `tests/fixtures/` (recorded by
//! `cargo run --release -- replay --mint tests/fixtures`) are fed through this build's
//! controller, and every command must come out bit-identical to the logged one. A controller
//! change that alters any command fails here with the first divergence (tick, joint, field,
//! logged vs replayed); if the change is intended, re-mint the fixtures and commit them.
//!
//! The walk fixture also checks the gait tiles (`adam plot tiles`) against the robot's
//! geometry.

use runtime::control::ControlState;
use runtime::telemetry::replay::{replay, FIXTURES};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

#[test]
fn every_fixture_replays_bit_identically() {
    use ControlState::*;
    for (name, what) in FIXTURES {
        let report = replay(fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            report.divergence.is_none(),
            "{name} ({what}):\n{report}\nIf this change of the controller is intended, re-mint \
             the fixtures: cargo run --release -- replay --mint tests/fixtures"
        );
        assert_eq!(report.truncated, None, "{name}");
        let (ticks, states): (u64, &[ControlState]) = match name {
            "walk.mcap" => (2000, &[Walk]),
            "state_machine.mcap" => (1600, &[Idle, Ramp, Stand, Walk, Stop, Damping, Idle]),
            "estop.mcap" => (800, &[Walk, Damping]),
            other => panic!("no expectation for fixture {other}"),
        };
        assert_eq!(report.ticks, ticks, "{name}");
        assert_eq!(report.states, states, "{name}");
        // One state and six command fields per leg motor, every tick.
        assert_eq!(report.values_compared, ticks * 25, "{name}");
        // The fixture is a complete log that `adam logs info` reads, with its trips.
        let info = runtime::telemetry::log_read::read_info(fixture(name)).expect("log info");
        assert_eq!(info.truncated, None, "{name}");
        assert_eq!(info.count("/input"), ticks, "{name}");
        assert_eq!(info.count("/command"), ticks, "{name}");
        let estops = info
            .safety_events
            .iter()
            .filter(|e| e.contains("\"reason\":\"e_stop\""))
            .count();
        assert_eq!(
            estops,
            usize::from(name != "walk.mcap"),
            "{name}: {:?}",
            info.safety_events
        );
    }
}

#[test]
fn gait_tiles_of_the_walk_fixture_respect_the_robot_geometry() {
    let tiles = runtime::tiles::gait_tiles(fixture("walk.mcap"), 8).expect("tiles");
    let gait = model::gait::GaitFile::load(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(runtime::DEFAULT_GAIT),
    )
    .expect("gait");
    assert_eq!(tiles.figures.len(), 8);
    assert_eq!(tiles.step, 1, "the middle complete step of a 2 s walk");
    // The logged step against the gait file: within 10 % (the end-to-end walk tolerance).
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(
        rel(tiles.step_duration_s, gait.step_duration_s) < 0.1,
        "{tiles:?}"
    );
    assert!(
        rel(tiles.step_length_m, gait.step_length_m) < 0.1,
        "{tiles:?}"
    );
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let (thigh, shin) = tiles.design_m;
    let mut last_phase = f64::NEG_INFINITY;
    for f in &tiles.figures {
        // Phases increase, one stance leg throughout the step.
        assert!(f.phase > last_phase, "{tiles:?}");
        last_phase = f.phase;
        assert_eq!(f.stance, tiles.figures[0].stance);
        // The stance foot is the origin; both legs hang from the hip at the torso's base.
        assert_eq!(f.stance_leg_m[2], [0.0, 0.0]);
        assert_eq!(f.stance_leg_m[0], f.swing_leg_m[0]);
        assert_eq!(f.stance_leg_m[0], f.torso_m[0]);
        // Link lengths are the design's: the figure is the robot, not a sketch.
        for leg in [&f.stance_leg_m, &f.swing_leg_m] {
            assert!((dist(leg[0], leg[1]) - thigh).abs() < 1e-9, "{f:?}");
            assert!((dist(leg[1], leg[2]) - shin).abs() < 1e-9, "{f:?}");
        }
        // Upright, the hip well above the ground, the swing foot not below it by more than
        // the touchdown tolerance.
        assert!(f.torso_m[1][1] > f.torso_m[0][1] + 0.2, "{f:?}");
        assert!(f.torso_m[0][1] > 0.5 * (thigh + shin), "{f:?}");
        assert!(f.swing_leg_m[2][1] > -0.01, "{f:?}");
    }
    // The swing foot starts behind the stance foot and ends ahead of it.
    let first = &tiles.figures[0];
    let last = &tiles.figures[7];
    assert!(first.phase < 0.05 && last.phase > 0.95, "{tiles:?}");
    assert!(first.swing_leg_m[2][0] < -0.1, "{first:?}");
    assert!(last.swing_leg_m[2][0] > 0.1, "{last:?}");
}

#[test]
fn tiles_of_a_log_without_a_complete_step_is_a_clear_error() {
    let e = runtime::tiles::gait_tiles(fixture("estop.mcap"), 8)
        .expect_err("a log without a complete step")
        .to_string();
    assert!(
        e.contains("estop.mcap") && e.contains("no complete step"),
        "{e}"
    );
    let e = runtime::tiles::gait_tiles(fixture("walk.mcap"), 1)
        .expect_err("one figure")
        .to_string();
    assert!(e.contains("at least 2"), "{e}");
}

/// A walk with treadmill speed control and a belt speed change (operator `belt` commands at 0,
/// 2 and 4 s; the gait library attached to the log) replays bit-identically: the speed
/// commands are logged inputs, and the replayed controller switches gaits at the same impacts.
#[test]
fn a_walk_with_speed_commands_replays_bit_identically() {
    use runtime::sim::faults::{Fault, FaultEvent, FaultProfile};
    use runtime::sim::run::{walk, SimWalkOptions};
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("runtime/tests/fixtures/library");
    let mut gaits: Vec<model::gait::GaitFile> = std::fs::read_dir(&dir)
        .expect("library fixtures")
        .map(|e| model::gait::GaitFile::load(e.expect("entry").path()).expect("gait"))
        .collect();
    gaits.sort_by(|a, b| a.speed_mps.total_cmp(&b.speed_mps));
    let origins: Vec<String> = (0..gaits.len()).map(|k| format!("library {k}")).collect();
    let mut setup = runtime::Setup::shipped()
        .expect("shipped")
        .with_library(gaits, &origins)
        .expect("library");
    setup.gait = setup.library[4].clone(); // 0.25 m/s
    let log = std::env::temp_dir().join(format!("adam-replay-speed-{}.mcap", std::process::id()));
    let mut options = SimWalkOptions::new(6.0);
    options.belt_speed_mps = Some(0.25);
    options.log_path = Some(log.clone());
    let mut profile = FaultProfile::none();
    profile.events = vec![FaultEvent {
        at_s: 2.0,
        duration_s: 2.0,
        fault: Fault::BeltSpeed { speed_mps: 0.3 },
    }];
    options.faults = Some(profile);
    let walked = walk(&setup, &options).expect("walk");
    assert!(walked.fall.is_none(), "{:?}", walked.fall);
    let report = replay(&log).expect("replay");
    assert!(report.divergence.is_none(), "{report}");
    assert_eq!(report.ticks, 6000);
    let rows = runtime::telemetry::speed_read::read_speed(&log).expect("/speed");
    assert!(
        rows.iter().any(|r| r.belt_mps == 0.3),
        "the belt change is logged"
    );
    assert!(rows.len() >= 6, "{} steps", rows.len());
    let _ = std::fs::remove_file(&log);
}
