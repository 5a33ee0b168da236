//! The gait library file: a round trip through `save` and `load`, errors that name the file,
//! the entry, the field and the value, and the check against the robot it is to run on.

use model::gait::GaitFile;
use model::library::*;
use model::PlanarModel;
use std::path::{Path, PathBuf};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// A library of the shipped co-designed gait, at `speeds` (each gait's length moved to v·T).
fn library(speeds: &[f64]) -> GaitLibrary {
    let gait = GaitFile::load(format!("{ROOT}/configs/gaits/adam_codesign.json")).expect("gait");
    let entries = speeds
        .iter()
        .map(|&v| {
            let mut g = gait.clone();
            g.step_length_m = v * g.step_duration_s;
            g.speed_mps = v;
            LibraryEntry {
                speed_mps: v,
                check: LibraryCheck {
                    eigenvalues: vec![[0.8, 0.0], [0.1, 0.2], [0.1, -0.2]],
                    spectral_radius: 0.8,
                    fixed_point_residual: 3e-9,
                    verified_step_length_m: g.step_length_m * 1.001,
                    verified_step_duration_s: g.step_duration_s * 0.999,
                    apex_margin: Some(0.08),
                },
                gait: g,
            }
        })
        .collect();
    GaitLibrary {
        schema_version: LIBRARY_SCHEMA_VERSION,
        robot: gait.robot.clone(),
        entries,
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("adam-library-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

#[test]
fn a_library_round_trips_through_its_file() {
    let lib = library(&[0.15, 0.175, 0.2]);
    let path = scratch("round_trip.json");
    lib.save(&path).expect("saves");
    let back = GaitLibrary::load(&path).expect("loads");
    assert_eq!(back, lib);
    let text = std::fs::read_to_string(&path).expect("text");
    assert!(text.contains("\"schema_version\": 1") && text.contains("verified_step_duration_s"));
    assert!(text.contains("\"apex_margin\": 0.08"), "{text}");
    // A library written before the apex margin was recorded loads, without one.
    let mut old = lib.clone();
    for e in &mut old.entries {
        e.check.apex_margin = None;
    }
    let old_path = scratch("round_trip_no_margin.json");
    old.save(&old_path).expect("saves");
    let old_text = std::fs::read_to_string(&old_path).expect("text");
    assert!(!old_text.contains("apex_margin"));
    assert_eq!(GaitLibrary::load(&old_path).expect("loads"), old);
    // The shipped robot's URDF is the one the library names, relative to the library's folder
    // (the shipped gait names `../robots/…` from configs/gaits/).
    let shipped = Path::new(ROOT).join("configs/gaits/library.json");
    let (urdf_path, urdf) = lib.read_urdf(&shipped).expect("urdf");
    let robot = PlanarModel::from_urdf_str(&urdf, &urdf_path.display().to_string()).expect("robot");
    lib.check_against(&robot, &urdf, "library.json", "adam_codesign.urdf")
        .expect("the library's own robot");
}

#[test]
fn a_library_saved_with_a_bad_entry_is_refused_before_writing() {
    let mut lib = library(&[0.2, 0.25]);
    lib.entries[1].speed_mps = 0.2;
    lib.entries[1].gait.step_length_m = 0.2 * lib.entries[1].gait.step_duration_s;
    let path = scratch("refused.json");
    let e = lib.save(&path).expect_err("duplicate").to_string();
    assert!(
        e.contains("refused.json")
            && e.contains("entries[1].speed_mps")
            && e.contains("duplicates"),
        "{e}"
    );
    assert!(!path.exists(), "nothing written");
}

#[test]
fn load_errors_name_the_file_the_entry_and_the_value() {
    let lib = library(&[0.15, 0.2, 0.25]);
    let text = serde_json::to_string_pretty(&lib).expect("json");
    for (what, edit, words) in [
        (
            "unsorted",
            Box::new(|l: &mut GaitLibrary| l.entries.swap(0, 2)) as Box<dyn Fn(&mut GaitLibrary)>,
            &[
                "entries[1].speed_mps",
                "0.2",
                "is below",
                "entries[0].speed_mps = 0.25",
            ][..],
        ),
        (
            "a foreign gait",
            Box::new(|l: &mut GaitLibrary| {
                l.entries[2].gait.robot.name = "five_link_walker".into();
                l.entries[2].gait.robot.sha256 = "0".repeat(64);
            }),
            &[
                "entries[2].gait.robot",
                "'five_link_walker'",
                "'adam_planar'",
            ][..],
        ),
        (
            "a negative speed",
            Box::new(|l: &mut GaitLibrary| l.entries[0].speed_mps = -0.15),
            &["entries[0].speed_mps", "-0.15", "positive"][..],
        ),
        (
            "a NaN eigenvalue",
            Box::new(|l: &mut GaitLibrary| l.entries[1].check.eigenvalues[2][1] = f64::NAN),
            &["entries[1].check.eigenvalues[2][1]", "NaN"][..],
        ),
    ] {
        let mut bad = lib.clone();
        edit(&mut bad);
        // NaN is not JSON: write `null`'s stand-in the way a broken writer would, as a string
        // the parser refuses, or validate directly.
        let origin = format!("{what}.json");
        let e = match serde_json::to_string(&bad) {
            Ok(t) if !t.contains("null") => GaitLibrary::from_json(&t, &origin),
            _ => bad.validate(&origin).map(|_| bad.clone()),
        }
        .expect_err(what)
        .to_string();
        assert!(e.contains(&origin), "{what}: {e}");
        for w in words {
            assert!(e.contains(w), "{what}: {w}: {e}");
        }
    }
    let future = text.replacen("\"schema_version\": 1", "\"schema_version\": 2", 1);
    let e = GaitLibrary::from_json(&future, "future.json")
        .expect_err("version")
        .to_string();
    assert!(
        e.contains("future.json") && e.contains("schema_version") && e.contains('2'),
        "{e}"
    );
    let typo = text.replacen("\"speed_mps\": 0.2,", "\"speed_mps\": \"fast\",", 1);
    let e = GaitLibrary::from_json(&typo, "typo.json")
        .expect_err("type")
        .to_string();
    assert!(e.contains("typo.json") && e.contains("line"), "{e}");
    let e = GaitLibrary::load("no/such/library.json")
        .expect_err("missing")
        .to_string();
    assert!(e.contains("no/such/library.json"), "{e}");
}

/// A library checked against another robot's URDF names both robots (by name and hash).
#[test]
fn a_library_meets_another_robot_and_names_both() {
    let lib = library(&[0.2]);
    let path = format!("{ROOT}/configs/robots/five_link_walker.urdf");
    let urdf = std::fs::read_to_string(&path).expect("urdf");
    let robot = PlanarModel::from_urdf_str(&urdf, &path).expect("robot");
    let e = lib
        .check_against(&robot, &urdf, "adam_library.json", "five_link_walker.urdf")
        .expect_err("another robot")
        .to_string();
    assert!(
        e.contains("adam_library.json")
            && e.contains("'adam_planar'")
            && e.contains(&format!("'{}'", robot.name))
            && e.contains(&lib.robot.sha256)
            && e.contains("five_link_walker.urdf"),
        "{e}"
    );
}
