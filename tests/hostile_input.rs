//! Hostile input (issue #8): every loader of a file a user hands us (gait JSON, runtime and
//! planner TOML, URDF) answers arbitrary and mutated input with `Ok` or an error that names the
//! source, never a panic. Inputs: random bytes, and the shipped files with bytes deleted,
//! duplicated or replaced, and numbers replaced by extreme values. And the MCAP log readers
//! (`runtime::telemetry::log_read`: `read_info`, `recover`, `joint_series`) fed a real log of a short
//! simulated walk, cut off, with bytes overwritten, deleted or duplicated: never a panic, and
//! every error names the file.

use proptest::prelude::*;

fn shipped(path: &str) -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/").to_string() + path)
        .expect("shipped file")
}

/// An edit of a text: delete a span, duplicate a span, overwrite a byte, or replace the number
/// at some position with an extreme value.
#[derive(Clone, Debug)]
enum Edit {
    Delete(usize, usize),
    Duplicate(usize, usize),
    Overwrite(usize, u8),
    Number(usize, &'static str),
}

fn edit() -> impl Strategy<Value = Edit> {
    let extreme = prop::sample::select(vec![
        "1e308",
        "-1e308",
        "1e-320",
        "0",
        "-0",
        "NaN",
        "inf",
        "-1",
        "99999999999999999999",
        "0.0000001",
        "\"x\"",
        "[]",
        "{}",
        "true",
        "null",
    ]);
    prop_oneof![
        (any::<usize>(), 1usize..64).prop_map(|(a, n)| Edit::Delete(a, n)),
        (any::<usize>(), 1usize..64).prop_map(|(a, n)| Edit::Duplicate(a, n)),
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| Edit::Overwrite(a, b)),
        (any::<usize>(), extreme).prop_map(|(a, v)| Edit::Number(a, v)),
    ]
}

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut bytes = text.as_bytes().to_vec();
    for e in edits {
        if bytes.is_empty() {
            break;
        }
        let len = bytes.len();
        match *e {
            Edit::Delete(a, n) => {
                let a = a % len;
                bytes.drain(a..(a + n).min(len));
            }
            Edit::Duplicate(a, n) => {
                let a = a % len;
                let span: Vec<u8> = bytes[a..(a + n).min(len)].to_vec();
                bytes.splice(a..a, span);
            }
            Edit::Overwrite(a, b) => bytes[a % len] = b,
            Edit::Number(a, v) => {
                // The first number at or after `a` (wrapping) is replaced by `v`.
                let start = (0..len)
                    .map(|k| (a + k) % len)
                    .find(|&k| bytes[k].is_ascii_digit());
                if let Some(s) = start {
                    let mut end = s;
                    while end < len
                        && (bytes[end].is_ascii_digit() || b".eE+-".contains(&bytes[end]))
                    {
                        end += 1;
                    }
                    bytes.splice(s..end, v.bytes());
                }
            }
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn gait_files_never_panic(edits in prop::collection::vec(edit(), 1..4)) {
        let text = apply(&shipped("configs/gaits/adam_codesign.json"), &edits);
        if let Err(e) = model::gait::GaitFile::from_json(&text, "hostile.json") {
            prop_assert!(e.to_string().contains("hostile.json"), "{e}");
        }
    }

    #[test]
    fn runtime_configs_never_panic(edits in prop::collection::vec(edit(), 1..4)) {
        let text = apply(&shipped("configs/runtime/adam.toml"), &edits);
        if let Err(e) = runtime::config::RuntimeConfig::from_toml(&text, "hostile.toml") {
            prop_assert!(e.to_string().contains("hostile.toml"), "{e}");
        }
    }

    #[test]
    fn planner_configs_never_panic(edits in prop::collection::vec(edit(), 1..4)) {
        let text = apply(&shipped("configs/planner/adam.toml"), &edits);
        if let Err(e) = planner::config::PlannerConfig::from_toml(&text, "hostile.toml") {
            prop_assert!(e.to_string().contains("hostile.toml"), "{e}");
        }
    }

    #[test]
    fn urdfs_never_panic(edits in prop::collection::vec(edit(), 1..4)) {
        let text = apply(&shipped("configs/robots/adam_codesign.urdf"), &edits);
        if let Err(e) = model::PlanarModel::from_urdf_str(&text, "hostile.urdf") {
            prop_assert!(e.to_string().contains("hostile.urdf"), "{e}");
        }
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        let text = String::from_utf8_lossy(&bytes);
        prop_assert!(model::gait::GaitFile::from_json(&text, "r").is_err());
        let _ = runtime::config::RuntimeConfig::from_toml(&text, "r");
        let _ = planner::config::PlannerConfig::from_toml(&text, "r");
        prop_assert!(model::PlanarModel::from_urdf_str(&text, "r").is_err());
    }
}

/// A real log: 0.3 s of simulated walking (≈ 300 samples on every channel), written once.
fn real_log() -> &'static [u8] {
    static LOG: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    LOG.get_or_init(|| {
        let setup = runtime::Setup::shipped().expect("shipped setup");
        let path = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("hostile-real-{}.mcap", std::process::id()));
        let mut options = runtime::sim::run::SimWalkOptions::new(0.3);
        options.log_path = Some(path.clone());
        runtime::sim::run::walk(&setup, &options).expect("short walk");
        let bytes = std::fs::read(&path).expect("log written");
        // Held in memory from here: the file would only pile up in target/tmp.
        std::fs::remove_file(&path).ok();
        bytes
    })
}

