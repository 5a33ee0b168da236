//! Every shipped gait walks as planned (issue #28 item 5): each gait file in `configs/gaits/`,
//! and each entry of each gait library there, is verified by `adam gait check`'s logic
//! (`planner::verify`: Newton on the Poincaré map of the closed loop) and its periodic orbit must
//! step within `planner::verify::PLAN_ACCURACY` (1 %) of the planned step duration and length.
//! A library entry's stored check (what `adam plan library` measured) must agree with the
//! re-verification too.
//!
//! No file is an exception: the runtime's default gait (`adam_codesign.json`) was the last, an
//! old uniform-mesh plan whose orbit stepped 3.55 % slower than planned, until it was re-planned
//! on the graded mesh (configs/gaits/README.md).

use model::gait::GaitFile;
use model::library::GaitLibrary;
use model::PlanarModel;
use planner::verify::{verify_gait, VerifyOptions, VerifyReport, PLAN_ACCURACY};
use std::path::{Path, PathBuf};

fn gaits_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/gaits")
}

/// One line of the printed table: the planned step against the verified orbit's.
fn row(what: &str, gait: &GaitFile, report: &VerifyReport) -> String {
    let (d, l) = report.plan_mismatch();
    format!(
        "{what}: planned {:.4} m in {:.4} s, orbit {:.4} m in {:.4} s ({:+.2} %, {:+.2} %)",
        gait.step_length_m,
        gait.step_duration_s,
        report.step_length_m,
        report.step_duration_s,
        100.0 * d,
        100.0 * l
    )
}

/// Verifies `gait` on `model`: a stable periodic orbit (the fixed point converged, |λ| < 1).
fn verify(what: &str, model: &PlanarModel, gait: &GaitFile) -> VerifyReport {
    let options = VerifyOptions::default();
    let report = verify_gait(model, gait, options)
        .unwrap_or_else(|e| panic!("{what}: the gait does not verify: {e}"));
    let failures = report.failures(options.fixed_point_tolerance);
    assert!(failures.is_empty(), "{what}: {failures:?}\n{report}");
    report
}

fn within_accuracy(report: &VerifyReport) -> bool {
    let (d, l) = report.plan_mismatch();
    d.abs() < PLAN_ACCURACY && l.abs() < PLAN_ACCURACY
}

#[test]
fn every_shipped_gait_steps_within_plan_accuracy_of_its_plan() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(gaits_dir())
        .expect("configs/gaits/ is readable")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    let (mut gaits, mut libraries) = (0, 0);
    let mut table = Vec::new();
    for path in &files {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("a UTF-8 file name")
            .to_string();
        let text = std::fs::read_to_string(path).expect("readable");
        let json: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        if json.get("entries").is_some() {
            libraries += 1;
            check_library(path, &name, &mut table);
        } else {
            gaits += 1;
            let (gait, model) =
                planner::verify::load_gait_and_robot(path).unwrap_or_else(|e| panic!("{e}"));
            let report = verify(&name, &model, &gait);
            let (d, l) = report.plan_mismatch();
            table.push(row(&name, &gait, &report));
            assert!(
                within_accuracy(&report),
                "{name}: orbit {:.4} m in {:.4} s against the plan's {:.4} m in {:.4} s \
                 ({:+.2} %, {:+.2} %; limit ±{:.0} %)",
                report.step_length_m,
                report.step_duration_s,
                gait.step_length_m,
                gait.step_duration_s,
                100.0 * d,
                100.0 * l,
                100.0 * PLAN_ACCURACY
            );
        }
    }
    println!("{}", table.join("\n"));
    // The shipped set: adam_walk.json and adam_codesign.json, and the library.
    assert!(
        gaits >= 2 && libraries >= 1,
        "{gaits} gaits, {libraries} libraries"
    );
}

/// Every entry of the library at `path`: its stored check within the accuracy, and the
/// re-verified orbit within it and equal to the stored one (to 1e-6 relative: the same
/// computation, on this machine).
fn check_library(path: &Path, name: &str, table: &mut Vec<String>) {
    let library = GaitLibrary::load(path).unwrap_or_else(|e| panic!("{e}"));
    let (urdf_path, urdf) = library.read_urdf(path).unwrap_or_else(|e| panic!("{e}"));
    let model = PlanarModel::from_urdf_str(&urdf, &urdf_path.display().to_string())
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        library.entries.len() >= 2,
        "{name}: {} entries",
        library.entries.len()
    );
    for (k, entry) in library.entries.iter().enumerate() {
        let what = format!("{name} entries[{k}] ({} m/s)", entry.speed_mps);
        let gait = &entry.gait;
        let stored = &entry.check;
        assert!(
            stored.duration_error(gait) < PLAN_ACCURACY
                && stored.length_error(gait) < PLAN_ACCURACY,
            "{what}: stored check {:.4} m in {:.4} s against {:.4} m in {:.4} s",
            stored.verified_step_length_m,
            stored.verified_step_duration_s,
            gait.step_length_m,
            gait.step_duration_s
        );
        let report = verify(&what, &model, gait);
        let (d, l) = report.plan_mismatch();
        assert!(
            within_accuracy(&report),
            "{what}: ({d:+.4}, {l:+.4})\n{report}"
        );
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
        assert!(
            rel(report.step_duration_s, stored.verified_step_duration_s) < 1e-6
                && rel(report.step_length_m, stored.verified_step_length_m) < 1e-6,
            "{what}: re-verified {:.6} m in {:.6} s, stored {:.6} m in {:.6} s",
            report.step_length_m,
            report.step_duration_s,
            stored.verified_step_length_m,
            stored.verified_step_duration_s
        );
        table.push(row(&what, gait, &report));
    }
}
