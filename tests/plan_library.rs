//! `adam plan library` end to end: two speeds of the shipped robot planned, the table printed,
//! the library written and loadable, and an existing output refused without `--force`.

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

#[test]
fn plan_library_writes_a_library_of_the_speeds_asked_for() {
    let dir = std::env::temp_dir().join(format!("adam-plan-library-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out = dir.join("lib.json");
    let out_arg = out.display().to_string();
    let (ok, stdout, stderr) = adam(&[
        "plan",
        "library",
        "--speeds",
        "0.2,0.225",
        "--out",
        &out_arg,
    ]);
    println!("{stdout}{stderr}");
    assert!(ok, "{stderr}");
    for words in [
        "max|λ|", "T err %", "  0.200 ", "  0.225 ", "wrote", "2 gaits",
    ] {
        assert!(stdout.contains(words), "{words}: {stdout}");
    }
    let library = model::library::GaitLibrary::load(&out).expect("loads");
    let speeds: Vec<f64> = library.entries.iter().map(|e| e.speed_mps).collect();
    assert_eq!(speeds, vec![0.2, 0.225]);
    // The URDF it names, from its own folder, is the shipped robot.
    let (_, urdf) = library.read_urdf(&out).expect("its URDF");
    let shipped = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/configs/robots/adam_codesign.urdf"
    ))
    .expect("shipped URDF");
    assert_eq!(urdf, shipped);
    let (ok, _, stderr) = adam(&["plan", "library", "--speeds", "0.2", "--out", &out_arg]);
    assert!(
        !ok && stderr.contains("--force") && stderr.contains("lib.json"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
