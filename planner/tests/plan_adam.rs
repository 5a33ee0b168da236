//! End to end: plan ADAM's gait with the shipped config, and check the problem's derivatives.

mod common;

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

#[test]
fn collocation_derivatives_match_finite_differences() {
    let (model, _, config) = setup();
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    for with_cost in [false, true] {
        let probe =
            HzdProblem::new(bp.clone(), config.clone(), Vec::new(), with_cost).expect("problem");
        let x = initial_guess(&bp, &probe.layout, 0.25, 0.75).expect("guess");
        let p = HzdProblem::new(bp.clone(), config.clone(), x.clone(), with_cost).expect("problem");
        let m = p.num_constraints();
        let lambda: Vec<f64> = (0..m)
            .map(|i| ((i * 7919) % 13) as f64 / 13.0 - 0.5)
            .collect();
        let r = check_derivatives(&p, &x, 0.7, &lambda).expect("evaluates");
        println!("with_cost {with_cost}: {r:?}");
        // Central differences with the cube-root step: errors near 1e-9 relative are rounding;
        // a wrong or missing derivative shows up at 1e-3 or above.
        assert!(r.max_gradient_error < 1e-6, "{r:?}");
        assert!(r.max_jacobian_error < 1e-6, "{r:?}");
        assert!(r.max_hessian_error < 1e-5, "{r:?}");
        assert_eq!(r.jacobian_entries_outside_pattern, 0);
        assert_eq!(r.hessian_entries_outside_pattern, 0);
    }
}

#[test]
fn plans_a_feasible_gait_inside_table_one_deterministically() {
    let (model, text, config) = setup();
    let a = plan_gait(
        &model,
        "../robots/adam_planar.urdf",
        &text,
        &config,
        &mut |_| {},
    )
    .expect("plans");
    for s in &a.stages {
        println!(
            "{:<18} {:>8} {:>4} iterations, objective {:.6}, violation {:.1e}, {:.3} s",
            s.stage, s.status, s.iterations, s.objective, s.violation, s.solve_time_s
        );
        // The feasibility stage may stop on a numerical status at a feasible point (plan.rs
        // keeps it only if it is feasible to 1e-8); the cost stage must be optimal.
        if s.stage == "cost of transport" {
            assert_eq!(s.status, "optimal");
        }
        assert!(s.violation < 1e-6, "{}: violation {}", s.stage, s.violation);
    }
    let g = &a.gait;
    println!(
        "step {:.4} m, duration {:.4} s, speed {:.4} m/s, CoT {:.4}",
        g.step_length_m, g.step_duration_s, g.speed_mps, g.cost_of_transport
    );
    let tol = 1e-6;
    assert!(g.step_length_m >= 0.15 - tol && g.step_length_m <= 0.35 + tol);
    assert!(g.step_duration_s >= 0.6 - tol && g.step_duration_s <= 0.9 + tol);
    assert!(g.cost_of_transport > 0.0 && g.cost_of_transport < 1.0);
    g.validate("planned").expect("valid gait file");
    // Same start, same gait, bit for bit (the cost stage again from the same feasible point;
    // re-running the ~2-minute feasibility stage as well would double the test's time).
    let again = planner::plan::solve_cost_stage(&model, &config, &a.feasible_x).expect("re-solves");
    assert_eq!(a.x, again);
}

