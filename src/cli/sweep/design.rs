//! The design studies of a sweep plan: the co-design convergence study (`codesign`: a task per
//! initial design) and the cost landscape (`landscape`: a task per fixed design). Their task
//! functions are the planner's (`planner::codesign::sweep_run`, `landscape_point`), the ones
//! `adam codesign sweep` and `adam codesign landscape --start initial` run in-process; their
//! reports are written by the same functions as those commands'.

use super::plan::{DesignGrid, Input, Study, SweepPlan, Task};
use super::result::{Payload, TaskResult};
use crate::cli::codesign::{codesign_config, warm_start, write_sweep_report};
use anyhow::{Context, Result};
use planner::codesign::SweepRun;
use planner::config::PlannerConfig;
use std::path::Path;

/// The role of the planner config among a design plan's inputs.
pub(crate) const PLANNER_CONFIG: &str = "planner config";

/// Stack of the task's worker thread, bytes (a main thread's 8 MiB, as the landscape's pool).
const TASK_STACK_BYTES: usize = 8 << 20;

/// The inputs and tasks of a design study over an n × n grid of `cfg`'s design box.
pub(crate) fn tasks(
    study: Study,
    cfg: &PlannerConfig,
    grid: usize,
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
    let tasks = points
        .into_iter()
        .enumerate()
        .map(|(index, p)| Task {
            index,
            initial_m: (study == Study::Codesign).then_some(p),
            lengths_m: (study == Study::Landscape).then_some(p),
            treadmill: None,
        })
        .collect();
    Ok((
        DesignGrid {
            grid,
            inertia: cfg.codesign.inertia,
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
            Study::Landscape => cfg.codesign.landscape_grid = d.grid,
            _ => cfg.codesign.sweep.grid = d.grid,
        }
    }
    Ok(cfg)
}

/// Runs one design task: plans the warm start (as the in-process study does once), then the
/// task's run on a one-thread rayon pool (as the in-process study runs each on a worker).
pub(crate) fn run_task(plan: &SweepPlan, plan_path: &Path, task: &Task) -> Result<Payload> {
    let cfg = plan_config(plan, plan_path)?;
    let initial = match warm_start(&cfg) {
        Ok(g) => g,
        Err(e) => {
            let e = format!("the warm start: {e:#}");
            return Ok(match plan.study {
                Study::Landscape => Payload::Landscape(Err(e)),
                _ => Payload::Codesign(Err(e)),
            });
        }
    };
    let model_lengths = cfg.codesign.initial_m;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .stack_size(TASK_STACK_BYTES)
        .build()
        .context("the task's thread pool")?;
    Ok(match (plan.study, task.initial_m, task.lengths_m) {
        (Study::Codesign, Some(start), _) => {
            let run =
                pool.install(|| planner::codesign::sweep_run(&cfg, &initial, model_lengths, start));
            Payload::Codesign(run.outcome)
        }
        (Study::Landscape, _, Some(lengths)) => {
            let point =
                pool.install(|| planner::codesign::landscape_point(&cfg, &initial, lengths));
            Payload::Landscape(point.outcome)
        }
        _ => anyhow::bail!(
            "{}: task {} is not a {} task",
            plan_path.display(),
            task.index,
            plan.study.name()
        ),
    })
}

/// Writes the report of a co-design plan from the results there are (in index order), as
/// `adam codesign sweep` does; returns `table.md`'s text.
pub(crate) fn collect_codesign(
    plan: &SweepPlan,
    plan_path: &Path,
    results: &[TaskResult],
) -> Result<String> {
    let cfg = plan_config(plan, plan_path)?;
    let mut runs = Vec::new();
    let mut walls = Vec::new();
    for r in results {
        if let (Payload::Codesign(outcome), Some(initial_m)) = (&r.payload, r.task.initial_m) {
            runs.push(SweepRun {
                initial_m,
                outcome: outcome.clone(),
                wall_time_s: r.wall_time_s,
            });
            walls.push(r.wall_time_s);
        }
    }
    write_sweep_report(&cfg, &runs, &walls, &plan.out_dir)
}

/// Writes the grid's report of a landscape plan from the results there are, as `adam codesign
/// landscape --start initial` does for its grid (`landscape.csv`, the heat map, and
/// `landscape.md` with the cost table); returns `landscape.md`'s text. A point without a
/// result is drawn and tabled as failed, with the reason.
pub(crate) fn collect_landscape(
    plan: &SweepPlan,
    plan_path: &Path,
    results: &[TaskResult],
) -> Result<String> {
    let cfg = plan_config(plan, plan_path)?;
    let n = cfg.codesign.landscape_grid;
    let c = &cfg.codesign;
    let points = plan
        .tasks
        .iter()
        .map(|t| {
            let lengths_m = t.lengths_m.unwrap_or_default();
            let outcome = results.iter().find(|r| r.index == t.index).map_or(
                Err("no result".to_string()),
                |r| match &r.payload {
                    Payload::Landscape(o) => o.clone(),
                    _ => Err("not a landscape result".into()),
                },
            );
            planner::codesign::LandscapePoint {
                lengths_m,
                outcome,
                from_neighbour: false,
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
    let mut md = format!("# Cost landscape ({n} × {n} fixed designs, initial-gait start)\n\n");
    md.push_str(&crate::cli::codesign::write_grid_report(
        &cfg,
        &land,
        &plan.out_dir,
        None,
        &[],
    )?);
    let path = plan.out_dir.join("landscape.md");
    std::fs::write(&path, &md).with_context(|| format!("writing {}", path.display()))?;
    Ok(md)
}
