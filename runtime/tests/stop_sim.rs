//! Walk → Stop → Stand on the simulated robot, through the whole CAN codec path.
//!
//! The co-designed gait lands each step at 0.40 m/s (torso): more than double support can
//! absorb over a 0.15 m step (the capture point lies beyond the front foot). After Stop, the
//! step under way ends, then one braking step of `walk.stop_step_length_m` (0.24 m) lands with
//! the front foot far enough ahead, and Stand holds the landing pose: the robot rocks from foot
//! to foot a few times and comes to rest on both feet.

use drivers::sim::robot::SimEvent;
use model::Side;
use runtime::control::{ControlState, OperatorCommand};
use runtime::rt_loop::{LoopOptions, SimulatedClock};
use runtime::sim::run::{sim_backend, SimWalkOptions};
use runtime::Setup;

/// Walks from the planned state, says Stop at `stop_at_s`, runs to `end_s`; checks the robot
/// ends standing at rest and returns (Stand entry time, braking step length).
fn stop_at(setup: &Setup, stop_at_s: f64, end_s: f64) -> (f64, f64) {
    let walk = SimWalkOptions::new(end_s);
    let backend = sim_backend(setup, &walk).expect("backend");
    let mut options = LoopOptions::simulation(end_s);
    options.start_walking = true;
    options.script = vec![(stop_at_s, OperatorCommand::Stop)];
    let (summary, backend) =
        runtime::run(setup, backend, SimulatedClock::default(), options, None).expect("run");
    let sim = backend.plant();
    let states: Vec<_> = summary.transitions.iter().map(|t| (t.1, t.2)).collect();
    assert_eq!(
        states,
        [
            (ControlState::Idle, ControlState::Walk),
            (ControlState::Walk, ControlState::Stop),
            (ControlState::Stop, ControlState::Stand)
        ],
        "stop at {stop_at_s} s"
    );
    assert_eq!(summary.trip, None);
    assert!(
        !sim.events()
            .iter()
            .any(|e| matches!(e, SimEvent::Fall { .. } | SimEvent::Fault { .. })),
        "stop at {stop_at_s} s: {:?}",
        sim.fallen()
    );
    let stand_at = summary.transitions[2].0;
    // The braking step: the longest touchdown after Stop, up to just after Stand (the
    // controller may detect the landing a few milliseconds before the foot strikes).
    let braking = sim
        .events()
        .iter()
        .filter_map(|e| match e {
            SimEvent::Touchdown(td) if td.t_s > stop_at_s && td.t_s <= stand_at + 0.1 => {
                Some(td.step_length_m)
            }
            _ => None,
        })
        .fold(f64::NEG_INFINITY, f64::max);
    // At rest on both feet: the kinetic energy of 15 kg moving at 1 mm/s is 7.5e-6 J.
    let ke = sim.kinetic_energy_j();
    eprintln!(
        "stop at {stop_at_s:.1} s: Stand at {stand_at:.3} s, braking step {braking:.3} m, \
         {} touchdowns after it, at {end_s} s KE {ke:.2e} J, pitch {:.2}°",
        sim.events()
            .iter()
            .filter(|e| matches!(e, SimEvent::Touchdown(td) if td.t_s > stand_at))
            .count(),
        sim.torso_pitch_rad().to_degrees()
    );
    assert!(ke < 1e-4, "still moving: {ke} J");
    assert!(sim.in_stance(Side::Left) && sim.in_stance(Side::Right));
    assert!(sim.torso_pitch_rad().abs() < 5f64.to_radians());
    (stand_at, braking)
}

#[test]
fn stop_finishes_the_step_brakes_with_a_long_step_and_stands_at_rest() {
    let setup = Setup::shipped().expect("setup");
    let target_m = setup.config.walk.stop_step_length_m;
    let period_s = setup.gait.step_duration_s;
    // Early and late in a step.
    for stop_s in [1.5, 3.0] {
        let (stand_at, braking_m) = stop_at(&setup, stop_s, stop_s + 4.5);
        // The step under way ends and one braking step follows: Stand within three steps.
        assert!(stand_at - stop_s < 3.0 * period_s, "{stand_at}");
        // The braking step lands at least at its planned length (the foot reaches the ground
        // a little late, after the stance leg has passed the planned angle), not a runaway.
        assert!(
            braking_m > 0.95 * target_m && braking_m < 1.35 * target_m,
            "braking step {braking_m} m"
        );
    }
}
