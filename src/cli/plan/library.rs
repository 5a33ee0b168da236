//! `adam plan library`: a gait per speed for one robot, verified, written as one library file,
//! with a table of what each speed gave.

use crate::cli::paths::{relative_path, writable};
use crate::cli::shipped;
use anyhow::{Context, Result};
use model::PlanarModel;
use planner::library::{LibraryOptions, LibraryPlan, Schedule};
use std::fmt;
use std::path::PathBuf;

/// The speeds the shipped library covers (issue #29: the treadmill's 0.15–0.35 m/s).
pub(crate) const DEFAULT_SPEEDS: &str = "0.15:0.35:0.025";

/// The robot of a library by default: the one `adam demo` walks.
pub(crate) const DEFAULT_ROBOT: &str = "configs/robots/adam_codesign.urdf";

/// The planner config of a library by default.
pub(crate) const DEFAULT_CONFIG: &str = "configs/planner/adam_library.toml";

/// Arguments of `adam plan library`.
#[derive(clap::Args, Clone)]
pub(crate) struct LibraryArgs {
    /// Robot URDF (the design is fixed: the URDF's); default the robot `adam demo` walks.
    #[arg(long, default_value = DEFAULT_ROBOT)]
    pub(crate) robot: PathBuf,
    /// Planner config (TOML); its `gait.speed_mps` is replaced by each speed.
    #[arg(long, default_value = DEFAULT_CONFIG)]
    pub(crate) config: PathBuf,
    /// Speeds, m/s: `lo:hi:step` or a list `v1,v2,…` (slowest first).
    #[arg(long, default_value = DEFAULT_SPEEDS)]
    pub(crate) speeds: String,
    /// Output library file (JSON); an existing file needs --force.
    #[arg(long, default_value = "out/gaits/adam_library.json")]
    pub(crate) out: PathBuf,
    /// Write over an existing --out.
    #[arg(long)]
    pub(crate) force: bool,
    /// NLP backend, overriding the config's `[solver] backend`: `ripopt` or `native`.
    #[arg(long, value_parser = super::parse_backend)]
    pub(crate) backend: Option<planner::config::SolverBackend>,
    /// How the walks out from the middle speed share the cores: `two-chains` (the slower and
    /// the faster speeds at once) or `sequential` (one after the other, each solve on all
    /// cores).
    #[arg(long, default_value = "two-chains", value_parser = parse_schedule)]
    pub(crate) schedule: Schedule,
    /// Largest relative difference between the verified step (duration, length) and the
    /// plan's for a gait to enter the library (default: the 1 % plan accuracy).
    #[arg(long, default_value_t = planner::verify::PLAN_ACCURACY)]
    pub(crate) max_step_error: f64,
}

/// `--schedule two-chains|sequential`.
pub(crate) fn parse_schedule(text: &str) -> std::result::Result<Schedule, String> {
    match text {
        "two-chains" => Ok(Schedule::TwoChains),
        "sequential" => Ok(Schedule::Sequential),
        other => Err(format!(
            "unknown schedule `{other}`: expected `two-chains` or `sequential`"
        )),
    }
}

/// What a library run needs, loaded and checked before any solve.
pub(crate) struct LibraryJob {
    pub(crate) model: PlanarModel,
    pub(crate) urdf_text: String,
    pub(crate) urdf_ref: String,
    pub(crate) config: planner::config::PlannerConfig,
    pub(crate) speeds_mps: Vec<f64>,
    pub(crate) options: LibraryOptions,
}

impl LibraryJob {
    /// Loads the robot and config and parses the speeds (the library names its URDF relative
    /// to `out`).
    pub(crate) fn load(args: &LibraryArgs) -> Result<Self> {
        if !(args.max_step_error.is_finite() && args.max_step_error > 0.0) {
            anyhow::bail!(
                "--max-step-error {}: must be a positive fraction (0.01 = 1 %)",
                args.max_step_error
            );
        }
        let speeds_mps = planner::library::parse_speeds(&args.speeds)?;
        let (robot, config) = (&shipped::input(&args.robot), &shipped::input(&args.config));
        let urdf_text = std::fs::read_to_string(robot)
            .with_context(|| format!("reading {}", robot.display()))?;
        let model = PlanarModel::from_urdf_str(&urdf_text, &robot.display().to_string())?;
        let mut cfg = planner::config::PlannerConfig::load(config)?;
        if let Some(backend) = args.backend {
            cfg.solver.backend = backend;
        }
        Ok(Self {
            model,
            urdf_ref: relative_path(robot, &args.out),
            urdf_text,
            config: cfg,
            speeds_mps,
            options: LibraryOptions {
                schedule: args.schedule,
                max_step_error: args.max_step_error,
                ..LibraryOptions::default()
            },
        })
    }

