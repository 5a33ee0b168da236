//! Calibration on the simulator (issue #30 item 4): a robot whose leg motors sit on their joints
//! with wrong zero offsets and one of them the other way round. `adam calibrate`'s procedure
//! (legs clamped in the config's jig poses A then B, the robot hung on the boom) recovers every
//! offset within 0.5° and names the flipped motor; the pre-flight refuses the robot under the
//! old (identity) calibration, joint by joint, and passes it under the measured one, which then
//! ramps the robot to Stand. A calibration that would move a joint past its URDF limit is refused.

use drivers::sim::firmware::EncoderMount;
use runtime::bringup::{self, JigPose, Refusal};
use runtime::control::ControlState;
use runtime::sim::run::{SimStart, SimWalkOptions};
use runtime::{RuntimeError, Setup};

/// The simulated robot's truth: the joint angle at which each motor reads zero, and its
/// direction (leg slot order: left hip, left knee, right hip, right knee). The left knee is
/// mounted the other way round.
const TRUE_OFFSETS_RAD: [f64; 4] = [0.5, -0.45, 0.4, -0.6];
const TRUE_DIRECTIONS: [i8; 4] = [1, -1, 1, 1];

fn mounts() -> [EncoderMount; 4] {
    std::array::from_fn(|k| EncoderMount {
        direction: f64::from(TRUE_DIRECTIONS[k]),
        joint_rad_at_zero: TRUE_OFFSETS_RAD[k],
    })
}

fn calibrate(setup: &Setup) -> bringup::CalibrationOutcome {
    let jig_a = bringup::jig_angles(setup, JigPose::A);
    let mut robot =
        runtime::sim::hung::hung_robot_sim(setup, &jig_a, &mounts()).expect("hung robot");
    bringup::calibrate(setup, &mut robot, |pose, r| {
        // The operator moves the jig while the motors are off: the joints now sit at the pose's
        // angles, at rest (the simulated robot is made anew there, its motors mounted as before:
        // teleporting the joints under running firmware would read as a huge speed).
        *r = runtime::sim::hung::hung_robot_sim(
            setup,
            &bringup::jig_angles(setup, pose),
            &mounts(),
        )?;
        Ok(())
    })
    .expect("calibration")
}

#[test]
fn wrong_offsets_and_a_flipped_knee_are_recovered_within_half_a_degree() {
    let setup = Setup::shipped().expect("setup");
    let outcome = calibrate(&setup);
    println!("{outcome}");
    for (k, j) in outcome.joints.iter().enumerate() {
        let error_deg = (j.zero_offset_rad - TRUE_OFFSETS_RAD[k]).to_degrees();
        println!(
            "{}: offset {:.5} rad (true {}), error {error_deg:.4}°, gear ratio {:.4}, play {:.4}°",
            j.motor.joint,
            j.zero_offset_rad,
            TRUE_OFFSETS_RAD[k],
            j.gear_ratio_measured,
            j.play_rad.to_degrees()
        );
        assert!(error_deg.abs() < 0.5, "{}: {error_deg}°", j.motor.joint);
        assert_eq!(j.direction, TRUE_DIRECTIONS[k], "{}", j.motor.joint);
        assert!((j.gear_ratio_measured - 1.0).abs() < 0.01, "{j:?}");
    }
    assert_eq!(outcome.flipped(), ["left_knee_pitch"]);
    let table = outcome.to_string();
    assert!(
        table.contains("FLIPPED") && table.contains("left_knee_pitch"),
        "{table}"
    );
}

