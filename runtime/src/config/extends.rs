//! `extends = "base.toml"`: a runtime config written as the changes to another. The file is
//! read as TOML; with a top-level `extends` (a file name, relative to this file's folder) its
//! base is read the same way (a chain of at most [`MAX_EXTENDS_DEPTH`] files) and this file's
//! values are laid over it: tables merge key by key, every other value (a number, a string, an
//! array, an array of tables such as `leg_motors`) replaces the base's whole. A path inside a
//! config (`speed.library`) is relative to the folder of the file that names it: a base's is
//! anchored to the base's folder as it is read (made absolute), so a config in any folder may
//! extend a shipped one; a path the extending file sets itself stays relative to that file.
//! What copies or hashes a config takes its chain along ([`extends_chain`]): a treadmill sweep
//! hashes every file of it; `adam calibrate`, which writes a copy of one whole config's text,
//! refuses a config that extends another, naming its base.

use crate::{Result, RuntimeError};
use std::path::{Path, PathBuf};

/// How many files one chain of `extends` may hold (a cycle ends here too).
pub const MAX_EXTENDS_DEPTH: usize = 8;

/// A config file as read: its own text, and its TOML laid over its `extends` chain.
pub(super) struct Merged {
    /// The file's own text (without a chain, what its errors' line numbers refer to).
    pub(super) text: String,
    /// The file's TOML laid over its bases (without `extends`).
    pub(super) value: toml::Value,
    /// The chain's files after the first, nearest first (empty: it extends none).
    pub(super) chain: Vec<PathBuf>,
}

/// Reads `path` and its `extends` chain.
pub(super) fn read_merged(path: &Path) -> Result<Merged> {
    let text = read_text(path)?;
    let mut chain = Vec::new();
    let value = merge_chain(path, &text, &mut chain)?;
    Ok(Merged { text, value, chain })
}

/// The files `path` extends, nearest first (empty: it extends none), each checked as
/// [`RuntimeConfig::load`](super::RuntimeConfig::load) checks it: what a copy or a content hash
/// of the config must carry along with it.
pub fn extends_chain(path: &Path) -> Result<Vec<PathBuf>> {
    Ok(read_merged(path)?.chain)
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|error| RuntimeError::Io {
        path: path.to_path_buf(),
        error,
    })
}

/// The TOML `text` of `path` laid over the chain it extends (each base pushed onto `chain`).
fn merge_chain(path: &Path, text: &str, chain: &mut Vec<PathBuf>) -> Result<toml::Value> {
    let origin = path.display().to_string();
    let mut value: toml::Value = toml::from_str(text).map_err(|e| RuntimeError::Parse {
        origin: origin.clone(),
        message: e.to_string(),
    })?;
    let Some(extends) = value.as_table_mut().and_then(|t| t.remove("extends")) else {
        return Ok(value);
    };
    let bad = |value: String, reason: String| RuntimeError::InvalidField {
        origin: origin.clone(),
        field: "extends".into(),
        value,
        reason,
    };
    let Some(name) = extends.as_str() else {
        return Err(bad(
            extends.to_string(),
            "must be a file name (a string), relative to this file's folder".into(),
        ));
    };
    if chain.len() + 1 >= MAX_EXTENDS_DEPTH {
        return Err(bad(
            format!("\"{name}\""),
            format!("more than {MAX_EXTENDS_DEPTH} configs chained (a cycle?): {chain:?}"),
        ));
    }
    let base_path = path.parent().unwrap_or(Path::new(".")).join(name);
    if !base_path.is_file() {
        return Err(bad(
            format!("\"{name}\""),
            format!("{} is not a readable file", base_path.display()),
        ));
    }
    chain.push(base_path.clone());
    let mut base = merge_chain(&base_path, &read_text(&base_path)?, chain)?;
    anchor_paths(&mut base, base_path.parent().unwrap_or(Path::new(".")));
    lay_over(&mut base, value);
    Ok(base)
}

/// The config's keys that hold a file path, relative to the folder of the file that sets them.
const PATH_KEYS: [(&str, &str); 1] = [("speed", "library")];

/// Makes the relative paths of `value` (a base's merged TOML) absolute from `dir`, the base's
/// folder (absolute paths, those of deeper bases included, are left as they are).
fn anchor_paths(value: &mut toml::Value, dir: &Path) {
    for (section, key) in PATH_KEYS {
        let Some(slot) = value.get_mut(section).and_then(|t| t.get_mut(key)) else {
            continue;
        };
        let Some(rel) = slot.as_str() else {
            continue; // the config's own check names a path that is not a string
        };
        if Path::new(rel).is_absolute() {
            continue;
        }
        // Absolute from the process's folder, so that the loaded file's folder does not
        // prefix it again.
        let dir = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
        *slot = toml::Value::String(dir.join(rel).display().to_string());
    }
}

