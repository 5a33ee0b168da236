//! The bad-input corpus (issue #27): every file under `tests/bad_inputs/<kind>/` is one bad input,
//! and its sibling `<case>.expect` lists the words its error must contain (format:
//! `tests/bad_inputs/README.md`). Each case goes through the library loader of its kind, not the
//! CLI: it must not panic, it must be refused, and the error must contain every expected word and
//! the case's file name (CAN frames and CLI flags excepted: they have no file behind them).

use std::path::{Path, PathBuf};

/// The kinds of input: folder, file extension.
const KINDS: [(&str, &str); 11] = [
    ("urdf", "urdf"),
    ("gait", "json"),
    ("gait_library", "json"),
    ("gait_robot", "json"),
    ("planner_config", "toml"),
    ("runtime_config", "toml"),
    ("runtime_setup", "toml"),
    ("faults", "toml"),
    ("can", "can"),
    ("mcap", "mcap"),
    ("cli", "args"),
];

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_inputs")
}

fn shipped_runtime_config() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/runtime/adam.toml")
}

/// The error messages of loading `path` as `kind`: one per loader that reads this kind, `Ok`
/// (with the loader's name) where a loader accepted the input.
fn load(kind: &str, path: &Path) -> Vec<Result<String, String>> {
    fn refused<T, E: std::fmt::Display>(loader: &str, r: Result<T, E>) -> Result<String, String> {
        match r {
            Ok(_) => Err(format!("{loader} accepted it")),
            Err(e) => Ok(e.to_string()),
        }
    }
    match kind {
        "urdf" => vec![refused(
            "PlanarModel::from_urdf_file",
            model::PlanarModel::from_urdf_file(path),
        )],
        "gait" => vec![refused("GaitFile::load", model::gait::GaitFile::load(path))],
        "gait_library" => vec![refused(
            "GaitLibrary::load",
            model::library::GaitLibrary::load(path),
        )],
        // Where the gait and its robot meet: the planner's and the runtime's loaders.
        "gait_robot" => vec![
            refused(
                "planner::verify::load_gait_and_robot",
                planner::verify::load_gait_and_robot(path),
            ),
            refused(
                "runtime::Setup::load",
                runtime::Setup::load(shipped_runtime_config(), path),
            ),
        ],
        "planner_config" => vec![refused(
            "PlannerConfig::load",
            planner::config::PlannerConfig::load(path),
        )],
        "runtime_config" => vec![refused(
            "RuntimeConfig::load",
            runtime::config::RuntimeConfig::load(path),
        )],
        // A runtime config that reads but does not fit the robot (its URDF joint limits).
        "runtime_setup" => vec![refused(
            "runtime::Setup::load",
            runtime::Setup::load(
                path,
                Path::new(env!("CARGO_MANIFEST_DIR")).join(runtime::DEFAULT_GAIT),
            ),
        )],
        "faults" => vec![refused(
            "FaultProfile::load",
            runtime::sim::faults::FaultProfile::load(path),
        )],
        "can" => vec![decode_can(path)],
        // What every reader of a log meets first (`adam plot`, `adam logs`): nothing usable left.
        "mcap" => vec![refused(
            "log_read::joint_series",
            runtime::telemetry::log_read::joint_series(path),
        )],
        "cli" => vec![run_cli(path)],
        other => panic!("unknown kind {other}"),
    }
}

/// A `.can` case: `<kind> <id> <byte>...` (kind `reply`, `command`, `special` or `host`, id and
/// bytes in hex), decoded by the matching `drivers::a1::codec` function.
fn decode_can(path: &Path) -> Result<String, String> {
    use drivers::a1::codec;
    let text = std::fs::read_to_string(path).map_err(|e| format!("read: {e}"))?;
    let line = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .ok_or("no frame line")?;
    let mut words = line.split_whitespace();
    let kind = words.next().ok_or("no kind")?;
    let id_text = words.next().ok_or("no id")?;
    let id = u32::from_str_radix(id_text.trim_start_matches("0x"), 16)
        .map_err(|e| format!("case file: id {id_text}: {e}"))?;
    let data: Vec<u8> = words
        .map(|b| u8::from_str_radix(b, 16).map_err(|e| format!("case file: byte {b}: {e}")))
        .collect::<Result<_, _>>()?;
    let message = |r: Result<(), codec::DecodeError>| match r {
        Ok(()) => Err(format!("{kind} decoder accepted it")),
        Err(e) => Ok(e.to_string()),
    };
    match kind {
        "reply" => message(codec::decode_reply(id, &data).map(drop)),
        "command" => message(codec::decode_command(id, &data).map(drop)),
        "special" => message(codec::decode_special(id, &data).map(drop)),
        "host" => message(codec::decode_host_frame(id, &data).map(drop)),
        other => Err(format!("case file: unknown frame kind {other}")),
    }
}

