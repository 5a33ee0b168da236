//! Every file under `configs/` loads and validates with the loader its extension names.

use std::path::{Path, PathBuf};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("configs/ is readable") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            files(&path, out);
        } else {
            out.push(path);
        }
    }
}

#[test]
fn every_config_file_loads_and_validates() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut all = Vec::new();
    files(&root, &mut all);
    all.sort();
    let mut checked = 0;
    for path in &all {
        match path.extension().and_then(|e| e.to_str()) {
            Some("md") => continue,
            Some("urdf") => {
                let m = model::PlanarModel::from_urdf_file(path).unwrap_or_else(|e| panic!("{e}"));
                m.legs()
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            }
            // A gait library (`*_library.json`), checked against the URDF it names.
            Some("json") if path.to_string_lossy().ends_with("_library.json") => {
                let library =
                    model::library::GaitLibrary::load(path).unwrap_or_else(|e| panic!("{e}"));
                let (urdf_path, urdf) = library.read_urdf(path).unwrap_or_else(|e| panic!("{e}"));
                let origin = urdf_path.display().to_string();
                let robot = model::PlanarModel::from_urdf_str(&urdf, &origin)
                    .unwrap_or_else(|e| panic!("{e}"));
                library
                    .check_against(&robot, &urdf, &path.display().to_string(), &origin)
                    .unwrap_or_else(|e| panic!("{e}"));
            }
            // A Foxglove layout: its topics are checked against a log and the live server in
            // tests/live.rs.
            Some("json")
                if path.parent().and_then(|p| p.file_name()) == Some("foxglove".as_ref()) =>
            {
                let text = std::fs::read_to_string(path).expect("readable");
                let v: serde_json::Value = serde_json::from_str(&text)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                assert!(
                    v["configById"].is_object() && v["layout"].is_object(),
                    "{}",
                    path.display()
                );
            }
            Some("json") => {
                model::gait::GaitFile::load(path).unwrap_or_else(|e| panic!("{e}"));
            }
            Some("toml") => {
                let folder = path
                    .parent()
                    .and_then(|p| p.file_name())
                    .and_then(|f| f.to_str());
                match folder {
                    Some("runtime") => {
                        runtime::config::RuntimeConfig::load(path)
                            .unwrap_or_else(|e| panic!("{e}"));
                    }
                    Some("planner") => {
                        planner::config::PlannerConfig::load(path)
                            .unwrap_or_else(|e| panic!("{e}"));
                    }
                    Some("faults") => {
                        runtime::sim::faults::FaultProfile::load(path)
                            .unwrap_or_else(|e| panic!("{e}"));
                    }
                    _ => panic!(
                        "{}: TOML outside configs/runtime/, configs/planner/ or configs/faults/; add a loader",
                        path.display()
                    ),
                }
            }
            _ => panic!(
                "{}: no loader for this kind of file; add one to this test",
                path.display()
            ),
        }
        checked += 1;
    }
    assert!(
        checked >= 1,
        "no config files found under {}",
        root.display()
    );
}

/// `configs/runtime/adam_treadmill.toml` is `adam.toml` with speed control on: every section but
/// `[speed]` is the same but for the reference lead, the unbiased touchdown pitch and the
/// touchdown gate, so the two cannot drift apart.
#[test]
fn the_treadmill_config_is_the_shipped_config_but_for_its_speed_section() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/runtime");
    // Besides [speed], the treadmill config's own values: the 2.5 ms reference lead and the
    // unbiased touchdown pitch its walked-speed calibration was measured with, and the touchdown
    // gate its pushes ride through with (`runtime::estimator`, "The touchdown gate").
    let own: [(&str, &str, toml::Value); 4] = [
        ("walk", "reference_lead_s", toml::Value::Float(0.0025)),
        ("estimator", "encoder_lag_samples", toml::Value::Integer(1)),
        (
            "estimator",
            "touchdown_after_impact",
            toml::Value::Boolean(true),
        ),
        ("estimator", "touchdown_gate_rad", toml::Value::Float(0.01)),
    ];
    let read = |name: &str| -> toml::Table {
        let text = std::fs::read_to_string(dir.join(name)).expect(name);
        let mut table: toml::Table = text.parse().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            table.remove("speed").is_some(),
            "{name}: no [speed] section"
        );
        table
    };
    let (shipped, mut treadmill) = (read("adam.toml"), read("adam_treadmill.toml"));
    for (section, key, want) in &own {
        let table = treadmill
            .get_mut(*section)
            .and_then(|t| t.as_table_mut())
            .unwrap_or_else(|| panic!("adam_treadmill.toml: no [{section}]"));
        let got = table.remove(*key);
        assert_eq!(
            got.as_ref(),
            Some(want),
            "adam_treadmill.toml: {section}.{key}"
        );
        // adam.toml's value, if it has one, is the one the treadmill config replaces.
        if let Some(v) = shipped[*section].get(*key) {
            table.insert((*key).to_string(), v.clone());
        }
    }
    for (key, value) in &shipped {
        assert_eq!(
            treadmill.get(key),
            Some(value),
            "[{key}] of adam_treadmill.toml is not adam.toml's"
        );
    }
    let extra: Vec<_> = treadmill
        .keys()
        .filter(|k| !shipped.contains_key(*k))
        .collect();
    assert!(extra.is_empty(), "adam_treadmill.toml only: {extra:?}");
}
