//! Where the shipped robots, gaits and configs are found, from any working directory.
//!
//! Every default input of `adam` is a path under `configs/` (e.g. `configs/runtime/adam.toml`),
//! and so are the files the README names. A relative `configs/…` input that exists from the
//! working directory is used as it is (running inside the repository changes nothing);
//! otherwise it is looked up in the config root, the first of
//!
//! 1. `$ADAM_CONFIG_DIR`, a folder laid out like the repository's `configs/` (when set, it is
//!    the only place searched);
//! 2. the `configs/` of the repository this binary was built from, if it is still there;
//! 3. the shipped files embedded in the binary, written once to
//!    `<temp dir>/adam-hzd-<version>/configs` (so an installed binary walks on its own).
//!
//! A path named inside a file resolves relative to that file (a gait's URDF, by
//! `runtime::Setup::load` and `planner::verify::load_gait_and_robot`), so a gait found here
//! finds its robot. Paths that are not under `configs/`, absolute paths and outputs are never
//! rewritten.

use std::path::{Path, PathBuf};

/// The shipped runtime config, the default of `run`, `demo`, `soak` and `op`.
pub(crate) const RUNTIME_CONFIG: &str = "configs/runtime/adam.toml";

/// The environment variable naming a config root.
pub(crate) const CONFIG_DIR_ENV: &str = "ADAM_CONFIG_DIR";

/// The files shipped in `configs/`, embedded: (path under `configs/`, contents).
const EMBEDDED: [(&str, &str); 18] = [
    (
        "runtime/adam.toml",
        include_str!("../../configs/runtime/adam.toml"),
    ),
    (
        "runtime/adam_treadmill.toml",
        include_str!("../../configs/runtime/adam_treadmill.toml"),
    ),
    (
        "foxglove/adam.json",
        include_str!("../../configs/foxglove/adam.json"),
    ),
    (
        "planner/adam.toml",
        include_str!("../../configs/planner/adam.toml"),
    ),
    (
        "planner/adam_default_gait.toml",
        include_str!("../../configs/planner/adam_default_gait.toml"),
    ),
    (
        "planner/adam_library.toml",
        include_str!("../../configs/planner/adam_library.toml"),
    ),
    (
        "gaits/adam_library.json",
        include_str!("../../configs/gaits/adam_library.json"),
    ),
    (
        "planner/adam_speeds_library.toml",
        include_str!("../../configs/planner/adam_speeds_library.toml"),
    ),
    (
        "robots/adam_codesign_speeds.urdf",
        include_str!("../../configs/robots/adam_codesign_speeds.urdf"),
    ),
    (
        "planner/adam_electrical.toml",
        include_str!("../../configs/planner/adam_electrical.toml"),
    ),
    (
        "robots/adam_planar_a1.urdf",
        include_str!("../../configs/robots/adam_planar_a1.urdf"),
    ),
    (
        "planner/five_link.toml",
        include_str!("../../configs/planner/five_link.toml"),
    ),
    (
        "gaits/adam_codesign.json",
        include_str!("../../configs/gaits/adam_codesign.json"),
    ),
    (
        "gaits/adam_walk.json",
        include_str!("../../configs/gaits/adam_walk.json"),
    ),
    (
        "robots/adam_planar.urdf",
        include_str!("../../configs/robots/adam_planar.urdf"),
    ),
    (
        "robots/adam_codesign.urdf",
        include_str!("../../configs/robots/adam_codesign.urdf"),
    ),
    (
        "robots/five_link_walker.urdf",
        include_str!("../../configs/robots/five_link_walker.urdf"),
    ),
    (
        "faults/example.toml",
        include_str!("../../configs/faults/example.toml"),
    ),
];

/// An input path, found as the module docs say; returned unchanged when it is not a relative
/// `configs/…` path, when it exists from the working directory, or when no root holds it (the
/// error that follows then names the path the user wrote).
pub(crate) fn input(path: &Path) -> PathBuf {
    let Ok(rest) = path.strip_prefix("configs") else {
        return path.to_path_buf();
    };
    if path.is_absolute() || path.exists() {
        return path.to_path_buf();
    }
    if let Some(root) = std::env::var_os(CONFIG_DIR_ENV) {
        let candidate = PathBuf::from(root).join(rest);
        return if candidate.exists() {
            candidate
        } else {
            path.to_path_buf()
        };
    }
    let built_in = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    if built_in.exists() {
        return built_in;
    }
    match embedded_root() {
        Some(root) if root.join(rest).exists() => root.join(rest),
        _ => path.to_path_buf(),
    }
}

