//! The apex-margin bound `gait.min_apex_margin = m`: at every interior collocation point the
//! angular momentum about the stance foot σ keeps σ² ≥ (1 − (1 − m)²)·σ⁺², σ⁺ the post-impact
//! one, so that the step passes over the stance foot from (1 − m)·σ⁺ (`planner::verify::
//! apex_margin`, which the verification measures on the closed-loop orbit).

mod common;

use planner::biped::PlanarBiped;
use planner::collocation::{ConstraintGroup, HzdProblem};
use planner::config::PlannerConfig;
use planner::guess::initial_guess;
use planner::nlp::NlpProblem;

use common::{load, ROOT};

fn margin_rows(p: &HzdProblem) -> Vec<usize> {
    let groups = p.constraint_groups();
    (0..p.num_constraints())
        .filter(|&i| groups.rows[i] == Some(ConstraintGroup::ApexMargin))
        .collect()
}

/// The rows are in the problem only when asked for: one inequality ≥ 0 per interior point
/// (2N − 1), in the apex-margin group, with derivatives (hyper-dual, through the kinematics of
/// two points) that match central finite differences.
#[test]
fn the_margin_rows_exist_only_when_asked_for_and_their_derivatives_are_exact() {
    let (model, _, config) = load(
        "configs/robots/adam_planar.urdf",
        "configs/planner/adam.toml",
    );
    assert_eq!(config.gait.min_apex_margin, None);
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    let free = HzdProblem::new(bp.clone(), config.clone(), Vec::new(), false).expect("problem");
    let x = initial_guess(&bp, &free.layout, 0.22, 0.8).expect("guess");
    let mut bounded = config.clone();
    bounded.gait.min_apex_margin = Some(0.15);
    let p = HzdProblem::new(bp.clone(), bounded, x.clone(), false).expect("problem");
    let plain = HzdProblem::new(bp, config.clone(), x.clone(), false).expect("problem");
    let interior = p.layout.points() - 2;
    assert_eq!(interior, 2 * config.collocation.intervals - 1);
    assert_eq!(p.num_constraints(), plain.num_constraints() + interior);
    assert!(margin_rows(&plain).is_empty());
    let rows = margin_rows(&p);
    assert_eq!(rows.len(), interior);
    let (lo, hi) = p.constraint_bounds_vec();
    for &r in &rows {
        assert_eq!((lo[r], hi[r]), (0.0, f64::INFINITY));
    }
    common::assert_exact_derivatives(&p, &x);
}

/// In the co-design problem the rows see the thigh and shin lengths (the link inertias follow
/// them, exact coupling), and their derivatives in them are exact too.
#[test]
fn with_the_lengths_as_variables_the_rows_derivatives_are_exact() {
    let mut config =
        PlannerConfig::load(format!("{ROOT}/configs/planner/adam.toml")).expect("config");
    config.gait.min_apex_margin = Some(0.15);
    common::assert_codesign_row_sees_the_lengths(config, ConstraintGroup::ApexMargin);
}

/// A gait planned with the bound verifies with its apex margin at the bound: the closed-loop
/// orbit's (the momentum along simulated steps, `planner::verify`) is the zero dynamics' the
/// rows bound. Measured 2026-12-06 (the co-designed ADAM at 0.20 m/s, the library config):
/// 9.5 % without the bound; the library's 0.15–0.25 m/s gaits with m ≥ 0.15: 14.9–15.0 %.
#[test]
fn a_gait_planned_with_the_bound_verifies_with_its_margin_at_the_bound() {
    let (_, report) = common::plan_and_verify_at_020(|c| c.gait.min_apex_margin = Some(0.15));
    // The collocation points sample σ; the simulated step samples it every millisecond, so
    // its minimum may fall between two points a little below the bound.
    assert!(
        (report.apex_margin - 0.15).abs() < 3e-3,
        "{}",
        report.apex_margin
    );
}

/// A margin outside (0, 1) is refused, naming the field and the value.
#[test]
fn a_margin_outside_zero_to_one_is_refused_naming_the_field() {
    common::assert_gait_field_range(
        "min_apex_margin",
        "0.15",
        |c| assert_eq!(c.gait.min_apex_margin, Some(0.15)),
        &["0.0", "1.0", "1.5", "-0.2", "nan"],
    );
}
