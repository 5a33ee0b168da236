//! The gait file: round trip and validation errors that name field and value.

use model::design::DesignLengths;
use model::gait::*;
use model::{ModelError, Side};

fn sample() -> GaitFile {
    GaitFile {
        schema_version: GAIT_SCHEMA_VERSION,
        robot: RobotReference {
            name: "adam_planar".into(),
            urdf: "../robots/adam_planar.urdf".into(),
            sha256: sha256_hex("<robot/>"),
        },
        design: DesignLengths::ADAM,
        outputs: OutputDefinition::adam(),
        bezier: BezierSpec {
            degree: 5,
            alpha: vec![vec![0.1, 0.2, 0.3, 0.2, 0.1, 0.0]; 4],
        },
        phase: PhaseDefinition::StateBased {
            theta_plus_rad: -0.2,
            theta_minus_rad: 0.2,
        },
        stance_leg: Side::Right,
        step_duration_s: 0.8,
        step_length_m: 0.23,
        speed_mps: 0.2875,
        cost_of_transport: 0.2,
        initial_state: Some(RobotState {
            q: vec![0.0; 11],
            dq: vec![0.0; 11],
        }),
        feedforward: Some(FeedforwardTable {
            phase: vec![0.0, 0.5, 1.0],
            torque_nm: vec![vec![1.0, -2.0, 0.5, 0.0]; 3],
        }),
        solver: SolverSummary {
            solver: "test".into(),
            status: "optimal".into(),
            iterations: 1,
            solve_time_s: 0.1,
            objective: 0.2,
            constraint_violation: 1e-9,
        },
    }
}

fn reject(gait: &GaitFile) -> String {
    let text = serde_json::to_string(gait).expect("serializes");
    GaitFile::from_json(&text, "g.json")
        .expect_err("must be rejected")
        .to_string()
}

