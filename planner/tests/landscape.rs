//! The cost landscape and the constraint activity: the multipliers' relief predicts what moving
//! a bound costs, the grid's two ways of starting reach the same optima, a grid of one point is
//! refused, the `[constraints]` switches only relax, and the sweep file round-trips.

use model::design::{generate_model, DesignLengths};
use planner::biped::PlanarBiped;
use planner::codesign::{activity, landscape, BoundSide, LandscapeStart};
use planner::collocation::{ConstraintGroup, HzdProblem};
use planner::config::{ClearanceProfile, PlannerConfig};
use planner::nlp::{solve, Backend, Solution, SolveOptions};

const CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/planner/adam.toml");

fn config() -> PlannerConfig {
    PlannerConfig::load(CONFIG).expect("config")
}

/// The gait planned at ADAM's lengths with the shipped config, planned once.
fn warm_start() -> &'static planner::plan::PlannedGait {
    static WARM: std::sync::OnceLock<planner::plan::PlannedGait> = std::sync::OnceLock::new();
    WARM.get_or_init(|| {
        let (model, urdf) = generate_model(&DesignLengths::ADAM).expect("model");
        planner::plan::plan_gait(&model, "r.urdf", &urdf, &config(), &mut |_| {}).expect("plan")
    })
}

/// The cost-of-transport problem at ADAM's lengths under `config`, from the planned gait.
fn fixed_problem(config: &PlannerConfig) -> HzdProblem {
    let (model, _) = generate_model(&DesignLengths::ADAM).expect("model");
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    HzdProblem::new(bp, config.clone(), warm_start().x.clone(), true).expect("problem")
}

fn solved(problem: &HzdProblem) -> Solution {
    let s = solve(
        problem,
        &SolveOptions {
            // The planner's own settings (plan::solve_stage_attempt).
            backend: Backend::Native,
            tolerance: 1e-6,
            constraint_violation_tolerance: 1e-6,
            max_iterations: 1000,
            ..SolveOptions::default()
        },
    )
    .expect("solves");
    assert!(s.status.is_success(), "{:?}", s.status);
    s
}

#[test]
fn the_relief_of_the_step_length_bound_predicts_the_cost_of_moving_it() {
    let cfg = config();
    let p = fixed_problem(&cfg);
    let s = solved(&p);
    let a = activity(&p, &s);
    println!("{a}");
    let step = a.group(ConstraintGroup::StepLength).expect("step length");
    let lower = cfg.gait.step_length_m[0];
    assert_eq!(
        step.value.map(|v| v.1),
        Some(Some((BoundSide::Lower, lower)))
    );
    assert!(step.relief_per_unit > 0.0, "{step:?}");
    // Tighten the bound by 1 mm: the optimum moves with it, by the relief to first order (over
    // 5 mm the curvature of the cost already made a 12 % difference on the graded mesh).
    let delta_m = 1e-3;
    let mut moved = cfg.clone();
    moved.gait.step_length_m[0] = lower + delta_m;
    let q = fixed_problem(&moved);
    let t = solved(&q);
    let change = t.statistics.objective - s.statistics.objective;
    let predicted = step.relief_per_unit * delta_m;
    println!(
        "cost {} → {}: change {change:.4e}, predicted {predicted:.4e}",
        s.statistics.objective, t.statistics.objective
    );
    assert!(
        (change / predicted - 1.0).abs() < 0.1,
        "change {change:e} against {predicted:e}"
    );
}

#[test]
fn landscape_grids_of_fewer_than_two_points_are_refused_by_name() {
    let cfg = config();
    for n in [0, 1] {
        let e = landscape(
            &cfg,
            warm_start(),
            cfg.codesign.initial_m,
            n,
            LandscapeStart::Initial,
            &|_| {},
        )
        .expect_err("refused")
        .to_string();
        assert!(e.contains("grid") && e.contains(&format!("= {n}")), "{e}");
    }
    let text = std::fs::read_to_string(CONFIG).expect("config text");
    assert!(text.contains("landscape_grid = 9"));
    let e = PlannerConfig::from_toml(
        &text.replace("landscape_grid = 9", "landscape_grid = 1"),
        "x.toml",
    )
    .expect_err("refused")
    .to_string();
    assert!(
        e.contains("x.toml") && e.contains("codesign.landscape_grid") && e.contains("= 1"),
        "{e}"
    );
}

