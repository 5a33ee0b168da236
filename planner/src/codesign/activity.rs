//! Which constraints hold an optimum where it is: the active inequality rows and variable
//! bounds of a solved [`HzdProblem`], grouped for a reader ([`ConstraintGroup`]: Table I, the
//! design box, torque, friction, clearance, ...), each with the rate at which the cost would
//! fall if its active bounds were relaxed.
//!
//! With the solver's Lagrangian f + λᵀg − z_Lᵀ(x − x_L) + z_Uᵀ(x − x_U) (planner::nlp), the
//! optimal cost f* moves with a bound b of an active row by ∂f*/∂b = −λ, with a variable's lower
//! bound by +z_L and with its upper bound by −z_U. The *relief* of an active bound is the cost
//! saved per unit the bound moves outward (a lower bound down, an upper bound up): −λ or +z_L
//! at a lower bound, +λ or +z_U at an upper one; it is ≥ 0 at a KKT point.
//! `planner/tests/codesign.rs` checks it against a re-solve with the step-length bound moved.

use crate::collocation::{ConstraintGroup, HzdProblem};
use crate::nlp::{NlpProblem, Solution};
use std::fmt;

/// An inequality counts as active when its slack is at most this, relative to 1 + |bound|
/// (the solver's tolerance is 1e-6; the barrier leaves inactive ones orders of magnitude
/// farther).
pub const ACTIVE_SLACK: f64 = 1e-5;

/// Which side of a bound is active.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundSide {
    /// The lower bound.
    Lower,
    /// The upper bound.
    Upper,
}

/// The activity of one group at an optimum.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupActivity {
    /// The group.
    pub group: ConstraintGroup,
    /// Inequality rows and bounded variables of the group.
    pub bounded: usize,
    /// Of which at an active bound.
    pub active: usize,
    /// Σ relief over the active bounds: cost saved per group unit (m, s, N·m, N, ...) if every
    /// active bound of the group moved outward by one unit.
    pub relief_per_unit: f64,
    /// The largest single relief, cost per group unit.
    pub largest_relief_per_unit: f64,
    /// For a group of one variable (step length and duration, thigh, shin): its value, the
    /// bound and side if active.
    pub value: Option<(f64, Option<(BoundSide, f64)>)>,
}

/// The constraints that hold an optimum, group by group.
#[derive(Clone, Debug, PartialEq)]
pub struct Activity {
    /// The cost (the solve's objective) at the optimum.
    pub cost: f64,
    /// Every group of the problem with a bounded row or variable, in report order.
    pub groups: Vec<GroupActivity>,
}

impl Activity {
    /// The group's activity, if the problem has it.
    pub fn group(&self, group: ConstraintGroup) -> Option<&GroupActivity> {
        self.groups.iter().find(|g| g.group == group)
    }
}

/// Which side of `[lo, hi]` the value `v` sits on, if it is within [`ACTIVE_SLACK`] of one
/// (an equality, lo = hi, is never "active" here).
fn active_side(v: f64, lo: f64, hi: f64) -> Option<(BoundSide, f64)> {
    if lo >= hi {
        return None;
    }
    let near = |b: f64| b.is_finite() && (v - b).abs() <= ACTIVE_SLACK * (1.0 + b.abs());
    if near(lo) {
        Some((BoundSide::Lower, lo))
    } else if near(hi) {
        Some((BoundSide::Upper, hi))
    } else {
        None
    }
}

/// The activity of `solution`, an optimum of `problem`.
pub fn activity(problem: &HzdProblem, solution: &Solution) -> Activity {
    let groups = problem.constraint_groups();
    let mut acc: Vec<GroupActivity> = ConstraintGroup::ALL
        .iter()
        .map(|&group| GroupActivity {
            group,
            bounded: 0,
            active: 0,
            relief_per_unit: 0.0,
            largest_relief_per_unit: 0.0,
            value: None,
        })
        .collect();
    let slot = |g: ConstraintGroup| ConstraintGroup::ALL.iter().position(|&a| a == g);
    let mut add = |g: ConstraintGroup, side: Option<(BoundSide, f64)>, relief: f64| {
        if let Some(a) = slot(g).map(|i| &mut acc[i]) {
            a.bounded += 1;
            if side.is_some() {
                a.active += 1;
                a.relief_per_unit += relief;
                a.largest_relief_per_unit = a.largest_relief_per_unit.max(relief);
            }
        }
    };
    let (lo_g, hi_g) = problem.constraint_bounds_vec();
    let mut g = vec![0.0; problem.num_constraints()];
    let values = if problem.constraints(&solution.x, &mut g).is_ok() {
        &g
    } else {
        &solution.constraint_values
    };
    for (i, group) in groups.rows.iter().enumerate() {
        let Some(group) = *group else { continue };
        let side = active_side(values[i], lo_g[i], hi_g[i]);
        let lambda = solution.constraint_multipliers[i];
        let relief = match side {
            Some((BoundSide::Lower, _)) => -lambda,
            Some((BoundSide::Upper, _)) => lambda,
            None => 0.0,
        };
        add(group, side, relief);
    }
    let (lo, hi) = problem.bounds();
    for (i, group) in groups.variables.iter().enumerate() {
        let Some(group) = *group else { continue };
        let side = active_side(solution.x[i], lo[i], hi[i]);
        let relief = match side {
            Some((BoundSide::Lower, _)) => solution.lower_bound_multipliers[i],
            Some((BoundSide::Upper, _)) => solution.upper_bound_multipliers[i],
            None => 0.0,
        } / groups.variable_scale[i];
        add(group, side, relief);
    }
    // One-variable groups also report their value.
    let l = &problem.layout;
    let mut singles = vec![
        (ConstraintGroup::StepLength, l.length()),
        (ConstraintGroup::StepDuration, l.duration()),
    ];
    if l.design > 0 {
        singles.push((ConstraintGroup::ThighLength, l.design_var(0)));
        singles.push((ConstraintGroup::ShinLength, l.design_var(1)));
    }
    for (group, i) in singles {
        if let Some(a) = slot(group).map(|s| &mut acc[s]) {
            let v = solution.x[i];
            a.value = Some((v, active_side(v, lo[i], hi[i])));
        }
    }
    Activity {
        cost: solution.statistics.objective,
        groups: acc.into_iter().filter(|a| a.bounded > 0).collect(),
    }
}

impl fmt::Display for Activity {
    /// A Markdown table: group, whose, active of bounded, relief, value.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "| constraint group | source | active / bounded | cost saved per unit relaxed (Σ) | largest single | value |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|")?;
        for a in &self.groups {
            let value = match a.value {
                None => String::new(),
                Some((v, None)) => format!("{v:.4} (interior)"),
                Some((v, Some((side, b)))) => format!(
                    "{v:.4} at its {} bound {b}",
                    match side {
                        BoundSide::Lower => "lower",
                        BoundSide::Upper => "upper",
                    }
                ),
            };
            writeln!(
                f,
                "| {} | {} | {} / {} | {:.3e} | {:.3e} | {} |",
                a.group.describe(),
                a.group.source(),
                a.active,
                a.bounded,
                a.relief_per_unit,
                a.largest_relief_per_unit,
                value
            )?;
        }
        Ok(())
    }
}
