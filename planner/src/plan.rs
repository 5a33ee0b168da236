//! The paper's two-step solve (Sec. IV-C) and the gait file it produces.
//!
//! Step 1 finds a feasible periodic gait from the hand-built guess with no cost; step 2 starts
//! from it and minimizes the mechanical cost of transport. Step 2's start keeps step 1's point
//! but moves the power slacks, which carried no cost in step 1, onto the central path of
//! `[solver] cost_stage_mu_init` and starts the barrier there
//! ([`HzdProblem::centre_power_slacks`]). Both run sequentially with a fixed
//! probe seed, so the same model and config give the same gait bit for bit.

use crate::biped::PlanarBiped;
use crate::collocation::{HzdProblem, TORQUE_SCALE};
use crate::config::{PlannerConfig, SolverBackend};
use crate::guess::initial_guess;
use crate::nlp::{self, IterationControl, IterationReport, SolveOptions};
use crate::{PlannerError, Result};
use model::design::DesignLengths;
use model::gait::{
    sha256_hex, BezierSpec, FeedforwardTable, GaitFile, PhaseDefinition, RobotReference,
    RobotState, SolverSummary, GAIT_SCHEMA_VERSION,
};
use model::PlanarModel;
use std::time::Instant;

/// What one solve did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StageReport {
    /// `feasibility` or `cost of transport`.
    pub stage: &'static str,
    /// Solver status.
    pub status: String,
    /// Iterations, those of the solver's feasibility-restoration phase included (ripopt does
    /// not say which ones those are).
    pub iterations: usize,
    /// Final objective.
    pub objective: f64,
    /// Largest constraint or bound violation at the end.
    pub violation: f64,
    /// Wall time of the solve, s.
    pub solve_time_s: f64,
    /// Wall time spent evaluating the problem (derivatives included), s.
    pub evaluation_time_s: f64,
    /// Iterations of the backend's feasibility-restoration phase among `iterations` (native;
    /// `None` if any part ran on ripopt, which does not say which iterations those are).
    pub restoration_iterations: Option<usize>,
    /// The rest of the solve time by phase (KKT factorizations, solves with the factors,
    /// other), where the backend measures it (native; `None` if any part ran on ripopt).
    pub phases: Option<nlp::PhaseTimes>,
    /// The backend that finished the solve (ripopt after a native solve whose restoration
    /// failed).
    pub backend: nlp::Backend,
}

impl StageReport {
    /// Adds the work of `earlier`, a solve this one stands for (a dropped feasibility start, a
    /// co-design solve that was restarted): iterations and times are the stage's in all.
    pub fn absorb(&mut self, earlier: &StageReport) {
        self.iterations += earlier.iterations;
        self.solve_time_s += earlier.solve_time_s;
        self.evaluation_time_s += earlier.evaluation_time_s;
        self.restoration_iterations =
            nlp::sum_if_both(self.restoration_iterations, earlier.restoration_iterations);
        self.phases = nlp::sum_if_both(self.phases, earlier.phases);
    }
}

/// A planned gait and how it was found.
#[derive(Clone, Debug)]
pub struct PlannedGait {
    /// The gait file content.
    pub gait: GaitFile,
    /// One report per solve.
    pub stages: Vec<StageReport>,
    /// The final NLP point.
    pub x: Vec<f64>,
    /// The feasibility stage's point (the start of the cost-of-transport solve; no power
    /// slacks, see [`cost_stage_problem`]).
    pub feasible_x: Vec<f64>,
    /// Variables and constraints of the cost-of-transport NLP.
    pub size: (usize, usize),
    /// Variables and constraints of the feasibility NLP (no power slacks), if one was solved.
    pub feasibility_size: Option<(usize, usize)>,
    /// Set-up time (problem construction, sparsity detection), s.
    pub setup_time_s: f64,
}

/// A progress event for a live display.
#[derive(Clone, Copy, Debug)]
pub enum Progress<'a> {
    /// A solve starts.
    Stage(&'static str),
    /// One solver iteration.
    Iteration(&'static str, &'a IterationReport),
}

