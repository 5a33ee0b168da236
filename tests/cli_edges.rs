//! The edges a user meets (issue #27): `adam` from any folder, outputs that never overwrite
//! what ships, flags checked where they are written and against the configured ranges, words
//! instead of Rust's debug output, and nothing from third parties on stderr.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `adam` in `dir`; (success, stdout, stderr).
fn adam_in(dir: &Path, args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_adam"))
        .args(args)
        .current_dir(dir)
        .env_remove("ADAM_CONFIG_DIR")
        .env_remove("IOX2_LOG_LEVEL")
        .output()
        .expect("adam runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A fresh empty folder outside the repository.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("adam-edges-{tag}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// What Rust's `Debug` output looks like and a user should never see.
fn debug_forms(text: &str) -> Vec<String> {
    let mut found: Vec<String> = ["Some(", "None)", "Ok(", "Err(", "Knee(", "Hip(", "\\\""]
        .iter()
        .filter(|p| text.contains(*p))
        .map(|p| p.to_string())
        .collect();
    // A struct literal: `Name { field: ` (a capitalised word, a brace, a snake_case field).
    for (i, _) in text.match_indices(" { ") {
        let before = text[..i].rsplit(|c: char| !c.is_alphanumeric()).next();
        let after: String = text[i + 3..]
            .chars()
            .take_while(|c| c.is_ascii_lowercase() || *c == '_')
            .collect();
        let starts_upper = before.is_some_and(|w| w.starts_with(|c: char| c.is_ascii_uppercase()));
        if starts_upper && !after.is_empty() && text[i + 3 + after.len()..].starts_with(':') {
            found.push(text[i.saturating_sub(20)..(i + 30).min(text.len())].to_string());
        }
    }
    found
}

#[test]
fn the_readme_commands_run_from_any_folder() {
    let dir = scratch("anywhere");
    let (ok, out, err) = adam_in(&dir, &["model", "configs/robots/adam_planar.urdf"]);
    assert!(ok && out.contains("total mass"), "{out}\n{err}");
    let (ok, out, err) = adam_in(&dir, &["run", "--backend", "sim", "--duration", "2s"]);
    assert!(ok && out.contains("steps "), "{out}\n{err}");
    let (ok, out, err) = adam_in(&dir, &["gait", "check", "configs/gaits/adam_walk.json"]);
    assert!(ok && out.contains("stable periodic orbit"), "{out}\n{err}");
    let (ok, out, err) = adam_in(&dir, &["plan", "--help"]);
    assert!(
        ok && out.contains("out/gaits/adam_walk.json"),
        "{out}\n{err}"
    );
    let (ok, out, err) = adam_in(&dir, &["--help"]);
    assert!(ok && out.contains("ADAM_CONFIG_DIR"), "{out}\n{err}");
    // A config root named by the environment is the only place searched.
    let out = Command::new(env!("CARGO_BIN_EXE_adam"))
        .args(["model", "configs/robots/adam_planar.urdf"])
        .current_dir(&dir)
        .env("ADAM_CONFIG_DIR", dir.join("nowhere"))
        .output()
        .expect("adam runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("configs/robots/adam_planar.urdf"),
        "{err}"
    );
    // Nothing was written into the scratch folder so far.
    let written: Vec<_> = std::fs::read_dir(&dir).expect("dir").collect();
    assert!(written.is_empty(), "{written:?}");
    // The demo: its log goes to logs/ of the working directory.
    let (ok, out, err) = adam_in(&dir, &["demo"]);
    assert!(ok || err.contains("the robot fell"), "{out}\n{err}");
    assert!(out.contains("log: logs/"), "{out}");
    let written: Vec<String> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(written, ["logs"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn outputs_never_overwrite_an_existing_file_without_force() {
    let dir = scratch("force");
    let (ok, _, err) = adam_in(&dir, &["generate-urdf", "--out", "robot.urdf"]);
    assert!(ok, "{err}");
    let first = std::fs::read_to_string(dir.join("robot.urdf")).expect("written");
    let (ok, _, err) = adam_in(
        &dir,
        &["generate-urdf", "--thigh", "0.3", "--out", "robot.urdf"],
    );
    assert!(
        !ok && err.contains("robot.urdf") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("robot.urdf")).expect("kept"),
        first
    );
    let (ok, _, err) = adam_in(
        &dir,
        &[
            "generate-urdf",
            "--thigh",
            "0.3",
            "--out",
            "robot.urdf",
            "--force",
        ],
    );
    assert!(ok, "{err}");
    assert_ne!(
        std::fs::read_to_string(dir.join("robot.urdf")).expect("rewritten"),
        first
    );

    // A run log.
    let run = [
        "run",
        "--backend",
        "sim",
        "--duration",
        "0.2s",
        "--log",
        "run.mcap",
    ];
    let (ok, _, err) = adam_in(&dir, &run);
    assert!(ok, "{err}");
    let (ok, _, err) = adam_in(&dir, &run);
    assert!(
        !ok && err.contains("run.mcap") && err.contains("--force"),
        "{err}"
    );
    let (ok, _, err) = adam_in(&dir, &[&run[..], &["--force"]].concat());
    assert!(ok, "{err}");

    // Gaits, URDFs and sweeps: refused before any solve.
    std::fs::create_dir_all(dir.join("out/gaits")).expect("dir");
    std::fs::write(dir.join("out/gaits/adam_walk.json"), "mine").expect("write");
    let (ok, _, err) = adam_in(&dir, &["plan"]);
    assert!(
        !ok && err.contains("out/gaits/adam_walk.json") && err.contains("--force"),
        "{err}"
    );
    let (ok, _, err) = adam_in(
        &dir,
        &["codesign", "--out-gait", "out/gaits/adam_walk.json"],
    );
    assert!(
        !ok && err.contains("out/gaits/adam_walk.json") && err.contains("--force"),
        "{err}"
    );
    std::fs::create_dir_all(dir.join("sweep")).expect("dir");
    std::fs::write(dir.join("sweep/table.md"), "mine").expect("write");
    let (ok, _, err) = adam_in(&dir, &["codesign", "sweep", "--out-dir", "sweep"]);
    assert!(
        !ok && err.contains("sweep/table.md") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("out/gaits/adam_walk.json")).expect("kept"),
        "mine"
    );
    // The shipped files are where they were: a plan named at one needs --force too.
    let shipped = repo().join("configs/gaits/adam_walk.json");
    let before = std::fs::read(&shipped).expect("shipped gait");
    let (ok, _, err) = adam_in(&dir, &["plan", "--out", &shipped.display().to_string()]);
    assert!(!ok && err.contains("--force"), "{err}");
    assert_eq!(std::fs::read(&shipped).expect("shipped gait"), before);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn options_are_accepted_where_a_user_writes_them_and_checked_against_the_config() {
    let dir = scratch("options");
    // `--config` after `sweep`, as before it: the config is read (and its error names it).
    for args in [
        &["codesign", "sweep", "--config", "missing.toml"][..],
        &["codesign", "--config", "missing.toml", "sweep"][..],
    ] {
        let (ok, _, err) = adam_in(&dir, args);
        assert!(!ok && err.contains("missing.toml"), "{args:?}: {err}");
    }
    // The design box and the sweep grid live in the config, checked like every field.
    let text = std::fs::read_to_string(repo().join("configs/planner/adam.toml")).expect("config");
    std::fs::write(
        dir.join("box.toml"),
        text.replace("shin_m = [0.15, 0.35]", "shin_m = [0.35, 0.15]"),
    )
    .expect("write");
    let (ok, _, err) = adam_in(&dir, &["codesign", "sweep", "--config", "box.toml"]);
    assert!(
        !ok && err.contains("box.toml")
            && err.contains("codesign.shin_m")
            && err.contains("[0.35, 0.15]"),
        "{err}"
    );
    let (ok, _, err) = adam_in(&dir, &["codesign", "sweep", "--grid", "0"]);
    assert!(!ok && err.contains("--grid 0"), "{err}");
    let (ok, _, err) = adam_in(&dir, &["codesign", "--out-gait", "g.json", "sweep"]);
    assert!(!ok && err.contains("--out-gait"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn belt_duration_and_backend_flags_are_refused_naming_the_flag_value_and_range() {
    let dir = scratch("flags");
    for (args, words) in [
        (
            &["run", "--backend", "sim", "--belt=-0.2", "--duration", "1s"][..],
            &["--belt", "-0.2 m/s", "[0, 0.5] m/s", "belt_speed_range_mps"][..],
        ),
        (
            &["run", "--backend", "sim", "--belt", "5", "--duration", "1s"],
            &["--belt", "5 m/s", "[0, 0.5] m/s"],
        ),
        (
            &["run", "--backend", "sim", "--duration", "1e30"],
            &["--duration", "1e30", "24 h"],
        ),
        (
            &["run", "--backend", "can", "--belt", "0.2", "--seed", "3"],
            &["--belt", "--seed", "--backend can"],
        ),
        (
            &["run", "--backend", "sim", "--can-interfaces", "can0"],
            &["--can-interfaces", "--backend sim"],
        ),
        (&["soak", "--minutes", "0"], &["--minutes", "'0'"]),
        (&["soak", "--minutes", "1e9"], &["--minutes", "24 h"]),
    ] {
        let (ok, out, err) = adam_in(&dir, args);
        assert!(!ok, "{args:?} accepted: {out}");
        for w in words {
            assert!(err.contains(w), "{args:?}: `{w}` missing from {err}");
        }
    }
    // A belt step of a fault profile outside the range.
    let profile = std::fs::read_to_string(repo().join("configs/faults/example.toml"))
        .expect("profile")
        .replace("speed_mps = 0.2", "speed_mps = 0.9");
    std::fs::write(dir.join("fast.toml"), profile).expect("write");
    let (ok, _, err) = adam_in(
        &dir,
        &[
            "run",
            "--backend",
            "sim",
            "--duration",
            "1s",
            "--faults",
            "fast.toml",
        ],
    );
    assert!(
        !ok && err.contains("fast.toml") && err.contains("0.9 m/s"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_normal_run_prints_nothing_on_stderr() {
    let dir = scratch("quiet");
    let (ok, out, err) = adam_in(&dir, &["run", "--backend", "sim", "--duration", "1s"]);
    assert!(ok, "{out}\n{err}");
    assert_eq!(err, "", "stderr of a normal run");
    // A wall-clock run opens iceoryx2 (operator commands), which by itself warns that it found
    // no config file of its own.
    let (ok, out, err) = adam_in(
        &dir,
        &[
            "run",
            "--backend",
            "sim",
            "--duration",
            "0.3s",
            "--real-time",
        ],
    );
    assert!(ok && out.contains("operator commands"), "{out}\n{err}");
    assert_eq!(err, "", "stderr of a wall-clock run");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn no_debug_form_reaches_the_user() {
    let dir = scratch("words");
    let runtime =
        std::fs::read_to_string(repo().join("configs/runtime/adam.toml")).expect("config");
    std::fs::write(
        dir.join("v2.toml"),
        runtime.replace("schema_version = 1", "schema_version = 2"),
    )
    .expect("write");
    std::fs::write(
        dir.join("joint.toml"),
        runtime.replacen("joint = \"left_hip_pitch\"", "joint = \"left_hip\"", 1),
    )
    .expect("write");
    std::fs::write(dir.join("garbage.mcap"), "not a log").expect("write");
    std::fs::write(dir.join("gait.json"), "{\"schema_version\": 1}").expect("write");
    let commands: [&[&str]; 14] = [
        &["model", "configs/robots/adam_planar.urdf"],
        &["run", "--backend", "sim", "--duration", "1s"],
        &[
            "run",
            "--backend",
            "sim",
            "--duration",
            "1s",
            "--config",
            "v2.toml",
        ],
        &[
            "run",
            "--backend",
            "sim",
            "--duration",
            "1s",
            "--config",
            "joint.toml",
        ],
        &[
            "run",
            "--backend",
            "sim",
            "--duration",
            "4s",
            "--belt",
            "0.4",
        ],
        &[
            "run",
            "--backend",
            "sim",
            "--duration",
            "0.5s",
            "--faults",
            "nonsense",
        ],
        &["run", "--backend", "can", "--duration", "1s"],
        &["gait", "check", "gait.json"],
        &["gait", "check", "missing.json"],
        &["logs", "info", "garbage.mcap"],
        &["replay", "garbage.mcap"],
        &["op", "dance"],
        &[
            "model",
            "configs/robots/adam_planar.urdf",
            "--design",
            "thigh=x",
        ],
        &["generate-urdf", "--thigh", "2"],
    ];
    for args in commands {
        let (_, out, err) = adam_in(&dir, args);
        let found = debug_forms(&format!("{out}\n{err}"));
        assert!(
            found.is_empty(),
            "{args:?} printed debug output {found:?}:\n{out}\n{err}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
