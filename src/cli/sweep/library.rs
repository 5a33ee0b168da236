//! The gait-library study of a sweep plan: a task per speed of `adam plan library`. Each task
//! is `planner::library::plan_speed`: the anchor speed's cold plan and the walk out to its own
//! speed, the same steps `planner::library::plan_library` (`adam plan library`) takes, so the
//! collected library file is the in-process one (but for the gaits' recorded solve times) and
//! `library.md` is its table. A task solves again the speeds between the anchor and its own
//! instead of reading other tasks' results: the array's longest task is as long as the
//! in-process library's longer walk.

use super::plan::{Input, LibrarySettings, SweepPlan, Task};
use super::result::{Payload, TaskResult};
use crate::cli::plan::library::{LibraryArgs, LibraryFigures, LibraryJob, LibraryTable};
use anyhow::{Context, Result};
use planner::library::{LibraryPlan, Schedule, SpeedOutcome};
use std::fmt::Write as _;
use std::path::Path;

/// The roles of the library study's inputs.
const ROBOT: &str = "robot";
const PLANNER_CONFIG: &str = "planner config";

/// What `adam sweep plan --study library` was given.
pub(crate) struct LibraryRequest<'a> {
    pub(crate) robot: &'a Path,
    pub(crate) config: &'a Path,
    pub(crate) speeds: &'a str,
    pub(crate) max_step_error: f64,
    /// The plan's output folder (absolute): the library file goes there.
    pub(crate) out_dir: &'a Path,
}

/// The arguments `adam plan library` would take for this library (one definition: the plan
/// and every task load robot, config and speeds as that command does).
fn library_args(
    robot: &Path,
    config: &Path,
    speeds: String,
    library_file: &Path,
    max_step_error: f64,
) -> LibraryArgs {
    LibraryArgs {
        robot: robot.to_path_buf(),
        config: config.to_path_buf(),
        speeds,
        out: library_file.to_path_buf(),
        force: true,
        backend: None,
        schedule: Schedule::default(),
        max_step_error,
    }
}

