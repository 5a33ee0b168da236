//! Pre-flight on the simulator (issue #30 item 5), the robot hung on the boom as on the lab's
//! treadmill (the legs free at the start pose behind the simulated A1 firmware and CAN codec):
//! each refusal happens on it and names the motor (joint, bus, id) or the IMU and the value: a silent motor, a dead IMU, a
//! frozen IMU, an IMU reading an implausible pitch (a joint far from the start pose:
//! `runtime/tests/calibration.rs`). A healthy robot passes. The gains ramp in after Start, and a
//! dry run sends zero torque while logging what it would have sent.

use drivers::a1::MotorId;
use drivers::imu::{Imu, ImuError, ImuSample};
use drivers::sim::bus::SimBus;
use drivers::sim::plant::InertiaDampingPlant;
use runtime::backend::{StaticImu, WithImu};
use runtime::bringup::{self, Refusal};
use runtime::control::{ControlState, Controller, OperatorCommand, TickInput, TickOutput};
use runtime::rt_loop::SimulatedClock;
use runtime::slots::{MotorSample, LEG_SLOTS};
use runtime::Setup;

/// The robot hung on the boom with its legs at the gait's first pose, the torso upright and
/// still, behind the simulated A1 firmware; its IMU is `imu`.
fn hung<I: Imu>(setup: &Setup, imu: I) -> WithImu<SimBus<InertiaDampingPlant>, I> {
    let first = setup.controller(false).expect("controller").first_pose();
    let start: [f64; LEG_SLOTS] = std::array::from_fn(|k| first[k]);
    let robot =
        runtime::sim::hung::hung_robot_sim(setup, &start, &Default::default()).expect("hung robot");
    WithImu {
        bus: robot.bus,
        imu,
    }
}

fn upright() -> StaticImu {
    StaticImu {
        pitch_rad: 0.02,
        gyro_bias_rad_s: 0.001,
    }
}

/// An IMU that never delivers a sample.
struct DeadImu;

impl Imu for DeadImu {
    fn read(&mut self, _out: &mut ImuSample) -> Result<(), ImuError> {
        Err(ImuError::Timeout)
    }
    fn read_at(&mut self, _t_s: f64) -> Option<ImuSample> {
        None
    }
}

/// An IMU whose output is stuck on one sample (its time stamps advance).
struct FrozenImu;

impl Imu for FrozenImu {
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        *out = self.read_at(out.t_s).unwrap_or_default();
        Ok(())
    }
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        Some(ImuSample {
            t_s,
            gyro_pitch_rad_s: 0.001,
            accel_x_mps2: 0.0,
            accel_z_mps2: 9.81,
        })
    }
}

fn preflight<B: runtime::Backend>(setup: &Setup, backend: &mut B) -> bringup::PreflightReport {
    let report = bringup::preflight(setup, backend, &mut SimulatedClock::default(), false)
        .expect("pre-flight");
    println!("{report}");
    report
}

#[test]
fn a_healthy_hung_robot_passes() {
    let setup = Setup::shipped().expect("setup");
    let report = preflight(&setup, &mut hung(&setup, upright()));
    assert!(report.passed(), "{report}");
    let heard = report.heard.as_ref().expect("listened");
    assert_eq!(heard.samples, setup.config.bringup.samples);
    assert_eq!(heard.imu_fresh, heard.samples);
    assert!((heard.imu_pitch_rad - 0.02).abs() < 1e-9, "{heard:?}");
    for (motor, reply, count) in &heard.motors {
        assert_eq!(*count, heard.samples, "{motor}");
        assert!(reply.is_some(), "{motor}");
    }
    assert!(report.to_string().contains("4 of 4 motors answered"));
}

#[test]
fn a_silent_motor_is_named_with_its_bus_and_id() {
    let setup = Setup::shipped().expect("setup");
    let mut robot = hung(&setup, upright());
    assert!(robot.bus.set_silent(MotorId::new(4).expect("id"), true));
    let report = preflight(&setup, &mut robot);
    assert_eq!(
        report.refusals.len(),
        1,
        "only the silent one: {:?}",
        report.refusals
    );
    assert!(
        matches!(&report.refusals[0], Refusal::MotorSilent(m) if m.joint == "right_knee_pitch")
    );
    assert!(report.heard.is_none(), "nothing enabled together");
    let text = report.to_string();
    assert!(
        text.contains("missing: right_knee_pitch (bus 1, id 4)"),
        "{text}"
    );
    let e = report.refuse().expect_err("refused").to_string();
    assert!(
        e.contains("pre-flight refused") && e.contains("right_knee_pitch (bus 1, id 4): no reply"),
        "{e}"
    );
}

#[test]
fn a_dead_imu_is_refused() {
    let setup = Setup::shipped().expect("setup");
    let report = preflight(&setup, &mut hung(&setup, DeadImu));
    match report.refusals.as_slice() {
        [Refusal::ImuDead { fresh, samples }] => {
            assert_eq!(*fresh, 0);
            assert_eq!(*samples, setup.config.bringup.samples);
        }
        other => panic!("{other:?}"),
    }
    assert!(report
        .to_string()
        .contains("IMU: 0 fresh samples in 50 periods"));
}

