//! `adam bench library`: the gait library of `adam plan library` planned `--runs` times (fresh
//! problems each time, nothing written), a row per run with its wall and CPU time, then the
//! medians.

use crate::cli::plan::library::{parse_schedule, LibraryArgs, LibraryJob, DEFAULT_SPEEDS};
use anyhow::{bail, Result};
use planner::library::Schedule;
use std::path::PathBuf;

/// Arguments of `adam bench library`.
#[derive(clap::Args)]
pub(crate) struct LibraryBenchArgs {
    /// Number of libraries planned.
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Robot URDF.
    #[arg(long, default_value = "configs/robots/adam_codesign.urdf")]
    robot: PathBuf,
    /// Planner config.
    #[arg(long, default_value = "configs/planner/adam_library.toml")]
    config: PathBuf,
    /// Speeds, m/s: `lo:hi:step` or `v1,v2,…`.
    #[arg(long, default_value = DEFAULT_SPEEDS)]
    speeds: String,
    /// `two-chains` or `sequential` (see `adam plan library --help`).
    #[arg(long, default_value = "two-chains", value_parser = parse_schedule)]
    schedule: Schedule,
    /// Largest relative step error of a verified gait (as `adam plan library`).
    #[arg(long, default_value_t = planner::verify::STEP_DURATION_TOLERANCE)]
    max_step_error: f64,
}

/// CPU time of this process so far (all threads, user + system), s, from `/proc/self/stat`
/// (clock ticks of 1/100 s); `None` where that file is not there.
fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The fields after the command name (which is in parentheses and may hold spaces).
    let rest = stat.get(stat.rfind(')')? + 2..)?;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the line, 12 and 13 after the name.
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// `adam bench library`: plans the library `runs` times; fails if a run's library would.
pub(crate) fn library(args: &LibraryBenchArgs) -> Result<()> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let job = LibraryJob::load(&LibraryArgs {
        robot: args.robot.clone(),
        config: args.config.clone(),
        speeds: args.speeds.clone(),
        out: PathBuf::from("robot-relative.json"),
        force: false,
        backend: None,
        schedule: args.schedule,
        max_step_error: args.max_step_error,
    })?;
    println!(
        "{:>3} {:>8} {:>8} {:>6} {:>5} {:>5} {:>6}",
        "run", "wall s", "CPU s", "gaits", "warm", "cold", "iter"
    );
    let (mut walls, mut cpus) = (Vec::new(), Vec::new());
    for run in 1..=args.runs {
        let cpu0 = process_cpu_s();
        let t0 = std::time::Instant::now();
        let plan = job.run()?;
        let wall = t0.elapsed().as_secs_f64();
        let cpu = cpu0.zip(process_cpu_s()).map(|(a, b)| b - a);
        let library = plan.library()?;
        let warm = plan.outcomes.iter().filter(|o| o.warm).count();
        println!(
            "{run:>3} {wall:>8.2} {:>8} {:>6} {warm:>5} {:>5} {:>6}",
            cpu.map_or("-".into(), |c| format!("{c:.2}")),
            library.entries.len(),
            plan.outcomes.len() - warm,
            plan.outcomes.iter().map(|o| o.iterations).sum::<usize>()
        );
        walls.push(wall);
        if let Some(c) = cpu {
            cpus.push(c);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    };
    let schedule = match args.schedule {
        Schedule::TwoChains => "two-chains",
        Schedule::Sequential => "sequential",
    };
    println!(
        "\n{} speeds ({}), schedule {schedule}, {} cores: median of {} runs: wall {:.2} s, CPU {}",
        job.speeds_mps.len(),
        args.speeds,
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        args.runs,
        median(&mut walls).unwrap_or(f64::NAN),
        median(&mut cpus).map_or("not measured".into(), |c| format!("{c:.2} s"))
    );
    Ok(())
}