const FEASIBILITY: &str = "feasibility";

/// Iterations allowed to one start of the feasibility solve before the next start is tried.
pub const FEASIBILITY_MAX_ITERATIONS: usize = 150;

/// The cost-of-transport solve alone, from a feasible point (for warm re-plans and tests).
pub fn solve_cost_stage(
    model: &PlanarModel,
    config: &PlannerConfig,
    feasible_x: &[f64],
) -> Result<Vec<f64>> {
    let biped = PlanarBiped::new(model.clone(), config.gait.stance_leg, &[])?;
    let costed = cost_stage_problem(biped, config, feasible_x)?;
    Ok(solve_stage(&costed, "cost of transport", config, &mut |_| {})?.0)
}

/// The cost-of-transport problem from a point of the feasibility problem (no power slacks),
/// with the power slacks made from its u q̇ and centred for `[solver] cost_stage_mu_init`.
pub fn cost_stage_problem(
    biped: PlanarBiped,
    config: &PlannerConfig,
    feasible_x: &[f64],
) -> Result<HzdProblem> {
    let mut costed = HzdProblem::new(biped, config.clone(), Vec::new(), true)?;
    costed.set_initial(costed.layout.with_slacks(feasible_x)?);
    costed.centre_power_slacks(config.solver.cost_stage_mu_init);
    Ok(costed)
}

pub(crate) fn solve_stage(
    problem: &HzdProblem,
    stage: &'static str,
    config: &PlannerConfig,
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<(Vec<f64>, StageReport)> {
    let attempt =
        solve_stage_attempt(problem, stage, config, None, Guards::default(), on_progress)?;
    attempt.into_result()
}

/// What the gait file says solved it: the backend, or each stage's where they differ.
fn solver_description(stages: &[StageReport]) -> String {
    let name = |b: nlp::Backend| match b {
        nlp::Backend::Native => "native interior point (planner::nlp, faer LDLᵀ)",
        _ => "ripopt 0.8 interior point via planner::nlp",
    };
    match stages.first() {
        Some(first) if stages.iter().all(|s| s.backend == first.backend) => {
            name(first.backend).into()
        }
        None => name(nlp::Backend::default()).into(),
        Some(_) => stages
            .iter()
            .map(|s| format!("{}: {}", s.stage, name(s.backend)))
            .collect::<Vec<_>>()
            .join("; "),
    }
}

/// Whether a stage the native interior point ended with `status` is solved again by ripopt:
/// when the native restoration phase or its linear algebra failed (ripopt's restoration is the
/// more seasoned), unless the caller drops starts that need restoration anyway or the solve
/// was stopped on purpose (`stopped`: the iteration cap or the stall guard).
fn retry_with_ripopt(
    backend: nlp::Backend,
    status: nlp::SolveStatus,
    guards: Guards,
    stopped: bool,
) -> bool {
    backend == nlp::Backend::Native
        && matches!(
            status,
            nlp::SolveStatus::RestorationFailed
                | nlp::SolveStatus::NumericalError
                | nlp::SolveStatus::TinyStep
        )
        && !guards.abandon_restoration
        && !stopped
}

/// When [`solve_stage_attempt`] gives up on a solve before the solver does (the default: never;
/// the solver runs to its own end or the iteration cap).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Guards {
    /// Stop a solve that stopped moving.
    pub stall: Option<StallGuard>,
    /// Stop a solve as soon as the solver enters its feasibility-restoration phase. On the HZD
    /// problem a feasibility start that needs restoration is a poor start: with step durations
    /// of 0.6-0.7 s the first start spent 58 s and ~1000 restoration iterations before it got
    /// back, while the next start needed 45 iterations.
    pub abandon_restoration: bool,
}

