//! The motor link across processes (issue #30): `adam emulate motors` in one process serves the
//! simulated robot over CAN-over-UDP, `adam run --backend udp` in another walks it for 20 s,
//! and the run's MCAP log holds the same raw CAN frames, tick for tick, as the in-process
//! `adam run --backend sim` run of the same seed (the emulator is lockstep: same physics).
//! `adam logs candump` writes them as a candump log.
#![allow(clippy::unwrap_used)]

use runtime::telemetry::frames_read::{read_frames, CanRow};
use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::adam;

fn temp(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("adam-udp-link-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(tag)
}

/// The frames of each (tick, operation), in a canonical order: the emulator's frames cross a
/// socket per bus, so their order between buses is not the in-process bus's.
fn by_tick(rows: &[CanRow]) -> BTreeMap<Option<u64>, Vec<String>> {
    let mut m: BTreeMap<Option<u64>, Vec<String>> = BTreeMap::new();
    for r in rows {
        m.entry(r.tick).or_default().push(format!(
            "{} {:?} {:X} {} {} {:02X?}",
            r.bus, r.direction, r.id, r.extended, r.remote, r.data
        ));
    }
    for v in m.values_mut() {
        v.sort();
    }
    m
}

/// The number after `key` in `text` (e.g. `steps 21`).
fn number_after(text: &str, key: &str) -> f64 {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("`{key}` not in:\n{text}"))
        + key.len();
    let word: String = text[at..]
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || "+-.".contains(*c))
        .collect();
    word.parse()
        .unwrap_or_else(|_| panic!("no number after `{key}` in:\n{text}"))
}

#[test]
fn the_runtime_walks_the_emulated_robot_over_udp_and_logs_the_in_process_frames() {
    let (mut emulator, out, addr) = common::spawn_emulator();

    let udp_log = temp("udp.mcap");
    let run = adam()
        .args([
            "run",
            "--backend",
            "udp",
            "--motors",
            &addr,
            "--duration",
            "20s",
        ])
        .arg("--log")
        .arg(&udp_log)
        .arg("--force")
        .output()
        .unwrap();
    let run_out = String::from_utf8_lossy(&run.stdout).to_string();
    let mut emulator_out = String::new();
    for line in out.lines() {
        emulator_out.push_str(&line.unwrap());
        emulator_out.push('\n');
    }
    let emulator_status = emulator.wait().unwrap();
    eprintln!(
        "{run_out}\n{}\n{emulator_out}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(run.status.success());
    assert!(emulator_status.success());
    // The runtime's summary: 20 s in Walk, no trip, no missing reply, an IMU sample each tick.
    assert!(run_out.contains("ran 20000 ticks"), "{run_out}");
    assert!(run_out.contains("final state walk"), "{run_out}");
    assert!(run_out.contains("safety trips: none"), "{run_out}");
    assert!(run_out.contains("missing replies 0"), "{run_out}");
    assert!(run_out.contains("20000 IMU samples"), "{run_out}");
    // The emulator's: no fall, the steps of a 20 s walk.
    assert!(emulator_out.contains("fall: none"), "{emulator_out}");
    assert!(emulator_out.contains("the host disabled every motor"));
    let steps = number_after(&emulator_out, "steps");
    assert!(steps >= 20.0, "{steps} steps");

    // The same walk in process: the same steps and end position, the same frames.
    let sim_log = temp("sim.mcap");
    let sim = adam()
        .args([
            "run",
            "--backend",
            "sim",
            "--duration",
            "20s",
            "--force",
            "--log",
        ])
        .arg(&sim_log)
        .output()
        .unwrap();
    let sim_out = String::from_utf8_lossy(&sim.stdout).to_string();
    assert!(sim.status.success(), "{sim_out}");
    assert_eq!(number_after(&sim_out, "steps"), steps, "{sim_out}");
    assert_eq!(
        number_after(&sim_out, "position on the belt at the end"),
        number_after(&emulator_out, "position on the belt"),
    );
    let udp_rows = read_frames(&udp_log).unwrap();
    let sim_rows = read_frames(&sim_log).unwrap();
    // Enable and a command and reply per leg motor and tick, then disable.
    assert_eq!(udp_rows.len(), 8 + 8 * 20_000 + 8);
    assert_eq!(udp_rows.len(), sim_rows.len());
    let (udp, sim) = (by_tick(&udp_rows), by_tick(&sim_rows));
    assert_eq!(udp.len(), sim.len());
    for (tick, frames) in &sim {
        assert_eq!(udp.get(tick), Some(frames), "tick {tick:?}");
    }

    // candump: one line per frame, can-utils' form.
    let dump = temp("udp.log");
    let c = adam()
        .args(["logs", "candump"])
        .arg(&udp_log)
        .arg("--out")
        .arg(&dump)
        .arg("--force")
        .output()
        .unwrap();
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    let text = std::fs::read_to_string(&dump).unwrap();
    assert_eq!(text.lines().count(), udp_rows.len());
    for line in text.lines().take(100) {
        let mut parts = line.split(' ');
        let (ts, iface, frame) = (parts.next(), parts.next(), parts.next());
        let ts = ts.unwrap();
        assert!(
            ts.starts_with('(') && ts.ends_with(')') && ts.contains('.'),
            "{line}"
        );
        assert!(iface.unwrap().starts_with("can"), "{line}");
        let (id, data) = frame.unwrap().split_once('#').unwrap();
        assert_eq!(id.len(), 3, "{line}");
        assert_eq!(data.len(), 16, "{line}");
        assert!(id
            .chars()
            .chain(data.chars())
            .all(|c| c.is_ascii_hexdigit()));
    }
    check_with_cantools(&udp_log);
    for p in [&udp_log, &sim_log, &dump] {
        let _ = std::fs::remove_file(p);
    }
}

/// `tests/python/check_candump.py` (cantools and the `mcap` package in its own venv) when
/// `ADAM_PYTHON_CHECKS=1` (it installs from PyPI; CI does not set it).
fn check_with_cantools(log: &Path) {
    if std::env::var("ADAM_PYTHON_CHECKS").as_deref() != Ok("1") {
        eprintln!("cantools check skipped (set ADAM_PYTHON_CHECKS=1 to run it)");
        return;
    }
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/check_candump.py");
    let out = Command::new("python3")
        .arg(script)
        .arg(env!("CARGO_BIN_EXE_adam"))
        .arg(log)
        .output()
        .unwrap();
    eprintln!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success());
}