#[test]
fn both_ways_of_starting_the_grid_reach_the_same_optima() {
    let cfg = config();
    let warm = warm_start();
    let runs: Vec<_> = [LandscapeStart::Initial, LandscapeStart::Neighbours]
        .into_iter()
        .map(|start| {
            landscape(&cfg, warm, cfg.codesign.initial_m, 2, start, &|_| {}).expect("landscape")
        })
        .collect();
    for (a, b) in runs[0].points.iter().zip(&runs[1].points) {
        assert_eq!(a.lengths_m, b.lengths_m);
        let (ca, cb) = (
            a.outcome.as_ref().expect("solved").cost_of_transport,
            b.outcome.as_ref().expect("solved").cost_of_transport,
        );
        assert!(
            (ca / cb - 1.0).abs() < 1e-3,
            "{:?}: {ca} vs {cb}",
            a.lengths_m
        );
    }
    // The corners of the box: the longest legs cost least today (planner/CODESIGN.md).
    let best = runs[0].best().expect("a best point");
    assert_eq!(
        best.lengths_m,
        [cfg.codesign.thigh_m[1], cfg.codesign.shin_m[1]]
    );
    assert!(runs[1].points.iter().any(|p| p.from_neighbour));
}

#[test]
fn switching_off_our_constraints_only_relaxes_the_problem() {
    let cfg = config();
    let base = fixed_problem(&cfg);
    let mut off = cfg.clone();
    off.constraints.liftoff = false;
    off.constraints.clearance_profile = ClearanceProfile::Midstep;
    let relaxed = fixed_problem(&off);
    let (lb, ub) = base.constraint_bounds_vec();
    let (lr, ur) = relaxed.constraint_bounds_vec();
    assert_eq!(lb.len(), lr.len());
    let mut looser = 0;
    for i in 0..lb.len() {
        assert!(lr[i] <= lb[i] && ur[i] >= ub[i], "row {i} tightened");
        looser += usize::from(lr[i] < lb[i]);
    }
    // Every interior swing point but the mid-step one, and the lift-off row.
    let points = 2 * cfg.collocation.intervals + 1;
    assert_eq!(looser, points - 3 + 1);
    // The paper's optimum is at least as good without them: solved from ours.
    let ours = solved(&base).statistics.objective;
    let theirs = solved(&relaxed).statistics.objective;
    assert!(theirs <= ours * (1.0 + 1e-6), "{theirs} > {ours}");
}

#[test]
fn the_sweep_file_round_trips_and_bad_lengths_are_named() {
    let dir = std::env::temp_dir().join(format!("adam-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("sweep.json");
    let runs = vec![
        planner::codesign::SweepRun {
            initial_m: [0.15, 0.2],
            outcome: Ok(planner::codesign::SweepOutcome {
                lengths_m: [0.3487, 0.35],
                step_length_m: 0.15,
                step_duration_s: 0.9,
                speed_mps: 0.1667,
                cost_of_transport: 0.01387,
                objective: 0.01387,
                iterations: 130,
                solve_time_s: 1.2,
            }),
            wall_time_s: 1.3,
        },
        planner::codesign::SweepRun {
            initial_m: [0.35, 0.35],
            outcome: Err("no".into()),
            wall_time_s: 0.1,
        },
    ];
    planner::codesign::save_sweep(&path, &runs).expect("saved");
    let back = planner::codesign::load_sweep_endpoints(&path).expect("loaded");
    assert_eq!(back.len(), 2);
    assert_eq!(back[0].lengths_m, Some([0.3487, 0.35]));
    assert_eq!(back[1].error.as_deref(), Some("no"));
    let text = std::fs::read_to_string(&path).expect("text");
    std::fs::write(&path, text.replacen("0.3487", "-0.3", 1)).expect("write");
    let e = planner::codesign::load_sweep_endpoints(&path)
        .expect_err("refused")
        .to_string();
    assert!(
        e.contains("sweep.json") && e.contains("runs[0]") && e.contains("-0.3"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
