//! The `adam` binary end to end: good input prints the model, bad input a clear error.

use std::process::Command;

fn adam(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_adam"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("adam runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn model_prints_mass_lengths_and_mass_matrix() {
    let (ok, out, err) = adam(&[
        "model",
        "configs/robots/adam_planar.urdf",
        "--design",
        "thigh=0.3,shin=0.2",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("total mass 16.09"), "{out}");
    assert!(
        out.contains("left  leg: thigh 0.3000 m, shin 0.2000 m"),
        "{out}"
    );
    assert!(
        out.contains("D(q)") && out.contains("eigenvalues of D: min"),
        "{out}"
    );
}

#[test]
fn bad_input_is_named_in_the_error() {
    let (ok, _, err) = adam(&["model", "configs/robots/missing.urdf"]);
    assert!(!ok && err.contains("configs/robots/missing.urdf"), "{err}");
    let (ok, _, err) = adam(&[
        "model",
        "configs/robots/adam_planar.urdf",
        "--design",
        "thigh=0.5,shin=0.2",
    ]);
    assert!(
        !ok && err.contains("left_thigh_design") && err.contains("0.2600"),
        "{err}"
    );
    let (ok, _, err) = adam(&[
        "model",
        "configs/robots/adam_planar.urdf",
        "--design",
        "thigh=0.3",
    ]);
    assert!(!ok && err.contains("needs both thigh and shin"), "{err}");
}

#[test]
fn demo_runs_and_says_what_is_not_built() {
    let (ok, out, err) = adam(&["demo"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("total mass") && out.contains("Not built yet"),
        "{out}"
    );
}