/// The cost stage starts from the feasibility solution (which has no power slacks) with the
/// slacks made from its u q̇ and put on the central path of `[solver] cost_stage_mu_init`:
/// p − n = u q̇, the smaller of p and n is μ₀ / (∂Φ/∂p) off its bound (∂Φ/∂p from the
/// problem's own gradient), and every other variable is the feasible point's. From there the
/// cost stage needs fewer than half the iterations it needs from the slacks in the middle of
/// their bounds with IPOPT's μ₀ = 0.1, where the feasibility stage used to leave them (28
/// against 84 when this was written), to an optimum at least as cheap. A start of the wrong
/// length is refused with both lengths.
#[test]
fn the_cost_stage_starts_with_its_power_slacks_centred() {
    use planner::nlp::{solve, SolveOptions};
    let (model, text, config) = setup();
    let a = plan_gait(&model, "u", &text, &config, &mut |_| {}).expect("plans");
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    let x1 = a.feasible_x.clone();
    let centred = planner::plan::cost_stage_problem(bp.clone(), &config, &x1).expect("problem");
    let mu = config.solver.cost_stage_mu_init;
    assert_eq!(centred.initial_barrier(), Some(mu));
    let n = centred.num_variables();
    let mut x = vec![0.0; n];
    centred.initial_point(&mut x);
    let mut gradient = vec![0.0; n];
    centred.gradient(&x, &mut gradient).expect("gradient");
    let l = centred.layout.clone();
    assert_eq!(x1.len(), l.len_without_slacks());
    let lifted = l.with_slacks(&x1).expect("lifts");
    let mut slack = vec![false; n];
    for k in 0..l.points() {
        for (i, &c) in bp.actuators.iter().enumerate() {
            let (p, m) = (l.p(k) + i, l.n(k) + i);
            slack[p] = true;
            slack[m] = true;
            let power = planner::collocation::TORQUE_SCALE * x[l.u(k) + i] * x[l.dq(k) + c];
            assert!(
                (x[p] - x[m] - power).abs() <= 1e-12 * power.abs().max(1.0),
                "k {k}, actuator {i}: p {} n {} u q̇ {power}",
                x[p],
                x[m]
            );
            let off = x[p].min(x[m]);
            assert!(
                (off * gradient[p] / mu - 1.0).abs() < 1e-12,
                "k {k}, actuator {i}: {off} W off the bound, ∂Φ/∂p {}",
                gradient[p]
            );
        }
    }
    for i in (0..n).filter(|&i| !slack[i]) {
        assert_eq!(x[i].to_bits(), lifted[i].to_bits(), "variable {i} moved");
    }
    // Every variable of the feasible point is in the lifted one, once.
    let mut kept: Vec<u64> = (0..n)
        .filter(|&i| !slack[i])
        .map(|i| x[i].to_bits())
        .collect();
    let mut given: Vec<u64> = x1.iter().map(|v| v.to_bits()).collect();
    kept.sort_unstable();
    given.sort_unstable();
    assert_eq!(kept, given);
    let e = planner::plan::cost_stage_problem(bp.clone(), &config, &x)
        .err()
        .expect("a point with slacks is refused")
        .to_string();
    assert!(
        e.contains(&n.to_string()) && e.contains(&x1.len().to_string()),
        "{e}"
    );
    let feasibility =
        HzdProblem::new(bp.clone(), config.clone(), Vec::new(), false).expect("problem");
    assert!(!feasibility.layout.slacks && feasibility.layout.len() == x1.len());
    let e = feasibility
        .layout
        .with_slacks(&x1)
        .expect_err("no slacks to add")
        .to_string();
    assert!(e.contains("no slacks"), "{e}");

    let options = SolveOptions {
        tolerance: config.solver.tolerance,
        constraint_violation_tolerance: 1e-6,
        ..SolveOptions::default()
    };
    let midrange = common::midrange_slack_start(&bp, &config, &x1);
    let from_midrange = solve(&midrange, &options).expect("solves");
    let from_centred = solve(
        &centred,
        &SolveOptions {
            initial_barrier: centred.initial_barrier(),
            ..options
        },
    )
    .expect("solves");
    let (c, u) = (&from_centred.statistics, &from_midrange.statistics);
    println!(
        "centred: {} iterations, CoT {:.6}; mid-range slacks: {} iterations, CoT {:.6}",
        c.iterations, c.objective, u.iterations, u.objective
    );
    assert!(from_centred.status.is_success() && from_midrange.status.is_success());
    assert!(2 * c.iterations < u.iterations, "{c:?} vs {u:?}");
    assert!(c.objective <= u.objective * (1.0 + 1e-6), "{c:?} vs {u:?}");
    assert_eq!(a.x, from_centred.x, "the plan's cost stage is this solve");
}

