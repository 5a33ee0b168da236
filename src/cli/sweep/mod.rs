//! `adam sweep`: a study split into independent tasks for a cluster's job array (SLURM), with
//! the same results as the in-process command.
//!
//! ```text
//! adam sweep plan --study S ─▶ plan.toml (study, inputs by SHA-256, out_dir, resources, tasks 0..n)
//! adam sweep slurm --plan P ─▶ array.sbatch (--array=0-(n-1)%limit) + collect.sbatch (afterany) + submit.sh
//! adam sweep task --plan P [--index I | $SLURM_ARRAY_TASK_ID] ─▶ results/task-NNNNN.json (tmp + rename)
//! adam sweep collect --plan P ─▶ the study's report; missing and failed tasks listed, exit 1 while any is missing
//! ```
//!
//! Where things live: this module is the generic machinery (the plan file `plan`, the result
//! files `result`, the sbatch scripts `slurm`, collect); the studies' task functions are in
//! the libraries (`planner::codesign::sweep_run` and `landscape_point`,
//! `runtime::sim::matrix::run`), called here (`design`, `treadmill`) and by the in-process
//! commands alike. The machinery is in the CLI because the treadmill task needs the runtime
//! and the planner may not depend on it.

mod design;
mod plan;
mod result;
mod slurm;
mod treadmill;

use crate::cli::paths::writable;
use anyhow::{bail, Context, Result};
use plan::{Input, Resources, Study, SweepPlan, PLAN_SCHEMA_VERSION};
use result::{read_result, write_result, TaskResult, RESULT_SCHEMA_VERSION};
use std::path::{Path, PathBuf};

/// The commands of `adam sweep`.
#[derive(clap::Subcommand)]
pub(crate) enum SweepCommand {
    /// Write a sweep plan: the study, its inputs with their SHA-256, the output folder, time
    /// and memory per task, and every task with its index.
    Plan(PlanArgs),
    /// Run one task of a plan and write its result file (atomically: a temporary file, then a
    /// rename). The index defaults to `$SLURM_ARRAY_TASK_ID`.
    Task {
        /// The plan.
        #[arg(long)]
        plan: PathBuf,
        /// The task's index (default: `$SLURM_ARRAY_TASK_ID`).
        #[arg(long)]
        index: Option<usize>,
    },
    /// Write the sbatch scripts of a plan under `<out_dir>/slurm/`: the job array, the collect
    /// job that runs after it, and submit.sh; submit them with `--submit` (needs `sbatch`).
    Slurm {
        /// The plan.
        #[arg(long)]
        plan: PathBuf,
        /// Submit the array and the collect job (afterany) with sbatch.
        #[arg(long)]
        submit: bool,
    },
    /// Merge the results that exist into the study's report; list missing and failed tasks;
    /// exit non-zero while any is missing (printing the `--array=` to run them again).
    Collect {
        /// The plan.
        #[arg(long)]
        plan: PathBuf,
    },
}

