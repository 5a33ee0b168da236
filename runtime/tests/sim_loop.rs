//! The loop driver on `SimBus` + `InertiaDampingPlant` (four independent leg joints, no robot
//! dynamics) with a simulated clock: Idle → Ramp → Stand reaches the gait's first pose, the
//! MCAP log holds every tick, and the bus ends deactivated (damping).

use drivers::a1::MotorId;
use drivers::bus::{Lifecycle, MotorBus};
use drivers::sim::{
    bus::SimBus,
    plant::{InertiaDampingPlant, JointPlant},
};
use runtime::backend::{StaticImu, WithImu};
use runtime::control::{ControlState, OperatorCommand};
use runtime::rt_loop::{self, LoopOptions, SimulatedClock};
use runtime::Setup;

fn backend(setup: &Setup, start_rad: [f64; 4]) -> WithImu<SimBus<InertiaDampingPlant>, StaticImu> {
    let imu = StaticImu {
        pitch_rad: 0.0,
        gyro_bias_rad_s: 0.002,
    };
    runtime::sim::run::joint_bench_backend(setup, &start_rad, imu).expect("joint bench")
}

#[test]
fn idle_ramp_stand_reaches_the_first_pose_on_simbus_with_a_simulated_clock() {
    let setup = Setup::shipped().expect("shipped setup");
    let first = setup.controller(false).expect("controller").first_pose();
    let start = [0.3, 0.5, -0.2, 0.1];
    let log_path = std::env::temp_dir().join(format!("adam-sim-loop-{}.mcap", std::process::id()));
    let mut options = LoopOptions::simulation(3.0);
    options.script = vec![(0.05, OperatorCommand::Start)];
    options.log_path = Some(log_path.clone());
    let wall = std::time::Instant::now();
    let (summary, backend) = rt_loop::run(
        &setup,
        backend(&setup, start),
        SimulatedClock::default(),
        options,
        None,
    )
    .expect("run");
    let wall_s = wall.elapsed().as_secs_f64();
    eprintln!(
        "3.0 s simulated in {wall_s:.3} s wall; tick compute median {} ns, p99 {} ns, max {} ns",
        summary.tick_times.median_ns, summary.tick_times.p99_ns, summary.tick_times.max_ns
    );
    assert_eq!(summary.ticks, 3000);
    assert_eq!(summary.trip, None, "{summary:?}");
    assert_eq!(summary.final_state, ControlState::Stand);
    let states: Vec<_> = summary
        .transitions
        .iter()
        .map(|&(_, a, b)| (a, b))
        .collect();
    assert_eq!(
        states,
        [
            (ControlState::Idle, ControlState::Ramp),
            (ControlState::Ramp, ControlState::Stand)
        ]
    );
    // Ramp starts at the first tick at or after 0.05 s and lasts max(2 s, 1.875·0.5/0.5 s).
    let (t_ramp, t_stand) = (summary.transitions[0].0, summary.transitions[1].0);
    assert!((t_ramp - 0.05).abs() < 1.5e-3, "{t_ramp}");
    assert!(
        (t_stand - t_ramp - 2.0).abs() < 1.5e-3,
        "{}",
        t_stand - t_ramp
    );
    assert_eq!(summary.overruns, 0, "a simulated clock is never late");
    assert_eq!(summary.missing_replies, 0);
    // After 0.95 s of Stand the PD (ωn ≈ 49 rad/s, ζ ≈ 0.6, no load) has settled: the true
    // joint angles sit on the first pose within the encoder/quantization noise (≪ 1 mrad).
    let plant = backend.bus.plant();
    for (j, target) in first.iter().take(4).enumerate() {
        let q = plant.position_rad(j);
        assert!((q - target).abs() < 1e-3, "joint {j}: {q} vs {target}");
        assert!(plant.velocity_rad_s(j).abs() < 1e-2);
    }
    assert_eq!(
        backend.bus.state(),
        Lifecycle::Configured,
        "deactivated at the end"
    );
    // The log holds every tick on the per-tick channels, and both transitions.
    let log = summary.log.expect("log stats");
    assert_eq!(log.dropped, 0);
    let bytes = std::fs::read(&log_path).expect("log file");
    let mut joints = 0;
    let mut transitions = 0;
    for m in mcap::MessageStream::new(&bytes).expect("mcap") {
        match m.expect("message").channel.topic.as_str() {
            "/joints" => joints += 1,
            "/transitions" => transitions += 1,
            _ => {}
        }
    }
    assert_eq!((joints, transitions), (3000, 2));
    std::fs::remove_file(&log_path).expect("remove log");
}

#[test]
fn a_silent_motor_stops_the_run_before_the_first_tick() {
    let setup = Setup::shipped().expect("shipped setup");
    let mut b = backend(&setup, [0.0; 4]);
    let cut = MotorId::new(3).expect("id");
    assert!(b.bus.set_silent(cut, true));
    let options = LoopOptions::simulation(0.2);
    match rt_loop::run(&setup, b, SimulatedClock::default(), options, None) {
        Err(runtime::RuntimeError::Bus(drivers::bus::BusError::MissingReply { motor, .. })) => {
            assert_eq!(motor, cut)
        }
        Err(e) => panic!("unexpected error {e}"),
        Ok((s, _)) => panic!("ran {} ticks with a silent motor", s.ticks),
    }
}