/// The speeds of the settings as `adam plan library --speeds` takes them.
fn speeds_spec(speeds_mps: &[f64]) -> String {
    speeds_mps
        .iter()
        .map(|v| format!("{v:?}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// The inputs, settings and tasks of a library plan.
pub(crate) fn plan(r: &LibraryRequest<'_>) -> Result<(Vec<Input>, LibrarySettings, Vec<Task>)> {
    let file = r.out_dir.join("adam_library.json");
    // Loaded here as the tasks will: a bad robot, config or speed list is refused at once.
    let job = LibraryJob::load(&library_args(
        r.robot,
        r.config,
        r.speeds.to_string(),
        &file,
        r.max_step_error,
    ))?;
    let inputs = vec![
        Input::hashed(ROBOT, &crate::cli::shipped::input(r.robot))?,
        Input::hashed(PLANNER_CONFIG, &crate::cli::shipped::input(r.config))?,
    ];
    let tasks = job
        .speeds_mps
        .iter()
        .enumerate()
        .map(|(index, &v)| Task {
            index,
            speed_mps: Some(v),
            ..Task::default()
        })
        .collect();
    Ok((
        inputs,
        LibrarySettings {
            speeds_mps: job.speeds_mps,
            max_step_error: r.max_step_error,
            library_file: file,
        },
        tasks,
    ))
}

/// The library job of a plan: its hashed robot and config, its speeds, its library file.
fn job<'a>(plan: &'a SweepPlan, plan_path: &Path) -> Result<(LibraryJob, &'a LibrarySettings)> {
    let settings = plan
        .library
        .as_ref()
        .with_context(|| format!("{}: field 'library': missing", plan_path.display()))?;
    let job = LibraryJob::load(&library_args(
        &plan.input(ROBOT, plan_path)?.path,
        &plan.input(PLANNER_CONFIG, plan_path)?.path,
        speeds_spec(&settings.speeds_mps),
        &settings.library_file,
        settings.max_step_error,
    ))?;
    if job.speeds_mps != settings.speeds_mps {
        anyhow::bail!(
            "{}: field 'library.speeds_mps' = {:?} reads back as {:?}",
            plan_path.display(),
            settings.speeds_mps,
            job.speeds_mps
        );
    }
    Ok((job, settings))
}

/// Runs one library task: the speed of its index (from the calling thread, as `adam plan
/// library` plans its anchor; the walk and the check go to the planner's own pool).
pub(crate) fn run_task(plan: &SweepPlan, plan_path: &Path, task: &Task) -> Result<Payload> {
    let (job, _) = job(plan, plan_path)?;
    let outcome = planner::library::plan_speed(
        &job.model,
        &job.urdf_ref,
        &job.urdf_text,
        &job.config,
        &job.speeds_mps,
        task.index,
        job.options,
    );
    Ok(Payload::Library(Box::new(
        outcome.map_err(|e| e.to_string()),
    )))
}

/// The library of a plan from the results there are: the table (`library.md`, as `adam plan
/// library` prints it but without times), the times (`times.csv`), and, once every task has
/// a result, the library file (or the hole that keeps it from being one); returns the text
/// printed.
pub(crate) fn collect(
    plan: &SweepPlan,
    plan_path: &Path,
    results: &[TaskResult],
) -> Result<String> {
    let (job, settings) = job(plan, plan_path)?;
    let mut complete = true;
    let outcomes: Vec<SpeedOutcome> = settings
        .speeds_mps
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            let found = results.iter().find(|r| r.index == k).map(|r| &r.payload);
            let found = match found {
                Some(Payload::Library(r)) => Some(r.as_ref()),
                _ => None,
            };
            match found {
                Some(Ok(o)) => o.clone(),
                other => {
                    complete = false;
                    SpeedOutcome {
                        speed_mps: v,
                        result: Err(match other {
                            Some(Err(e)) => format!("task {k} failed: {e}"),
                            _ => format!("task {k}: no result"),
                        }),
                        warm: false,
                        iterations: 0,
                        solve_time_s: 0.0,
                        verify_time_s: 0.0,
                    }
                }
            }
        })
        .collect();
    let lp = LibraryPlan {
        robot: planner::library::robot_reference(&job.model, &job.urdf_ref, &job.urdf_text),
        outcomes,
        wall_time_s: results.iter().map(|r| r.wall_time_s).sum(),
    };
    std::fs::create_dir_all(&plan.out_dir)
        .with_context(|| format!("creating {}", plan.out_dir.display()))?;
    let md = format!(
        "# Gait library ({} speeds, {} … {} m/s)\n\n```text\n{}```\n",
        settings.speeds_mps.len(),
        settings.speeds_mps.first().copied().unwrap_or_default(),
        settings.speeds_mps.last().copied().unwrap_or_default(),
        LibraryFigures(&lp)
    );
    let path = plan.out_dir.join("library.md");
    std::fs::write(&path, &md).with_context(|| format!("writing {}", path.display()))?;
    let mut times = String::from("speed_mps,task_wall_s,solve_s,verify_s\n");
    for r in results {
        if let Payload::Library(p) = &r.payload {
            let Ok(o) = p.as_ref() else { continue };
            writeln!(
                times,
                "{},{:.3},{:.3},{:.3}",
                o.speed_mps, r.wall_time_s, o.solve_time_s, o.verify_time_s
            )?;
        }
    }
    let path = plan.out_dir.join("times.csv");
    std::fs::write(&path, &times).with_context(|| format!("writing {}", path.display()))?;
    let mut text = format!(
        "{}\n(wall: the tasks' wall times summed)\n",
        LibraryTable(&lp)
    );
    if !complete {
        writeln!(
            text,
            "not written: {} (the library waits for every task)",
            settings.library_file.display()
        )?;
        return Ok(text);
    }
    match lp.library() {
        Ok(library) => {
            library.save(&settings.library_file)?;
            writeln!(
                text,
                "wrote {} ({} gaits, {:.3}–{:.3} m/s)",
                settings.library_file.display(),
                library.entries.len(),
                library.speed_range_mps()[0],
                library.speed_range_mps()[1]
            )?;
        }
        Err(e) => writeln!(text, "no library: {e}")?,
    }
    Ok(text)
}