/// Arguments of `adam sweep plan`.
#[derive(clap::Args)]
pub(crate) struct PlanArgs {
    /// The study: `codesign` (a co-design per initial design of an n × n grid), `landscape`
    /// (the fixed-design gait at every point of an n × n grid), `treadmill` (the treadmill
    /// matrix: belt speeds, belt steps, pushes, restarts × seeds), `library` (not yet).
    #[arg(long, value_enum)]
    study: Study,
    /// Grid size n (n × n tasks) of `codesign` and `landscape` (default: the config's
    /// `[codesign.sweep] grid`, `[codesign] landscape_grid`).
    #[arg(long)]
    grid: Option<usize>,
    /// Planner config (`codesign`, `landscape`).
    #[arg(long, default_value = "configs/planner/adam.toml")]
    config: PathBuf,
    /// Inertia coupling of `codesign` and `landscape`, overriding the config.
    #[arg(long, value_enum)]
    inertia: Option<crate::cli::codesign::InertiaArg>,
    /// Runtime config (`treadmill`).
    #[arg(long, default_value = crate::cli::shipped::RUNTIME_CONFIG)]
    runtime_config: PathBuf,
    /// Gait file (`treadmill`).
    #[arg(long, default_value = runtime::DEFAULT_GAIT)]
    gait: PathBuf,
    /// Seeds of `treadmill`, e.g. `1,2,3` (default 1–5; with --quick 1,2).
    #[arg(long, value_delimiter = ',')]
    seeds: Option<Vec<u64>>,
    /// `treadmill`: the shorter set of `adam bench treadmill --quick`.
    #[arg(long)]
    quick: bool,
    /// Where results, task logs and the report go (default: `out/sweep-<study>`).
    #[arg(long)]
    out_dir: Option<PathBuf>,
    /// Wall-time limit per task, minutes.
    #[arg(long, default_value_t = 30)]
    time_per_task_min: u32,
    /// Memory per task, MB.
    #[arg(long, default_value_t = 2048)]
    mem_per_task_mb: u32,
    /// Tasks of the array running at once.
    #[arg(long, default_value_t = 50)]
    array_limit: u32,
    /// The plan file.
    #[arg(long, default_value = "out/sweep-plan.toml")]
    out: PathBuf,
    /// Write over an existing plan file.
    #[arg(long)]
    force: bool,
}

/// `adam sweep …`.
pub(crate) fn sweep(command: SweepCommand) -> Result<()> {
    match command {
        SweepCommand::Plan(args) => write_plan(&args),
        SweepCommand::Task { plan, index } => task(&plan, index),
        SweepCommand::Slurm { plan, submit } => slurm_scripts(&plan, submit),
        SweepCommand::Collect { plan } => collect(&plan),
    }
}

/// Why `--study library` is refused.
const LIBRARY_NOT_YET: &str = "--study library: not a sweep study yet: `adam plan library` warm-starts each speed's gait from its neighbour's, so its gaits are not independent tasks (use `adam plan library`)";

/// `adam sweep plan`.
fn write_plan(args: &PlanArgs) -> Result<()> {
    if args.study == Study::Library {
        bail!(LIBRARY_NOT_YET);
    }
    writable(&args.out, args.force)?;
    let out_dir = args
        .out_dir
        .clone()
        .unwrap_or_else(|| Path::new("out").join(format!("sweep-{}", args.study.name())));
    let out_dir = std::path::absolute(&out_dir)
        .with_context(|| format!("--out-dir {}", out_dir.display()))?;
    let mut plan = SweepPlan {
        schema_version: PLAN_SCHEMA_VERSION,
        tool: plan::tool_version(),
        study: args.study,
        out_dir,
        task_count: 0,
        resources: Resources {
            time_per_task_min: args.time_per_task_min,
            mem_per_task_mb: args.mem_per_task_mb,
            array_limit: args.array_limit,
        },
        inputs: Vec::new(),
        design: None,
        treadmill: None,
        tasks: Vec::new(),
    };
    match args.study {
        Study::Codesign | Study::Landscape => {
            let path = crate::cli::shipped::input(&args.config);
            let cfg = crate::cli::codesign::codesign_config(&path, args.inertia)?;
            let grid = args.grid.unwrap_or(match args.study {
                Study::Landscape => cfg.codesign.landscape_grid,
                _ => cfg.codesign.sweep.grid,
            });
            let (design, tasks) = design::tasks(args.study, &cfg, grid)?;
            plan.inputs = vec![Input::hashed(design::PLANNER_CONFIG, &path)?];
            plan.design = Some(design);
            plan.tasks = tasks;
        }
        Study::Treadmill => {
            if args.grid.is_some() {
                bail!("--grid is not used by the treadmill study (its matrix is --seeds × the scenarios)");
            }
            let (inputs, settings, tasks) = treadmill::plan(
                &crate::cli::shipped::input(&args.runtime_config),
                &crate::cli::shipped::input(&args.gait),
                args.seeds.clone(),
                args.quick,
            )?;
            plan.inputs = inputs;
            plan.treadmill = Some(settings);
            plan.tasks = tasks;
        }
        Study::Library => bail!(LIBRARY_NOT_YET),
    }
    plan.task_count = plan.tasks.len();
    plan.validate(&args.out)?;
    std::fs::write(&args.out, plan.to_toml()?)
        .with_context(|| format!("writing {}", args.out.display()))?;
    println!(
        "wrote {}: the {} study, {} tasks (0..={}), results to {}",
        args.out.display(),
        plan.study.name(),
        plan.tasks.len(),
        plan.tasks.len() - 1,
        plan.results_dir().display()
    );
    println!(
        "next: adam sweep slurm --plan {0} [--submit]  (or each task: adam sweep task --plan {0} --index I), then adam sweep collect --plan {0}",
        args.out.display()
    );
    Ok(())
}

