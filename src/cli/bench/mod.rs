//! `adam bench plan`, `adam bench check` and `adam bench library`: the plan, the gait check and
//! the gait library repeated, a row per run and the medians; `adam bench treadmill`
//! ([`mod@treadmill`]): the treadmill scenarios of issue #29 over seeds, a table per scenario;
//! `adam bench live` ([`mod@live`]): loop jitter and tick time with 0 and N live clients.

mod library;
mod live;
mod report;
mod treadmill;

pub(crate) use treadmill::{matrix_runs, seeds_or_default, tables as treadmill_tables, treadmill};

pub(crate) use library::library;
pub(crate) use live::live;

use crate::cli::plan::{CommandTimes, PhaseSeconds};
use crate::cli::shipped;
use anyhow::{bail, Result};
use report::{CheckRow, CheckSummary, PlanRow, PlanSummary};
use std::path::{Path, PathBuf};

/// The benchmarks of `adam bench`.
#[derive(clap::Subcommand)]
pub(crate) enum BenchWhat {
    /// Run the whole `adam plan` `--runs` times (fresh problem each time, the gait written to a
    /// scratch file): set-up, iterations and solve time per stage, then the command's wall time
    /// by phase (load, problems, both solves, feed-forward, gait file, verification) with its
    /// CPU time, and the medians.
    Plan {
        /// Number of plans.
        #[arg(long, default_value_t = 5)]
        runs: usize,
        /// Robot.
        #[arg(long, default_value = "configs/robots/adam_planar.urdf")]
        robot: PathBuf,
        /// Planner config.
        #[arg(long, default_value = "configs/planner/adam.toml")]
        config: PathBuf,
        /// NLP backend, overriding the config's `[solver] backend`: `ripopt` or `native`.
        #[arg(long, value_parser = crate::cli::plan::parse_backend)]
        backend: Option<planner::config::SolverBackend>,
    },
    /// The loop's wake-up jitter and tick time in real time on the simulated robot, publishing
    /// to `adam live` (its own process), with 0 and with 3 Foxglove clients subscribed to every
    /// channel (`--clients 0,3`): a row per client count.
    Live(live::LiveBenchArgs),
    /// Plan the gait library of `adam plan library` `--runs` times (nothing written): wall and
    /// CPU time per run, and the medians.
    Library(library::LibraryBenchArgs),
    /// Verify a gait `--runs` times like `adam gait check` (Newton on the Poincaré map,
    /// eigenvalues): wall time per run, the median, and whether the reports are identical.
    Check {
        /// Number of checks.
        #[arg(long, default_value_t = 3)]
        runs: usize,
        /// The gait file.
        #[arg(default_value = "configs/gaits/adam_walk.json")]
        gait: PathBuf,
    },
    /// The treadmill scenarios on the simulated robot, in parallel, a table each: belts at
    /// 0.15–0.35 m/s for 60 s, a belt step 0.20 → 0.30 → 0.20 m/s, pushes at five points of the
    /// step (and the largest ridden through each way), start and restart.
    Treadmill {
        /// Seeds, e.g. `1,2,3` (default 1–5; with --quick 1,2).
        #[arg(long, value_delimiter = ',')]
        seeds: Option<Vec<u64>>,
        /// A shorter set: 20 s belts, a 30 s belt step, three push points, 3 bisections.
        #[arg(long)]
        quick: bool,
        /// The constant belts of table (a), m/s: `lo:hi:step` or `v1,v2,…` (default the
        /// issue's 0.15, 0.20, 0.25, 0.30, 0.35; e.g. `0.15:0.35:0.025` for the speeds between).
        #[arg(long)]
        belts: Option<String>,
        /// Runtime config (TOML).
        #[arg(long, default_value = shipped::RUNTIME_CONFIG)]
        config: PathBuf,
        /// Gait file (JSON); default: the co-designed ADAM's.
        #[arg(long, default_value = runtime::DEFAULT_GAIT)]
        gait: PathBuf,
    },
}