#[test]
fn round_trips_through_a_file() {
    let dir = std::env::temp_dir().join(format!("adam-gait-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("g.json");
    let g = sample();
    g.save(&path).expect("saves");
    assert_eq!(GaitFile::load(&path).expect("loads"), g);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn validation_names_field_and_value() {
    let mut g = sample();
    g.bezier.alpha[2][3] = f64::NAN;
    // JSON has no NaN: serde_json writes null, which is a parse error naming the position.
    let text = serde_json::to_string(&g).expect("serializes");
    assert!(GaitFile::from_json(&text, "g.json").is_err());
    assert!(g
        .validate("g.json")
        .expect_err("nan")
        .to_string()
        .contains("bezier.alpha[2][3]"));

    let mut g = sample();
    g.bezier.alpha[1].pop();
    let e = reject(&g);
    assert!(
        e.contains("g.json") && e.contains("bezier.alpha[1]") && e.contains("5 coefficients"),
        "{e}"
    );

    let mut g = sample();
    g.bezier.alpha.pop();
    assert!(reject(&g).contains("bezier.alpha"));

    let mut g = sample();
    g.phase = PhaseDefinition::StateBased {
        theta_plus_rad: 0.2,
        theta_minus_rad: 0.2,
    };
    let e = reject(&g);
    assert!(
        e.contains("phase.theta_minus_rad") && e.contains("0.2"),
        "{e}"
    );

    let mut g = sample();
    g.step_duration_s = -1.0;
    assert!(reject(&g).contains("step_duration_s"));

    let mut g = sample();
    g.robot.sha256 = "xyz".into();
    assert!(reject(&g).contains("robot.sha256"));
}

#[test]
fn unknown_versions_and_unknown_fields_are_refused() {
    let mut v: serde_json::Value = serde_json::to_value(sample()).expect("value");
    v["schema_version"] = serde_json::json!(2);
    let e = GaitFile::from_json(&v.to_string(), "g.json").expect_err("version");
    assert!(
        matches!(&e, ModelError::InvalidField { field, value, .. } if field == "schema_version" && value == "2"),
        "{e}"
    );
    let mut v: serde_json::Value = serde_json::to_value(sample()).expect("value");
    v["surprise"] = serde_json::json!(1);
    let e = GaitFile::from_json(&v.to_string(), "g.json").expect_err("unknown field");
    assert!(e.to_string().contains("surprise"), "{e}");
}

#[test]
fn output_joint_names_follow_the_stance_leg() {
    let outs = OutputDefinition::adam();
    assert_eq!(outs[0].joint_name(Side::Right), "right_hip_pitch");
    assert_eq!(outs[3].joint_name(Side::Right), "left_knee_pitch");
    assert_eq!(outs[3].joint_name(Side::Left), "right_knee_pitch");
}

#[test]
fn feedforward_tables_are_checked_and_interpolate_linearly() {
    let mut g = sample();
    g.feedforward = Some(FeedforwardTable {
        phase: vec![0.0, 0.5, 0.4],
        torque_nm: vec![vec![0.0; 4]; 3],
    });
    let e = reject(&g);
    assert!(
        e.contains("feedforward.phase[2]") && e.contains("0.4"),
        "{e}"
    );
    g.feedforward = Some(FeedforwardTable {
        phase: vec![0.0, 1.0],
        torque_nm: vec![vec![0.0; 4], vec![0.0; 3]],
    });
    let e = reject(&g);
    assert!(
        e.contains("feedforward.torque_nm[1]") && e.contains("3 entries"),
        "{e}"
    );
    g.feedforward = Some(FeedforwardTable {
        phase: vec![0.0, 1.0],
        torque_nm: vec![vec![0.0; 4], vec![f64::NAN, 0.0, 0.0, 0.0]],
    });
    // JSON has no NaN: check the in-memory validation (what `save` runs).
    let e = g.validate("g.json").expect_err("NaN torque").to_string();
    assert!(e.contains("feedforward.torque_nm[1][0]"), "{e}");
    // A gait without the table (older planner) still loads.
    g.feedforward = None;
    let text = serde_json::to_string(&g).expect("serializes");
    assert!(!text.contains("feedforward"));
    assert_eq!(GaitFile::from_json(&text, "g.json").expect("loads"), g);

    let table = FeedforwardTable {
        phase: vec![0.0, 0.5, 1.0],
        torque_nm: vec![vec![0.0, 10.0], vec![1.0, 20.0], vec![3.0, 0.0]],
    };
    let mut out = [0.0; 2];
    for (tau, want) in [
        (-0.2, [0.0, 10.0]),
        (0.25, [0.5, 15.0]),
        (0.5, [1.0, 20.0]),
        (0.75, [2.0, 10.0]),
        (1.3, [3.0, 0.0]),
    ] {
        table.eval(tau, &mut out);
        assert!(
            (out[0] - want[0]).abs() < 1e-12 && (out[1] - want[1]).abs() < 1e-12,
            "tau {tau}: {out:?} vs {want:?}"
        );
    }
}

/// Issue #27: a bare `NaN` (not JSON) and the string `"NaN"` in a numeric field are reported with
/// the line and the field, not only a position.
#[test]
fn a_nan_in_the_json_names_the_line_and_the_field() {
    let text = serde_json::to_string_pretty(&sample()).expect("serializes");
    let bare = text.replacen("\"step_length_m\": 0.23", "\"step_length_m\": NaN", 1);
    let e = GaitFile::from_json(&bare, "g.json").expect_err("bare NaN");
    let line = 1 + bare[..bare.find("NaN").expect("NaN")].matches('\n').count();
    assert!(
        matches!(&e, ModelError::Json { field, line: l, .. } if field == "step_length_m" && *l == line),
        "{e}"
    );
    assert!(e.to_string().contains("JSON has no NaN"), "{e}");

    let mut v: serde_json::Value = serde_json::to_value(sample()).expect("value");
    v["bezier"]["alpha"][2][4] = serde_json::json!("NaN");
    let quoted = serde_json::to_string_pretty(&v).expect("text");
    let e = GaitFile::from_json(&quoted, "g.json").expect_err("string NaN");
    let m = e.to_string();
    assert!(
        m.contains("g.json") && m.contains("field 'bezier.alpha[2][4]'") && m.contains("\"NaN\""),
        "{m}"
    );
}

fn robot() -> model::PlanarModel {
    model::PlanarModel::from_urdf_file(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/robots/adam_planar.urdf"
    ))
    .expect("shipped URDF")
}

/// Issue #27: a `q` of 5 entries was reported against `dq`; now `q` is named with its length and
/// the robot's coordinate count.
#[test]
fn state_lengths_are_checked_against_the_robot_and_name_the_vector() {
    let robot = robot();
    let mut g = sample();
    g.check_against(&robot, "g.json", "r.urdf")
        .expect("the sample fits the shipped robot");
    g.initial_state.as_mut().expect("state").q.truncate(5);
    let e = g
        .check_against(&robot, "g.json", "r.urdf")
        .expect_err("short q")
        .to_string();
    assert!(
        e.contains("initial_state.q") && e.contains("5 entries") && e.contains("expected 11"),
        "{e}"
    );
    // Without the robot, the mismatch still names q first and both lengths.
    let e = g
        .validate("g.json")
        .expect_err("q and dq differ")
        .to_string();
    assert!(
        e.contains("initial_state.q") && e.contains("dq has 11"),
        "{e}"
    );
}

/// Issue #27: a Bézier coefficient of 1e300 was found only in simulation; it is refused up front
/// against the joint limits, naming the output, the coefficient, the value and the limits.
#[test]
fn bezier_coefficients_are_checked_against_the_joint_limits() {
    let robot = robot();
    let mut g = sample();
    g.bezier.alpha[1][3] = 1e300;
    let e = g
        .check_against(&robot, "g.json", "r.urdf")
        .expect_err("1e300")
        .to_string();
    assert!(
        e.contains("bezier.alpha[1][3]")
            && e.contains("1e300")
            && e.contains("stance_knee")
            && e.contains("[0, 2.4] rad"),
        "{e}"
    );
    // One limit range of margin: the knee (limits [0, 2.4]) may plan down to −2.4, not below.
    g.bezier.alpha[1][3] = -2.39;
    g.check_against(&robot, "g.json", "r.urdf")
        .expect("inside the margin");
    g.bezier.alpha[1][3] = -2.41;
    assert!(g.check_against(&robot, "g.json", "r.urdf").is_err());
}

/// Issue #27: a missing URDF named by a relative path says which gait file named it.
#[test]
fn a_missing_urdf_names_the_gait_file_that_named_it() {
    let g = sample();
    let e = g
        .read_urdf(std::path::Path::new("/nonexistent/gaits/g.json"))
        .expect_err("missing")
        .to_string();
    assert!(
        e.contains("/nonexistent/gaits/g.json")
            && e.contains("robot.urdf")
            && e.contains("../robots/adam_planar.urdf"),
        "{e}"
    );
}
