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