/// A warm start with multipliers resumes at the optimum instead of re-solving: the cost stage
/// from its own solution took 91 iterations cold (the default barrier parameter re-centres
/// the point), 80 with the point alone (multipliers dropped by ripopt and reset to 1) and
/// 10 with point and multipliers. This is what makes the co-design's polish solve cheap.
#[test]
fn a_warm_start_from_the_cost_optimum_resumes_instead_of_re_solving() {
    use planner::nlp::{solve, SolveOptions};
    let (model, text, config) = setup();
    let a = plan_gait(&model, "u", &text, &config, &mut |_| {}).expect("plans");
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    let costed = HzdProblem::new(bp, config.clone(), a.x.clone(), true).expect("problem");
    let options = SolveOptions {
        tolerance: config.solver.tolerance,
        constraint_violation_tolerance: 1e-6,
        ..SolveOptions::default()
    };
    let cold = solve(&costed, &options).expect("solves");
    let warm = solve(
        &costed,
        &SolveOptions {
            warm_start: Some(cold.warm_start()),
            ..options
        },
    )
    .expect("solves");
    let (c, w) = (&cold.statistics, &warm.statistics);
    println!(
        "cold {} iterations, warm {} iterations",
        c.iterations, w.iterations
    );
    assert!(warm.status.is_success(), "{:?}", warm.status);
    assert!(
        w.iterations <= 20 && 4 * w.iterations <= c.iterations,
        "{w:?} vs {c:?}"
    );
    assert!(
        (w.objective - c.objective).abs() <= 1e-6 * c.objective,
        "{w:?} vs {c:?}"
    );
    assert!(costed.max_violation(&warm.x) < 1e-6);
}

/// Any planar point-foot biped that follows the naming convention plans: a five-link walker
/// with different masses, lengths and actuators.
#[test]
fn plans_and_verifies_a_second_different_five_link_walker() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/robots/five_link_walker.urdf"
    );
    let text = std::fs::read_to_string(path).expect("URDF");
    let model = model::PlanarModel::from_urdf_str(&text, path).expect("model");
    assert!(model.design_joints().is_empty());
    let config = PlannerConfig::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/planner/five_link.toml"
    ))
    .expect("config");
    let a = plan_gait(
        &model,
        "../robots/five_link_walker.urdf",
        &text,
        &config,
        &mut |_| {},
    )
    .expect("plans");
    for s in &a.stages {
        println!(
            "{:<18} {:>8} {:>4} iterations, violation {:.1e}",
            s.stage, s.status, s.iterations, s.violation
        );
        assert!(s.violation < 1e-6);
    }
    let g = &a.gait;
    println!(
        "five-link: step {:.4} m, duration {:.4} s, CoT {:.4}",
        g.step_length_m, g.step_duration_s, g.cost_of_transport
    );
    assert!(g.step_length_m >= 0.2 - 1e-6 && g.step_length_m <= 0.5 + 1e-6);
    // Verified independently of the optimizer, like ADAM's: a stable periodic orbit, the planned one.
    // Verified independently of the optimizer, like ADAM's: a stable periodic orbit, the
    // planned one, its step duration and length within 1 % of the plan's.
    let report = planner::verify::assert_orbit_matches_plan(&model, g);
    println!("{report}");
}

/// The constraints, Jacobian and Hessian are evaluated block by block on the rayon pool when called from
/// outside it and sequentially from inside it (a co-design sweep); both must give the same bits,
/// or the same config would not give the same gait.
#[test]
fn derivatives_are_bit_identical_in_parallel_and_sequentially() {
    let (model, _, config) = setup();
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    let probe = HzdProblem::new(bp.clone(), config.clone(), Vec::new(), true).expect("problem");
    let x = initial_guess(&bp, &probe.layout, 0.25, 0.65).expect("guess");
    let p = HzdProblem::new(bp, config, x.clone(), true).expect("problem");
    let lambda: Vec<f64> = (0..p.num_constraints())
        .map(|i| ((i * 7919) % 13) as f64 / 13.0 - 0.5)
        .collect();
    let evaluate = || {
        let mut g = vec![0.0; p.num_constraints()];
        let mut jac = vec![0.0; p.jacobian_structure().len()];
        let mut hess = vec![0.0; p.hessian_structure().len()];
        p.constraints(&x, &mut g).expect("constraints");
        p.jacobian_values(&x, &mut jac).expect("jacobian");
        p.hessian_values(&x, 0.7, &lambda, &mut hess)
            .expect("hessian");
        let bits = |v: &[f64]| v.iter().map(|f| f.to_bits()).collect::<Vec<u64>>();
        (bits(&g), bits(&jac), bits(&hess))
    };
    let parallel = evaluate();
    let sequential = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(evaluate);
    assert!(
        parallel.0.iter().any(|&b| b != 0)
            && parallel.1.iter().any(|&b| b != 0)
            && parallel.2.iter().any(|&b| b != 0)
    );
    assert_eq!(parallel, sequential);
}