/// A byte-level edit of a log.
#[derive(Clone, Debug)]
enum LogEdit {
    Truncate(usize),
    Overwrite(usize, u8),
    Delete(usize, usize),
    Duplicate(usize, usize),
}

fn log_edit() -> impl Strategy<Value = LogEdit> {
    prop_oneof![
        any::<usize>().prop_map(LogEdit::Truncate),
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| LogEdit::Overwrite(a, b)),
        (any::<usize>(), 1usize..256).prop_map(|(a, n)| LogEdit::Delete(a, n)),
        (any::<usize>(), 1usize..256).prop_map(|(a, n)| LogEdit::Duplicate(a, n)),
    ]
}

fn apply_log(bytes: &[u8], edits: &[LogEdit]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for e in edits {
        let len = b.len();
        if len == 0 {
            break;
        }
        match *e {
            LogEdit::Truncate(a) => b.truncate(a % len),
            LogEdit::Overwrite(a, v) => b[a % len] = v,
            LogEdit::Delete(a, n) => {
                let a = a % len;
                b.drain(a..(a + n).min(len));
            }
            LogEdit::Duplicate(a, n) => {
                let a = a % len;
                let span: Vec<u8> = b[a..(a + n).min(len)].to_vec();
                b.splice(a..a, span);
            }
        }
    }
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn mcap_readers_never_panic_on_damaged_logs(edits in prop::collection::vec(log_edit(), 1..4)) {
        let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
        // One file per test thread: proptest runs cases in sequence, tests run in parallel.
        let path = dir.join("hostile-damaged.mcap");
        let out = dir.join("hostile-recovered.mcap");
        std::fs::write(&path, apply_log(real_log(), &edits)).expect("write");
        let name = "hostile-damaged.mcap";
        if let Err(e) = runtime::telemetry::log_read::read_info(&path) {
            prop_assert!(e.to_string().contains(name), "read_info: {e}");
        }
        if let Err(e) = runtime::telemetry::log_read::joint_series(&path) {
            prop_assert!(e.to_string().contains(name), "joint_series: {e}");
        }
        match runtime::telemetry::log_read::recover(&path, &out) {
            Ok(_) => {
                // What recover writes reads back whole.
                let info = runtime::telemetry::log_read::read_info(&out);
                prop_assert!(info.as_ref().is_ok_and(|i| i.truncated.is_none()), "{info:?}");
            }
            Err(e) => {
                let m = e.to_string();
                prop_assert!(m.contains(name) || m.contains("hostile-recovered.mcap"), "recover: {m}");
            }
        }
    }
}

#[test]
fn the_undamaged_log_reads_whole() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join("hostile-intact.mcap");
    std::fs::write(&path, real_log()).expect("write");
    let info = runtime::telemetry::log_read::read_info(&path).expect("reads");
    assert_eq!(info.truncated, None);
    assert_eq!(info.count("/joints"), 300);
    let series = runtime::telemetry::log_read::joint_series(&path).expect("series");
    assert_eq!(series.t_s.len(), 300);
}
