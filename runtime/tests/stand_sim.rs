//! Idle → Ramp → Stand on the simulated robot (not just free joints): ADAM standing on both
//! feet of a stopped treadmill in the gait's first pose (its post-impact configuration, at
//! rest), through the whole CAN codec path. Then the whole cycle on one robot: Stand → Walk
//! (a launch in double support carries the torso over the stance foot, then the rear foot
//! lifts and the gait takes over) → Stop (the braking step) → Stand at rest.

use drivers::sim::robot::SimEvent;
use model::Side;
use runtime::control::{ControlState, OperatorCommand};
use runtime::rt_loop::{LoopOptions, SimulatedClock};
use runtime::sim::run::{sim_backend, SimWalkOptions};
use runtime::Setup;

#[test]
fn the_simulated_robot_ramps_stands_walks_from_stand_stops_and_stands_again() {
    let setup = Setup::shipped().expect("setup");
    let mut walk = SimWalkOptions::new(7.0);
    walk.belt_speed_mps = Some(0.0);
    // 22 s of walking on a belt at rest covers 3.5 m: an endless belt.
    walk.belt_length_m = f64::INFINITY;
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

    // The whole cycle: Stand → Walk (a launch in double support, then steps) → Stop (the
    // braking step) → Stand, on the same robot.
    let mut backend = sim_backend(&setup, &walk).expect("backend");
    backend
        .plant_mut()
        .set_state(&q0, &vec![0.0; q0.len()])
        .expect("state");
    let (walk_at, stop_at, end) = (3.0, 25.0, 30.0);
    let mut options = LoopOptions::simulation(end);
    options.script = vec![
        (0.05, OperatorCommand::Start),
        (walk_at, OperatorCommand::Walk),
        (stop_at, OperatorCommand::Stop),
    ];
    let (summary, backend) =
        runtime::run(&setup, backend, SimulatedClock::default(), options, None).expect("run");
    let sim = backend.plant();
    let states: Vec<_> = summary.transitions.iter().map(|t| t.2).collect();
    assert_eq!(
        states,
        [
            ControlState::Ramp,
            ControlState::Stand,
            ControlState::Walk,
            ControlState::Stop,
            ControlState::Stand
        ],
        "{:?}, trip {:?}",
        summary.transitions,
        summary.trip
    );
    assert_eq!(summary.trip, None);
    assert!(
        !sim.events()
            .iter()
            .any(|e| matches!(e, SimEvent::Fall { .. } | SimEvent::Fault { .. })),
        "{:?}",
        sim.fallen()
    );
    // Steps between Walk and Stop: forward touchdowns, one foot after the other.
    let steps: Vec<_> = sim
        .events()
        .iter()
        .filter_map(|e| match e {
            SimEvent::Touchdown(td) if td.t_s > walk_at && td.t_s < stop_at => Some(*td),
            _ => None,
        })
        .collect();
    let times: Vec<f64> = steps.iter().map(|td| td.t_s).collect();
    let lengths: Vec<f64> = steps.iter().map(|td| td.step_length_m).collect();
    eprintln!("walk from Stand: touchdowns at {times:.3?}, step lengths {lengths:.3?}");
    // The launch takes 1 s, then the steps start quick (0.47 s) and slow toward the gait's
    // (0.90 s): at least 20 steps in 22 s, every one forward and alternating (no scuffs or
    // bounces), each after the first within 10 % of the gait's step length.
    assert!(steps.len() >= 20, "{} steps", steps.len());
    for pair in steps.windows(2) {
        assert_ne!(pair[0].side, pair[1].side, "{pair:?}");
    }
    // The first step starts from the launch, mid-stride.
    let planned_m = setup.gait.step_length_m;
    for &l in &lengths[1..] {
        assert!((l - planned_m).abs() < 0.1 * planned_m, "step {l} m");
    }
    // The last step is near the gait's duration: the walk has converged to the orbit.
    let last_s = times[times.len() - 1] - times[times.len() - 2];
    assert!(
        (last_s - setup.gait.step_duration_s).abs() < 0.15 * setup.gait.step_duration_s,
        "last step {last_s} s"
    );
    // Stop → Stand at rest on both feet.
    assert!(sim.kinetic_energy_j() < 1e-4, "{}", sim.kinetic_energy_j());
    assert!(sim.in_stance(Side::Left) && sim.in_stance(Side::Right));
}
