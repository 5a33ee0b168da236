//! File paths the commands derive: a gait file's reference to its URDF, output prefixes beside
//! an input, the demo's timestamped log; and the rule every written file follows.
//!
//! **Never over what ships.** Generated gaits, URDFs and sweeps go under [`OUT_DIR`] (`out/`
//! of the working directory, created if missing) unless the user names another path; a file
//! that exists is written over only with `--force` ([`writable`]). The shipped files under
//! `configs/` change only when a user names them and passes `--force`.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// The default output folder of `adam plan`, `adam codesign` and `adam codesign sweep`.
pub(crate) const OUT_DIR: &str = "out";

/// Checks that `path` may be written: it does not exist, or `force` is set; then creates its
/// folder. The error names the file and `--force`.
pub(crate) fn writable(path: &Path, force: bool) -> Result<()> {
    if path.exists() && !force {
        bail!(
            "{} exists: pass --force to write over it, or name another output",
            path.display()
        );
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    Ok(())
}

/// `target` as seen from the folder of `from` (for the gait file's robot reference).
pub(crate) fn relative_path(target: &std::path::Path, from: &std::path::Path) -> String {
    // A file that does not exist yet: its folder's canonical path joined with its name.
    let abs = |p: &std::path::Path| {
        std::fs::canonicalize(p)
            .or_else(|_| {
                let dir = match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => std::path::Path::new("."),
                };
                std::fs::canonicalize(dir).map(|d| d.join(p.file_name().unwrap_or_default()))
            })
            .unwrap_or_else(|_| p.to_path_buf())
    };
    let t = abs(target);
    let f = from.parent().map(abs).unwrap_or_default();
    let (tc, fc): (Vec<_>, Vec<_>) = (t.components().collect(), f.components().collect());
    let common = tc.iter().zip(&fc).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = vec!["..".to_string(); fc.len().saturating_sub(common)];
    parts.extend(
        tc[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    parts.join("/")
}

/// `logs/<UTC timestamp>.mcap`, e.g. `logs/20250101-120000.mcap`.
pub(crate) fn timestamped_log_path() -> PathBuf {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    PathBuf::from(format!(
        "logs/{year:04}{month:02}{day:02}-{:02}{:02}{:02}.mcap",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    ))
}

#[cfg(test)]
mod tests {
    use super::relative_path;
    use std::path::Path;

    #[test]
    fn relative_paths_between_config_folders_even_for_files_not_written_yet() {
        let dir = std::env::temp_dir().join(format!("adam-rel-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("configs/robots")).expect("dir");
        std::fs::create_dir_all(dir.join("configs/gaits")).expect("dir");
        let urdf = dir.join("configs/robots/new.urdf");
        let gait = dir.join("configs/gaits/new.json");
        assert_eq!(relative_path(&urdf, &gait), "../robots/new.urdf");
        std::fs::write(&urdf, "x").expect("write");
        assert_eq!(relative_path(&urdf, &gait), "../robots/new.urdf");
        assert_eq!(
            relative_path(
                Path::new("configs/robots/adam_planar.urdf"),
                Path::new("configs/gaits/g.json")
            ),
            "../robots/adam_planar.urdf"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
