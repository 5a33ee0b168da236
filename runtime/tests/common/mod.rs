//! What the speed-control tests share: the shipped setup with the test gait library.

use runtime::Setup;
use std::path::{Path, PathBuf};

/// The shipped setup with the gaits of `runtime/tests/fixtures/library/` (0.15–0.35 m/s,
/// planned with `adam plan` at pinned step lengths and 0.8 s steps), sorted by speed.
pub fn library_setup() -> Setup {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/library");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("library fixtures")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    let mut gaits: Vec<_> = files
        .iter()
        .map(|p| model::gait::GaitFile::load(p).expect("a library gait"))
        .collect();
    gaits.sort_by(|a, b| a.speed_mps.total_cmp(&b.speed_mps));
    let origins: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
    Setup::shipped()
        .expect("shipped setup")
        .with_library(gaits, &origins)
        .expect("library")
}