/// `adam bench check`: verifies a gait `runs` times, one row per run, then the median.
pub(crate) fn check(runs: usize, gait_path: &std::path::Path) -> Result<()> {
    if runs == 0 {
        bail!("--runs must be at least 1");
    }
    let gait_path = &shipped::input(gait_path);
    let (gait, robot) = planner::verify::load_gait_and_robot(gait_path)?;
    let options = planner::verify::VerifyOptions::default();
    println!("{}", CheckRow::header());
    let mut times = Vec::with_capacity(runs);
    let mut first: Option<planner::verify::VerifyReport> = None;
    let mut identical = true;
    for run in 1..=runs {
        let t0 = std::time::Instant::now();
        let r = planner::verify::verify_gait(&robot, &gait, options)?;
        let wall = t0.elapsed().as_secs_f64();
        println!(
            "{}",
            CheckRow {
                run,
                wall_s: wall,
                newton_iterations: r.newton_iterations,
                fixed_point_residual: r.fixed_point_residual,
                spectral_radius: r.spectral_radius,
            }
        );
        times.push(wall);
        match &first {
            None => first = Some(r),
            Some(f) => identical &= *f == r,
        }
    }
    times.sort_by(f64::total_cmp);
    println!(
        "\n{}",
        CheckSummary {
            gait: gait_path,
            median_s: times[runs / 2],
            runs,
            identical,
        }
    );
    Ok(())
}

/// `adam bench plan`: plans the gait `runs` times, one row per run, then the medians.
pub(crate) fn plan(
    runs: usize,
    robot: &Path,
    config: &Path,
    backend: Option<planner::config::SolverBackend>,
) -> Result<()> {
    if runs == 0 {
        bail!("--runs must be at least 1");
    }
    let (robot, config) = (&shipped::input(robot), &shipped::input(config));
    let mut cfg = planner::config::PlannerConfig::load(config)?;
    if let Some(backend) = backend {
        cfg.solver.backend = backend;
    }
    // Each run is the whole `adam plan` (reading, planning, the feed-forward table, the gait
    // file, the verification), writing its gait to a scratch file.
    let scratch = std::env::temp_dir().join(format!("adam-bench-plan-{}.json", std::process::id()));
    let mut commands = Vec::with_capacity(runs);
    println!("{}", PlanRow::header());
    let mut phases = Vec::with_capacity(runs);
    let mut totals = Vec::with_capacity(runs);
    let mut iterations = Vec::with_capacity(runs);
    let mut size = (0, 0);
    let mut first_x: Option<Vec<f64>> = None;
    let mut identical = true;
    for run in 1..=runs {
        let (command, p) =
            crate::cli::plan::plan_command(robot, config, &scratch, true, backend, false)?;
        let total = command.total_s;
        commands.push(command);
        let (f, c) = (&p.stages[0], &p.stages[1]);
        let phase = PhaseSeconds::of_plan(&p.stages);
        println!(
            "{}",
            PlanRow {
                run,
                setup_s: p.setup_time_s,
                feasibility_iterations: f.iterations,
                feasibility_solve_s: f.solve_time_s,
                cost_iterations: c.iterations,
                cost_solve_s: c.solve_time_s,
                phases: phase,
                total_s: total,
            }
        );
        phases.push(phase);
        totals.push(total);
        iterations.push(f.iterations + c.iterations);
        size = p.size;
        match &first_x {
            None => first_x = Some(p.x.clone()),
            Some(x) => identical &= *x == p.x,
        }
    }
    std::fs::remove_file(&scratch).ok();
    println!("\nthe whole command by phase, wall s (median of {runs} runs last):");
    println!("{:>3} {}", "run", CommandTimes::header());
    for (run, c) in commands.iter().enumerate() {
        println!("{:>3} {}", run + 1, c.row());
    }
    println!("{:>3} {}", "med", CommandTimes::median(&commands).row());
    totals.sort_by(f64::total_cmp);
    iterations.sort_unstable();
    // Each phase's median over the runs (so they need not add up to the median total).
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[runs / 2]
    };
    let mut evaluation: Vec<f64> = phases.iter().map(|p| p.evaluation).collect();
    let backend: Option<Vec<[f64; 3]>> = phases.iter().map(PhaseSeconds::split).collect();
    let split_s = backend.map(|b| {
        let column = |k: usize| median(&mut b.iter().map(|p| p[k]).collect());
        [column(0), column(1), column(2)]
    });
    println!(
        "\n{}",
        PlanSummary {
            size,
            backend: cfg.solver.backend,
            median_total_s: totals[runs / 2],
            median_iterations: iterations[runs / 2],
            runs,
            identical,
            evaluation_s: median(&mut evaluation),
            split_s,
        }
    );
    Ok(())
}
