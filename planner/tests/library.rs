//! Gaits at a speed: the `gait.speed_mps` constraint, and the gait library over a speed range.

use planner::biped::PlanarBiped;
use planner::collocation::HzdProblem;
use planner::config::PlannerConfig;
use planner::guess::initial_guess;
use planner::nlp::check::check_derivatives;
use planner::nlp::NlpProblem;
use planner::plan::plan_gait;

const URDF: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../configs/robots/adam_planar.urdf"
);
const CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/planner/adam.toml");

fn setup() -> (model::PlanarModel, String, PlannerConfig) {
    let text = std::fs::read_to_string(URDF).expect("URDF");
    let model = model::PlanarModel::from_urdf_str(&text, URDF).expect("model");
    (model, text, PlannerConfig::load(CONFIG).expect("config"))
}

/// ADAM planned at 0.25 m/s walks 0.25 m/s: d/T within the solver's constraint tolerance
/// (1e-6 on d − v·T, so 1e-6 / T on the speed), and the gait verifies.
#[test]
fn adam_planned_at_a_quarter_metre_per_second_walks_it() {
    let (model, text, mut config) = setup();
    config.gait.speed_mps = Some([0.25, 0.25]);
    let planned = plan_gait(&model, "robot.urdf", &text, &config, &mut |_| {}).expect("plans");
    let g = &planned.gait;
    println!(
        "step {:.6} m in {:.6} s: {:.8} m/s, CoT {:.6}, {} iterations",
        g.step_length_m, g.step_duration_s, g.speed_mps, g.cost_of_transport, g.solver.iterations
    );
    for s in &planned.stages {
        assert!(s.violation < 1e-6, "{s:?}");
    }
    assert!(
        (g.step_length_m / g.step_duration_s - 0.25).abs() < 1e-6 / g.step_duration_s,
        "{} m / {} s",
        g.step_length_m,
        g.step_duration_s
    );
    assert!((g.speed_mps - 0.25).abs() < 2e-6, "{}", g.speed_mps);
    let report = planner::verify::verify_gait(&model, g, planner::verify::VerifyOptions::default())
        .expect("verifies");
    println!("{report}");
    assert!(report.spectral_radius < 1.0, "{report}");
}

/// The speed rows are in the problem only when asked for (the default config has none: its
/// problem, and so its plan, is the one without them), one row for one speed, two for a band,
/// and their derivatives match finite differences.
#[test]
fn the_speed_rows_exist_only_when_asked_for_and_their_derivatives_are_exact() {
    let (model, _, config) = setup();
    assert_eq!(config.gait.speed_mps, None);
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    let free = HzdProblem::new(bp.clone(), config.clone(), Vec::new(), false).expect("problem");
    let x = initial_guess(&bp, &free.layout, 0.22, 0.8).expect("guess");
    let mut band = config.clone();
    band.gait.speed_mps = Some([0.2, 0.3]);
    let mut one = config.clone();
    one.gait.speed_mps = Some([0.25, 0.25]);
    let banded = HzdProblem::new(bp.clone(), band, x.clone(), false).expect("problem");
    let fixed = HzdProblem::new(bp.clone(), one, x.clone(), false).expect("problem");
    let plain = HzdProblem::new(bp, config, x.clone(), false).expect("problem");
    assert_eq!(banded.num_constraints(), plain.num_constraints() + 2);
    assert_eq!(fixed.num_constraints(), plain.num_constraints() + 1);
    let mut g = vec![0.0; banded.num_constraints()];
    banded.constraints(&x, &mut g).expect("evaluates");
    let n = plain.num_constraints();
    // 0.22 m in 0.8 s = 0.275 m/s: 0.06 m above the slowest, 0.02 m below the fastest.
    assert!((g[n] - (0.22 - 0.2 * 0.8)).abs() < 1e-12, "{}", g[n]);
    assert!(
        (g[n + 1] - (0.3 * 0.8 - 0.22)).abs() < 1e-12,
        "{}",
        g[n + 1]
    );
    let (lo, hi) = banded.constraint_bounds_vec();
    assert_eq!((lo[n], hi[n]), (0.0, f64::INFINITY));
    for p in [&banded, &fixed] {
        let lambda: Vec<f64> = (0..p.num_constraints())
            .map(|i| ((i * 7919) % 13) as f64 / 13.0 - 0.5)
            .collect();
        let r = check_derivatives(p, &x, 0.7, &lambda).expect("evaluates");
        assert!(r.max_jacobian_error < 1e-6, "{r:?}");
        assert!(r.max_hessian_error < 1e-5, "{r:?}");
        assert_eq!(r.jacobian_entries_outside_pattern, 0);
    }
}

/// A speed band that is not one (lo > hi, zero, non-finite) or that no step within the length
/// and duration bounds reaches is refused, naming the field (and both bounds it contradicts).
#[test]
fn a_bad_or_unreachable_speed_band_is_refused_naming_the_fields() {
    let text = std::fs::read_to_string(CONFIG).expect("config");
    let with = |speed: &str| {
        text.replace(
            "step_duration_s = [0.6, 0.9]",
            &format!("step_duration_s = [0.6, 0.9]\nspeed_mps = {speed}"),
        )
    };
    assert!(text.contains("step_duration_s = [0.6, 0.9]"));
    let ok = PlannerConfig::from_toml(&with("[0.2, 0.3]"), "x.toml").expect("a band");
    assert_eq!(ok.gait.speed_mps, Some([0.2, 0.3]));
    for (speed, words) in [
        ("[0.3, 0.2]", &["0.3, 0.2", "lower ≤ upper"][..]),
        ("[0.0, 0.2]", &["0 < lower"][..]),
        ("[nan, 0.2]", &["NaN"][..]),
        (
            "[0.6, 0.7]",
            &["gait.step_length_m", "gait.step_duration_s", "0.5833"][..],
        ),
        ("[0.05, 0.1]", &["gait.step_length_m", "0.1667"][..]),
    ] {
        let e = PlannerConfig::from_toml(&with(speed), "x.toml")
            .expect_err(speed)
            .to_string();
        assert!(e.contains("x.toml") && e.contains("gait.speed_mps"), "{e}");
        for w in words {
            assert!(e.contains(w), "{speed}: {w}: {e}");
        }
    }
}
