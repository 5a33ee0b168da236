//! The design studies of a sweep plan: the co-design convergence study (`codesign`: a task per
//! initial design) and the cost landscape (`landscape`: a task per fixed design, one for the
//! co-design optimum and its multipliers, and one per run of the convergence study whose
//! endpoints it draws). Their task functions are the planner's (`planner::codesign::sweep_run`,
//! `landscape_point` or `landscape_point_from_neighbours` by the plan's start,
//! `codesign_study_run`), the ones `adam codesign sweep` and `adam codesign landscape` run
//! in-process; their reports are written by the same functions as those commands'.
//!
//! Inputs: the planner config is the one file a design study reads (the robot at each design
//! is generated from the config's lengths and mass model by this `adam`, whose version the
//! plan names), so it is the one input hashed.

use super::plan::{DesignGrid, Input, Study, SweepPlan, Task};
use super::result::{Payload, TaskResult};
use crate::cli::codesign::{
    codesign_config, sweep_ends, warm_start, write_landscape_report, write_sweep_report,
    OptimumSummary, StartArg,
};
use anyhow::{Context, Result};
use planner::codesign::SweepRun;
use planner::config::PlannerConfig;
use std::path::Path;

/// The role of the planner config among a design plan's inputs.
pub(crate) const PLANNER_CONFIG: &str = "planner config";

/// Stack of the task's worker thread, bytes (a main thread's 8 MiB, as the landscape's pool).
const TASK_STACK_BYTES: usize = 8 << 20;

/// The inputs and tasks of a design study over an n × n grid of `cfg`'s design box (a
/// landscape's grid points first, thigh-major, then its optimum and its convergence study's
/// runs).
pub(crate) fn tasks(
    study: Study,
    cfg: &PlannerConfig,
    grid: usize,
    start: StartArg,
) -> Result<(DesignGrid, Vec<Task>)> {
    let points: Vec<[f64; 2]> = match study {
        Study::Landscape => {
            planner::config::check_landscape_grid(grid, "adam sweep plan", "--grid")?;
            let c = &cfg.codesign;
            let (thigh, shin) = (
                planner::codesign::grid_values(c.thigh_m, grid),
                planner::codesign::grid_values(c.shin_m, grid),
            );
            thigh
                .iter()
                .flat_map(|&t| shin.iter().map(move |&s| [t, s]))
                .collect()
        }
        _ => {
            crate::cli::codesign::check_sweep_grid(grid)?;
            planner::codesign::sweep_grid(cfg, grid)
        }
    };
    let task = |index: usize| Task {
        index,
        ..Task::default()
    };
    let mut tasks: Vec<Task> = points
        .into_iter()
        .enumerate()
        .map(|(index, p)| Task {
            initial_m: (study == Study::Codesign).then_some(p),
            lengths_m: (study == Study::Landscape).then_some(p),
            ..task(index)
        })
        .collect();
    let landscape = study == Study::Landscape;
    if landscape {
        tasks.push(Task {
            optimum_from_m: Some(cfg.codesign.initial_m),
            ..task(tasks.len())
        });
        for p in planner::codesign::sweep_grid(cfg, cfg.codesign.sweep.grid) {
            tasks.push(Task {
                initial_m: Some(p),
                ..task(tasks.len())
            });
        }
    }
    Ok((
        DesignGrid {
            grid,
            inertia: cfg.codesign.inertia,
            start: landscape.then_some(start),
            sweep_grid: landscape.then_some(cfg.codesign.sweep.grid),
        },
        tasks,
    ))
}

/// The planner config of a plan (its hashed input) with the plan's grid and coupling.
fn plan_config(plan: &SweepPlan, plan_path: &Path) -> Result<PlannerConfig> {
    let input: &Input = plan.input(PLANNER_CONFIG, plan_path)?;
    let mut cfg = codesign_config(&input.path, None)?;
    if let Some(d) = &plan.design {
        cfg.codesign.inertia = d.inertia;
        match plan.study {
            Study::Landscape => {
                cfg.codesign.landscape_grid = d.grid;
                if let Some(g) = d.sweep_grid {
                    cfg.codesign.sweep.grid = g;
                }
            }
            _ => cfg.codesign.sweep.grid = d.grid,
        }
    }
    Ok(cfg)
}

/// The start of a landscape plan's grid solves.
fn landscape_start(plan: &SweepPlan) -> StartArg {
    plan.design
        .as_ref()
        .and_then(|d| d.start)
        .unwrap_or(StartArg::Initial)
}

