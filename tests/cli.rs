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
fn demo_walks_the_shipped_gait_logs_and_prints_the_summary() {
    let (ok, out, err) = adam(&["demo"]);
    for needle in [
        "steps ",
        "mean step length",
        "tracking RMS: hip",
        "safety trips:",
        "tick compute time: median",
        "log: logs/",
    ] {
        assert!(out.contains(needle), "missing {needle:?}: {out}");
    }
    // Today the shipped gait falls after about 1 s (tests/walk_sim.rs); demo must say so.
    assert!(ok || err.contains("the robot fell"), "{err}");
}

#[test]
fn run_on_can_without_interfaces_names_the_interface() {
    let (ok, _, err) = adam(&["run", "--backend", "can", "--duration", "1s"]);
    assert!(
        !ok && err.contains("cannot open CAN interface `can0`"),
        "{err}"
    );
}

#[test]
fn run_rejects_a_bad_duration() {
    let (ok, _, err) = adam(&["run", "--backend", "sim", "--duration", "0s"]);
    assert!(
        !ok && err.contains("0s") && err.contains("positive"),
        "{err}"
    );
}

#[test]
fn sim_run_reports_steps_and_tracking() {
    let (ok, out, err) = adam(&["run", "--backend", "sim", "--duration", "3s"]);
    assert!(ok, "{out}\n{err}");
    assert!(
        out.contains("steps ") && out.contains("tracking RMS: hip"),
        "{out}"
    );
    assert!(out.contains("falls: none"), "{out}");
    assert!(out.contains("tick compute time: median"), "{out}");
}

#[test]
fn real_time_sim_run_reports_the_loop_jitter() {
    // Wall-clock figures are machine-dependent: only their presence is checked.
    let (ok, out, err) = adam(&[
        "run",
        "--backend",
        "sim",
        "--duration",
        "0.5s",
        "--real-time",
    ]);
    assert!(ok, "{out}\n{err}");
    assert!(
        out.contains("loop wake-up latency (jitter): median"),
        "{out}"
    );
}