/// An `.args` case: one line of `adam` arguments (split at white space), run by the binary from
/// the repository's root; it must fail, without a panic, and its stderr is the message.
fn run_cli(path: &Path) -> Result<String, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("read: {e}"))?;
    let line = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .ok_or("no argument line")?;
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_adam"))
        .args(line.split_whitespace())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .map_err(|e| format!("adam did not start: {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    if out.status.success() {
        return Err(format!("adam {line} succeeded"));
    }
    if stderr.contains("panicked") {
        return Err(format!("adam {line} PANICKED: {stderr}"));
    }
    Ok(stderr)
}

/// The expected words of a case: the non-empty lines of `<case>.expect` that are not comments.
fn expected_words(case: &Path) -> Vec<String> {
    let expect = case.with_extension("expect");
    let text = std::fs::read_to_string(&expect)
        .unwrap_or_else(|e| panic!("{}: {e} (every case needs one)", expect.display()));
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(String::from)
        .collect()
}

/// Every case of the corpus: (kind, path), sorted.
fn cases() -> Vec<(&'static str, PathBuf)> {
    let mut out = Vec::new();
    for (kind, ext) in KINDS {
        let dir = corpus().join(kind);
        let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        for entry in entries {
            let path = entry.expect("directory entry").path();
            match path.extension().and_then(|e| e.to_str()) {
                Some(e) if e == ext => out.push((kind, path)),
                Some("expect") => assert!(
                    path.with_extension(ext).exists(),
                    "{} has no case file",
                    path.display()
                ),
                _ => panic!("{}: not a .{ext} case or .expect file", path.display()),
            }
        }
    }
    out.sort();
    out
}

/// Runs one case; the failures found, empty when the case holds.
fn check(kind: &str, path: &Path) -> Vec<String> {
    let words = expected_words(path);
    assert!(!words.is_empty(), "{}: no expected words", path.display());
    let file_name = path
        .file_name()
        .and_then(|n| n.to_str())
        .expect("file name")
        .to_string();
    let outcome = std::panic::catch_unwind(|| load(kind, path));
    let results = match outcome {
        Ok(results) => results,
        Err(_) => return vec![format!("{kind}/{file_name}: PANICKED")],
    };
    let mut failures = Vec::new();
    for result in results {
        match result {
            Err(why) => failures.push(format!("{kind}/{file_name}: {why}")),
            Ok(message) => {
                if std::env::var_os("BAD_INPUTS_SHOW").is_some() {
                    println!("{kind}/{file_name}:\n    {message}");
                }
                let mut missing: Vec<&str> = words
                    .iter()
                    .map(String::as_str)
                    .filter(|w| !message.contains(w))
                    .collect();
                // CAN frames and CLI flags have no file behind them.
                if !matches!(kind, "can" | "cli") && !message.contains(&file_name) {
                    missing.push(&file_name);
                }
                if !missing.is_empty() {
                    failures.push(format!(
                        "{kind}/{file_name}: the error lacks {missing:?}:\n    {message}"
                    ));
                }
            }
        }
    }
    failures
}

#[test]
fn every_bad_input_is_refused_with_an_error_that_names_it() {
    let cases = cases();
    assert!(
        cases.len() >= 60,
        "the corpus has {} cases, issue #27 asks for at least 60",
        cases.len()
    );
    for (kind, _) in KINDS {
        assert!(
            cases.iter().any(|(k, _)| *k == kind),
            "no case of kind {kind}"
        );
    }
    let failures: Vec<String> = cases
        .iter()
        .flat_map(|(kind, path)| check(kind, path))
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} cases fail:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

#[test]
fn no_error_of_the_corpus_prints_rust_debug_output() {
    // `Some(2)`, `QDes`, `[1.0, 0.0, 0.0]`: a user never typed those.
    let debug_forms = [
        "Some(", "None", "QDes", "DqDes", "TauFf", "1.0, 0.0", "0.0, 1.0",
    ];
    let mut failures = Vec::new();
    for (kind, path) in cases() {
        let results = std::panic::catch_unwind(|| load(kind, &path)).unwrap_or_default();
        for message in results.into_iter().flatten() {
            if let Some(form) = debug_forms.iter().find(|f| message.contains(*f)) {
                failures.push(format!("{}: {form}: {message}", path.display()));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
