//! The constraint audit (`adam codesign audit`, planner/CODESIGN.md "Constraints"): the gait
//! optimized with and without each constraint that is ours, not the paper's, at a fixed robot.
//!
//! Each variant relaxes the shipped config (a `[gait]` margin down to its physical form, or a
//! `[constraints]` switch) and is solved twice: the cost-of-transport solve from the baseline
//! optimum (feasible for every variant, since each only relaxes; it finds the nearest optimum
//! of the relaxed problem), and the whole two-step plan from the hand-built guess (as an
//! independent formulation would start; it may find another local optimum). The baseline's
//! [`Activity`](super::Activity) says how hard each of ours pushes at the optimum.

use super::{activity, Activity};
use crate::biped::PlanarBiped;
use crate::collocation::{ConstraintGroup, HzdProblem};
use crate::config::{ClearanceProfile, PlannerConfig};
use crate::plan::{self, PlannedGait};
use crate::Result;
use model::PlanarModel;

/// A relaxation of the shipped constraints.
#[derive(Clone, Debug)]
pub struct AuditVariant {
    /// Short name.
    pub name: &'static str,
    /// What it changes, in words.
    pub change: &'static str,
    /// The group it relaxes (`None`: the baseline, or several).
    pub group: Option<ConstraintGroup>,
    /// The config with the change.
    pub config: PlannerConfig,
}

/// The pitch range of the variants without our pitch limits, rad: wide enough never to bind
/// (the torso lying flat is ±π/2).
pub const WIDE_PITCH_RAD: [f64; 2] = [-1.5, 1.5];

/// The baseline and one variant per constraint of ours, and all of them off together.
pub fn audit_variants(base: &PlannerConfig) -> Vec<AuditVariant> {
    let with = |f: &dyn Fn(&mut PlannerConfig)| {
        let mut c = base.clone();
        f(&mut c);
        c
    };
    let none = |c: &mut PlannerConfig| {
        c.gait.swing_clearance_m = 0.0;
        c.gait.impact_velocity_mps = 0.0;
        c.gait.min_normal_force_n = 0.0;
        c.constraints.liftoff = false;
        c.gait.pitch_limits_rad = WIDE_PITCH_RAD;
    };
    vec![
        AuditVariant {
            name: "baseline",
            change: "the shipped constraints",
            group: None,
            config: base.clone(),
        },
        AuditVariant {
            name: "clearance z ≥ 0",
            change: "swing foot only above the ground (swing_clearance_m = 0)",
            group: Some(ConstraintGroup::SwingClearance),
            config: with(&|c| c.gait.swing_clearance_m = 0.0),
        },
        AuditVariant {
            name: "clearance at mid-step",
            change: "clearance c at mid-step only, z ≥ 0 elsewhere (clearance_profile = midstep)",
            group: Some(ConstraintGroup::SwingClearance),
            config: with(&|c| c.constraints.clearance_profile = ClearanceProfile::Midstep),
        },
        AuditVariant {
            name: "no impact-velocity margin",
            change: "touchdown descent ż ≤ 0 instead of ≤ −impact_velocity_mps",
            group: Some(ConstraintGroup::ImpactVelocity),
            config: with(&|c| c.gait.impact_velocity_mps = 0.0),
        },
        AuditVariant {
            name: "no lift-off",
            change: "the old stance foot need not rise after impact (liftoff = false)",
            group: Some(ConstraintGroup::Liftoff),
            config: with(&|c| c.constraints.liftoff = false),
        },
        AuditVariant {
            name: "no pitch limits",
            change: "torso pitch within ±1.5 rad instead of pitch_limits_rad",
            group: Some(ConstraintGroup::Pitch),
            config: with(&|c| c.gait.pitch_limits_rad = WIDE_PITCH_RAD),
        },
        AuditVariant {
            name: "none of ours",
            change: "all of the above at once, and min_normal_force_n = 0",
            group: None,
            config: with(&none),
        },
    ]
}

/// A solved variant's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct AuditSolve {
    /// Cost of transport.
    pub cost_of_transport: f64,
    /// Step length, m.
    pub step_length_m: f64,
    /// Step duration, s.
    pub step_duration_s: f64,
    /// Lowest swing-foot height over the interior points, m.
    pub min_swing_height_m: f64,
    /// Iterations.
    pub iterations: usize,
}