/// With step durations of 0.8–0.9 s ripopt's first two feasibility starts fall into its
/// restoration phase (with 0.6–0.7 s, before the feasibility problem lost its power slacks, the
/// first did: about a thousand nested iterations and 58 s before the guard). A start that needs
/// restoration is dropped for the next one, so the whole feasibility stage stays within one
/// start's iteration cap, counting every iteration the solver reports (restoration included),
/// and the gait still satisfies the config's durations. (The scenario is ripopt's: the native
/// backend, the default, solves the first start.)
#[test]
fn a_feasibility_start_that_needs_restoration_gives_way_to_the_next() {
    use planner::plan::{Progress, FEASIBILITY_MAX_ITERATIONS};
    let (model, text, mut config) = setup();
    config.gait.step_duration_s = [0.8, 0.9];
    config.solver.backend = planner::config::SolverBackend::Ripopt;
    // On the uniform mesh, where the first start needs restoration (on the default graded
    // mesh ripopt solves the first start without it).
    config.collocation.mesh_grading = 0.0;
    let (mut starts, mut iterations) = (0, 0);
    let mut per_start: Vec<usize> = Vec::new();
    let mut in_feasibility = false;
    // Whether each start reported a second iteration 0 (its nested restoration solve).
    let (mut zeros, mut restored) = (0, Vec::new());
    let gait = plan_gait(
        &model,
        "../robots/adam_planar.urdf",
        &text,
        &config,
        &mut |p| match p {
            Progress::Stage(s) => {
                in_feasibility = s == "feasibility";
                starts += usize::from(in_feasibility);
                if in_feasibility {
                    per_start.push(0);
                    restored.push(false);
                }
                zeros = 0;
            }
            Progress::Iteration(_, r) => {
                let counted = usize::from(in_feasibility && r.iteration > 0);
                iterations += counted;
                zeros += usize::from(r.iteration == 0);
                if in_feasibility && zeros > 1 {
                    if let Some(last) = restored.last_mut() {
                        *last = true;
                    }
                }
                if let Some(n) = per_start.last_mut() {
                    *n += counted;
                }
            }
        },
    )
    .expect("plans");
    let feasibility = &gait.stages[0];
    println!(
        "{starts} starts ({per_start:?} iterations, restored {restored:?}), stage: {feasibility:?}"
    );
    assert!(starts >= 2, "a start is dropped, a later one succeeds");
    assert!(iterations < FEASIBILITY_MAX_ITERATIONS, "{iterations}");
    // The stage's report counts the dropped start's iterations too, every one of them.
    assert_eq!(feasibility.iterations, iterations);
    // The dropped starts did enter restoration (that is why they were dropped); the last did not.
    assert!(restored[..starts - 1].iter().all(|&r| r), "{restored:?}");
    assert!(!restored[starts - 1], "{restored:?}");
    // ripopt neither flags its restoration iterations nor times its phases: the report says
    // so instead of a zero.
    assert_eq!(
        (feasibility.restoration_iterations, feasibility.phases),
        (None, None)
    );
    let d = gait.gait.step_duration_s;
    assert!((0.8 - 1e-6..=0.9 + 1e-6).contains(&d), "{d}");
}

/// A config no robot can walk (0.9 m of swing-foot clearance on 0.7 m legs) fails every start
/// with an error that says which constraint groups are left violated, worst first.
#[test]
fn an_infeasible_config_fails_naming_the_most_violated_constraints() {
    let (model, text, mut config) = setup();
    config.gait.swing_clearance_m = 0.9;
    config.solver.max_iterations = 30;
    let e = plan_gait(
        &model,
        "../robots/adam_planar.urdf",
        &text,
        &config,
        &mut |_| {},
    )
    .expect_err("no gait clears 0.9 m");
    println!("{e}");
    let planner::PlannerError::NotSolved {
        violation,
        ref violated,
        ..
    } = e
    else {
        panic!("{e:?}");
    };
    assert!(!violated.is_empty() && violated.len() <= 3, "{violated:?}");
    assert!(
        violated.windows(2).all(|w| w[0].1 >= w[1].1),
        "{violated:?}"
    );
    assert!(violated.iter().all(|(_, v)| *v > 1e-6));
    // The worst group is the violation the error reports.
    assert!(
        (violated[0].1 - violation).abs() <= 1e-9 * violation.max(1.0),
        "{violated:?}"
    );
    let message = e.to_string();
    assert!(
        message.contains("most violated: ") && message.contains(&violated[0].0),
        "{message}"
    );
}

