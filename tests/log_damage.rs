//! Every reader degrades the same way (issue #27): `adam logs info`, `adam replay`, `adam plot
//! portrait|tiles` and `adam logs recover` on a log damaged in the middle, cut off, or damaged
//! in its summary read what is intact, say how much, and exit 0 with a warning; where nothing
//! usable is left, a clear error naming the file. A recovered log replays and says which part
//! it checked. The recovered files read in the Python `mcap` package too, when it is installed
//! (`tests/python/check_mcap.py`; skipped with a printed reason otherwise).

use std::path::{Path, PathBuf};
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

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("log-damage-cli")
}

/// 5 s of simulated walking (several steps), logged (every channel, replayable), once.
fn walk_log() -> &'static [u8] {
    static LOG: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    LOG.get_or_init(|| {
        std::fs::create_dir_all(dir()).expect("dir");
        let setup = runtime::Setup::shipped().expect("shipped setup");
        // Per process: cargo-nextest runs each test in a process of its own, each writing it.
        let path = dir().join(format!("walk-{}.mcap", std::process::id()));
        let mut options = runtime::sim::run::SimWalkOptions::new(5.0);
        options.log_path = Some(path.clone());
        runtime::sim::run::walk(&setup, &options).expect("walk");
        let bytes = std::fs::read(&path).expect("log");
        // Held in memory from here: the file would only pile up in target/tmp.
        std::fs::remove_file(&path).ok();
        bytes
    })
}

fn write(name: &str, bytes: &[u8]) -> (PathBuf, String) {
    // Tests run in parallel: the folder may not be made yet by the one that logs the walk.
    std::fs::create_dir_all(dir()).expect("dir");
    let path = dir().join(name);
    std::fs::write(&path, bytes).expect("write");
    let s = path.display().to_string();
    (path, s)
}

/// Where the undamaged log's summary starts (its footer's `summary_start`: the footer is the
/// 29-byte record before the 8-byte end magic).
fn summary_start() -> usize {
    let bytes = walk_log();
    let at = bytes.len() - 8 - 29 + 9;
    u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes")) as usize
}

/// Every reader reads `path` (damaged as `what`), exits 0 and warns.
fn every_reader_reads(path: &Path, what: &str) {
    let p = path.display().to_string();
    let (ok, out, err) = adam(&["logs", "info", &p]);
    assert!(ok, "info, {what}: {out}\n{err}");
    assert!(out.contains("complete  NO"), "info, {what}: {out}");
    assert!(
        err.contains("warning") && err.contains(&p),
        "info, {what}: {err}"
    );
    let (ok, out, err) = adam(&["replay", &p]);
    assert!(ok, "replay, {what}: {out}\n{err}");
    assert!(
        out.contains("bit-identical") && out.contains("checked    ticks 0–"),
        "replay, {what}: {out}"
    );
    assert!(err.contains("warning"), "replay, {what}: {err}");
    let prefix = dir().join(format!("{what}-portrait")).display().to_string();
    let (ok, out, err) = adam(&["plot", "portrait", &p, "--out", &prefix, "--force"]);
    assert!(ok, "portrait, {what}: {out}\n{err}");
    assert!(err.contains("warning"), "portrait, {what}: {err}");
    let prefix = dir().join(format!("{what}-tiles")).display().to_string();
    let (ok, out, err) = adam(&["plot", "tiles", &p, "--out", &prefix, "--force"]);
    assert!(ok, "tiles, {what}: {out}\n{err}");
    assert!(err.contains("warning"), "tiles, {what}: {err}");
}