    /// Plans and verifies every speed.
    pub(crate) fn run(&self) -> Result<LibraryPlan> {
        Ok(planner::library::plan_library(
            &self.model,
            &self.urdf_ref,
            &self.urdf_text,
            &self.config,
            &self.speeds_mps,
            self.options,
        )?)
    }
}

/// `adam plan library`: plans, prints the table, writes the library (or fails naming the hole).
pub(crate) fn plan_library(args: &LibraryArgs) -> Result<()> {
    let job = LibraryJob::load(args)?;
    // Refused before the solves, not after them.
    writable(&args.out, args.force)?;
    println!(
        "planning {} gaits ({} … {} m/s) for {}",
        job.speeds_mps.len(),
        job.speeds_mps.first().copied().unwrap_or_default(),
        job.speeds_mps.last().copied().unwrap_or_default(),
        args.robot.display()
    );
    let plan = job.run()?;
    println!("{}", LibraryTable(&plan));
    let library = plan.library()?;
    library.save(&args.out)?;
    println!(
        "wrote {} ({} gaits, {:.3}–{:.3} m/s)",
        args.out.display(),
        library.entries.len(),
        library.speed_range_mps()[0],
        library.speed_range_mps()[1]
    );
    Ok(())
}

/// The table of a library run: one row per speed, the left-out ones with their reason, each
/// speed's solve time and the wall time.
pub(crate) struct LibraryTable<'a>(pub(crate) &'a LibraryPlan);

impl fmt::Display for LibraryTable<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_table(f, self.0, true)
    }
}

/// [`LibraryTable`] without times: what a library run found, the same from `adam plan library`
/// and from a library sweep's tasks (`adam sweep collect` writes it to `library.md`).
pub(crate) struct LibraryFigures<'a>(pub(crate) &'a LibraryPlan);

impl fmt::Display for LibraryFigures<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_table(f, self.0, false)
    }
}

fn write_table(f: &mut fmt::Formatter<'_>, plan: &LibraryPlan, times: bool) -> fmt::Result {
    write!(
        f,
        "{:>7} {:>8} {:>7} {:>9} {:>8} {:>8} {:>9} {:>9} {:>5} {:>5}",
        "v m/s", "d m", "T s", "CoT", "max|λ|", "apex %", "T err %", "d err %", "start", "iter"
    )?;
    if times {
        write!(f, " {:>8}", "solve s")?;
    }
    writeln!(f)?;
    for o in &plan.outcomes {
        match &o.result {
            Ok(e) => {
                let g = &e.gait;
                write!(
                    f,
                    "{:>7.3} {:>8.4} {:>7.4} {:>9.5} {:>8.4} {:>8} {:>9.3} {:>9.3} {:>5} {:>5}",
                    o.speed_mps,
                    g.step_length_m,
                    g.step_duration_s,
                    g.cost_of_transport,
                    e.check.spectral_radius,
                    e.check
                        .apex_margin
                        .map_or("—".to_string(), |m| format!("{:.1}", 100.0 * m)),
                    100.0 * e.check.duration_error(g),
                    100.0 * e.check.length_error(g),
                    if o.warm { "warm" } else { "cold" },
                    o.iterations,
                )?;
                if times {
                    write!(f, " {:>8.2}", o.solve_time_s)?;
                }
                writeln!(f)?;
            }
            Err(why) => writeln!(f, "{:>7.3} left out: {why}", o.speed_mps)?,
        }
    }
    if !times {
        return Ok(());
    }
    let solve: f64 = plan.outcomes.iter().map(|o| o.solve_time_s).sum();
    let verify: f64 = plan.outcomes.iter().map(|o| o.verify_time_s).sum();
    write!(
        f,
        "wall {:.2} s (solves {solve:.2} s, verification and feed-forward {verify:.2} s, summed over speeds)",
        plan.wall_time_s
    )
}