/// Runs one design task: plans the warm start (as the in-process study does once), then the
/// task's run: a co-design run or a grid point on a one-thread rayon pool (as the in-process
/// study runs each on a worker), the optimum's co-design on this thread (as `adam codesign
/// landscape` runs it).
pub(crate) fn run_task(plan: &SweepPlan, plan_path: &Path, task: &Task) -> Result<Payload> {
    let cfg = plan_config(plan, plan_path)?;
    let failed = |e: String| {
        if task.lengths_m.is_some() {
            Payload::Landscape {
                outcome: Err(e),
                from_neighbour: false,
            }
        } else if task.optimum_from_m.is_some() {
            Payload::Optimum(Err(e))
        } else {
            Payload::Codesign(Err(e))
        }
    };
    let initial = match warm_start(&cfg) {
        Ok(g) => g,
        Err(e) => return Ok(failed(format!("the warm start: {e:#}"))),
    };
    let model_lengths = cfg.codesign.initial_m;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .stack_size(TASK_STACK_BYTES)
        .build()
        .context("the task's thread pool")?;
    let n = cfg.codesign.landscape_grid;
    Ok(
        match (task.initial_m, task.lengths_m, task.optimum_from_m) {
            (Some(start), None, None) => {
                let run = pool
                    .install(|| planner::codesign::sweep_run(&cfg, &initial, model_lengths, start));
                Payload::Codesign(run.outcome)
            }
            (None, Some(lengths), None) if plan.study == Study::Landscape => {
                let point = match landscape_start(plan) {
                    StartArg::Initial => Ok(pool
                        .install(|| planner::codesign::landscape_point(&cfg, &initial, lengths))),
                    StartArg::Neighbours => pool.install(|| {
                        planner::codesign::landscape_point_from_neighbours(
                            &cfg,
                            &initial,
                            model_lengths,
                            n,
                            task.index,
                        )
                    }),
                };
                match point {
                Ok(p) if p.lengths_m == lengths => Payload::Landscape {
                    outcome: p.outcome,
                    from_neighbour: p.from_neighbour,
                },
                Ok(p) => anyhow::bail!(
                    "{}: task {} is the grid point {:?} m, but point {} of the {n} × {n} grid is {:?} m",
                    plan_path.display(),
                    task.index,
                    lengths,
                    task.index,
                    p.lengths_m
                ),
                Err(e) => failed(e.to_string()),
            }
            }
            (None, None, Some(from)) if plan.study == Study::Landscape => Payload::Optimum(
                planner::codesign::codesign_study_run(&cfg, &initial, model_lengths, from)
                    .map(|co| OptimumSummary::of(&co))
                    .map_err(|e| e.to_string()),
            ),
            _ => anyhow::bail!(
                "{}: task {} is not a {} task",
                plan_path.display(),
                task.index,
                plan.study.name()
            ),
        },
    )
}

/// The convergence study's runs among `results` (in index order), as `planner::codesign::sweep`
/// returns them.
fn sweep_runs(results: &[TaskResult]) -> Vec<SweepRun> {
    results
        .iter()
        .filter_map(|r| match (&r.payload, r.task.initial_m) {
            (Payload::Codesign(outcome), Some(initial_m)) => Some(SweepRun {
                initial_m,
                outcome: outcome.clone(),
                wall_time_s: r.wall_time_s,
            }),
            _ => None,
        })
        .collect()
}

/// Writes the report of a co-design plan from the results there are (in index order), as
/// `adam codesign sweep` does; returns `table.md`'s text.
pub(crate) fn collect_codesign(
    plan: &SweepPlan,
    plan_path: &Path,
    results: &[TaskResult],
) -> Result<String> {
    let cfg = plan_config(plan, plan_path)?;
    let runs = sweep_runs(results);
    let walls: Vec<f64> = runs.iter().map(|r| r.wall_time_s).collect();
    write_sweep_report(&cfg, &runs, &walls, &plan.out_dir)
}

/// Writes the report of a landscape plan from the results there are, as `adam codesign
/// landscape` does (`landscape.csv`, the heat map with the optimum and the convergence study's
/// endpoints, `activity.md` with the cost table, the optimum and its active constraints, and
/// `sweep.json`); returns `activity.md`'s text. A grid point without a result is drawn and
/// tabled as failed, with the reason.
pub(crate) fn collect_landscape(
    plan: &SweepPlan,
    plan_path: &Path,
    results: &[TaskResult],
) -> Result<String> {
    let cfg = plan_config(plan, plan_path)?;
    let n = cfg.codesign.landscape_grid;
    let c = &cfg.codesign;
    let result = |index: usize| results.iter().find(|r| r.index == index);
    let points = plan
        .tasks
        .iter()
        .filter_map(|t| t.lengths_m.map(|l| (t.index, l)))
        .map(|(index, lengths_m)| {
            let (outcome, from_neighbour) = match result(index).map(|r| &r.payload) {
                Some(Payload::Landscape {
                    outcome,
                    from_neighbour,
                }) => (outcome.clone(), *from_neighbour),
                _ => (Err("no result".to_string()), false),
            };
            planner::codesign::LandscapePoint {
                lengths_m,
                outcome,
                from_neighbour,
            }
        })
        .collect();
    let land = planner::codesign::Landscape {
        n,
        thigh_m: planner::codesign::grid_values(c.thigh_m, n),
        shin_m: planner::codesign::grid_values(c.shin_m, n),
        points,
        wall_time_s: results.iter().map(|r| r.wall_time_s).sum(),
    };
    let optimum = plan
        .tasks
        .iter()
        .find(|t| t.optimum_from_m.is_some())
        .and_then(|t| match result(t.index).map(|r| &r.payload) {
            Some(Payload::Optimum(Ok(o))) => Some(o.clone()),
            _ => None,
        });
    let runs = sweep_runs(results);
    std::fs::create_dir_all(&plan.out_dir)
        .with_context(|| format!("creating {}", plan.out_dir.display()))?;
    planner::codesign::save_sweep(&plan.out_dir.join("sweep.json"), &runs)?;
    write_landscape_report(
        &cfg,
        &land,
        landscape_start(plan),
        &plan.out_dir,
        optimum.as_ref(),
        &sweep_ends(&runs),
    )
}
