//! The treadmill study of a sweep plan: the matrix of `adam bench treadmill` (belt speeds, belt
//! steps, pushes at points of the step, start and restart, × seeds), a task per run. The task
//! function is `runtime::sim::matrix::run` and the report the bench's tables, the same the
//! bench prints (without its push bisection, a search and not a matrix). Its inputs, by
//! content hash: the runtime config (and the configs it extends), the gait and its robot, and the
//! gait library the config names for speed control (with the library's robot, if another file).

use super::plan::{Input, SweepPlan, Task, TreadmillSettings};
use super::result::{Payload, TaskResult};
use crate::cli::bench::{matrix_runs, seeds_or_default, treadmill_tables};
use anyhow::{Context, Result};
use runtime::sim::scenarios::BELT_SPEEDS_MPS;
use std::path::Path;

/// The roles of the treadmill study's inputs.
const RUNTIME_CONFIG: &str = "runtime config";
const RUNTIME_CONFIG_BASE: &str = "runtime config base";
const GAIT: &str = "gait";
const ROBOT: &str = "robot";
const GAIT_LIBRARY: &str = "gait library";
const LIBRARY_ROBOT: &str = "library robot";

/// The inputs, settings and tasks of a treadmill plan.
pub(crate) fn plan(
    config: &Path,
    gait: &Path,
    seeds: Option<Vec<u64>>,
    quick: bool,
) -> Result<(Vec<Input>, TreadmillSettings, Vec<Task>)> {
    let seeds = seeds_or_default(seeds, quick)?;
    // Loaded once here: a bad config or gait is refused before any task runs.
    runtime::Setup::load(config, gait)?;
    let g = model::gait::GaitFile::load(gait)?;
    let urdf = gait
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .join(&g.robot.urdf);
    let mut inputs = vec![
        Input::hashed(RUNTIME_CONFIG, config)?,
        Input::hashed(GAIT, gait)?,
        Input::hashed(ROBOT, &urdf)?,
    ];
    // The configs it extends: a change there is a change of the config.
    for base in runtime::config::extends_chain(config)? {
        inputs.push(Input::hashed(RUNTIME_CONFIG_BASE, &base)?);
    }
    // The gait library the config names (speed control) and its robot, if another file.
    if let Some(rel) = runtime::config::RuntimeConfig::load(config)?.speed.library {
        let library = config.parent().unwrap_or_else(|| Path::new(".")).join(rel);
        let lib = model::library::GaitLibrary::load(&library)?;
        let lib_urdf = library
            .parent()
            .unwrap_or_else(|| Path::new("."))
            .join(&lib.robot.urdf);
        inputs.push(Input::hashed(GAIT_LIBRARY, &library)?);
        let same = |a: &Path, b: &Path| matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y);
        if !same(&lib_urdf, &urdf) {
            inputs.push(Input::hashed(LIBRARY_ROBOT, &lib_urdf)?);
        }
    }
    let tasks = matrix_runs(&seeds, quick, &BELT_SPEEDS_MPS)
        .into_iter()
        .enumerate()
        .map(|(index, run)| Task {
            index,
            treadmill: Some(run),
            ..Task::default()
        })
        .collect();
    Ok((inputs, TreadmillSettings { seeds, quick }, tasks))
}

/// Runs one treadmill task.
pub(crate) fn run_task(plan: &SweepPlan, plan_path: &Path, task: &Task) -> Result<Payload> {
    let run = task.treadmill.with_context(|| {
        format!(
            "{}: task {} is not a treadmill run",
            plan_path.display(),
            task.index
        )
    })?;
    let setup = runtime::Setup::load(
        &plan.input(RUNTIME_CONFIG, plan_path)?.path,
        &plan.input(GAIT, plan_path)?.path,
    )?;
    Ok(Payload::Treadmill(
        runtime::sim::matrix::run(&setup, &run).map_err(|e| e.to_string()),
    ))
}

/// The tables of a treadmill plan from the results there are, written to `treadmill.md` in
/// the plan's folder; returns the text.
pub(crate) fn collect(plan: &SweepPlan, results: &[TaskResult]) -> Result<String> {
    let settings = plan
        .treadmill
        .as_ref()
        .context("the plan has no [treadmill] settings")?;
    let runs: Vec<runtime::sim::matrix::Run> =
        plan.tasks.iter().filter_map(|t| t.treadmill).collect();
    let mut summaries = vec![None; runs.len()];
    let mut failed = Vec::new();
    for r in results {
        match &r.payload {
            Payload::Treadmill(Ok(s)) => summaries[r.index] = Some(s.clone()),
            Payload::Treadmill(Err(e)) => failed.push(format!("task {}: {e}", r.index)),
            _ => {}
        }
    }
    let text = format!(
        "# Treadmill matrix ({} runs, seeds {:?}{})\n{}",
        runs.len(),
        settings.seeds,
        if settings.quick { ", quick" } else { "" },
        treadmill_tables(&settings.seeds, settings.quick, &runs, &summaries)?
    );
    std::fs::create_dir_all(&plan.out_dir)
        .with_context(|| format!("creating {}", plan.out_dir.display()))?;
    let path = plan.out_dir.join("treadmill.md");
    std::fs::write(&path, &text).with_context(|| format!("writing {}", path.display()))?;
    Ok(text)
}
