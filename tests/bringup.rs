//! Bring-up from the command line (issue #30 items 4 and 5), on the simulated robot: `adam
//! calibrate` recovers wrong offsets and a flipped motor into a new config (never in place),
//! `adam can scan` names a silent motor, the pre-flight of a run from Stand passes on a healthy
//! robot and refuses a config whose calibration does not fit it, and `--dry-run` runs the loop
//! at zero torque. `--backend can` stops at once naming the missing interface.

use std::path::PathBuf;
use std::process::Command;

fn adam(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_adam"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run adam");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("adam-bringup-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn calibrate_writes_a_new_config_with_the_offsets_and_the_flip_and_never_in_place() {
    let dir = temp_dir("calibrate");
    let out = dir.join("calibrated.toml");
    let out_s = out.to_str().expect("path");
    let args = [
        "calibrate",
        "--backend",
        "sim",
        "--sim-offsets",
        "0.5,-0.45,0.4,-0.6",
        "--sim-flip",
        "left_knee_pitch",
        "--out",
        out_s,
    ];
    let (ok, stdout, stderr) = adam(&args);
    println!("{stdout}{stderr}");
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("FLIPPED (direction changed in the new config): left_knee_pitch"),
        "{stdout}"
    );
    let config = runtime::config::RuntimeConfig::load(&out).expect("the new config loads");
    let truth = [(0.5, 1), (-0.45, -1), (0.4, 1), (-0.6, 1)];
    for ((name, c), (offset, direction)) in config.calibration.joints().into_iter().zip(truth) {
        let error_deg = (c.zero_offset_rad - offset).to_degrees();
        assert!(error_deg.abs() < 0.5, "{name}: {error_deg}°");
        assert_eq!(c.direction, direction, "{name}");
    }
    // The rest of the input is kept as written.
    let text = std::fs::read_to_string(&out).expect("read");
    assert!(text.contains("[speed]") && text.contains("# Held still during planar walking"));
    // Again without --force: refused; over the input config: refused even with --force.
    let (ok, _, stderr) = adam(&args);
    assert!(!ok && stderr.contains(out_s), "{stderr}");
    let (ok, _, stderr) = adam(&[
        "calibrate",
        "--backend",
        "sim",
        "--config",
        out_s,
        "--out",
        out_s,
        "--force",
    ]);
    assert!(!ok && stderr.contains("never writes in place"), "{stderr}");
    // A config that extends another: refused, naming both (its copy could not find its base).
    let lab = dir.join("lab.toml");
    std::fs::write(
        &lab,
        format!(
            "extends = {:?}\n",
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("configs/runtime/adam_treadmill.toml")
        ),
    )
    .expect("written");
    let (ok, _, stderr) = adam(&[
        "calibrate",
        "--backend",
        "sim",
        "--config",
        lab.to_str().expect("path"),
        "--out",
        dir.join("options.toml").to_str().expect("path"),
    ]);
    assert!(
        !ok && stderr.contains("lab.toml extends") && stderr.contains("adam_treadmill.toml"),
        "{stderr}"
    );
    assert!(!dir.join("options.toml").exists());

    // That calibration does not fit the simulated robot of `adam run` (its motors sit as the
    // model's joints): the pre-flight refuses before any gain, naming the joints.
    let (ok, stdout, stderr) = adam(&[
        "run",
        "--backend",
        "sim",
        "--start",
        "stand",
        "--duration",
        "2s",
        "--config",
        out_s,
    ]);
    println!("{stdout}{stderr}");
    assert!(!ok, "{stdout}");
    assert!(
        stderr.contains("pre-flight refused")
            && stderr.contains("motor left_knee_pitch (bus 0, id 2): joint at"),
        "{stderr}"
    );
    // On the robot it was measured on, it passes and Start ramps the robot to Stand.
    let (ok, stdout, stderr) = adam(&[
        "run",
        "--backend",
        "sim",
        "--start",
        "stand",
        "--duration",
        "3s",
        "--config",
        out_s,
        "--sim-offsets",
        "0.5,-0.45,0.4,-0.6",
        "--sim-flip",
        "left_knee_pitch",
    ]);
    println!("{stdout}{stderr}");
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("pre-flight: passed") && stdout.contains("final state stand"),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn can_scan_lists_every_motor_and_names_the_silent_one() {
    let (ok, stdout, stderr) = adam(&["can", "scan", "--backend", "sim"]);
    println!("{stdout}{stderr}");
    assert!(ok, "{stderr}");
    assert!(stdout.contains("4 of 4 motors answered"), "{stdout}");
    for joint in [
        "left_hip_pitch",
        "left_knee_pitch",
        "right_hip_pitch",
        "right_knee_pitch",
    ] {
        assert!(stdout.contains(joint), "{stdout}");
    }
    let (ok, stdout, stderr) = adam(&["can", "scan", "--backend", "sim", "--sim-silent", "4"]);
    println!("{stdout}{stderr}");
    assert!(!ok);
    assert!(stdout.contains("SILENT"), "{stdout}");
    assert!(
        stderr.contains("1 of 4 motors did not answer")
            && stderr.contains("right_knee_pitch (bus 1, id 4)"),
        "{stderr}"
    );
    // No SocketCAN here: it stops at once, naming the interface.
    let (ok, _, stderr) = adam(&["can", "scan", "--backend", "can"]);
    assert!(!ok && stderr.contains("can0"), "{stderr}");
}

#[test]
fn a_run_from_stand_passes_its_preflight_and_a_dry_run_sends_zero_torque() {
    let (ok, stdout, stderr) = adam(&[
        "run",
        "--backend",
        "sim",
        "--start",
        "stand",
        "--duration",
        "3s",
    ]);
    println!("{stdout}{stderr}");
    assert!(ok, "{stderr}");
    assert!(stdout.contains("pre-flight: passed"), "{stdout}");
    let dir = temp_dir("dry-run");
    let log = dir.join("dry.mcap");
    let (ok, stdout, stderr) = adam(&[
        "run",
        "--backend",
        "sim",
        "--dry-run",
        "--duration",
        "3s",
        "--log",
        log.to_str().expect("path"),
    ]);
    println!("{stdout}{stderr}");
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("pre-flight: passed")
            && stdout.contains("dry run: every command sent was zero torque"),
        "{stdout}"
    );
    assert!(log.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