#[test]
fn a_frozen_imu_is_refused() {
    let setup = Setup::shipped().expect("setup");
    let report = preflight(&setup, &mut hung(&setup, FrozenImu));
    assert!(
        matches!(report.refusals.as_slice(), [Refusal::ImuFrozen { .. }]),
        "{:?}",
        report.refusals
    );
}

#[test]
fn an_imu_reading_an_implausible_pitch_is_refused() {
    let setup = Setup::shipped().expect("setup");
    // The robot hung on the boom with its legs at the start pose, the IMU mounted tilted 0.6 rad.
    let report = preflight(
        &setup,
        &mut hung(
            &setup,
            StaticImu {
                pitch_rad: 0.6,
                gyro_bias_rad_s: 0.0,
            },
        ),
    );
    match report.refusals.as_slice() {
        [Refusal::ImuPitch {
            pitch_rad,
            limit_rad,
        }] => {
            assert!((pitch_rad - 0.6).abs() < 1e-9, "{pitch_rad}");
            assert_eq!(*limit_rad, setup.config.bringup.max_start_pitch_rad);
        }
        other => panic!("{other:?}"),
    }
    assert!(report.to_string().contains("IMU: pitch 0.6000 rad"));
}

#[test]
fn the_gains_ramp_in_linearly_after_start() {
    let setup = Setup::shipped().expect("setup");
    let ramp_s = setup.config.bringup.gains_ramp_s;
    assert!(ramp_s > 0.0, "the shipped config ramps its gains");
    let mut controller: Controller = setup.controller(false).expect("controller");
    let first = controller.first_pose();
    let mut input = TickInput::default();
    for (k, m) in input.motors.iter_mut().enumerate().take(LEG_SLOTS) {
        *m = MotorSample {
            fresh: true,
            q_rad: first[k],
            temperature_c: 30.0,
            ..MotorSample::default()
        };
    }
    let mut out = TickOutput::default();
    let mut kp_at = Vec::new();
    for tick in 0..=800u32 {
        let t = f64::from(tick) * 1e-3;
        input.t_s = t;
        input.imu = Some(drivers::imu::ImuSample {
            t_s: t,
            gyro_pitch_rad_s: runtime::backend::test_dither_rad_s(t),
            accel_x_mps2: 0.0,
            accel_z_mps2: 9.81,
        });
        input.operator = (tick == 100).then_some(OperatorCommand::Start);
        controller.tick(&input, &mut out);
        if tick >= 100 && tick % 50 == 0 {
            kp_at.push((t - 0.1, out.commands[1].kp_nm_per_rad));
        }
    }
    assert_eq!(out.status.state, ControlState::Ramp);
    let kp = setup.config.gains.kp_nm_per_rad[1];
    for (since_s, got) in kp_at {
        let want = kp * (since_s / ramp_s).min(1.0);
        assert!(
            (got - want).abs() < 1e-9,
            "{since_s} s after Start: kp {got}, want {want}"
        );
    }
}

#[test]
fn a_dry_run_sends_zero_torque_and_logs_what_it_would_have_sent() {
    let setup = Setup::shipped().expect("setup");
    let log = std::env::temp_dir().join(format!("adam-dry-run-{}.mcap", std::process::id()));
    let dry =
        runtime::sim::hung::dry_run_sim(&setup, 3.0, &[], Some(log.clone())).expect("dry run");
    println!("{}", dry.preflight);
    assert!(dry.preflight.passed());
    // The controller went through Ramp to Stand and commanded the first pose with its gains...
    assert_eq!(dry.summary.final_state, ControlState::Stand);
    assert_eq!(dry.summary.trip, None);
    let last = &dry.summary.last_sample;
    let first = setup.controller(false).expect("controller").first_pose();
    for (k, (cmd, want)) in last.q_cmd_rad.iter().zip(first).take(LEG_SLOTS).enumerate() {
        assert!((cmd - want).abs() < 1e-9, "slot {k}");
    }
    // ...and the legs, 0.1 rad off that pose, stayed there: every command sent was zero torque
    // (the commands logged would have moved them the 0.1 rad; what is left is the disabled
    // firmware's damping of its encoder noise, ~1e-4 rad).
    assert!(dry.largest_motion_rad < 1e-3, "{}", dry.largest_motion_rad);
    let info = runtime::telemetry::log_read::read_info(&log).expect("log");
    let _ = std::fs::remove_file(&log);
    assert!(format!("{info:?}").contains("dry_run"), "{info:?}");
}

#[test]
fn a_run_on_the_robot_refuses_before_its_loop_under_the_wall_clock() {
    // The hardware path (any backend, the wall clock): a silent motor stops it before the
    // loop starts, so no gain ever came on.
    let setup = Setup::shipped().expect("setup");
    let mut robot = hung(&setup, upright());
    assert!(robot.bus.set_silent(MotorId::new(1).expect("id"), true));
    let run = bringup::RobotRun {
        duration_s: 1.0,
        dry_run: false,
        with_held: false,
        log_path: None,
    };
    let e = bringup::run_on_robot(&setup, robot, &run, None)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("pre-flight refused") && e.contains("left_hip_pitch (bus 0, id 1): no reply"),
        "{e}"
    );
}