/// A fault profile argument: a built-in name stays as it is, a `configs/…` TOML file is found
/// like any input.
pub(crate) fn fault_profile(name_or_path: &str) -> String {
    if name_or_path.ends_with(".toml") {
        input(Path::new(name_or_path)).display().to_string()
    } else {
        name_or_path.to_string()
    }
}

/// The embedded files written under `<temp dir>/adam-hzd-<version>/configs` (once per version;
/// a file whose contents differ is written again).
fn embedded_root() -> Option<PathBuf> {
    let root = std::env::temp_dir()
        .join(format!("adam-hzd-{}", env!("CARGO_PKG_VERSION")))
        .join("configs");
    write_embedded(&root).ok()?;
    Some(root)
}

/// Writes the embedded files under `root`, each through a temporary name and a rename so that
/// two processes never see half a file.
pub(crate) fn write_embedded(root: &Path) -> std::io::Result<()> {
    for (name, text) in EMBEDDED {
        let path = root.join(name);
        if std::fs::read_to_string(&path).is_ok_and(|t| t == text) {
            continue;
        }
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let partial = path.with_extension(format!("partial-{}", std::process::id()));
        std::fs::write(&partial, text)?;
        std::fs::rename(&partial, &path)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_files_are_the_shipped_ones_and_a_gait_among_them_finds_its_robot() {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
        for (name, text) in EMBEDDED {
            let shipped = std::fs::read_to_string(repo.join(name)).expect("shipped file");
            assert_eq!(shipped, text, "{name}");
        }
        let root = std::env::temp_dir()
            .join(format!("adam-embedded-{}", std::process::id()))
            .join("configs");
        write_embedded(&root).expect("written");
        write_embedded(&root).expect("written again, unchanged");
        let setup = runtime::Setup::load(
            root.join("runtime/adam.toml"),
            root.join("gaits/adam_codesign.json"),
        )
        .expect("the embedded config and gait load, the gait's URDF found beside it");
        assert!(setup.gait.speed_mps > 0.0);
        // A config that extends another finds its base, and the library, among them.
        let lab = root.join("runtime/lab.toml");
        std::fs::write(
            &lab,
            "extends = \"adam_treadmill.toml\"\n[speed]\nstart_on_plan = false\n",
        )
        .expect("written");
        let options = runtime::Setup::load(&lab, root.join("gaits/adam_codesign.json")).expect(
            "a config extending the embedded treadmill config, its base and its gait library load",
        );
        assert!(!options.config.speed.start_on_plan && !options.library.is_empty());
        let (_, robot) = planner::verify::load_gait_and_robot(&root.join("gaits/adam_walk.json"))
            .expect("the other gait and its robot");
        assert!(!robot.joints.is_empty());
        std::fs::remove_dir_all(root.parent().expect("parent")).ok();
    }

    #[test]
    fn every_shipped_file_is_embedded() {
        fn walk(dir: &Path, out: &mut Vec<String>, root: &Path) {
            for entry in std::fs::read_dir(dir).expect("readable") {
                let path = entry.expect("entry").path();
                if path.is_dir() {
                    walk(&path, out, root);
                } else if path.extension().is_some_and(|e| e != "md") {
                    let rel = path.strip_prefix(root).expect("under root");
                    out.push(rel.display().to_string());
                }
            }
        }
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
        let mut shipped = Vec::new();
        walk(&root, &mut shipped, &root);
        for name in shipped {
            assert!(
                EMBEDDED.iter().any(|(n, _)| *n == name),
                "configs/{name} is not embedded in cli::shipped"
            );
        }
    }

    #[test]
    fn only_missing_relative_configs_paths_are_looked_up() {
        for unchanged in ["logs/run.mcap", "/abs/configs/x.toml", "mine.toml"] {
            assert_eq!(input(Path::new(unchanged)), Path::new(unchanged));
        }
        assert_eq!(
            fault_profile("soak"),
            "soak",
            "a built-in profile name is a name"
        );
    }
}
