//! Treadmill speed control on the simulated robot: a library of gaits at 0.15–0.35 m/s
//! (`runtime/tests/fixtures/library/`, planned with `adam plan` at pinned step lengths and
//! 0.8 s steps until the planner's `adam plan library` ships one), the controller switching
//! between them at impacts, the step-to-step regulator and the belt-position loop.

use runtime::sim::faults::{Fault, FaultEvent, FaultProfile};
use runtime::sim::run::{walk, SimWalkOptions};
use runtime::telemetry::speed_read::{read_speed, SpeedRow};
use runtime::Setup;
use std::path::{Path, PathBuf};

mod common;

/// The shipped setup with the test library, starting on the library gait nearest `belt_mps`.
fn setup_at(belt_mps: f64) -> Setup {
    common::library_setup().starting_near(belt_mps)
}

fn temp_log(tag: &str) -> PathBuf {
    std::env::temp_dir().join(format!("adam-speed-{tag}-{}.mcap", std::process::id()))
}

/// Walks `duration_s` on a belt at `belt_mps` (with `events` from the fault profile), seed
/// `seed`; returns the report and the `/speed` rows. With `logged`, the run also writes a log,
/// and its `/speed` messages must read back as the summary's rows, row for row; without, the
/// rows come from the summary alone (a 60 s log is some 60 MB to write and read).
fn run(
    belt_mps: f64,
    duration_s: f64,
    seed: u64,
    events: Vec<FaultEvent>,
    logged: bool,
) -> (runtime::sim::run::SimWalkReport, Vec<SpeedRow>) {
    let setup = setup_at(belt_mps);
    let mut options = SimWalkOptions::new(duration_s);
    options.belt_speed_mps = Some(belt_mps);
    options.seed = seed;
    let log = temp_log(&format!("{belt_mps}-{seed}"));
    if logged {
        options.log_path = Some(log.clone());
    }
    if !events.is_empty() {
        let mut profile = FaultProfile::none();
        profile.events = events;
        options.faults = Some(profile);
    }
    let report = walk(&setup, &options).expect("walk");
    let kept = report.summary.speed_rows.clone();
    assert_eq!(
        report.summary.speed_rows_dropped, 0,
        "the summary kept every row"
    );
    assert!(!kept.is_empty(), "speed control ran");
    if logged {
        let rows = read_speed(&log).expect("speed rows");
        let _ = std::fs::remove_file(&log);
        assert_eq!(
            kept.len(),
            rows.len(),
            "as many rows in the summary as in the log"
        );
        for (k, (a, b)) in kept.iter().zip(&rows).enumerate() {
            assert!(
                same_row(a, b),
                "row {k}: the summary's {a:?}, the log's {b:?}"
            );
        }
    }
    (report, kept)
}

/// Whether two rows hold the same values, NaN equal to NaN.
fn same_row(a: &SpeedRow, b: &SpeedRow) -> bool {
    let eq = |x: f64, y: f64| x == y || (x.is_nan() && y.is_nan());
    eq(a.t_s, b.t_s)
        && eq(a.belt_mps, b.belt_mps)
        && eq(a.commanded_mps, b.commanded_mps)
        && eq(a.requested_mps, b.requested_mps)
        && eq(a.step_speed_mps, b.step_speed_mps)
        && eq(a.position_m, b.position_m)
        && eq(a.true_position_m, b.true_position_m)
        && eq(a.library_mps, b.library_mps)
        && a.clamped == b.clamped
}

fn print(rows: &[SpeedRow]) {
    for r in rows {
        eprintln!(
            "t {:7.3} belt {:.3} cmd {:.3} step {:.3} lib {:.3} p_est {:+.3} p_true {:+.3}",
            r.t_s,
            r.belt_mps,
            r.commanded_mps,
            r.step_speed_mps,
            r.library_mps,
            r.position_m,
            r.true_position_m
        );
    }
}

