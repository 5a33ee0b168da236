//! Helpers shared by the planner's integration tests.

use planner::biped::PlanarBiped;
use planner::collocation::{HzdProblem, TORQUE_SCALE};
use planner::config::PlannerConfig;
use planner::nlp::NlpProblem;

/// The cost-of-transport problem started the way the planner started it before the eleventh
/// round (planner/NLP.md): from the feasibility point `feasible_x` (no power slacks) with each
/// actuator's slacks where the feasibility stage's barrier, with no cost on them, used to leave
/// them: p = (p_max + u q̇)/2, n = (p_max − u q̇)/2, the middle of their bounds; and no initial
/// barrier parameter of its own (IPOPT's 0.1).
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