/// The task index: `--index`, else `$SLURM_ARRAY_TASK_ID`.
fn task_index(index: Option<usize>) -> Result<usize> {
    if let Some(i) = index {
        return Ok(i);
    }
    match std::env::var("SLURM_ARRAY_TASK_ID") {
        Ok(v) => v.trim().parse().with_context(|| {
            format!("SLURM_ARRAY_TASK_ID = \"{v}\": not a task index (a whole number from 0)")
        }),
        Err(_) => bail!(
            "no task index: pass --index I or set SLURM_ARRAY_TASK_ID (as a SLURM job array does)"
        ),
    }
}

/// `adam sweep task`.
fn task(plan_path: &Path, index: Option<usize>) -> Result<()> {
    let plan = SweepPlan::load(plan_path)?;
    let index = task_index(index)?;
    let task = plan.task(index, plan_path)?.clone();
    plan.verify_inputs(plan_path)?;
    let t0 = std::time::Instant::now();
    println!(
        "task {index} of {} ({} study): {}",
        plan.tasks.len(),
        plan.study.name(),
        serde_json::to_string(&task).context("the task as JSON")?
    );
    let payload = match plan.study {
        Study::Codesign | Study::Landscape => design::run_task(&plan, plan_path, &task)?,
        Study::Treadmill => treadmill::run_task(&plan, plan_path, &task)?,
        Study::Library => bail!("{}: library plans are not supported", plan_path.display()),
    };
    let failed = payload.error().map(str::to_string);
    let path = write_result(
        &plan,
        &TaskResult {
            schema_version: RESULT_SCHEMA_VERSION,
            tool: plan::tool_version(),
            index,
            task,
            payload,
            wall_time_s: t0.elapsed().as_secs_f64(),
            host: result::host_name(),
        },
    )?;
    match failed {
        Some(e) => println!("task {index} failed: {e}\nwrote {}", path.display()),
        None => println!(
            "task {index} done in {:.1} s; wrote {}",
            t0.elapsed().as_secs_f64(),
            path.display()
        ),
    }
    Ok(())
}

/// `adam sweep slurm`.
fn slurm_scripts(plan_path: &Path, submit: bool) -> Result<()> {
    let plan = SweepPlan::load(plan_path)?;
    plan.verify_inputs(plan_path)?;
    let plan_abs = std::path::absolute(plan_path)
        .with_context(|| format!("--plan {}", plan_path.display()))?;
    let adam = std::env::current_exe().context("the path of this adam")?;
    let scripts = slurm::scripts(&plan, &plan_abs, &adam)?;
    let [array, collect, submit_sh] = slurm::write_scripts(&plan, &scripts)?;
    println!(
        "wrote {}, {} and {} ({} tasks, --array=0-{}%{})",
        array.display(),
        collect.display(),
        submit_sh.display(),
        plan.tasks.len(),
        plan.tasks.len() - 1,
        plan.resources.array_limit
    );
    if !submit {
        println!("submit with: bash {}", submit_sh.display());
        return Ok(());
    }
    let Some(sbatch) = slurm::sbatch_on_path() else {
        bail!("--submit: sbatch is not on the PATH (the scripts are written; submit them where SLURM is: bash {})", submit_sh.display());
    };
    let (array_id, collect_id) = slurm::submit(&sbatch, &array, &collect)?;
    println!("submitted: array job {array_id}, collect job {collect_id} (afterany:{array_id})");
    Ok(())
}