/// Largest |true position on the belt| after `after_s`, m.
fn max_position_after(rows: &[SpeedRow], after_s: f64) -> f64 {
    rows.iter()
        .filter(|r| r.t_s > after_s)
        .map(|r| r.true_position_m.abs())
        .fold(0.0, f64::max)
}

/// Belt at 0.25 m/s for 60 s: no fall, no trip, the walking speed over the belt within 2 % of
/// the belt's (the acceptance threshold), and within ±0.16 m of the belt centre after 10 s,
/// seeds 1–5 (measured with the step lever and the shipped gains, 2026-12-05: 0.147, 0.127,
/// 0.110, 0.115, 0.123 m; before the lever: 0.146, 0.133, 0.129, 0.121, 0.125 m; with σ
/// following the belt speed instead of the command, the removed `command_share = 0`: 0.139–0.188 m). The
/// issue's ±0.10 m is not met yet: the library's gaits walk up to 30 % faster than planned in
/// the simulator (0.25 → 0.29 m/s, 0.30 → 0.38 m/s open loop).
/// Gains tried with the law before the lever over seeds 1–5 (k_p, k_s, k_i, σ rate; worst
/// |position|): its defaults 0.3, 0.5, 0.1, 0.02 m/s → 0.146 m; k_i 0.03 → 0.168; k_i 0.2 →
/// 0.160; k_p 0.2 → 0.170; k_p 0.5, k_i 0.03 → 0.195; k_s 0.8 → 0.162; rate 0.03 → 0.135,
/// rate 0.04 → 0.135, but rate 0.04 with k_i 0.2 or with k_p 0.4 fell in 2 of 5 seeds.
#[test]
fn walks_a_belt_at_a_quarter_metre_per_second_at_the_belt_speed() {
    for seed in 1..=5 {
        // One logged run checks the log against the summary; the rest read the summary.
        let (report, rows) = run(0.25, 60.0, seed, Vec::new(), seed == 1);
        let max_p = max_position_after(&rows, 10.0);
        eprintln!(
            "seed {seed}: speed {:.4} m/s, max |position| after 10 s {max_p:.3} m, {} steps",
            report.speed_mps, report.steps
        );
        assert!(report.fall.is_none(), "seed {seed}: {:?}", report.fall);
        assert_eq!(report.summary.trip, None, "seed {seed}");
        assert!(
            (report.speed_mps - 0.25).abs() <= 0.02 * 0.25,
            "seed {seed}: walked {:.4} m/s on a 0.25 m/s belt",
            report.speed_mps
        );
        assert!(max_p < 0.16, "seed {seed}: {max_p:.3} m from the centre");
        // The estimate follows the truth (leg odometry drifts slowly).
        let last = rows.last().expect("rows");
        assert!(
            (last.position_m - last.true_position_m).abs() < 0.15,
            "seed {seed}: estimate {:.3} m, truth {:.3} m",
            last.position_m,
            last.true_position_m
        );
        // Speed control switched gaits: the library speed in use moved.
        let (lo, hi) = rows.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), r| {
            (a.min(r.library_mps), b.max(r.library_mps))
        });
        assert!(
            hi - lo > 0.01,
            "seed {seed}: library speed stayed in [{lo}, {hi}]"
        );
    }
}

/// A belt step 0.20 → 0.30 → 0.20 m/s (the simulator's belt stepping at 20 s and back at 40 s,
/// the operator telling the controller): no fall, no trip, and the walking speed follows.
#[test]
fn follows_a_belt_step_up_and_back() {
    let step = FaultEvent {
        at_s: 20.0,
        duration_s: 20.0,
        fault: Fault::BeltSpeed { speed_mps: 0.30 },
    };
    let (report, rows) = run(0.20, 60.0, 1, vec![step], false);
    print(&rows);
    eprintln!("{report}");
    assert!(report.fall.is_none(), "{:?}", report.fall);
    assert_eq!(report.summary.trip, None);
    let mean = |from: f64, to: f64| {
        let r: Vec<_> = rows
            .iter()
            .filter(|r| r.t_s > from && r.t_s <= to)
            .collect();
        r.iter().map(|r| r.step_speed_mps).sum::<f64>() / r.len() as f64
    };
    let (before, during, after) = (mean(10.0, 20.0), mean(30.0, 40.0), mean(50.0, 60.0));
    eprintln!("mean step speed: {before:.3} / {during:.3} / {after:.3} m/s");
    assert!((during - 0.30).abs() < 0.03, "{during}");
    assert!((after - 0.20).abs() < 0.03, "{after}");
}

