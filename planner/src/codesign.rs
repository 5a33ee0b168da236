//! HZD co-design of the thigh and shin lengths with the gait (paper Sec. III–IV).
//!
//! ```text
//! DesignLengths L₀ ─▶ GenerateModel(L₀) ─▶ plan_gait (fixed design, two-step solve) ─▶ x₀
//!   loop j: HzdProblem::with_codesign(model_j, x_j ++ L_j) ─▶ solve ─▶ (x*, L*)
//!           GenerateModel(L*) ─▶ model_{j+1}      until ‖L* − L_j‖∞ < δ (Alg. 1)
//!                                                  or once (exact coupling)
//!   polish: the cost-of-transport solve at the final model, design fixed ─▶ gait file + URDF
//! ```
//!
//! The lengths enter the NLP through the design virtual joints (massless prismatic joints in
//! the URDF), equal left and right and constant over the step ([`Codesign`]). Link inertias
//! follow the lengths in one of two ways ([`InertiaCoupling`]):
//! - **exact**: the cubic fits of mass, com and inertia are evaluated inside every dynamics and
//!   impact constraint and differentiated with them (dual numbers), so one solve is
//!   self-consistent;
//! - **alg1** (the paper's Alg. 1): inertias frozen at the current model during a solve, then
//!   the model is regenerated at the new lengths and the solve repeated, warm-started, until no
//!   length moves more than δ.
//!
//! Submodules: `activity` (which constraints hold an optimum, with their multipliers),
//! `landscape` (the optimal cost over a grid of the design box), `audit` (the gait with and
//! without each constraint that is ours), `speeds` (one design for the gaits of several speeds,
//! one NLP), `endpoints` (the sweep's
//! endpoints as a JSON file, for the landscape figure).
//!
//! The objective during a co-design solve normalises by the total mass of the model the solve
//! started from (the leg masses change a few percent with the lengths); the final polish solve,
//! at the final model, reports the exact cost of transport.

mod activity;
mod audit;
mod endpoints;
mod landscape;
mod speeds;

pub use activity::{activity, Activity, BoundSide, GroupActivity, ACTIVE_SLACK};
pub use audit::{audit, audit_variants, Audit, AuditRow, AuditSolve, AuditVariant, WIDE_PITCH_RAD};
pub use endpoints::{load_sweep_endpoints, save_sweep, SweepEndpoint};
pub use landscape::{
    grid_values, landscape, landscape_point, Landscape, LandscapePoint, LandscapeStart,
};
pub use speeds::{codesign_speeds, MultiSpeedProblem, MultiSpeedResult};

use crate::biped::PlanarBiped;
use crate::collocation::{Codesign, HzdProblem};
use crate::config::{InertiaCoupling, PlannerConfig};
use crate::nlp;
use crate::plan::{self, PlannedGait, Progress, StageReport};
use crate::{PlannerError, Result};
use model::design::DesignLengths;
use std::time::Instant;

/// One solve of the outer loop.
#[derive(Clone, Debug, PartialEq)]
pub struct OuterIteration {
    /// Lengths the solve started from (the model's), m: thigh, shin.
    pub start_m: [f64; 2],
    /// Lengths it found, m.
    pub lengths_m: [f64; 2],
    /// Cost of transport at its solution (mass of the starting model).
    pub cost_of_transport: f64,
    /// The solve.
    pub report: StageReport,
}

/// A co-designed robot and gait.
#[derive(Clone, Debug)]
pub struct CodesignResult {
    /// The final lengths.
    pub design: DesignLengths,
    /// The gait planned at the final lengths (the polish solve); its URDF is [`Self::urdf`]. In
    /// a convergence-study run with exact coupling it is the co-design optimum evaluated on
    /// that robot, and `stages` is empty when the polish was not needed.
    pub planned: PlannedGait,
    /// The URDF of the co-designed robot.
    pub urdf: String,
    /// The gait at the initial design (the warm start).
    pub initial: PlannedGait,
    /// The co-design solves.
    pub outer: Vec<OuterIteration>,
    /// Whether the outer loop met its tolerance (always, for exact coupling).
    pub converged: bool,
    /// The constraints that hold the last co-design solve's optimum, with their multipliers
    /// ([`activity`]); `None` if that solve did not end usable.
    pub activity: Option<Activity>,
    /// Wall time of everything, s.
    pub wall_time_s: f64,
}

/// Iterations a co-design solve gets before it is restarted from its last iterate (a
/// backstop: a solve that stops moving is restarted earlier, by [`CODESIGN_STALL`]). In the 5×5
/// sweep 24 runs need 138–156 iterations in all (co-design and polish).
pub const CODESIGN_RESTART_ITERATIONS: usize = 300;