#[test]
fn logs_info_and_phase_portraits_read_a_run_log() {
    let dir = std::env::temp_dir().join(format!("adam-cli-logs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let log = dir.join("run.mcap");
    let log_s = log.display().to_string();
    let (ok, out, err) = adam(&[
        "run",
        "--backend",
        "sim",
        "--duration",
        "2s",
        "--log",
        &log_s,
    ]);
    assert!(ok, "{out}\n{err}");
    let (ok, out, err) = adam(&["logs", "info", &log_s]);
    assert!(ok, "{out}\n{err}");
    assert!(
        out.contains("/joints") && out.contains("2000 msgs"),
        "{out}"
    );
    assert!(
        out.contains("dropped   0 records") && out.contains("robot adam_planar"),
        "{out}"
    );
    let prefix = dir.join("portrait");
    let (ok, out, err) = adam(&[
        "plot",
        "portrait",
        &log_s,
        "--compare",
        &log_s,
        "--out",
        &prefix.display().to_string(),
    ]);
    assert!(ok, "{out}\n{err}");
    for ext in ["png", "svg"] {
        let len = std::fs::metadata(prefix.with_extension(ext))
            .expect("figure")
            .len();
        assert!(len > 10_000, "{ext}: {len} bytes");
    }
    let svg = std::fs::read_to_string(prefix.with_extension("svg")).expect("svg");
    assert!(
        svg.contains("left knee pitch") && svg.contains("q (rad)"),
        "axes and titles"
    );
    let (ok, _, err) = adam(&["logs", "info", "Cargo.toml"]);
    assert!(!ok && err.contains("Cargo.toml"), "{err}");

    // The same log replays bit for bit through this build's controller.
    let (ok, out, err) = adam(&["replay", &log_s]);
    assert!(ok, "{out}\n{err}");
    assert!(
        out.contains("ticks      2000") && out.contains("bit-identical"),
        "{out}"
    );
    // Gait tiles of its middle complete step.
    let tiles = dir.join("tiles");
    let (ok, out, err) = adam(&[
        "plot",
        "tiles",
        &log_s,
        "--count",
        "6",
        "--out",
        &tiles.display().to_string(),
    ]);
    assert!(ok, "{out}\n{err}");
    assert!(
        out.contains("step 1 (") && out.contains("6 figures"),
        "{out}"
    );
    // Figures are not written over without --force, and are with it.
    let tiles_s = tiles.display().to_string();
    let (ok, _, err) = adam(&["plot", "tiles", &log_s, "--out", &tiles_s]);
    assert!(
        !ok && err.contains("tiles.png") && err.contains("--force"),
        "{err}"
    );
    let (ok, out, err) = adam(&[
        "plot", "tiles", &log_s, "--count", "6", "--out", &tiles_s, "--force",
    ]);
    assert!(ok && out.contains("6 figures"), "{out}\n{err}");
    let svg = std::fs::read_to_string(tiles.with_extension("svg")).expect("svg");
    assert!(
        svg.contains("Gait tiles") && svg.contains("stance leg"),
        "captions and legend"
    );
    // Six phases from the step's start to its end (the touchdown may come at τ a little
    // below 1: the impact spike switches from τ = 0.8 on).
    let phases: Vec<f64> = svg
        .split("τ = ")
        .skip(1)
        .filter_map(|rest| rest.get(..4)?.parse().ok())
        .collect();
    assert_eq!(phases.len(), 6, "{phases:?}");
    assert!(phases[0] <= 0.02 && phases[5] >= 0.95, "{phases:?}");
    assert!(phases.windows(2).all(|w| w[1] > w[0]), "{phases:?}");
    assert!(
        std::fs::metadata(tiles.with_extension("png"))
            .expect("png")
            .len()
            > 10_000
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn replay_mints_fixtures_that_replay_and_names_a_bad_log() {
    let dir = std::env::temp_dir().join(format!("adam-cli-replay-{}", std::process::id()));
    let dir_s = dir.display().to_string();
    let (ok, out, err) = adam(&["replay", "--mint", &dir_s]);
    assert!(ok, "{out}\n{err}");
    assert_eq!(out.matches("wrote ").count(), 3, "{out}");
    let logs: Vec<String> = ["walk.mcap", "state_machine.mcap", "estop.mcap"]
        .iter()
        .map(|n| dir.join(n).display().to_string())
        .collect();
    let mut args = vec!["replay"];
    args.extend(logs.iter().map(String::as_str));
    let (ok, out, err) = adam(&args);
    assert!(ok, "{out}\n{err}");
    assert_eq!(out.matches("bit-identical").count(), 3, "{out}");
    assert!(
        out.contains("idle → ramp → stand → walk → stop → damping → idle"),
        "{out}"
    );
    let (ok, _, err) = adam(&["replay", "Cargo.toml"]);
    assert!(
        !ok && err.contains("Cargo.toml") && err.contains("not an MCAP file"),
        "{err}"
    );
    let (ok, _, err) = adam(&["replay"]);
    assert!(!ok && err.contains("<LOGS>"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_run_killed_with_sigkill_leaves_a_log_that_reads_recovers_and_replays() {
    let dir = std::env::temp_dir().join(format!("adam-cli-kill-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let log = dir.join("killed.mcap");
    let log_s = log.display().to_string();
    // A wall-clock run that would last 30 s, killed (SIGKILL: no destructor, no footer) once
    // its log has grown past 1.5 MB (some 3000 ticks of messages, several complete chunks;
    // waiting on the file, not on a fixed time, keeps this independent of the machine's speed).
    let mut child = Command::new(env!("CARGO_BIN_EXE_adam"))
        .args([
            "run",
            "--backend",
            "sim",
            "--duration",
            "30s",
            "--real-time",
            "--log",
            &log_s,
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("adam runs");
    let waited = std::time::Instant::now();
    while std::fs::metadata(&log).map_or(0, |m| m.len()) < 1_500_000 {
        if waited.elapsed() > std::time::Duration::from_secs(60) {
            child.kill().ok();
            panic!("the log did not grow to 1.5 MB in 60 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.kill().expect("SIGKILL");
    child.wait().expect("reaped");

    let (ok, out, err) = adam(&["logs", "info", &log_s]);
    assert!(ok, "{out}\n{err}");
    assert!(out.contains("complete  NO"), "{out}");
    let ticks = |out: &str, topic: &str| -> u64 {
        out.lines()
            .find(|l| l.trim_start().starts_with(topic))
            .and_then(|l| l.split_whitespace().rev().nth(1))
            .and_then(|n| n.parse().ok())
            .unwrap_or(0)
    };
    // At least a second of 1 kHz samples made it to complete chunks before the kill.
    let logged = ticks(&out, "/joints");
    assert!(logged > 1000, "{out}");

    // Replay covers every complete tick of the cut log, bit for bit.
    let (ok, out, err) = adam(&["replay", &log_s]);
    assert!(ok, "{out}\n{err}");
    assert!(
        out.contains("bit-identical") && out.contains("cut off"),
        "{out}"
    );

    let recovered = dir.join("recovered.mcap");
    let recovered_s = recovered.display().to_string();
    let (ok, out, err) = adam(&["logs", "recover", &log_s, "--out", &recovered_s]);
    assert!(ok, "{out}\n{err}");
    let (ok, out, err) = adam(&["logs", "info", &recovered_s]);
    assert!(ok, "{out}\n{err}");
    assert!(out.contains("complete  yes"), "{out}");
    assert_eq!(ticks(&out, "/joints"), logged, "{out}");
    let (ok, out, err) = adam(&["replay", &recovered_s]);
    assert!(ok && out.contains("bit-identical"), "{out}\n{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn soak_walks_under_faults_and_prints_its_table() {
    // 0.05 min = 3 s of simulated walking under the `rough` profile (a fault every ~1.5 s).
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("soak-cli");
    let _ = std::fs::remove_dir_all(&dir);
    let (ok, out, err) = adam(&[
        "soak",
        "--minutes",
        "0.05",
        "--faults",
        "rough",
        "--seed",
        "3",
        "--log-dir",
        dir.to_str().expect("utf-8 path"),
    ]);
    assert!(ok, "{err}");
    for row in [
        "ticks",
        "overruns",
        "trips",
        "log drops",
        "worst tick compute time",
        "distance walked",
    ] {
        assert!(out.contains(row), "no `{row}` in:\n{out}");
    }
    // 3 s at 1 kHz: every tick of every episode is counted once.
    let ticks = out
        .lines()
        .find(|l| l.starts_with("ticks "))
        .and_then(|l| l.split_whitespace().last())
        .and_then(|v| v.parse::<u64>().ok());
    assert_eq!(ticks, Some(3000), "{out}");
    // Each episode left a complete log.
    let logs: Vec<_> = std::fs::read_dir(&dir).expect("log dir").collect();
    assert!(!logs.is_empty());
    for entry in logs {
        let path = entry.expect("entry").path();
        let info = runtime::telemetry::log_read::read_info(&path).expect("log reads");
        assert_eq!(info.truncated, None, "{}", path.display());
    }
}

#[test]
fn soak_refuses_an_unknown_fault_profile_by_name() {
    let (ok, _, err) = adam(&["soak", "--minutes", "0.01", "--faults", "lossy"]);
    assert!(
        !ok && err.contains("`lossy`") && err.contains("loss-1"),
        "{err}"
    );
    let (ok, _, err) = adam(&["soak", "--minutes=-1"]);
    assert!(
        !ok && err.contains("minutes") && err.contains("-1"),
        "{err}"
    );
}

#[test]
fn sim_run_injects_a_fault_profile_and_names_a_bad_one() {
    let (ok, out, err) = adam(&[
        "run",
        "--backend",
        "sim",
        "--duration",
        "2s",
        "--faults",
        "loss-1",
        "--seed",
        "2",
    ]);
    assert!(ok, "{out}\n{err}");
    // 1 % of about 2 × 4 × 2000 frames: lost frames are counted and each is a missing reply.
    let lost: u64 = out
        .split("CAN frames lost ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or_else(|| panic!("no lost-frame count: {out}"));
    assert!((50..=300).contains(&lost), "{lost}: {out}");
    assert!(out.contains("safety trips: none"), "{out}");
    let (ok, _, err) = adam(&[
        "run",
        "--backend",
        "sim",
        "--duration",
        "1s",
        "--faults",
        "nope",
    ]);
    assert!(
        !ok && err.contains("faults") && err.contains("nope"),
        "{err}"
    );
}

/// `adam bench check` verifies the shipped gait repeatedly: one row per run, the median, and
/// the same report every time (the parallel Jacobian does not depend on the schedule).
#[test]
fn bench_check_reports_identical_verifications() {
    let (ok, out, err) = adam(&["bench", "check", "--runs", "2"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("median") && out.contains("over 2 checks"),
        "{out}"
    );
    assert!(out.contains("the reports are identical"), "{out}");
    assert!(out.contains("0.86"), "|λ|max of the shipped gait: {out}");
    let (ok, _, err) = adam(&["bench", "check", "--runs", "0"]);
    assert!(!ok && err.contains("--runs must be at least 1"), "{err}");
}

/// `--backend native` reaches the planner: one benchmark plan with the native interior point
/// (39 + 28 iterations on ADAM), and an unknown backend is refused with the choices.
#[test]
fn bench_plan_runs_the_native_backend_and_rejects_unknown_ones() {
    let (ok, out, err) = adam(&["bench", "plan", "--runs", "1", "--backend", "native"]);
    assert!(ok, "{err}");
    assert!(out.contains("Native backend: median"), "{out}");
    // The time by phase: evaluation, then the native backend's own split.
    assert!(
        out.contains("time by phase (medians): problem evaluation")
            && out.contains("factorizations")
            && out.contains("solves with the factors"),
        "{out}"
    );
    // The iteration count printed after the median: 67 here; ripopt takes 85.
    let iterations: usize = out
        .split(" s and ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("iterations in the summary");
    assert!((60..=95).contains(&iterations), "{out}");
    let (ok, _, err) = adam(&["plan", "--backend", "ipopt"]);
    assert!(
        !ok && err.contains("unknown backend `ipopt`") && err.contains("native"),
        "{err}"
    );
}

/// `adam plan` end to end: live progress, the summary table (with the solver's time by phase),
/// the gait file it writes and its verification; `adam gait check` passes that file and fails,
/// naming it and why, copies whose swing-hip trajectory is shifted.
#[test]
fn plan_writes_a_gait_that_gait_check_passes_and_shifted_copies_fail() {
    let dir = format!("logs/cli-plan-{}", std::process::id());
    let gait = format!("{dir}/gait.json");
    let (ok, out, err) = adam(&[
        "plan",
        "--robot",
        "configs/robots/adam_planar.urdf",
        "--config",
        "configs/planner/adam.toml",
        "--out",
        &gait,
    ]);
    assert!(ok, "{err}\n{out}");
    for expected in [
        "solve: feasibility",
        "solve: cost of transport",
        "iter    0  objective",
        "resto",
        "factor",
        "kkt sol",
        "step length 0.1500 m",
        "|λ|max 0.86",
        "stable periodic orbit",
    ] {
        assert!(out.contains(expected), "`{expected}` missing from\n{out}");
    }
    // Both stages optimal, none in restoration, and their factorization counts named.
    let rows: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with("feasibility ") || l.starts_with("cost of transport "))
        .collect();
    assert_eq!(rows.len(), 2, "{out}");
    for row in rows {
        // The last nine cells: status, iter, resto, objective, violation, solve s, eval,
        // factor, kkt sol, other (the stage name before them has one or three words).
        let cells: Vec<&str> = row.split_whitespace().collect();
        let tail = &cells[cells.len() - 10..];
        assert_eq!((tail[0], tail[2]), ("optimal", "0"), "{row}");
        let seconds: Vec<f64> = tail[5..]
            .iter()
            .map(|c| c.parse().unwrap_or_else(|_| panic!("`{c}` in {row}")))
            .collect();
        // The solve time is the evaluation plus the native backend's three phases: five
        // figures each rounded to the millisecond, ±0.5 ms each, so within 2.5 ms.
        let phases: f64 = seconds[1..].iter().sum();
        assert!((phases - seconds[0]).abs() <= 2.5e-3 + 1e-12, "{row}");
    }
    assert!(out.contains(" in all; kkt sol"), "{out}");

    let (ok, out, err) = adam(&["gait", "check", &gait]);
    assert!(ok, "{err}\n{out}");
    assert!(out.contains("stable periodic orbit"), "{out}");

    // Shifting the swing hip's Bézier coefficients: by 0.3 rad there is no orbit near the plan;
    // by 0.05 rad the robot falls within a step; by 0.005 rad there is a stable orbit with the
    // planned joints, walked at another pace.
    let text = std::fs::read_to_string(&gait).expect("gait written");
    for (shift, why) in [
        (0.3, "no periodic orbit near the planned step"),
        (0.05, "the robot falls"),
        (0.005, "not the planned pace"),
    ] {
        let mut broken: serde_json::Value = serde_json::from_str(&text).expect("json");
        for a in broken["bezier"]["alpha"][2]
            .as_array_mut()
            .expect("alpha rows")
        {
            *a = serde_json::json!(a.as_f64().expect("number") + shift);
        }
        let broken_path = format!("{dir}/shifted-{shift}.json");
        std::fs::write(&broken_path, broken.to_string()).expect("write");
        let (ok, out, err) = adam(&["gait", "check", &broken_path]);
        assert!(
            !ok,
            "a swing hip shifted by {shift} rad must not pass: {out}"
        );
        assert!(
            err.contains(&format!("{broken_path} fails its check")) && err.contains(why),
            "{err}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `adam plan library` end to end: two speeds of the shipped robot planned, the table printed,
/// the library written and loadable, and an existing output refused without `--force`.
#[test]
fn plan_library_writes_a_library_of_the_speeds_asked_for() {
    let dir = std::env::temp_dir().join(format!("adam-plan-library-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out = dir.join("lib.json");
    let out_arg = out.display().to_string();
    let (ok, stdout, stderr) = adam(&[
        "plan",
        "library",
        "--speeds",
        "0.2,0.225",
        "--out",
        &out_arg,
    ]);
    println!("{stdout}{stderr}");
    assert!(ok, "{stderr}");
    for words in [
        "max|λ|", "T err %", "  0.200 ", "  0.225 ", "wrote", "2 gaits",
    ] {
        assert!(stdout.contains(words), "{words}: {stdout}");
    }
    let library = model::library::GaitLibrary::load(&out).expect("loads");
    let speeds: Vec<f64> = library.entries.iter().map(|e| e.speed_mps).collect();
    assert_eq!(speeds, vec![0.2, 0.225]);
    // The URDF it names, from its own folder, is the shipped robot.
    let (_, urdf) = library.read_urdf(&out).expect("its URDF");
    let shipped = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/configs/robots/adam_codesign.urdf"
    ))
    .expect("shipped URDF");
    assert_eq!(urdf, shipped);
    let (ok, _, stderr) = adam(&["plan", "library", "--speeds", "0.2", "--out", &out_arg]);
    assert!(
        !ok && stderr.contains("--force") && stderr.contains("lib.json"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `adam gait check --runtime CONFIG` walks the gait under that config's joint PD with late
/// references: with the references on time (the latency equal to the config's lead) the PD
/// walks the plan; with the simulated bus's latency it walks faster (the creep of
/// `late_references_speed_the_gait_up`); a negative latency is refused by name.
#[test]
fn gait_check_walks_the_gait_under_the_runtime_s_pd() {
    // The binary runs in the workspace's folder (`adam`).
    let gait = "configs/gaits/adam_codesign.json".to_string();
    let config = "configs/runtime/adam.toml".to_string();
    let speed_percent = |out: &str| -> f64 {
        let line = out
            .lines()
            .find(|l| l.contains("% of the plan's"))
            .unwrap_or_else(|| panic!("no walked speed in {out}"));
        let before = line.split(" % of the plan's").next().expect("a figure");
        before
            .rsplit('(')
            .next()
            .expect("a percentage")
            .trim()
            .parse()
            .expect("a number")
    };
    let (ok, out, err) = adam(&[
        "gait",
        "check",
        &gait,
        "--runtime",
        &config,
        "--latency-s",
        "0.0005",
    ]);
    assert!(ok, "{err}\n{out}");
    assert!(out.contains("references 0.0 ms late"), "{out}");
    let on_time = speed_percent(&out);
    assert!((on_time - 100.0).abs() < 1.0, "{out}");
    let (ok, out, err) = adam(&["gait", "check", &gait, "--runtime", &config]);
    assert!(ok, "{err}\n{out}");
    assert!(out.contains("references 2.5 ms late"), "{out}");
    let late = speed_percent(&out);
    assert!(late > 120.0, "{out}");
    let (ok, _, err) = adam(&[
        "gait",
        "check",
        &gait,
        "--runtime",
        &config,
        "--latency-s=-0.001",
    ]);
    assert!(
        !ok && err.contains("--latency-s") && err.contains("-0.001"),
        "{err}"
    );
    // A latency without a config to walk under is an error, not ignored.
    let (ok, _, err) = adam(&["gait", "check", &gait, "--latency-s", "0.002"]);
    assert!(!ok && err.contains("--runtime"), "{err}");
    // One gain per joint differing: refused, naming the field.
    let text = std::fs::read_to_string(&config).expect("config");
    let anchor = "kp_nm_per_rad = [150.0, 150.0, 150.0, 150.0]";
    assert!(text.contains(anchor), "{config}");
    let dir = std::env::temp_dir().join(format!("adam-gait-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let uneven = dir.join("uneven.toml");
    std::fs::write(
        &uneven,
        text.replace(anchor, "kp_nm_per_rad = [150.0, 120.0, 150.0, 120.0]"),
    )
    .expect("write");
    let (ok, _, err) = adam(&[
        "gait",
        "check",
        &gait,
        "--runtime",
        uneven.to_str().expect("utf-8"),
    ]);
    assert!(
        !ok && err.contains("gains.kp_nm_per_rad") && err.contains("uneven.toml"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