/// When a solve counts as stalled: its primal step has stayed below `step_norm` for
/// `iterations` consecutive iterations while the constraint violation is still above
/// `infeasibility`. The co-design's 0.25/0.25 m sweep start does this from iteration ~45: steps
/// of 3e-9, violation frozen at 2.1e-2, objective moving by 2e-12 per iteration, at a fixed
/// barrier parameter; left alone it crawls to its iteration limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StallGuard {
    /// Largest primal step (max norm) that counts as not moving.
    pub step_norm: f64,
    /// Consecutive such iterations that make a stall.
    pub iterations: usize,
    /// Constraint violation above which a standing iterate is not converging.
    pub infeasibility: f64,
}

/// One solve of a stage, successful or not: the solver's last iterate with its multipliers
/// (to warm-start a neighbouring solve) and the stage's report.
pub(crate) struct StageAttempt {
    /// The solver's outcome.
    pub solution: nlp::Solution,
    /// Its report.
    pub report: StageReport,
    /// Whether the stage may use it.
    pub usable: bool,
    /// Whether the [`StallGuard`] stopped it.
    pub stalled: bool,
    /// If not usable: the most violated constraint groups at its end, worst first.
    pub violated: Vec<(String, f64)>,
}

impl StageAttempt {
    /// The iterate if usable, else the error naming the stage, status and violation.
    pub fn into_result(self) -> Result<(Vec<f64>, StageReport)> {
        if !self.usable {
            return Err(PlannerError::NotSolved {
                stage: self.report.stage.to_string(),
                status: self.report.status.clone(),
                iterations: self.report.iterations,
                violation: self.report.violation,
                violated: self.violated,
            });
        }
        Ok((self.solution.x, self.report))
    }

    /// The solver stopped at its iteration limit.
    pub fn hit_iteration_limit(&self) -> bool {
        self.solution.status == nlp::SolveStatus::IterationLimit
    }
}

/// One solve of a stage, from the problem's initial point or from `warm_start` (a point and
/// multipliers of a neighbouring solve), stopped early if `stall` says it stopped moving.
pub(crate) fn solve_stage_attempt(
    problem: &HzdProblem,
    stage: &'static str,
    config: &PlannerConfig,
    warm_start: Option<nlp::WarmStart>,
    guards: Guards,
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<StageAttempt> {
    on_progress(Progress::Stage(stage));
    let backend = match config.solver.backend {
        SolverBackend::Ripopt => nlp::Backend::Ripopt,
        SolverBackend::Native => nlp::Backend::Native,
    };
    let mut options = SolveOptions {
        tolerance: config.solver.tolerance,
        constraint_violation_tolerance: 1e-6,
        max_iterations: config.solver.max_iterations,
        initial_barrier: warm_start
            .is_none()
            .then(|| problem.initial_barrier())
            .flatten(),
        warm_start,
        backend,
        ..SolveOptions::default()
    };
    let mut standing = 0;
    let mut stalled = false;
    // ripopt counts only its main iterations against `max_iterations`; its restoration phase
    // is a nested solve with iterations of its own (reported through the same callback,
    // numbered from 0 again, not flagged). Every reported iteration counts here, so that the
    // cap of a feasibility start bounds its time: with step durations of 0.6-0.7 s the first
    // start spent 58 s in restoration (about 1000 iterations) before this.
    let mut performed = 0;
    let mut capped = false;
    let mut earlier: Option<nlp::SolveStatistics> = None;
    let sol = loop {
        let mut starts_seen = 0;
        let cap = config.solver.max_iterations;
        let mut callback = |r: &IterationReport| {
            on_progress(Progress::Iteration(stage, r));
            // Restoration: a second iteration 0, a nested solve starting (ripopt; also when it
            // starts right after the initial point), or a report flagged as restoration (the
            // native backend).
            if r.iteration == 0 {
                starts_seen += 1;
            } else {
                performed += 1;
            }
            let restoration = starts_seen > 1 || r.restoration;
            if performed >= cap {
                capped = true;
                return IterationControl::Stop;
            }
            if restoration && guards.abandon_restoration {
                return IterationControl::Stop;
            }
            if let Some(g) = guards.stall {
                let stuck = r.iteration > 0
                    && r.step_norm < g.step_norm
                    && r.primal_infeasibility > g.infeasibility;
                standing = if stuck { standing + 1 } else { 0 };
                if standing >= g.iterations {
                    stalled = true;
                    return IterationControl::Stop;
                }
            }
            IterationControl::Continue
        };
        let mut sol = nlp::solve_with_callback(problem, &options, &mut callback)
            .map_err(|e| PlannerError::Solver(e.to_string()))?;
        if let Some(e) = &earlier {
            sol.statistics.absorb(e);
        }
        if !retry_with_ripopt(options.backend, sol.status, guards, capped || stalled) {
            break sol;
        }
        earlier = Some(sol.statistics);
        options.backend = nlp::Backend::Ripopt;
    };
    let violation = problem.max_violation(&sol.x);
    let status = if capped && !sol.status.is_success() {
        nlp::SolveStatus::IterationLimit
    } else {
        sol.status
    };
    let report = StageReport {
        stage,
        status: format!("{status:?}").to_lowercase(),
        iterations: sol.statistics.iterations.max(performed),
        objective: sol.statistics.objective,
        violation,
        solve_time_s: sol.statistics.total_time.as_secs_f64(),
        evaluation_time_s: sol.statistics.evaluation_time.as_secs_f64(),
        restoration_iterations: sol.statistics.restoration_iterations,
        phases: sol.statistics.phases,
        backend: options.backend,
    };
    // The feasibility stage only has to deliver a feasible start for the second: a point that
    // satisfies every constraint is kept even if the solver stopped on a numerical status.
    let usable =
        (status.is_success() || (stage == FEASIBILITY && violation < 1e-8)) && violation <= 1e-5;
    let usable = usable && !stalled;
    // What a failed stage leaves violated, for the error a user reads (which Table I or physical
    // constraint the config asks too much of).
    let violated = if usable {
        Vec::new()
    } else {
        let mut v: Vec<(String, f64)> = problem
            .violation_by_kind(&sol.x)
            .into_iter()
            .filter(|(_, v)| *v > 1e-6)
            .collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1));
        v.truncate(3);
        v
    };
    let mut solution = sol;
    solution.status = status;
    Ok(StageAttempt {
        solution,
        report,
        usable,
        stalled,
        violated,
    })
}