/// The test library as a library file ([`model::library::GaitLibrary`]) in `dir`, its URDF
/// named by absolute path; the checks are those `adam plan` printed for each gait (|λ|max,
/// verified step length and duration).
fn write_library_file(dir: &Path, robot_name: &str) -> PathBuf {
    use model::library::{GaitLibrary, LibraryCheck, LibraryEntry};
    let checks = [
        (0.9405, 0.1201, 0.8582),
        (0.9256, 0.1401, 0.8321),
        (0.9080, 0.1601, 0.8236),
        (0.8921, 0.1800, 0.8069),
        (0.8745, 0.2000, 0.7977),
        (0.8595, 0.2200, 0.7969),
        (0.8494, 0.2399, 0.7938),
        (0.8460, 0.2599, 0.7933),
        (0.8266, 0.2798, 0.7905),
    ];
    let setup = common::library_setup();
    let mut robot = setup.gait.robot.clone();
    robot.name = robot_name.to_string();
    robot.urdf = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../configs/robots/adam_codesign.urdf")
        .display()
        .to_string();
    let entries = setup
        .library
        .iter()
        .zip(checks)
        .map(|(g, (radius, length, duration))| {
            let mut gait = g.clone();
            gait.robot.name = robot_name.to_string();
            LibraryEntry {
                speed_mps: g.speed_mps,
                gait,
                check: LibraryCheck {
                    eigenvalues: vec![[radius, 0.0]],
                    spectral_radius: radius,
                    fixed_point_residual: 1e-9,
                    verified_step_length_m: length,
                    verified_step_duration_s: duration,
                    apex_margin: None,
                },
            }
        })
        .collect();
    let library = GaitLibrary {
        schema_version: model::library::LIBRARY_SCHEMA_VERSION,
        robot,
        entries,
    };
    let path = dir.join(format!("library-{robot_name}.json"));
    library.save(&path).expect("save the library");
    path
}

/// A library file named by the runtime config's `speed.library` loads with the setup; one of
/// another robot is refused, the error naming both robots.
#[test]
fn the_config_names_a_library_file_and_one_of_another_robot_is_refused() {
    let dir = std::env::temp_dir().join(format!("adam-speed-library-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let config_text =
        std::fs::read_to_string(root.join("configs/runtime/adam.toml")).expect("config");
    let gait = root.join(runtime::DEFAULT_GAIT);
    let robot = common::library_setup().gait.robot.name.clone();
    let good = write_library_file(&dir, &robot);
    let config = dir.join("runtime.toml");
    let with_library = |library: &Path| {
        config_text.replace(
            "[speed]\n",
            &format!("[speed]\nlibrary = \"{}\"\n", library.display()),
        )
    };
    std::fs::write(&config, with_library(&good)).expect("write config");
    let setup = Setup::load(&config, &gait).expect("setup with its library");
    assert_eq!(setup.library.len(), 9);
    assert!(
        (setup.library[0].speed_mps - 0.15).abs() < 1e-3
            && (setup.library[8].speed_mps - 0.35).abs() < 1e-3
    );
    let bad = write_library_file(&dir, "other_robot");
    std::fs::write(&config, with_library(&bad)).expect("write config");
    let err = Setup::load(&config, &gait)
        .expect_err("a library of another robot")
        .to_string();
    assert!(
        err.contains("other_robot") && err.contains(&robot),
        "the error names both robots: {err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
