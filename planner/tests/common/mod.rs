//! Helpers shared by the planner's integration tests.

use model::design::{generate_model, DesignLengths};
use planner::biped::PlanarBiped;
use planner::collocation::{Codesign, HzdProblem, TORQUE_SCALE};
use planner::config::PlannerConfig;
use planner::guess::initial_guess;
use planner::nlp::check::{check_derivatives, DerivativeCheck};
use planner::nlp::NlpProblem;

/// The co-design problem of ADAM's model (lengths 0.24 / 0.25 m nominal, Table I's box) with
/// `config`, and a point to test it at: the initial guess with the lengths away from the
/// nominal ones (0.27 / 0.21 m), so that the design joints are not at zero.
#[allow(dead_code)] // not every test binary uses every helper
pub fn codesign_problem(
    config: PlannerConfig,
    exact_inertia: bool,
    with_cost: bool,
) -> (HzdProblem, Vec<f64>) {
    let (model, _) = generate_model(&DesignLengths::ADAM).expect("model");
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    let spec = Codesign {
        nominal_m: [0.24, 0.25],
        bounds_m: [[0.15, 0.35], [0.15, 0.35]],
        exact_inertia,
        mass: model::design::MassModel::default(),
    };
    let probe = HzdProblem::with_codesign(
        bp.clone(),
        config.clone(),
        Vec::new(),
        with_cost,
        Some(spec.clone()),
    )
    .expect("problem");
    let l = &probe.layout;
    let mut x = initial_guess(&bp, l, 0.25, 0.75).expect("guess");
    x.truncate(l.design_var(0));
    x.extend([0.27, 0.21]);
    let p =
        HzdProblem::with_codesign(bp, config, x.clone(), with_cost, Some(spec)).expect("problem");
    (p, x)
}

/// Checks `p`'s derivatives at `x` against central finite differences, with fixed pseudo-random
/// multipliers: central differences with the cube-root step leave rounding near 1e-9
/// relative; a wrong or missing derivative shows at 1e-3 or above. Returns the report.
#[allow(dead_code)] // not every test binary uses every helper
pub fn assert_exact_derivatives(p: &HzdProblem, x: &[f64]) -> DerivativeCheck {
    let lambda: Vec<f64> = (0..p.num_constraints())
        .map(|i| ((i * 7919) % 13) as f64 / 13.0 - 0.5)
        .collect();
    let r = check_derivatives(p, x, 0.7, &lambda).expect("evaluates");
    assert!(r.max_gradient_error < 1e-6, "{r:?}");
    assert!(r.max_jacobian_error < 1e-6, "{r:?}");
    assert!(r.max_hessian_error < 1e-5, "{r:?}");
    assert_eq!(r.jacobian_entries_outside_pattern, 0);
    assert_eq!(r.hessian_entries_outside_pattern, 0);
    r
}

/// The cost-of-transport problem started the way the planner started it before the eleventh
/// round (planner/NLP.md): from the feasibility point `feasible_x` (no power slacks) with each
/// actuator's slacks where the feasibility stage's barrier, with no cost on them, used to leave
/// them: p = (p_max + u q̇)/2, n = (p_max − u q̇)/2, the middle of their bounds; and no initial
/// barrier parameter of its own (IPOPT's 0.1).
#[allow(dead_code)] // not every test binary uses every helper
pub fn midrange_slack_start(
    biped: &PlanarBiped,
    config: &PlannerConfig,
    feasible_x: &[f64],
) -> HzdProblem {
    let mut costed =
        HzdProblem::new(biped.clone(), config.clone(), Vec::new(), true).expect("problem");
    let l = costed.layout.clone();
    let mut x = l.with_slacks(feasible_x).expect("a feasibility point");
    let n = costed.num_variables();
    let (mut lo, mut hi) = (vec![0.0; n], vec![0.0; n]);
    costed.variable_bounds(&mut lo, &mut hi);
    for k in 0..l.points() {
        for (i, &c) in biped.actuators.iter().enumerate() {
            let power = TORQUE_SCALE * x[l.u(k) + i] * x[l.dq(k) + c];
            let p_max = hi[l.p(k) + i];
            x[l.p(k) + i] = 0.5 * (p_max + power);
            x[l.n(k) + i] = 0.5 * (p_max - power);
        }
    }
    costed.set_initial(x);
    costed
}