/// Where the wall time of [`plan_gait_timed`] went, s (the parts add up to its whole).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlanTimes {
    /// Building the problems and the starts' guesses (the probe's set-up included).
    pub problems_s: f64,
    /// The feasibility solves (every start tried).
    pub feasibility_s: f64,
    /// The cost-of-transport solve.
    pub cost_s: f64,
    /// The gait file's content from the solution (with its collocation feed-forward).
    pub gait_s: f64,
    /// The feed-forward table along the closed-loop orbit ([`crate::verify::feedforward_from_orbit`]).
    pub feedforward_s: f64,
}

/// Plans a periodic HZD gait for `model` with its design joints at zero (the URDF's design).
/// `urdf_ref` is how the gait file names the URDF and `urdf_text` its content (for the hash).
pub fn plan_gait(
    model: &PlanarModel,
    urdf_ref: &str,
    urdf_text: &str,
    config: &PlannerConfig,
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<PlannedGait> {
    Ok(plan_gait_timed(model, urdf_ref, urdf_text, config, on_progress)?.0)
}

/// [`plan_gait`], and where its wall time went.
pub fn plan_gait_timed(
    model: &PlanarModel,
    urdf_ref: &str,
    urdf_text: &str,
    config: &PlannerConfig,
    on_progress: &mut dyn FnMut(Progress<'_>),
) -> Result<(PlannedGait, PlanTimes)> {
    let start = Instant::now();
    let mut times = PlanTimes::default();
    config.validate("planner config")?;
    let setup = Instant::now();
    let biped = PlanarBiped::new(model.clone(), config.gait.stance_leg, &[])?;
    let step0 = 0.5 * (config.gait.step_length_m[0] + config.gait.step_length_m[1]);
    let step0 = step0.clamp(
        config.gait.step_length_m[0],
        0.25_f64.max(config.gait.step_length_m[0]),
    );
    let [s_lo, s_hi] = config.gait.step_length_m;
    let [d_lo, d_hi] = config.gait.step_duration_s;
    let probe = HzdProblem::new(biped.clone(), config.clone(), Vec::new(), false)?;
    let setup_time_s = setup.elapsed().as_secs_f64();
    let feasibility_size = (
        nlp::NlpProblem::num_variables(&probe),
        nlp::NlpProblem::num_constraints(&probe),
    );
    // The feasibility solve is sensitive to its start: from some hand-built steps the interior
    // point drifts into a long restoration phase (the default ADAM problem from 0.25 m / 0.75 s
    // took 67 iterations and 106 s; from 0.25 m / 0.65 s, 43 iterations and 2.3 s). So a fixed,
    // deterministic list of starts is tried in order, each capped at FEASIBILITY_MAX_ITERATIONS.
    let starts = [
        (step0, d_lo + (d_hi - d_lo) / 6.0),
        ((step0 + 0.05).min(s_hi), d_lo + (d_hi - d_lo) / 3.0),
        (s_lo, d_hi),
        ((step0 - 0.05).max(s_lo), d_lo + 2.0 * (d_hi - d_lo) / 3.0),
        (step0, 0.5 * (d_lo + d_hi)),
    ];
    // With a speed asked for, each start keeps its duration and takes the step length of the
    // band's middle speed (the duration moves instead where the length hits its bounds).
    let starts = starts.map(|(step, duration)| start_at_speed(config, step, duration));
    let mut capped = config.clone();
    capped.solver.max_iterations = config.solver.max_iterations.min(FEASIBILITY_MAX_ITERATIONS);
    // The dropped starts' work, counted in the stage's figures.
    let mut spent = StageReport {
        restoration_iterations: Some(0),
        phases: Some(nlp::PhaseTimes::default()),
        ..StageReport::default()
    };
    let mut found = None;
    let mut last_error = None;
    for (k, &(step, duration)) in starts.iter().enumerate() {
        let guess = initial_guess(&biped, &probe.layout, step, duration)?;
        let feasibility = HzdProblem::new(biped.clone(), config.clone(), guess, false)?;
        // A start that needs the solver's restoration phase is dropped for the next one; the
        // last start may use it.
        let guards = Guards {
            abandon_restoration: k + 1 < starts.len(),
            ..Guards::default()
        };
        let attempt = Instant::now();
        let outcome = solve_stage_attempt(
            &feasibility,
            FEASIBILITY,
            &capped,
            None,
            guards,
            on_progress,
        );
        times.feasibility_s += attempt.elapsed().as_secs_f64();
        match outcome {
            Ok(a) if a.usable => {
                let (x, mut report) = a.into_result()?;
                report.absorb(&spent);
                found = Some((x, report));
                break;
            }
            Ok(a) => {
                spent.absorb(&a.report);
                last_error = a.into_result().err();
            }
            Err(e) => {
                // Not split by phase: the solve reported nothing.
                spent.solve_time_s += attempt.elapsed().as_secs_f64();
                spent.phases = None;
                spent.restoration_iterations = None;
                last_error = Some(e);
            }
        }
    }
    let Some((x1, r1)) = found else {
        return Err(last_error.unwrap_or_else(|| PlannerError::Solver("no start".into())));
    };
    let costed = cost_stage_problem(biped, config, &x1)?;
    let size = (
        nlp::NlpProblem::num_variables(&costed),
        nlp::NlpProblem::num_constraints(&costed),
    );
    let solve = Instant::now();
    let (x, r2) = solve_stage(&costed, "cost of transport", config, on_progress)?;
    times.cost_s = solve.elapsed().as_secs_f64();
    let writing = Instant::now();
    let mut gait = gait_from_solution(&costed, &x, urdf_ref, urdf_text, &[r1.clone(), r2.clone()])?;
    times.gait_s = writing.elapsed().as_secs_f64();
    // The runtime's feed-forward: the torques along the closed-loop orbit (finer and more
    // faithful than the collocation points' torques that gait_from_solution records).
    let feedforward = Instant::now();
    gait.feedforward = Some(crate::verify::feedforward_from_orbit(
        model,
        &gait,
        crate::verify::VerifyOptions::default(),
    )?);
    times.feedforward_s = feedforward.elapsed().as_secs_f64();
    times.problems_s = start.elapsed().as_secs_f64()
        - times.feasibility_s
        - times.cost_s
        - times.gait_s
        - times.feedforward_s;
    let planned = PlannedGait {
        gait,
        stages: vec![r1, r2],
        x,
        feasible_x: x1,
        size,
        feasibility_size: Some(feasibility_size),
        setup_time_s,
    };
    Ok((planned, times))
}

/// A hand-built start's (step length m, duration s) moved onto `gait.speed_mps`'s middle
/// speed, within the length and duration bounds; unchanged without a speed.
pub fn start_at_speed(config: &PlannerConfig, step_m: f64, duration_s: f64) -> (f64, f64) {
    let g = &config.gait;
    let Some([lo, hi]) = g.speed_mps else {
        return (step_m, duration_s);
    };
    let v = 0.5 * (lo + hi);
    let [s_lo, s_hi] = g.step_length_m;
    let [t_lo, t_hi] = g.step_duration_s;
    let step = (v * duration_s).clamp(s_lo, s_hi);
    let duration = (step / v).clamp(t_lo, t_hi);
    (step, duration)
}

/// The planned torque of each output's joint at every collocation point, by phase: the
/// runtime's feed-forward term. Points whose phase does not increase (never at an optimum) are
/// skipped so the table stays strictly increasing.
pub fn feedforward_table(problem: &HzdProblem, x: &[f64]) -> FeedforwardTable {
    let l = &problem.layout;
    let bp = &problem.biped;
    let mut table = FeedforwardTable {
        phase: Vec::with_capacity(l.points()),
        torque_nm: Vec::with_capacity(l.points()),
    };
    for k in 0..l.points() {
        let tau = x[l.tau(k)];
        if table.phase.last().is_some_and(|t| tau <= *t) {
            continue;
        }
        let row = bp
            .output_coords
            .iter()
            .map(|&c| {
                bp.actuators
                    .iter()
                    .position(|&a| a == c)
                    .map_or(0.0, |i| TORQUE_SCALE * x[l.u(k) + i])
            })
            .collect();
        table.phase.push(tau);
        table.torque_nm.push(row);
    }
    table
}

/// The gait file for the NLP point `x`.
pub fn gait_from_solution(
    problem: &HzdProblem,
    x: &[f64],
    urdf_ref: &str,
    urdf_text: &str,
    stages: &[StageReport],
) -> Result<GaitFile> {
    let l = &problem.layout;
    let bp = &problem.biped;
    let alpha = (0..l.m)
        .map(|o| (0..=l.degree).map(|j| x[l.alpha(o, j)]).collect())
        .collect();
    let qr = &x[l.q(0)..l.q(0) + l.nq];
    let dqr = &x[l.dq(0)..l.dq(0) + l.nq];
    let [q, dq, _] = bp.full_state(qr, dqr, &vec![0.0; l.nq])?;
    let q_nom = bp.model.nominal_pose()?;
    let (thigh, shin) = bp.model.leg_lengths(&q_nom, bp.stance)?;
    let (duration, length) = (x[l.duration()], x[l.length()]);
    Ok(GaitFile {
        schema_version: GAIT_SCHEMA_VERSION,
        robot: RobotReference {
            name: bp.model.name.clone(),
            urdf: urdf_ref.to_string(),
            sha256: sha256_hex(urdf_text),
        },
        design: DesignLengths {
            thigh_length_m: thigh,
            shin_length_m: shin,
        },
        outputs: bp.outputs.clone(),
        bezier: BezierSpec {
            degree: l.degree,
            alpha,
        },
        phase: PhaseDefinition::StateBased {
            theta_plus_rad: x[l.theta_plus()],
            theta_minus_rad: x[l.theta_minus()],
        },
        stance_leg: bp.stance,
        step_duration_s: duration,
        step_length_m: length,
        speed_mps: length / duration,
        cost_of_transport: problem.cost_of_transport(x),
        initial_state: Some(RobotState { q, dq }),
        feedforward: Some(feedforward_table(problem, x)),
        solver: SolverSummary {
            solver: solver_description(stages),
            status: stages.last().map(|s| s.status.clone()).unwrap_or_default(),
            iterations: stages.iter().map(|s| s.iterations).sum(),
            solve_time_s: stages.iter().map(|s| s.solve_time_s).sum(),
            objective: stages.last().map(|s| s.objective).unwrap_or(0.0),
            constraint_violation: problem.max_violation(x),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlp::{Backend, SolveStatus};

    #[test]
    fn only_a_failed_native_restoration_or_factorization_goes_back_to_ripopt() {
        let free = Guards::default();
        for status in [
            SolveStatus::RestorationFailed,
            SolveStatus::NumericalError,
            SolveStatus::TinyStep,
        ] {
            assert!(retry_with_ripopt(Backend::Native, status, free, false));
            // ripopt's own failures, a start the caller drops, a solve stopped on purpose: no.
            assert!(!retry_with_ripopt(Backend::Ripopt, status, free, false));
            let dropping = Guards {
                abandon_restoration: true,
                ..Guards::default()
            };
            assert!(!retry_with_ripopt(Backend::Native, status, dropping, false));
            assert!(!retry_with_ripopt(Backend::Native, status, free, true));
        }
        for status in [
            SolveStatus::Optimal,
            SolveStatus::Acceptable,
            SolveStatus::Infeasible,
            SolveStatus::IterationLimit,
            SolveStatus::UserStop,
        ] {
            assert!(!retry_with_ripopt(Backend::Native, status, free, false));
        }
    }

    /// A stage that stands for several solves reports all their work, and a time by phase
    /// only if every solve measured one (a dropped start on ripopt makes it unknown).
    #[test]
    fn a_stage_report_absorbs_the_solves_it_stands_for() {
        let phases = nlp::PhaseTimes {
            factorizations: 40,
            factorization_time: std::time::Duration::from_millis(100),
            linear_solves: 41,
            linear_solve_time: std::time::Duration::from_millis(10),
            other_time: std::time::Duration::from_millis(30),
        };
        let native = StageReport {
            iterations: 39,
            solve_time_s: 0.25,
            evaluation_time_s: 0.11,
            restoration_iterations: Some(2),
            phases: Some(phases),
            ..StageReport::default()
        };
        let mut both = native.clone();
        both.absorb(&native);
        assert_eq!(both.iterations, 78);
        assert_eq!(both.restoration_iterations, Some(4));
        assert_eq!((both.solve_time_s, both.evaluation_time_s), (0.5, 0.22));
        let p = both.phases.expect("both measured");
        assert_eq!((p.factorizations, p.linear_solves), (80, 82));
        assert_eq!(p.factorization_time, std::time::Duration::from_millis(200));
        let ripopt = StageReport {
            iterations: 58,
            ..StageReport::default()
        };
        let mut mixed = native.clone();
        mixed.absorb(&ripopt);
        assert_eq!(mixed.iterations, 97);
        assert_eq!((mixed.restoration_iterations, mixed.phases), (None, None));
    }

    #[test]
    fn the_gait_file_names_the_backend_of_each_stage_when_they_differ() {
        let stage = |stage, backend| StageReport {
            stage,
            backend,
            ..StageReport::default()
        };
        let native = solver_description(&[
            stage(FEASIBILITY, Backend::Native),
            stage("cost of transport", Backend::Native),
        ]);
        assert_eq!(native, "native interior point (planner::nlp, faer LDLᵀ)");
        let mixed = solver_description(&[
            stage(FEASIBILITY, Backend::Native),
            stage("cost of transport", Backend::Ripopt),
        ]);
        assert!(
            mixed.starts_with("feasibility: native") && mixed.contains("cost of transport: ripopt"),
            "{mixed}"
        );
        assert!(solver_description(&[]).starts_with("native"));
    }
}
