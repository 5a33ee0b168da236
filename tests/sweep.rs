//! Sweeps as a cluster runs them (issue #32): every task of a small plan as its own `adam`
//! process with `SLURM_ARRAY_TASK_ID` set, as a job array would, one of them killed mid-run and
//! run again; the collected report is the in-process command's, file for file. Plans whose
//! inputs changed, indices out of range, plans of another version, corrupt results: refused,
//! naming the file and the value. The sbatch scripts pass `bash -n` and name every task.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

fn adam() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_adam"));
    c.env_remove("ADAM_CONFIG_DIR")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

/// Runs `adam args`; (success, stdout, stderr).
fn run(args: &[&str]) -> (bool, String, String) {
    run_cmd(adam().args(args))
}

fn run_cmd(c: &mut Command) -> (bool, String, String) {
    let out: Output = c.output().expect("adam runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A fresh empty folder outside the repository.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("adam-sweep-{tag}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// A task of `plan` as a job array's element: `adam sweep task --plan P` with
/// `SLURM_ARRAY_TASK_ID` set, no `--index`.
/// `adam sweep plan --study <study> --out-dir <out_dir> --out <plan>` with `args`: whether it
/// succeeded, its stdout and stderr.
fn sweep_plan(study: &str, out_dir: &str, plan: &Path, args: &[&str]) -> (bool, String, String) {
    let plan = s(plan);
    let mut all = vec![
        "sweep",
        "plan",
        "--study",
        study,
        "--out-dir",
        out_dir,
        "--out",
        &plan,
    ];
    all.extend_from_slice(args);
    run(&all)
}

fn array_task(plan: &Path, index: usize) -> Child {
    adam()
        .args(["sweep", "task", "--plan", &s(plan)])
        .env("SLURM_ARRAY_TASK_ID", index.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("adam sweep task starts")
}

fn finish(child: Child) -> (bool, String, String) {
    let out = child.wait_with_output().expect("task ends");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn a_codesign_plan_run_task_by_task_with_one_killed_collects_to_the_in_process_report() {
    let dir = scratch("codesign");
    let (inproc, array, plan) = (dir.join("inproc"), dir.join("array"), dir.join("plan.toml"));
    let (ok, _, err) = run(&["codesign", "sweep", "--grid", "2", "--out-dir", &s(&inproc)]);
    assert!(ok, "{err}");
    let (ok, out, err) = sweep_plan("codesign", &s(&array), &plan, &["--grid", "2"]);
    assert!(ok && out.contains("4 tasks (0..=3)"), "{out}{err}");

    // Task 2 is killed while it runs: it leaves no result.
    let mut doomed = array_task(&plan, 2);
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert!(
        doomed.try_wait().expect("task 2").is_none(),
        "task 2 ended before it could be killed (a task plans a warm start and a co-design: \
         seconds)"
    );
    doomed.kill().expect("kill task 2");
    doomed.wait().expect("task 2 reaped");
    let result = |i: usize| array.join(format!("results/task-{i:05}.json"));
    assert!(!result(2).exists(), "a killed task left a result");

    // The others, two at a time as a 2-core node would run them.
    for pair in [[0, 1], [3, 3]] {
        let children: Vec<Child> = if pair[0] == pair[1] {
            vec![array_task(&plan, pair[0])]
        } else {
            pair.iter().map(|&i| array_task(&plan, i)).collect()
        };
        for c in children {
            let (ok, out, err) = finish(c);
            assert!(ok && out.contains("wrote"), "{out}{err}");
        }
    }
    // Collect: task 2 is missing, named with the --array to run it again; exit non-zero.
    let (ok, out, err) = run(&["sweep", "collect", "--plan", &s(&plan)]);
    assert!(!ok, "collect succeeded with a task missing: {out}");
    assert!(
        err.contains("missing task 2") && err.contains("--array=2"),
        "{err}"
    );
    assert!(out.contains("3 of 4 tasks have results"), "{out}");

    // Task 2 again: only its own file is written.
    let before: Vec<Vec<u8>> = [0, 1, 3].iter().map(|&i| read(&result(i))).collect();
    let (ok, out, err) = finish(array_task(&plan, 2));
    assert!(ok, "{out}{err}");
    let after: Vec<Vec<u8>> = [0, 1, 3].iter().map(|&i| read(&result(i))).collect();
    assert_eq!(before, after, "a re-run task touched another task's result");
    let (ok, out, err) = run(&["sweep", "collect", "--plan", &s(&plan)]);
    assert!(ok, "{out}{err}");
    assert!(
        out.contains("4 of 4 tasks have results (0 failed, 0 missing)"),
        "{out}"
    );

    // The report is the in-process sweep's, file for file (times are in times.csv only).
    for f in [
        "table.md",
        "sweep.csv",
        "sweep.json",
        "convergence.svg",
        "convergence.png",
    ] {
        assert!(
            read(&inproc.join(f)) == read(&array.join(f)),
            "{f} differs:\n{}\n---\n{}",
            String::from_utf8_lossy(&read(&inproc.join(f))),
            String::from_utf8_lossy(&read(&array.join(f)))
        );
    }
    let table = String::from_utf8_lossy(&read(&array.join("table.md"))).into_owned();
    assert!(table.contains("4 runs from a 2×2 grid"), "{table}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn changed_inputs_bad_indices_other_versions_and_corrupt_results_are_named() {
    let dir = scratch("bad");
    let config = dir.join("planner.toml");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/planner/adam.toml"),
        &config,
    )
    .expect("copy the config");
    let plan = dir.join("plan.toml");
    let (ok, _, err) = sweep_plan(
        "codesign",
        &s(&dir.join("out")),
        &plan,
        &["--grid", "2", "--config", &s(&config)],
    );
    assert!(ok, "{err}");
    let plan_text = std::fs::read_to_string(&plan).expect("plan");

    // An index out of range, from --index or from SLURM_ARRAY_TASK_ID; no index at all.
    let (ok, _, err) = run(&["sweep", "task", "--plan", &s(&plan), "--index", "4"]);
    assert!(!ok && err.contains("index 4 is out of range") && err.contains("plan.toml"));
    let (ok, _, err) = run_cmd(
        adam()
            .args(["sweep", "task", "--plan", &s(&plan)])
            .env("SLURM_ARRAY_TASK_ID", "x7"),
    );
    assert!(!ok && err.contains("SLURM_ARRAY_TASK_ID = \"x7\""), "{err}");
    let (ok, _, err) = run(&["sweep", "task", "--plan", &s(&plan)]);
    assert!(!ok && err.contains("SLURM_ARRAY_TASK_ID"), "{err}");

    // A corrupt result and a result of another task: named, counted as missing.
    let results = dir.join("out/results");
    std::fs::create_dir_all(&results).expect("results dir");
    std::fs::write(
        results.join("task-00001.json"),
        "{\"schema_version\": 1, \"to",
    )
    .expect("w");
    let (ok, out, err) = run(&["sweep", "collect", "--plan", &s(&plan)]);
    assert!(!ok, "{out}");
    assert!(
        err.contains("missing task 1") && err.contains("task-00001.json: not a task result"),
        "{err}"
    );
    assert!(
        err.contains("4 of 4 tasks are missing") && err.contains("--array=0-3"),
        "{err}"
    );

    // A plan written by another version of adam: refused, naming file, field and value.
    let old = dir.join("old.toml");
    let version = format!("tool = \"adam {}\"", env!("CARGO_PKG_VERSION"));
    assert!(plan_text.contains(&version), "{plan_text}");
    std::fs::write(&old, plan_text.replace(&version, "tool = \"adam 0.0.9\"")).expect("w");
    let old_s = s(&old);
    for args in [
        &["sweep", "task", "--plan", &old_s, "--index", "0"][..],
        &["sweep", "collect", "--plan", &old_s][..],
        &["sweep", "slurm", "--plan", &old_s][..],
    ] {
        let (ok, _, err) = run(args);
        assert!(
            !ok && err.contains("old.toml") && err.contains("'tool'") && err.contains("adam 0.0.9"),
            "{args:?}: {err}"
        );
    }

    // The config changed after the plan: refused with both hashes.
    let planned = plan_text
        .lines()
        .find_map(|l| l.strip_prefix("sha256 = \""))
        .and_then(|l| l.strip_suffix('"'))
        .expect("the plan's hash")
        .to_string();
    let mut changed = std::fs::read_to_string(&config).expect("config");
    changed.push_str("\n# edited after the plan\n");
    std::fs::write(&config, &changed).expect("edit");
    for args in [
        &["sweep", "task", "--plan", &s(&plan), "--index", "0"][..],
        &["sweep", "collect", "--plan", &s(&plan)][..],
    ] {
        let (ok, _, err) = run(args);
        assert!(
            !ok && err.contains(&planned) && err.contains("has changed since the plan"),
            "{err}"
        );
        let now = err
            .split("in the plan, ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .expect("the hash now");
        assert_eq!(now.len(), 64, "{err}");
        assert_ne!(now, planned);
    }
    assert!(!results.join("task-00000.json").exists());
    // A flag of another study is refused, naming it.
    let (ok, _, err) = run(&[
        "sweep",
        "plan",
        "--study",
        "library",
        "--grid",
        "2",
        "--out",
        &s(&old),
    ]);
    assert!(
        !ok && err.contains("--grid: not used by the library study"),
        "{err}"
    );
    let (ok, _, err) = run(&[
        "sweep",
        "plan",
        "--study",
        "codesign",
        "--speeds",
        "0.2,0.3",
        "--out",
        &s(&old),
    ]);
    assert!(
        !ok && err.contains("--speeds: not used by the codesign study"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_sbatch_scripts_pass_bash_n_name_every_task_and_are_not_submitted_without_sbatch() {
    let dir = scratch("slurm");
    let plan = dir.join("plan.toml");
    let (ok, _, err) = sweep_plan(
        "codesign",
        &s(&dir.join("out")),
        &plan,
        &[
            "--grid",
            "3",
            "--time-per-task-min",
            "90",
            "--mem-per-task-mb",
            "1500",
            "--array-limit",
            "4",
        ],
    );
    assert!(ok, "{err}");
    let (ok, out, err) = run(&["sweep", "slurm", "--plan", &s(&plan)]);
    assert!(ok && out.contains("9 tasks, --array=0-8%4"), "{out}{err}");
    let slurm = dir.join("out/slurm");
    for f in ["array.sbatch", "collect.sbatch", "submit.sh"] {
        let status = Command::new("bash")
            .arg("-n")
            .arg(slurm.join(f))
            .status()
            .expect("bash runs");
        assert!(status.success(), "bash -n {f}");
    }
    let array = std::fs::read_to_string(slurm.join("array.sbatch")).expect("array");
    for line in [
        "#SBATCH --array=0-8%4",
        "#SBATCH --time=01:30:00",
        "#SBATCH --mem=1500M",
        "#SBATCH --cpus-per-task=1",
        "task-%a.out",
        "sweep task --plan",
        "--index \"$SLURM_ARRAY_TASK_ID\"",
    ] {
        assert!(array.contains(line), "{line} not in\n{array}");
    }
    for i in 0..9 {
        assert!(
            array.contains(&format!("#   task {i}: {{\"index\":{i},")),
            "task {i}"
        );
    }
    assert!(!array.contains("#   task 9:"));
    let collect = std::fs::read_to_string(slurm.join("collect.sbatch")).expect("collect");
    assert!(collect.contains("sweep collect --plan") && collect.contains("collect.out"));
    let submit = std::fs::read_to_string(slurm.join("submit.sh")).expect("submit");
    assert!(
        submit.contains("--dependency=afterany:\"$array_id\""),
        "{submit}"
    );
    // --submit without sbatch on the PATH: the scripts are written, nothing submitted.
    let (ok, _, err) = run_cmd(
        adam()
            .args(["sweep", "slurm", "--plan", &s(&plan), "--submit"])
            .env("PATH", &dir),
    );
    assert!(!ok && err.contains("sbatch is not on the PATH"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs every task of `plan` one after another with `--index`; panics naming a failed one.
fn every_task(plan: &Path, n: usize) {
    for i in 0..n {
        let (ok, out, err) = run(&[
            "sweep",
            "task",
            "--plan",
            &s(plan),
            "--index",
            &i.to_string(),
        ]);
        assert!(ok, "task {i}: {out}{err}");
    }
}

/// Runs every task of `plan` as job-array elements (`SLURM_ARRAY_TASK_ID`), two at a time as
/// a 2-core node would; panics naming a failed one.
fn every_task_as_array(plan: &Path, n: usize) {
    let indices: Vec<usize> = (0..n).collect();
    for pair in indices.chunks(2) {
        let children: Vec<Child> = pair.iter().map(|&i| array_task(plan, i)).collect();
        for (c, i) in children.into_iter().zip(pair) {
            let (ok, out, err) = finish(c);
            assert!(ok && out.contains("wrote"), "task {i}: {out}{err}");
        }
    }
}

#[test]
fn a_landscape_plan_collects_to_the_in_process_landscape_report() {
    let dir = scratch("landscape");
    // The shipped config with a 2 × 2 convergence study (its 5 × 5 takes minutes here).
    let config = dir.join("planner.toml");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/planner/adam.toml"),
    )
    .expect("config");
    assert_eq!(
        text.matches("\ngrid = 5 ").count(),
        1,
        "the sweep's grid line"
    );
    std::fs::write(&config, text.replace("\ngrid = 5 ", "\ngrid = 2 ")).expect("config");
    // The in-process default: each grid point from its inner neighbour's solution.
    let inproc = dir.join("inproc");
    let (ok, out, err) = run(&[
        "codesign",
        "landscape",
        "--grid",
        "3",
        "--config",
        &s(&config),
        "--out-dir",
        &s(&inproc),
    ]);
    assert!(ok, "{out}{err}");
    let plan = dir.join("plan.toml");
    let array = dir.join("array");
    let (ok, out, err) = sweep_plan(
        "landscape",
        &s(&array),
        &plan,
        &["--grid", "3", "--config", &s(&config)],
    );
    // 9 grid points, the optimum, 4 convergence-study runs.
    assert!(ok && out.contains("14 tasks (0..=13)"), "{out}{err}");
    let plan_text = std::fs::read_to_string(&plan).expect("plan");
    assert!(plan_text.contains("start = \"neighbours\""), "{plan_text}");
    every_task_as_array(&plan, 14);
    let (ok, out, err) = run(&["sweep", "collect", "--plan", &s(&plan)]);
    assert!(ok, "{out}{err}");
    // The whole report is the in-process one, file for file (times are printed, not written).
    for f in [
        "landscape.csv",
        "activity.md",
        "sweep.json",
        "landscape.svg",
        "landscape.png",
    ] {
        assert!(
            read(&inproc.join(f)) == read(&array.join(f)),
            "{f} differs:\n{}\n---\n{}",
            String::from_utf8_lossy(&read(&inproc.join(f))),
            String::from_utf8_lossy(&read(&array.join(f)))
        );
    }
    let activity = String::from_utf8_lossy(&read(&array.join("activity.md"))).into_owned();
    for words in [
        "neighbour start",
        "Best grid point: thigh",
        "## Co-design optimum",
        "4 convergence-study endpoints drawn",
        "Active constraints at the optimum",
    ] {
        assert!(activity.contains(words), "{words}:\n{activity}");
    }
    let csv = String::from_utf8_lossy(&read(&array.join("landscape.csv"))).into_owned();
    assert!(
        csv.contains(",true,"),
        "no point started from a neighbour:\n{csv}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_treadmill_plan_collects_to_the_tables_of_the_bench() {
    let dir = scratch("treadmill");
    let plan = dir.join("plan.toml");
    let array = dir.join("array");
    let (ok, out, err) = sweep_plan("treadmill", &s(&array), &plan, &["--quick", "--seeds", "1"]);
    // 5 belt speeds, 1 belt step, 2 forces × 3 points, 3 restarts: 15 runs of seed 1.
    assert!(ok && out.contains("15 tasks (0..=14)"), "{out}{err}");
    every_task(&plan, 15);
    let (ok, out, err) = run(&["sweep", "collect", "--plan", &s(&plan)]);
    assert!(ok, "{out}{err}");
    let tables = String::from_utf8_lossy(&read(&array.join("treadmill.md"))).into_owned();
    let tables = tables
        .split_once('\n')
        .map(|(_, rest)| rest.to_string())
        .expect("a title line");
    let (ok, bench, err) = run(&["bench", "treadmill", "--quick", "--seeds", "1"]);
    assert!(ok, "{err}");
    assert!(tables.contains("(d) start and restart"), "{tables}");
    assert!(bench.contains(&tables), "{tables}\n---\n{bench}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Every "solve_time_s" of a JSON document set to 0: the one field of a gait that is a wall
/// time, different between any two runs of the same plan.
fn without_solve_times(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m.iter_mut() {
                if k == "solve_time_s" {
                    *x = serde_json::Value::from(0.0);
                } else {
                    without_solve_times(x);
                }
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(without_solve_times),
        _ => {}
    }
}

#[test]
fn a_library_plan_run_as_an_array_collects_to_the_in_process_library() {
    let dir = scratch("library");
    let (inproc, array, plan) = (dir.join("inproc"), dir.join("array"), dir.join("plan.toml"));
    std::fs::create_dir_all(&inproc).expect("inproc dir");
    // Five speeds: the anchor 0.25 m/s, walks of two speeds down and two up, so the tasks of
    // the ends solve their neighbour again on the way.
    let speeds = "0.2:0.3:0.025";
    let in_lib = inproc.join("adam_library.json");
    let (ok, table, err) = run(&["plan", "library", "--speeds", speeds, "--out", &s(&in_lib)]);
    assert!(ok, "{table}{err}");
    let (ok, out, err) = sweep_plan("library", &s(&array), &plan, &["--speeds", speeds]);
    assert!(ok && out.contains("5 tasks (0..=4)"), "{out}{err}");
    // Collect before any task: nothing written, every task named missing.
    let (ok, out, err) = run(&["sweep", "collect", "--plan", &s(&plan)]);
    assert!(!ok && err.contains("--array=0-4"), "{out}{err}");
    assert!(
        out.contains("not written") && !array.join("adam_library.json").exists(),
        "{out}"
    );
    // The tasks as a job array runs them, two at a time.
    for group in [&[4, 0][..], &[1, 3][..], &[2][..]] {
        let children: Vec<Child> = group.iter().map(|&i| array_task(&plan, i)).collect();
        for c in children {
            let (ok, out, err) = finish(c);
            assert!(ok && out.contains("wrote"), "{out}{err}");
        }
    }
    let (ok, out, err) = run(&["sweep", "collect", "--plan", &s(&plan)]);
    assert!(ok, "{out}{err}");
    assert!(
        out.contains("5 of 5 tasks have results (0 failed, 0 missing)"),
        "{out}"
    );
    // The library file is the in-process one but for the solves' wall times.
    let json = |p: &Path| {
        let mut v: serde_json::Value = serde_json::from_slice(&read(p)).expect("JSON");
        without_solve_times(&mut v);
        v
    };
    let arr_lib = array.join("adam_library.json");
    assert_eq!(json(&in_lib), json(&arr_lib), "the libraries differ");
    // library.md is the in-process table row for row, without the solve-time column.
    let md = String::from_utf8_lossy(&read(&array.join("library.md"))).into_owned();
    let rows: Vec<&str> = md
        .lines()
        .filter(|l| l.trim_start().starts_with("0."))
        .collect();
    assert_eq!(rows.len(), 5, "{md}");
    for row in &rows {
        assert!(
            table.lines().any(|l| l.starts_with(row)),
            "{row}\nnot in\n{table}"
        );
    }
    assert_eq!(
        rows.iter().filter(|r| r.contains(" cold ")).count(),
        1,
        "{md}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The `planned` and `now` hashes of a refusal (`SHA-256 <planned> in the plan, <now> now`).
fn refused_hashes(err: &str) -> (String, String) {
    let planned = err
        .split("SHA-256 ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .expect("the plan's hash");
    let now = err
        .split("in the plan, ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .expect("the hash now");
    (planned.to_string(), now.to_string())
}

#[test]
fn every_input_that_changes_a_result_is_hashed_and_a_changed_one_refused() {
    let dir = scratch("inputs");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (from, to) in [
        (
            "configs/robots/adam_codesign.urdf",
            "robots/adam_codesign.urdf",
        ),
        ("configs/gaits/adam_library.json", "gaits/adam_library.json"),
        (
            "configs/planner/adam_library.toml",
            "planner/adam_library.toml",
        ),
    ] {
        std::fs::create_dir_all(dir.join(to).parent().expect("a folder")).expect("mkdir");
        std::fs::copy(repo.join(from), dir.join(to)).expect("copy");
    }
    // A runtime config that names the library copy for speed control.
    let runtime = std::fs::read_to_string(repo.join("configs/runtime/adam.toml")).expect("cfg");
    let runtime = runtime.replacen(
        "[speed]\n",
        "[speed]\nlibrary = \"../gaits/adam_library.json\"\n",
        1,
    );
    std::fs::create_dir_all(dir.join("runtime")).expect("mkdir");
    std::fs::write(dir.join("runtime/adam.toml"), runtime).expect("w");
    // And one that extends it (`extends`): its base is an input too.
    std::fs::write(
        dir.join("runtime/over.toml"),
        "extends = \"adam.toml\"\n[gains]\nkd_nm_s_per_rad = [3.0, 3.0, 3.0, 3.0]\n",
    )
    .expect("w");

    // The treadmill plan hashes the config and its base, the gait, its robot, the library and its
    // robot.
    let tread = dir.join("treadmill.toml");
    let (ok, _, err) = sweep_plan(
        "treadmill",
        &s(&dir.join("out-t")),
        &tread,
        &[
            "--quick",
            "--seeds",
            "1",
            "--runtime-config",
            &s(&dir.join("runtime/over.toml")),
        ],
    );
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&tread).expect("plan");
    for role in [
        "runtime config",
        "runtime config base",
        "gait",
        "robot",
        "gait library",
        "library robot",
    ] {
        assert!(
            text.contains(&format!("role = \"{role}\"")),
            "{role}:\n{text}"
        );
    }
    // The library plan hashes the robot and the planner config.
    let lib = dir.join("library.toml");
    let (ok, _, err) = sweep_plan(
        "library",
        &s(&dir.join("out-l")),
        &lib,
        &[
            "--speeds",
            "0.2,0.225",
            "--robot",
            &s(&dir.join("robots/adam_codesign.urdf")),
            "--config",
            &s(&dir.join("planner/adam_library.toml")),
        ],
    );
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&lib).expect("plan");
    for role in ["robot", "planner config"] {
        assert!(
            text.contains(&format!("role = \"{role}\"")),
            "{role}:\n{text}"
        );
    }

    // Each input changed in turn: the task and the collect refuse, naming the file and both
    // hashes; restored, the plan holds again.
    for (plan, file, roles) in [
        (&tread, "gaits/adam_library.json", &["gait library"][..]),
        (&tread, "runtime/adam.toml", &["runtime config base"][..]),
        (&tread, "robots/adam_codesign.urdf", &["library robot"][..]),
        (&lib, "robots/adam_codesign.urdf", &["robot"][..]),
        (&lib, "planner/adam_library.toml", &["planner config"][..]),
    ] {
        let path = dir.join(file);
        let original = std::fs::read(&path).expect("input");
        let mut changed = original.clone();
        changed.extend_from_slice(b"\n");
        std::fs::write(&path, &changed).expect("edit");
        for args in [
            &["sweep", "task", "--plan", &s(plan), "--index", "0"][..],
            &["sweep", "collect", "--plan", &s(plan)][..],
        ] {
            let (ok, _, err) = run(args);
            assert!(
                !ok && err.contains("has changed since the plan") && err.contains(file),
                "{args:?}: {err}"
            );
            assert!(
                roles.iter().any(|r| err.contains(&format!("'{r}'"))),
                "{err}"
            );
            let (planned, now) = refused_hashes(&err);
            assert_eq!(planned.len(), 64, "{err}");
            assert_eq!(now.len(), 64, "{err}");
            assert_ne!(planned, now);
        }
        std::fs::write(&path, &original).expect("restore");
    }
    let (ok, out, err) = run(&["sweep", "slurm", "--plan", &s(&lib)]);
    assert!(ok, "{out}{err}");
    std::fs::remove_dir_all(&dir).ok();
}