/// The native interior point (`[solver] backend = "native"`) plans ADAM on its own: the
/// feasibility solve from the planner's first start ends optimal without ripopt's restoration
/// phase, and the whole plan gives the ripopt plan's gait (cost of transport 0.020741 with
/// `--backend ripopt`) to within 0.1 %, verified by the closed-loop simulation.
#[test]
fn the_native_backend_plans_a_gait_that_verifies() {
    use planner::config::SolverBackend;
    use planner::nlp::{solve, Backend, SolveOptions, SolveStatus};
    let (model, text, mut config) = setup();
    config.solver.backend = SolverBackend::Native;
    let bp = PlanarBiped::new(model.clone(), config.gait.stance_leg, &[]).expect("biped");
    let probe = HzdProblem::new(bp.clone(), config.clone(), Vec::new(), false).expect("problem");
    let x0 = initial_guess(&bp, &probe.layout, 0.25, 0.65).expect("guess");
    let feasibility = HzdProblem::new(bp, config.clone(), x0, false).expect("problem");
    let alone = solve(
        &feasibility,
        &SolveOptions {
            backend: Backend::Native,
            tolerance: config.solver.tolerance,
            constraint_violation_tolerance: 1e-6,
            ..SolveOptions::default()
        },
    )
    .expect("solves");
    println!(
        "native feasibility: {:?} in {} iterations",
        alone.status, alone.statistics.iterations
    );
    assert_eq!(alone.status, SolveStatus::Optimal);

    let a = plan_gait(
        &model,
        "../robots/adam_planar.urdf",
        &text,
        &config,
        &mut |_| {},
    )
    .expect("plans");
    for s in &a.stages {
        println!(
            "native {:<18} {:>8} {:>4} iterations, objective {:.6}, violation {:.1e}, {:.3} s",
            s.stage, s.status, s.iterations, s.objective, s.violation, s.solve_time_s
        );
        assert_eq!(s.status, "optimal");
        assert!(s.violation < 1e-6, "{}: violation {}", s.stage, s.violation);
        // The native backend says where its time went: no restoration, at least one KKT
        // factorization and solve per iteration, and the phases add up to the solve time
        // (they are disjoint wall times; 1 µs of rounding in the seconds).
        assert_eq!(s.restoration_iterations, Some(0), "{s:?}");
        let p = s.phases.expect("the native backend times its phases");
        println!("  {p:?}");
        assert!(p.factorizations >= s.iterations, "{p:?}");
        assert!(p.linear_solves >= s.iterations, "{p:?}");
        let phases = s.evaluation_time_s
            + (p.factorization_time + p.linear_solve_time + p.other_time).as_secs_f64();
        assert!((phases - s.solve_time_s).abs() < 1e-6, "{phases} vs {s:?}");
    }
    let g = &a.gait;
    // Both stages by the native backend alone (no re-solve by ripopt), and the file says so.
    assert!(
        g.solver.solver.starts_with("native interior point"),
        "{}",
        g.solver.solver
    );
    // 0.020741 on the uniform mesh of 20 intervals: that gait's orbit stepped 10 % slower than
    // planned; the graded mesh's plan is walked as planned and costs 3 % more.
    assert!(
        (g.cost_of_transport / 0.021386 - 1.0).abs() < 1e-3,
        "CoT {}",
        g.cost_of_transport
    );
    let report = planner::verify::assert_orbit_matches_plan(&model, g);
    println!("{report}");
}

/// Issue #28 item 5: the closed loop walks the plan. On robots the planner was not tuned on,
/// ADAM with a 50 % heavier torso (20 kg) and a small ADAM generated at 0.20 / 0.20 m legs,
/// the verified orbit's step duration and length are the plan's within 1 % with the shipped
/// config (graded mesh of 20 intervals; measured +0.43 % and +0.50 %, where the uniform mesh
/// gave +15.5 % and +13.4 %).
#[test]
fn held_out_robots_walk_their_plans_within_one_percent() {
    let (_, text, config) = setup();
    let heavy = text.replace("<mass value=\"13.33\"/>", "<mass value=\"20.0\"/>");
    assert_ne!(heavy, text, "the torso mass is where the test expects it");
    let small = model::design::generate_urdf(&model::design::DesignLengths {
        thigh_length_m: 0.2,
        shin_length_m: 0.2,
    })
    .expect("generates");
    for (name, urdf) in [("heavy torso", heavy), ("small ADAM", small)] {
        let model = model::PlanarModel::from_urdf_str(&urdf, name).expect("model");
        let planned = plan_gait(&model, "robot.urdf", &urdf, &config, &mut |_| {}).expect(name);
        let report = planner::verify::assert_orbit_matches_plan(&model, &planned.gait);
        let (duration, length) = report.plan_mismatch();
        println!(
            "{name}: orbit {:.4} s, {:.4} m ({:+.2} %, {:+.2} %), |λ|max {:.4}",
            report.step_duration_s,
            report.step_length_m,
            100.0 * duration,
            100.0 * length,
            report.spectral_radius
        );
    }
}