/// When a co-design solve counts as stalled and is restarted from its last iterate. The sweep's
/// 0.25/0.25 m start stalls after ~45 iterations (steps of 3e-9 m-or-rad, violation frozen at
/// 2.1e-2, objective moving by 2e-12 per iteration at μ = 1.5e-4); it used to crawl to the
/// config's 1000-iteration limit (1139 iterations in all), then to the 300-iteration cap (439).
/// Ten standing iterations are far more than a healthy solve ever shows: near convergence the
/// violation is below the threshold, and far from it the steps are not 1e-7 small.
pub const CODESIGN_STALL: plan::StallGuard = plan::StallGuard {
    step_norm: 1e-7,
    iterations: 10,
    infeasibility: 1e-4,
};

/// Co-designs the thigh and shin lengths with the gait, starting from `config.codesign`'s
/// initial lengths: plans the gait at that design first (the warm start), then
/// [`codesign_from`]. `urdf_ref` is how the gait file will name the co-designed URDF.
pub fn codesign(
    config: &PlannerConfig,
    urdf_ref: &str,
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<CodesignResult> {
    config.validate("planner config")?;
    let start = Instant::now();
    let lengths = config.codesign.initial_m;
    let (model, urdf) = generate(lengths, &config.codesign)?;
    let initial = plan::plan_gait(&model, urdf_ref, &urdf, config, on_progress)?;
    let mut r = codesign_from(config, urdf_ref, &initial, lengths, lengths, on_progress)?;
    r.wall_time_s = start.elapsed().as_secs_f64();
    Ok(r)
}

/// The co-design from a gait `initial` planned for the robot generated at `model_lengths`,
/// with the length variables starting at `start_lengths` (the convergence study starts every
/// run from the same gait and a different initial design).
pub fn codesign_from(
    config: &PlannerConfig,
    urdf_ref: &str,
    initial: &PlannedGait,
    model_lengths: [f64; 2],
    start_lengths: [f64; 2],
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<CodesignResult> {
    codesign_run(
        config,
        urdf_ref,
        initial,
        [model_lengths, start_lengths],
        false,
        on_progress,
    )
}

/// One run of the convergence study ([`codesign_from`] without the gait file's extras: no
/// feed-forward table, and with exact coupling no polish when the co-design optimum already
/// holds on the regenerated robot); its [`CodesignResult::activity`] says which constraints
/// hold the optimum.
pub fn codesign_study_run(
    config: &PlannerConfig,
    initial: &PlannedGait,
    model_lengths: [f64; 2],
    start_lengths: [f64; 2],
) -> Result<CodesignResult> {
    codesign_run(
        config,
        "robot.urdf",
        initial,
        [model_lengths, start_lengths],
        true,
        &mut |_| {},
    )
}

/// Largest constraint or bound violation of an exactly coupled co-design optimum on the
/// regenerated robot for which a convergence-study run reports it without the polish solve
/// (the solver's own constraint tolerance). Measured: 6.3e-9.
const STUDY_POLISH_SKIP_VIOLATION: f64 = 1e-6;

/// [`codesign_from`], or (`study`) one run of the convergence study, which reports designs and
/// costs and writes no gait file:
/// - no feed-forward table (the closed-loop orbit simulation was 4 % of the study's CPU time);
/// - with exact inertia coupling, no polish solve when the co-design optimum satisfies every
///   constraint of the regenerated robot to [`STUDY_POLISH_SKIP_VIOLATION`]: the one solve is
///   self-consistent, and its point is evaluated on that robot (cost of transport with its
///   mass). The polish that `adam codesign` runs moves that cost by 2.5e-5 relative
///   (0.01387237 → 0.01387271) in 11 iterations, 7 % of a run.
fn codesign_run(
    config: &PlannerConfig,
    urdf_ref: &str,
    initial: &PlannedGait,
    [model_lengths, start_lengths]: [[f64; 2]; 2],
    study: bool,
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<CodesignResult> {
    let start = Instant::now();
    let c = &config.codesign;
    let (mut model, mut urdf) = generate(model_lengths, &config.codesign)?;
    let mut nominal = model_lengths;
    let mut lengths = start_lengths;
    let mut x = initial.x.clone();
    let n_fixed = x.len();
    let exact = c.inertia == InertiaCoupling::Exact;
    let mut outer = Vec::new();
    let mut converged = false;
    // The last co-design solve's point and multipliers, for the polish, and the mass its cost
    // of transport was normalised by. (Alg. 1's next solve starts from the point alone: after
    // the model is regenerated the multipliers did not help, 126 iterations against 119 from
    // 0.24/0.25 m.)
    let mut warm: Option<(nlp::WarmStart, f64)> = None;
    let mut last_activity = None;
    for _ in 0..c.max_outer_iterations {
        let mass_kg = model.total_mass_kg();
        let biped = PlanarBiped::new(model.clone(), config.gait.stance_leg, &[])?;
        let spec = Codesign {
            nominal_m: nominal,
            bounds_m: [c.thigh_m, c.shin_m],
            exact_inertia: exact,
            mass: c.mass_model(),
        };
        let mut x0 = x.clone();
        x0.extend(lengths);
        let problem =
            HzdProblem::with_codesign(biped.clone(), config.clone(), x0, true, Some(spec.clone()))?;
        let mut capped = config.clone();
        capped.solver.max_iterations = config
            .solver
            .max_iterations
            .min(CODESIGN_RESTART_ITERATIONS);
        let guards = plan::Guards {
            stall: Some(CODESIGN_STALL),
            ..plan::Guards::default()
        };
        let attempt =
            plan::solve_stage_attempt(&problem, "co-design", &capped, None, guards, on_progress)?;
        // A solve that stalled or ran out of iterations is restarted once from its last iterate
        // (the barrier parameter starts afresh; the initial design of the run is unchanged),
        // with the config's whole iteration limit.
        let (problem, attempt) = if attempt.stalled || attempt.hit_iteration_limit() {
            let restarted = HzdProblem::with_codesign(
                biped,
                config.clone(),
                attempt.solution.x.clone(),
                true,
                Some(spec),
            )?;
            let mut again = plan::solve_stage_attempt(
                &restarted,
                "co-design (restarted)",
                config,
                None,
                guards,
                on_progress,
            )?;
            // Report both solves together: iterations and times are the run's.
            again.report.absorb(&attempt.report);
            (restarted, again)
        } else {
            (problem, attempt)
        };
        warm = Some((attempt.solution.warm_start(), mass_kg));
        last_activity = attempt
            .usable
            .then(|| activity(&problem, &attempt.solution));
        let (xs, report) = attempt.into_result()?;
        let l = &problem.layout;
        let found = [xs[l.design_var(0)], xs[l.design_var(1)]];
        outer.push(OuterIteration {
            start_m: lengths,
            lengths_m: found,
            cost_of_transport: problem.cost_of_transport(&xs),
            report,
        });
        let moved = (found[0] - lengths[0])
            .abs()
            .max((found[1] - lengths[1]).abs());
        lengths = found;
        nominal = found;
        (model, urdf) = generate(lengths, &config.codesign)?;
        x = xs[..n_fixed].to_vec();
        if exact || moved < c.tolerance_m {
            converged = true;
            break;
        }
    }
    // Polish at the final model, design fixed: the gait file's robot is exactly this URDF.
    let biped = PlanarBiped::new(model.clone(), config.gait.stance_leg, &[])?;
    let problem = HzdProblem::new(biped, config.clone(), x, true)?;
    // From the co-design solution with its multipliers: at the design it found (and, with
    // exact coupling, the same inertias) that point is already optimal up to the cost's
    // mass normalisation, so the polish only confirms it instead of re-centring from scratch.
    let mut x0 = vec![0.0; problem.layout.len()];
    crate::nlp::NlpProblem::initial_point(&problem, &mut x0);
    let skip_polish = study && exact && problem.max_violation(&x0) <= STUDY_POLISH_SKIP_VIOLATION;
    let (xf, reports) = if skip_polish {
        (x0, Vec::new())
    } else {
        let resume = warm.map(|(start, from_kg)| {
            let mut start = rescaled(start, from_kg / model.total_mass_kg());
            for v in [
                &mut start.lower_bound_multipliers,
                &mut start.upper_bound_multipliers,
            ] {
                v.truncate(n_fixed);
            }
            if let Some(x) = &mut start.x {
                x.truncate(n_fixed);
            }
            start
        });
        let (xf, report) = plan::solve_stage_attempt(
            &problem,
            "polish",
            config,
            resume,
            plan::Guards::default(),
            on_progress,
        )?
        .into_result()?;
        (xf, vec![report])
    };
    // The gait file's solver summary: the polish, or the co-design solve it stands for.
    let gait_reports = match (reports.is_empty(), outer.last()) {
        (true, Some(o)) => std::slice::from_ref(&o.report),
        _ => &reports[..],
    };
    let mut gait = plan::gait_from_solution(&problem, &xf, urdf_ref, &urdf, gait_reports)?;
    if !study {
        gait.feedforward = Some(crate::verify::feedforward_from_orbit(
            &model,
            &gait,
            crate::verify::VerifyOptions::default(),
        )?);
    }
    let size = (problem.layout.len(), nlp_constraints(&problem));
    let planned = PlannedGait {
        gait,
        stages: reports,
        x: xf,
        feasible_x: Vec::new(),
        size,
        feasibility_size: None,
        setup_time_s: 0.0,
    };
    Ok(CodesignResult {
        design: DesignLengths {
            thigh_length_m: lengths[0],
            shin_length_m: lengths[1],
        },
        planned,
        urdf,
        initial: initial.clone(),
        outer,
        converged,
        activity: last_activity,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

/// A warm start for a problem whose objective is `factor` times the one it came from (the
/// cost of transport normalised by another mass): multipliers scale with the objective.
fn rescaled(mut start: nlp::WarmStart, factor: f64) -> nlp::WarmStart {
    for v in [
        &mut start.constraint_multipliers,
        &mut start.lower_bound_multipliers,
        &mut start.upper_bound_multipliers,
    ] {
        v.iter_mut().for_each(|m| *m *= factor);
    }
    start
}

fn nlp_constraints(problem: &HzdProblem) -> usize {
    crate::nlp::NlpProblem::num_constraints(problem)
}

/// GenerateModel at `lengths` (thigh, shin, m) with the config's mass model (the tubes' density
/// scale, the A1 drives).
fn generate(
    lengths: [f64; 2],
    codesign: &crate::config::CodesignConfig,
) -> Result<(model::PlanarModel, String)> {
    let design = DesignLengths {
        thigh_length_m: lengths[0],
        shin_length_m: lengths[1],
    };
    let mass = codesign.mass_model();
    let (model, urdf) =
        model::design::generate_model_with(&design, &mass).map_err(|e| PlannerError::Robot {
            robot: "adam_planar".into(),
            reason: format!(
                "GenerateModel at thigh {} m, shin {} m: {e}",
                lengths[0], lengths[1]
            ),
        })?;
    Ok((model, urdf))
}

/// One run of the convergence study.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRun {
    /// Initial thigh and shin length, m.
    pub initial_m: [f64; 2],
    /// The outcome: converged lengths and gait figures, or why the run failed.
    pub outcome: std::result::Result<SweepOutcome, String>,
    /// Wall time of the run, s.
    pub wall_time_s: f64,
}

/// Where a run of the convergence study ended (also a point of the landscape, and the result
/// of a sweep task, which `adam sweep task` writes as JSON).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepOutcome {
    /// Converged thigh and shin length, m.
    pub lengths_m: [f64; 2],
    /// Step length, m.
    pub step_length_m: f64,
    /// Step duration, s.
    pub step_duration_s: f64,
    /// Speed, m/s.
    pub speed_mps: f64,
    /// Cost of transport at the run's final lengths (of the co-design optimum on the
    /// regenerated robot with exact coupling, else of the polished gait): the mechanical one,
    /// Σ∫|u q̇| dt / (m g d), whatever `[cost]` minimizes.
    pub cost_of_transport: f64,
    /// The objective `[cost]` minimizes, at the run's last solve (equal to the cost of
    /// transport for the default mechanical cost): what ranks runs and grid points.
    pub objective: f64,
    /// Solver iterations over the run's solves.
    pub iterations: usize,
    /// Solve time over the run's solves, s.
    pub solve_time_s: f64,
}

/// The initial lengths of an `n × n` grid over the config's design bounds (thigh varies
/// slowest).
pub fn sweep_grid(config: &PlannerConfig, n: usize) -> Vec<[f64; 2]> {
    let c = &config.codesign;
    let at = |[a, b]: [f64; 2], i: usize| {
        if n <= 1 {
            0.5 * (a + b)
        } else {
            a + (b - a) * i as f64 / (n - 1) as f64
        }
    };
    (0..n)
        .flat_map(|i| (0..n).map(move |j| [at(c.thigh_m, i), at(c.shin_m, j)]))
        .collect()
}

/// One run of the convergence study: the co-design from the initial design `start`, warm-started
/// from `initial` (planned at `model_lengths`). The task of `adam codesign sweep` and of
/// `adam sweep task` for a co-design plan (the same function on both paths). Call it from a
/// rayon worker (the in-process sweep's `par_iter`, `adam sweep task`'s one-thread pool) so
/// that its solves evaluate their derivatives on one thread, as the sweep always did.
pub fn sweep_run(
    config: &PlannerConfig,
    initial: &PlannedGait,
    model_lengths: [f64; 2],
    start: [f64; 2],
) -> SweepRun {
    let t0 = Instant::now();
    let outcome = codesign_run(
        config,
        "robot.urdf",
        initial,
        [model_lengths, start],
        true,
        &mut |_| {},
    )
    .map(|r| {
        let g = &r.planned.gait;
        let reports = r
            .outer
            .iter()
            .map(|o| &o.report)
            .chain(r.planned.stages.iter());
        let objective = r
            .planned
            .stages
            .last()
            .map_or(g.cost_of_transport, |s| s.objective);
        let (iterations, solve_time_s) =
            reports.fold((0, 0.0), |(i, t), s| (i + s.iterations, t + s.solve_time_s));
        SweepOutcome {
            lengths_m: [r.design.thigh_length_m, r.design.shin_length_m],
            step_length_m: g.step_length_m,
            step_duration_s: g.step_duration_s,
            speed_mps: g.speed_mps,
            cost_of_transport: g.cost_of_transport,
            objective,
            iterations,
            solve_time_s,
        }
    })
    .map_err(|e| e.to_string());
    SweepRun {
        initial_m: start,
        outcome,
        wall_time_s: t0.elapsed().as_secs_f64(),
    }
}

/// The paper's convergence study: one co-design per initial design in `starts` ([`sweep_run`]),
/// all from the same warm start `initial` (planned at `model_lengths`), in parallel on all
/// cores. `on_done` is called from the worker threads as runs finish (for a progress bar).
pub fn sweep(
    config: &PlannerConfig,
    initial: &PlannedGait,
    model_lengths: [f64; 2],
    starts: &[[f64; 2]],
    on_done: &(dyn Fn(&SweepRun) + Sync),
) -> Vec<SweepRun> {
    use rayon::prelude::*;
    starts
        .par_iter()
        .map(|&start| {
            let run = sweep_run(config, initial, model_lengths, start);
            on_done(&run);
            run
        })
        .collect()
}

/// Runs whose objective (the cost `[cost]` minimizes) is more than `relative` above the best
/// run's: local minima.
pub fn local_minima(runs: &[SweepRun], relative: f64) -> Vec<bool> {
    let best = runs
        .iter()
        .filter_map(|r| r.outcome.as_ref().ok())
        .map(|o| o.objective)
        .fold(f64::INFINITY, f64::min);
    runs.iter()
        .map(|r| {
            r.outcome
                .as_ref()
                .is_ok_and(|o| o.objective > best * (1.0 + relative))
        })
        .collect()
}

/// Mean and standard deviation (population) of a sample.
pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    if values.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

/// The gait optimized at a fixed design, warm-started from `initial` (a gait of another design):
/// the cost-of-transport solve on the robot generated at `lengths_m`.
pub fn fixed_design(
    config: &PlannerConfig,
    initial: &PlannedGait,
    lengths_m: [f64; 2],
) -> std::result::Result<SweepOutcome, String> {
    let run = || -> Result<SweepOutcome> {
        let (model, urdf) = generate(lengths_m, &config.codesign)?;
        let biped = PlanarBiped::new(model, config.gait.stance_leg, &[])?;
        let problem = HzdProblem::new(biped, config.clone(), initial.x.clone(), true)?;
        let (x, report) = plan::solve_stage(&problem, "fixed design", config, &mut |_| {})?;
        let g = plan::gait_from_solution(
            &problem,
            &x,
            "robot.urdf",
            &urdf,
            std::slice::from_ref(&report),
        )?;
        Ok(SweepOutcome {
            lengths_m,
            step_length_m: g.step_length_m,
            step_duration_s: g.step_duration_s,
            speed_mps: g.speed_mps,
            cost_of_transport: g.cost_of_transport,
            objective: report.objective,
            iterations: report.iterations,
            solve_time_s: report.solve_time_s,
        })
    };
    run().map_err(|e| e.to_string())
}

/// [`fixed_design`] for several designs, in parallel.
pub fn compare_fixed_designs(
    config: &PlannerConfig,
    initial: &PlannedGait,
    designs: &[[f64; 2]],
) -> Vec<std::result::Result<SweepOutcome, String>> {
    use rayon::prelude::*;
    designs
        .par_iter()
        .map(|&d| fixed_design(config, initial, d))
        .collect()
}
