//! Idle → Ramp → Stand on the simulated robot (not just free joints): ADAM standing on both
//! feet of a stopped treadmill in the gait's first pose (its post-impact configuration, at
//! rest), through the whole CAN codec path. Then Walk from rest: the state-based phase cannot
//! start a step without momentum, so the step timeout ends it in Damping, a known state.

use drivers::sim::SimEvent;
use model::Side;
use runtime::controller::{ControlState, OperatorCommand};
use runtime::rt_loop::{LoopOptions, SimulatedClock};
use runtime::safety::Trip;
use runtime::sim_run::{sim_backend, SimWalkOptions};
use runtime::Setup;

#[test]
fn the_simulated_robot_ramps_stands_and_a_walk_from_rest_times_out_into_damping() {
    let setup = Setup::shipped().expect("setup");
    let mut walk = SimWalkOptions::new(7.0);
    walk.belt_speed_mps = Some(0.0);
    let mut backend = sim_backend(&setup, &walk).expect("backend");
    let q0 = setup
        .gait
        .initial_state
        .as_ref()
        .expect("initial state")
        .q
        .clone();
    backend
        .plant_mut()
        .set_state(&q0, &vec![0.0; q0.len()])
        .expect("state");
    for side in [Side::Left, Side::Right] {
        assert!(
            backend.plant().in_stance(side),
            "{side:?} foot on the ground"
        );
    }
    let first = setup.controller(false).expect("controller").first_pose();
    let leg_joints: Vec<usize> = [
        "left_hip_pitch",
        "left_knee_pitch",
        "right_hip_pitch",
        "right_knee_pitch",
    ]
    .iter()
    .map(|n| setup.model.joints[setup.model.require_joint(n).expect("joint")].coordinate)
    .collect();

    // Start, then stand: 2 s of ramp (config minimum), then 2.9 s of Stand.
    let mut options = LoopOptions::simulation(5.0);
    options.script = vec![(0.05, OperatorCommand::Start)];
    let (summary, backend) =
        runtime::run(&setup, backend, SimulatedClock::default(), options, None).expect("run");
    let sim = backend.plant();
    let states: Vec<_> = summary.transitions.iter().map(|t| (t.1, t.2)).collect();
    assert_eq!(
        states,
        [
            (ControlState::Idle, ControlState::Ramp),
            (ControlState::Ramp, ControlState::Stand)
        ]
    );
    assert_eq!(summary.final_state, ControlState::Stand);
    assert_eq!(summary.trip, None);
    // Both feet stayed down the whole time; nothing fell.
    assert!(
        !sim.events()
            .iter()
            .any(|e| matches!(e, SimEvent::Liftoff { .. } | SimEvent::Fall { .. })),
        "{:?}",
        sim.events()
    );
    // Every leg joint holds the first pose within 1° (the PD sags under the robot's weight);
    // the torso stays within 2° of upright.
    for (k, &c) in leg_joints.iter().enumerate() {
        let err = (sim.q()[c] - first[k]).abs().to_degrees();
        assert!(err < 1.0, "joint {k}: {err:.3}° from the first pose");
    }
    assert!(
        sim.torso_pitch_rad().abs().to_degrees() < 2.0,
        "{}",
        sim.torso_pitch_rad()
    );

    // Walk from rest: no momentum to carry the stance leg forward, the phase does not reach
    // the switch, and the step timeout (3 × the gait's step duration) trips to Damping.
    let mut backend = sim_backend(&setup, &walk).expect("backend");
    backend
        .plant_mut()
        .set_state(&q0, &vec![0.0; q0.len()])
        .expect("state");
    let mut options = LoopOptions::simulation(7.0);
    options.script = vec![(0.05, OperatorCommand::Start), (3.0, OperatorCommand::Walk)];
    let (summary, _) =
        runtime::run(&setup, backend, SimulatedClock::default(), options, None).expect("run");
    let limit_s = 3.0 * setup.gait.step_duration_s;
    match summary.trip {
        Some(Trip::StepTimeout {
            elapsed_s,
            limit_s: l,
        }) => {
            assert!(
                (l - limit_s).abs() < 1e-12 && elapsed_s > l,
                "{elapsed_s} {l}"
            );
        }
        other => panic!("{other:?}: {:?}", summary.transitions),
    }
    let damping_at = summary
        .transitions
        .iter()
        .find(|t| t.2 == ControlState::Damping)
        .expect("damping")
        .0;
    assert!((damping_at - (3.0 + limit_s)).abs() < 0.01, "{damping_at}");
}