/// One row of the audit.
#[derive(Clone, Debug)]
pub struct AuditRow {
    /// The variant.
    pub variant: AuditVariant,
    /// The cost-of-transport solve from the baseline optimum.
    pub from_baseline: std::result::Result<AuditSolve, String>,
    /// The whole two-step plan from the hand-built guess.
    pub from_scratch: std::result::Result<AuditSolve, String>,
}

/// The audit of `model` under `config`: the baseline plan, its activity, and every variant.
pub struct Audit {
    /// The baseline's constraint activity (the cost-of-transport solve at the plan's optimum).
    pub baseline_activity: Option<Activity>,
    /// One row per variant, the baseline first.
    pub rows: Vec<AuditRow>,
}

/// Runs the audit, the variants in parallel.
pub fn audit(model: &PlanarModel, urdf: &str, config: &PlannerConfig) -> Result<Audit> {
    use rayon::prelude::*;
    let baseline = plan::plan_gait(model, "robot.urdf", urdf, config, &mut |_| {})?;
    let variants = audit_variants(config);
    let rows: Vec<(AuditRow, Option<Activity>)> = variants
        .into_par_iter()
        .map(|variant| {
            let warm = solve_from(model, urdf, &variant.config, &baseline);
            let scratch = plan::plan_gait(model, "robot.urdf", urdf, &variant.config, &mut |_| {})
                .and_then(|p| figures(model, &variant.config, &p.x, &p))
                .map_err(|e| e.to_string());
            let (from_baseline, act) = match warm {
                Ok((s, a)) => (Ok(s), a),
                Err(e) => (Err(e.to_string()), None),
            };
            let act = if variant.name == "baseline" {
                act
            } else {
                None
            };
            (
                AuditRow {
                    variant,
                    from_baseline,
                    from_scratch: scratch,
                },
                act,
            )
        })
        .collect();
    let baseline_activity = rows.iter().find_map(|r| r.1.clone());
    Ok(Audit {
        baseline_activity,
        rows: rows.into_iter().map(|r| r.0).collect(),
    })
}

/// The cost-of-transport solve of `config` from the baseline optimum, with its activity.
fn solve_from(
    model: &PlanarModel,
    urdf: &str,
    config: &PlannerConfig,
    baseline: &PlannedGait,
) -> Result<(AuditSolve, Option<Activity>)> {
    let biped = PlanarBiped::new(model.clone(), config.gait.stance_leg, &[])?;
    let problem = HzdProblem::new(biped, config.clone(), baseline.x.clone(), true)?;
    let attempt = plan::solve_stage_attempt(
        &problem,
        "audit",
        config,
        None,
        plan::Guards::default(),
        &mut |_| {},
    )?;
    let act = attempt
        .usable
        .then(|| activity(&problem, &attempt.solution));
    let (x, report) = attempt.into_result()?;
    let g = plan::gait_from_solution(
        &problem,
        &x,
        "robot.urdf",
        urdf,
        std::slice::from_ref(&report),
    )?;
    Ok((
        AuditSolve {
            cost_of_transport: g.cost_of_transport,
            step_length_m: g.step_length_m,
            step_duration_s: g.step_duration_s,
            min_swing_height_m: min_swing_height(&problem, &x),
            iterations: report.iterations,
        },
        act,
    ))
}

/// A planned gait's figures.
fn figures(
    model: &PlanarModel,
    config: &PlannerConfig,
    x: &[f64],
    p: &PlannedGait,
) -> Result<AuditSolve> {
    let biped = PlanarBiped::new(model.clone(), config.gait.stance_leg, &[])?;
    let problem = HzdProblem::new(biped, config.clone(), x.to_vec(), true)?;
    Ok(AuditSolve {
        cost_of_transport: p.gait.cost_of_transport,
        step_length_m: p.gait.step_length_m,
        step_duration_s: p.gait.step_duration_s,
        min_swing_height_m: min_swing_height(&problem, x),
        iterations: p.stages.iter().map(|s| s.iterations).sum(),
    })
}

/// The lowest swing-foot height over the interior collocation points, m.
fn min_swing_height(problem: &HzdProblem, x: &[f64]) -> f64 {
    problem
        .swing_heights_m(x)
        .iter()
        .rev()
        .skip(1)
        .copied()
        .fold(f64::INFINITY, f64::min)
}