/// Ranges of indices for `--array=`: `3,17` or `0-4,9`.
fn array_spec(indices: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut k = 0;
    while k < indices.len() {
        let start = indices[k];
        let mut end = start;
        while k + 1 < indices.len() && indices[k + 1] == end + 1 {
            k += 1;
            end = indices[k];
        }
        parts.push(if end > start + 1 {
            format!("{start}-{end}")
        } else if end == start + 1 {
            format!("{start},{end}")
        } else {
            start.to_string()
        });
        k += 1;
    }
    parts.join(",")
}

/// `adam sweep collect`.
fn collect(plan_path: &Path) -> Result<()> {
    let plan = SweepPlan::load(plan_path)?;
    plan.verify_inputs(plan_path)?;
    let mut results = Vec::new();
    let mut missing: Vec<(usize, String)> = Vec::new();
    for t in &plan.tasks {
        match read_result(&plan, t.index) {
            Ok(Some(r)) => results.push(r),
            Ok(None) => missing.push((
                t.index,
                format!("no result file {}", plan.result_path(t.index).display()),
            )),
            Err(e) => missing.push((t.index, format!("{e:#}"))),
        }
    }
    let report = match plan.study {
        Study::Codesign => design::collect_codesign(&plan, plan_path, &results)?,
        Study::Landscape => design::collect_landscape(&plan, plan_path, &results)?,
        Study::Treadmill => treadmill::collect(&plan, &results)?,
        Study::Library => bail!("{}: library plans are not supported", plan_path.display()),
    };
    print!("{report}");
    let failed: Vec<(usize, &str)> = results
        .iter()
        .filter_map(|r| r.payload.error().map(|e| (r.index, e)))
        .collect();
    let walls: Vec<f64> = results.iter().map(|r| r.wall_time_s).collect();
    println!(
        "\n{} of {} tasks have results ({} failed, {} missing); task wall time {:.1} s in all, {:.1} s the longest; report in {}",
        results.len(),
        plan.tasks.len(),
        failed.len(),
        missing.len(),
        walls.iter().sum::<f64>(),
        walls.iter().copied().fold(0.0, f64::max),
        plan.out_dir.display()
    );
    for (i, e) in &failed {
        println!("failed task {i}: {e}");
    }
    if !failed.is_empty() {
        let idx: Vec<usize> = failed.iter().map(|f| f.0).collect();
        println!(
            "to run the failed tasks again: sbatch --array={} {}",
            array_spec(&idx),
            plan.out_dir.join("slurm/array.sbatch").display()
        );
    }
    if missing.is_empty() {
        return Ok(());
    }
    for (i, why) in &missing {
        eprintln!("missing task {i}: {why}");
    }
    let idx: Vec<usize> = missing.iter().map(|m| m.0).collect();
    bail!(
        "{} of {} tasks are missing ({}): run them again with sbatch --array={} {} (or adam sweep task --plan {} --index I), then collect again",
        missing.len(),
        plan.tasks.len(),
        idx.iter().map(usize::to_string).collect::<Vec<_>>().join(", "),
        array_spec(&idx),
        plan.out_dir.join("slurm/array.sbatch").display(),
        plan_path.display()
    )
}

#[cfg(test)]
mod tests {
    use super::array_spec;

    #[test]
    fn array_specs_join_runs_of_indices() {
        assert_eq!(array_spec(&[3, 17]), "3,17");
        assert_eq!(array_spec(&[0, 1, 2, 3, 9]), "0-3,9");
        assert_eq!(array_spec(&[4, 5]), "4,5");
        assert_eq!(array_spec(&[7]), "7");
        assert_eq!(array_spec(&[]), "");
    }
}