/// The 1 % check can fail, and the graded mesh is what passes it: ADAM planned on a uniform
/// mesh of 20 intervals (the default until December 2026) verifies as a stable orbit whose
/// steps take ~10 % longer than planned, and the accuracy check names the step duration.
#[test]
fn a_uniform_mesh_of_20_intervals_misses_the_plan_and_the_accuracy_check_says_so() {
    let (model, text, mut config) = setup();
    config.collocation.mesh_grading = 0.0;
    let planned = plan_gait(&model, "robot.urdf", &text, &config, &mut |_| {}).expect("plans");
    let report = planner::verify::verify_gait(
        &model,
        &planned.gait,
        planner::verify::VerifyOptions::default(),
    )
    .expect("verifies");
    println!("{report}");
    assert!(
        report.passed(1e-6),
        "a stable orbit near the plan: {report}"
    );
    let (duration, _) = report.plan_mismatch();
    assert!(duration > 0.05, "{report}");
    let failed = report.accuracy_failures();
    assert_eq!(failed.len(), 1, "{failed:?}");
    assert!(failed[0].contains("step duration"), "{failed:?}");
}

/// The interior point asks for the Jacobian and the Hessian together after an accepted step,
/// and the collocation problem then reads the Jacobian off the Hessian's hyper-dual passes
/// for the kinds whose first-order rules are `Dual`'s. The values must be those of the two
/// separate sweeps bit for bit (or the plan would depend on which path ran), for active and
/// inactive blocks (all multipliers zero: no Hessian pass) alike.
#[test]
fn merged_jacobian_and_hessian_are_the_separate_sweeps_bits() {
    let (model, _, config) = setup();
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    let probe = HzdProblem::new(bp.clone(), config.clone(), Vec::new(), true).expect("problem");
    for (step, duration) in [(0.25, 0.65), (0.18, 0.85)] {
        let x = initial_guess(&bp, &probe.layout, step, duration).expect("guess");
        let p = HzdProblem::new(bp.clone(), config.clone(), x.clone(), true).expect("problem");
        let m = p.num_constraints();
        // Multipliers of every sign and size, with a stretch of zeros (inactive blocks).
        let lambda: Vec<f64> = (0..m)
            .map(|i| {
                if (m / 3..m / 3 + 60).contains(&i) {
                    0.0
                } else {
                    (((i * 7919) % 13) as f64 / 13.0 - 0.5) * 10f64.powi((i % 5) as i32 - 2)
                }
            })
            .collect();
        let (nj, nh) = (p.jacobian_structure().len(), p.hessian_structure().len());
        let (mut jac, mut hess) = (vec![0.0; nj], vec![0.0; nh]);
        p.jacobian_values(&x, &mut jac).expect("jacobian");
        p.hessian_values(&x, 0.3, &lambda, &mut hess)
            .expect("hessian");
        let (mut jac2, mut hess2) = (vec![f64::NAN; nj], vec![f64::NAN; nh]);
        p.jacobian_and_hessian_values(&x, &mut jac2, 0.3, &lambda, &mut hess2)
            .expect("both");
        let bits = |v: &[f64]| v.iter().map(|f| f.to_bits()).collect::<Vec<u64>>();
        assert!(jac.iter().filter(|v| **v != 0.0).count() > nj / 2);
        assert!(hess.iter().filter(|v| **v != 0.0).count() > nh / 2);
        assert_eq!(bits(&jac), bits(&jac2), "Jacobian at ({step}, {duration})");
        assert_eq!(bits(&hess), bits(&hess2), "Hessian at ({step}, {duration})");
    }
}