/// `recover` on `path`: exit 0, an honest account; the result reads whole and replays.
fn recovers(path: &Path, what: &str, must_say: &[&str]) -> PathBuf {
    let p = path.display().to_string();
    let out_path = path.with_extension("recovered.mcap");
    let o = out_path.display().to_string();
    let (ok, out, err) = adam(&["logs", "recover", &p, "--out", &o, "--force"]);
    assert!(ok, "recover, {what}: {out}\n{err}");
    assert!(!out.contains("intact"), "recover, {what}: {out}");
    for s in must_say {
        assert!(out.contains(s), "recover, {what}: want {s:?} in\n{out}");
    }
    let (ok, out, err) = adam(&["logs", "info", &o]);
    assert!(ok && out.contains("complete  yes"), "{what}: {out}\n{err}");
    assert!(out.contains("recovered from"), "{what}: {out}");
    let (ok, out, err) = adam(&["replay", &o]);
    assert!(ok, "replay recovered, {what}: {out}\n{err}");
    assert!(
        out.contains("bit-identical") && out.contains("recovered  from") && out.contains("checked"),
        "replay recovered, {what}: {out}"
    );
    out_path
}

#[test]
fn damaged_cut_and_summary_damaged_logs_read_recover_and_replay() {
    let bytes = walk_log();
    let summary_start = summary_start();
    assert!(summary_start > bytes.len() / 2 && summary_start < bytes.len());
    // Zeroed 4 KiB in the middle of the file (compressed chunk data).
    let mid = bytes.len() / 2;
    let mut damaged = bytes.to_vec();
    damaged[mid..mid + 4096].fill(0);
    let (path, _) = write("middle.mcap", &damaged);
    every_reader_reads(&path, "middle");
    let middle = recovers(
        &path,
        "middle",
        &["lost 1 chunk", "messages t = ", "in all:"],
    );
    // The replay of the damaged file stops at the gap and says so.
    let (_, out, _) = adam(&["replay", &path.display().to_string()]);
    assert!(out.contains("missing (lost to damage)"), "{out}");

    // Cut off at 70 %: `plot portrait` draws it as `plot tiles` does.
    let (path, _) = write("cut.mcap", &bytes[..bytes.len() * 7 / 10]);
    every_reader_reads(&path, "cut");
    let cut = recovers(&path, "cut", &["cut off", "unknown"]);

    // Damage in the summary loses nothing; every command reads the file.
    let mut damaged = bytes.to_vec();
    damaged[summary_start + 40..summary_start + 104].fill(0);
    let (path, _) = write("summary.mcap", &damaged);
    every_reader_reads(&path, "summary");
    let summary = recovers(&path, "summary", &["no messages lost"]);

    python_reads(&[middle, cut, summary]);
}

#[test]
fn nothing_usable_left_is_a_clear_error_naming_the_file() {
    let (_, zeros) = write("zeros.mcap", &[0u8; 10_000]);
    for args in [
        vec!["logs", "info", &zeros],
        vec!["logs", "recover", &zeros],
        vec!["replay", &zeros],
        vec!["plot", "portrait", &zeros],
    ] {
        let (ok, out, err) = adam(&args);
        assert!(!ok, "{args:?}: {out}");
        assert!(
            err.contains(&zeros) && err.contains("not an MCAP file"),
            "{args:?}: {err}"
        );
    }
    // Only the start of a log: no message survives.
    let (_, head) = write("head.mcap", &walk_log()[..300]);
    let (ok, _, err) = adam(&["plot", "portrait", &head]);
    assert!(
        !ok && err.contains(&head) && err.contains("no /joints messages"),
        "{err}"
    );
    let (ok, _, err) = adam(&["replay", &head]);
    assert!(!ok && err.contains(&head), "{err}");
}

/// The recovered files read in the official Python reader, when it is installed.
fn python_reads(paths: &[PathBuf]) {
    let has_mcap = Command::new("python3")
        .args(["-c", "import mcap, zstandard"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_mcap {
        println!(
            "skipped the Python check: `python3 -c \"import mcap, zstandard\"` fails \
             (pip install mcap zstandard to run it)"
        );
        return;
    }
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/check_mcap.py");
    let mut args = vec![script.to_string()];
    for p in paths {
        let info = runtime::telemetry::log_read::read_info(p).expect("recovered log reads");
        let n: u64 = info.channels.iter().map(|c| c.messages).sum();
        args.push(format!("{}={n}", p.display()));
    }
    let out = Command::new("python3")
        .args(&args)
        .output()
        .expect("python3");
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