/// Lays `over` onto `base`: tables key by key, anything else replaced.
fn lay_over(base: &mut toml::Value, over: toml::Value) {
    match (base, over) {
        (toml::Value::Table(b), toml::Value::Table(o)) => {
            for (key, value) in o {
                match b.get_mut(&key) {
                    Some(slot) if slot.is_table() && value.is_table() => lay_over(slot, value),
                    _ => {
                        b.insert(key, value);
                    }
                }
            }
        }
        (b, o) => *b = o,
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::config::RuntimeConfig;

    const CONFIGS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/runtime");

    /// A fresh folder for this test's files.
    fn folder(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("adam-extends-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A config in another folder that extends the shipped treadmill config by a path and
    /// changes two values is that config with those two changed, and its gait library anchored
    /// to the base's folder (the file is found); its chain names the base.
    #[test]
    fn a_config_extending_the_treadmill_config_is_it_with_its_own_values() {
        let base_path = format!("{CONFIGS}/adam_treadmill.toml");
        let base = RuntimeConfig::load(&base_path).unwrap();
        assert!(base.speed.start_on_plan && base.speed.max_step_lean_rad > 0.0);
        let dir = folder("lab");
        let path = dir.join("lab.toml");
        let text = format!(
            "extends = {base_path:?}\n[speed]\nstart_on_plan = false\nmax_step_lean_rad = 0.004\n"
        );
        std::fs::write(&path, text).unwrap();
        let lab = RuntimeConfig::load(&path).unwrap();
        let mut want = base.clone();
        want.speed.start_on_plan = false;
        want.speed.max_step_lean_rad = 0.004;
        let library = std::path::absolute(CONFIGS)
            .unwrap()
            .join(base.speed.library.as_deref().unwrap());
        want.speed.library = Some(library.display().to_string());
        assert_eq!(lab, want);
        assert!(library.is_file(), "{}", library.display());
        // Set in the extending file, a path is relative to that file.
        std::fs::write(
            &path,
            format!("extends = {base_path:?}\n[speed]\nlibrary = \"x.json\"\n"),
        )
        .unwrap();
        let own = RuntimeConfig::load(&path).unwrap();
        assert_eq!(own.speed.library.as_deref(), Some("x.json"));
        assert_eq!(extends_chain(&path).unwrap(), [PathBuf::from(&base_path)]);
        let none = extends_chain(Path::new(&base_path));
        assert!(none.unwrap().is_empty());
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A missing base, a base that is not a string, a chain that loops, a bad value laid over a
    /// good base, and `extends` in text with no file to find the base from: each refused,
    /// naming the file, `extends` or the field, and the value.
    #[test]
    fn a_bad_extends_is_refused_naming_the_file_the_field_and_the_value() {
        let dir = folder("bad");
        let write = |name: &str, text: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).unwrap();
            path
        };
        let shipped = std::fs::read_to_string(format!("{CONFIGS}/adam.toml")).unwrap();
        write("base.toml", &shipped);
        let cases = [
            (
                "missing.toml",
                "extends = \"nowhere.toml\"\n",
                &[
                    "missing.toml",
                    "extends",
                    "nowhere.toml",
                    "not a readable file",
                ][..],
            ),
            (
                "number.toml",
                "extends = 3\n",
                &["number.toml", "extends", "3", "a string"][..],
            ),
            (
                "a.toml",
                "extends = \"b.toml\"\n",
                &["extends", "cycle"][..],
            ),
            (
                "over.toml",
                "extends = \"base.toml\"\n[gains]\nkp_nm_per_rad = [150.0, -1.0, 150.0, 150.0]\n",
                &[
                    "over.toml (extends base.toml)",
                    "gains.kp_nm_per_rad[1]",
                    "-1",
                ][..],
            ),
            (
                "typo.toml",
                "extends = \"base.toml\"\n[speed]\nstart_on_plans = true\n",
                &["typo.toml (extends base.toml)", "start_on_plans"][..],
            ),
            (
                "kind.toml",
                "extends = \"base.toml\"\n[loop]\nrate_hz = \"fast\"\n",
                &["kind.toml (extends base.toml)", "loop.rate_hz", "\"fast\""][..],
            ),
        ];
        write("b.toml", "extends = \"a.toml\"\n");
        for (name, text, words) in cases {
            let path = write(name, text);
            let e = RuntimeConfig::load(&path).unwrap_err().to_string();
            for w in words {
                assert!(e.contains(w), "{name}: {w}: {e}");
            }
        }
        // A good overlay: one gain changed, the rest the base's.
        let path = write(
            "good.toml",
            "extends = \"base.toml\"\n[gains]\nkp_nm_per_rad = [100.0, 100.0, 100.0, 100.0]\n",
        );
        let good = RuntimeConfig::load(&path).unwrap();
        let mut want = RuntimeConfig::from_toml(&shipped, "adam.toml").unwrap();
        want.gains.kp_nm_per_rad = [100.0; 4];
        assert_eq!(good, want);
        // From text alone there is no folder to find a base in.
        let e = RuntimeConfig::from_toml("extends = \"base.toml\"\n", "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("t.toml") && e.contains("extends"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A config that extends none is read from its own text: an error's line number is the
    /// line of the file (not of the TOML written back from its parsed value, as it was).
    #[test]
    fn an_error_in_a_file_of_its_own_names_its_own_line() {
        let dir = folder("line");
        let shipped = std::fs::read_to_string(format!("{CONFIGS}/adam.toml")).unwrap();
        let anchor = "rate_hz = 1000.0";
        let line = 1 + shipped.lines().position(|l| l == anchor).unwrap();
        let path = dir.join("bad.toml");
        std::fs::write(&path, shipped.replacen(anchor, "rate_hz = \"fast\"", 1)).unwrap();
        let e = RuntimeConfig::load(&path).unwrap_err().to_string();
        assert!(
            e.contains("bad.toml") && e.contains(&format!("line {line},")) && e.contains("fast"),
            "line {line}: {e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn tables_merge_key_by_key_and_other_values_replace_the_base_s() {
        let mut base: toml::Value =
            toml::from_str("a = 1\nlist = [1, 2]\n[t]\nx = 1\ny = 2\n[t.u]\nz = 3\n").unwrap();
        let over: toml::Value = toml::from_str("list = [9]\n[t]\ny = 5\n[t.u]\nw = 4\n").unwrap();
        lay_over(&mut base, over);
        let want: toml::Value =
            toml::from_str("a = 1\nlist = [9]\n[t]\nx = 1\ny = 5\n[t.u]\nz = 3\nw = 4\n").unwrap();
        assert_eq!(base, want);
    }
}