/// The workspace's root folder.
#[allow(dead_code)] // not every test binary uses every helper
pub const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// A robot (URDF path relative to the workspace), its URDF text and a planner config.
#[allow(dead_code)] // not every test binary uses every helper
pub fn load(urdf: &str, config: &str) -> (model::PlanarModel, String, PlannerConfig) {
    let urdf = format!("{ROOT}/{urdf}");
    let text = std::fs::read_to_string(&urdf).expect("URDF");
    let model = model::PlanarModel::from_urdf_str(&text, &urdf).expect("model");
    let config = PlannerConfig::load(format!("{ROOT}/{config}")).expect("config");
    (model, text, config)
}

/// `gait.<field> = <value>` added to configs/planner/adam.toml: `ok` loads (and `check` sees
/// it), and each of `bad` is refused with an error that names the file, the field and the
/// value.
#[allow(dead_code)] // not every test binary uses every helper
pub fn assert_gait_field_range(
    field: &str,
    ok: &str,
    check: impl Fn(&PlannerConfig),
    bad: &[&str],
) {
    let text =
        std::fs::read_to_string(format!("{ROOT}/configs/planner/adam.toml")).expect("config");
    let anchor = "step_duration_s = [0.6, 0.9]";
    assert!(text.contains(anchor));
    let with = |v: &str| text.replace(anchor, &format!("{anchor}\n{field} = {v}"));
    check(&PlannerConfig::from_toml(&with(ok), "x.toml").expect(ok));
    for v in bad {
        let e = PlannerConfig::from_toml(&with(v), "x.toml")
            .expect_err(v)
            .to_string();
        let value = v.parse::<f64>().expect("a number").to_string();
        assert!(
            e.contains("x.toml") && e.contains(&format!("gait.{field}")) && e.contains(&value),
            "{e}"
        );
    }
}

/// In the co-design problem of `config` (exact inertia coupling) the first row of `group`
/// has entries in both length variables, and every derivative of the problem is exact.
#[allow(dead_code)] // not every test binary uses every helper
pub fn assert_codesign_row_sees_the_lengths(
    config: PlannerConfig,
    group: planner::collocation::ConstraintGroup,
) {
    let (p, x) = codesign_problem(config, true, false);
    let groups = p.constraint_groups();
    let row = (0..p.num_constraints())
        .find(|&i| groups.rows[i] == Some(group))
        .expect("a row of the group");
    let jac = p.jacobian_structure();
    for d in [p.layout.design_var(0), p.layout.design_var(1)] {
        assert!(
            jac.rows
                .iter()
                .zip(&jac.cols)
                .any(|(&r, &c)| r == row && c == d),
            "no entry of the {group:?} row in design variable {d}"
        );
    }
    assert_exact_derivatives(&p, &x);
}

/// Plans the co-designed ADAM at 0.20 m/s with the library config changed by `change`, and
/// verifies the gait (every stage feasible to 1e-6).
#[allow(dead_code)] // not every test binary uses every helper
pub fn plan_and_verify_at_020(
    change: impl Fn(&mut PlannerConfig),
) -> (model::gait::GaitFile, planner::verify::VerifyReport) {
    let (model, text, mut config) = load(
        "configs/robots/adam_codesign.urdf",
        "configs/planner/adam_library.toml",
    );
    config.gait.speed_mps = Some([0.2, 0.2]);
    change(&mut config);
    let planned =
        planner::plan::plan_gait(&model, "robot.urdf", &text, &config, &mut |_| {}).expect("plans");
    for s in &planned.stages {
        assert!(s.violation < 1e-6, "{s:?}");
    }
    let g = planned.gait;
    let report = planner::verify::verify_gait(&model, &g, Default::default()).expect("verifies");
    println!(
        "{:.4} m in {:.4} s, CoT {:.5}: {report}",
        g.step_length_m, g.step_duration_s, g.cost_of_transport
    );
    (g, report)
}