#[test]
fn the_preflight_refuses_the_miscalibrated_robot_and_passes_the_calibrated_one() {
    let shipped = Setup::shipped().expect("setup");
    let mut options = SimWalkOptions::new(3.0);
    options.start = SimStart::Stand;
    options.belt_speed_mps = Some(0.0);
    options.preflight = true;
    options.encoder_mounts = mounts();
    // Under the identity calibration every leg joint reads far from the start pose.
    let e = runtime::sim::run::walk(&shipped, &options).expect_err("refused");
    let text = e.to_string();
    println!("{text}");
    assert!(matches!(e, RuntimeError::Preflight { .. }), "{e:?}");
    for motor in [
        "left_hip_pitch (bus 0, id 1)",
        "left_knee_pitch (bus 0, id 2)",
        "right_hip_pitch (bus 1, id 3)",
        "right_knee_pitch (bus 1, id 4)",
    ] {
        assert!(
            text.contains(&format!("motor {motor}: joint at")),
            "{motor}: {text}"
        );
    }
    // Under the measured calibration: the pre-flight passes and Start ramps the robot to Stand.
    let mut calibrated = shipped.clone();
    calibrated.config.calibration = calibrate(&shipped).calibration;
    let report = runtime::sim::run::walk(&calibrated, &options).expect("walk");
    let preflight = report.preflight.as_ref().expect("pre-flight report");
    println!("{preflight}");
    assert!(preflight.passed(), "{preflight}");
    assert_eq!(report.summary.trip, None, "{report}");
    assert_eq!(report.summary.final_state, ControlState::Stand, "{report}");
    assert!(report.fall.is_none(), "{report}");
}

#[test]
fn the_preflight_names_the_one_joint_whose_calibration_is_off() {
    let mut setup = Setup::shipped().expect("setup");
    setup.config.calibration.right_hip_pitch.zero_offset_rad = 0.6;
    let mut options = SimWalkOptions::new(1.0);
    options.start = SimStart::Stand;
    options.belt_speed_mps = Some(0.0);
    let bus = runtime::sim::run::sim_backend(&setup, &options).expect("backend");
    let pitch_rad = bus.plant().torso_pitch_rad();
    let report = runtime::sim::hung::preflight_hung(&setup, &bus, pitch_rad, &Default::default())
        .expect("pre-flight");
    println!("{report}");
    match report.refusals.as_slice() {
        [Refusal::JointOffStart {
            motor,
            q_rad,
            start_rad,
            tolerance_rad,
        }] => {
            assert_eq!(motor.joint, "right_hip_pitch");
            assert!(
                ((q_rad - start_rad).abs() - 0.6).abs() < 0.01,
                "{q_rad} {start_rad}"
            );
            assert_eq!(
                *tolerance_rad,
                setup.config.bringup.start_pose_tolerance_rad
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_calibration_that_would_move_a_joint_past_its_urdf_limit_is_refused() {
    let shipped = Setup::shipped().expect("setup");
    let gait = shipped.gait.clone();
    let urdf = shipped.urdf_text.clone();
    // A jig pose past the knee's URDF limit [0, 2.4] rad.
    let mut config = shipped.config.clone();
    config.calibration.left_knee_pitch.jig_rad = [0.2, 2.6];
    let e = Setup::from_parts(config, gait.clone(), urdf.clone(), "adam.urdf")
        .expect_err("refused")
        .to_string();
    assert!(
        e.contains("calibration.left_knee_pitch.jig_rad")
            && e.contains("[0.2, 2.6]")
            && e.contains("URDF limits"),
        "{e}"
    );
    // A gear ratio and offset under which the hip's range [-1.6, 1.6] rad needs motor angles
    // past the A1's ±12.5 rad: a command inside the limits would be clamped elsewhere.
    let mut config = shipped.config.clone();
    config.calibration.right_hip_pitch.gear_ratio = 5.0;
    config.calibration.right_hip_pitch.zero_offset_rad = 1.5;
    let e = Setup::from_parts(config, gait, urdf, "adam.urdf")
        .expect_err("refused")
        .to_string();
    assert!(
        e.contains("calibration.right_hip_pitch.zero_offset_rad")
            && e.contains("1.5")
            && e.contains("12.5"),
        "{e}"
    );
}
