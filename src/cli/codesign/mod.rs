//! `adam codesign [sweep]`: the thigh and shin lengths co-designed with the gait (paper Sec.
//! III), compared with gaits at fixed designs; the sweep is the paper's convergence study.

mod audit;
mod landscape;
mod report;
mod speeds;
mod sweep;

pub(crate) use sweep::write_sweep_report;

pub(crate) use audit::audit;
pub(crate) use landscape::{
    landscape, sweep_ends, write_landscape_report, LandscapeRequest, OptimumSummary, StartArg,
};

use crate::cli::paths::{relative_path, writable, OUT_DIR};
use crate::cli::plan::{gait_check, progress_printer};
use crate::cli::shipped;
use anyhow::{bail, Context, Result};
use model::design::DesignLengths;
use report::{CodesignReport, DesignRow};
use std::path::{Path, PathBuf};

/// Arguments of `adam codesign`. `--config`, `--inertia` and `--force` are accepted before
/// and after `sweep`.
#[derive(clap::Args)]
pub(crate) struct CodesignArgs {
    /// Planner config (TOML) with its `[codesign]` section (design box, sweep grid).
    #[arg(long, global = true, default_value = "configs/planner/adam.toml")]
    config: PathBuf,
    /// Inertia coupling, overriding the config: `exact` (inside the NLP) or `alg1`
    /// (the paper's Alg. 1: frozen per solve, regenerated between solves).
    #[arg(long, global = true, value_enum)]
    inertia: Option<InertiaArg>,
    /// Write over existing output files.
    #[arg(long, global = true)]
    force: bool,
    /// Output gait file (default: `out/gaits/adam_codesign.json`).
    #[arg(long)]
    out_gait: Option<PathBuf>,
    /// Output URDF of the co-designed robot (default: `out/robots/adam_codesign.urdf`).
    #[arg(long)]
    out_urdf: Option<PathBuf>,
    /// Co-design one robot for the gaits of several speeds together, m/s, comma-separated
    /// (e.g. `0.20,0.25,0.30`): one NLP with shared lengths minimizing the mean cost of
    /// transport; writes the URDF and one gait per speed beside `--out-gait`
    /// (`<stem>_<speed>.json`), and compares with the single-speed co-design at each speed.
    #[arg(long, value_delimiter = ',')]
    speeds: Option<Vec<f64>>,
    /// `sweep`: the convergence study instead of one co-design.
    #[command(subcommand)]
    pub(crate) study: Option<CodesignStudy>,
}

/// The studies of `adam codesign`.
#[derive(clap::Subcommand)]
pub(crate) enum CodesignStudy {
    /// The paper's convergence study: co-design from an n × n grid of initial thigh and shin
    /// lengths over the config's design box, in parallel on all cores; writes sweep.csv,
    /// table.md (like the paper's Table II) and convergence.png/.svg (like its Fig. 3).
    Sweep {
        /// Grid size n (n × n runs), overriding the config's `[codesign.sweep] grid`.
        #[arg(long)]
        grid: Option<usize>,
        /// Output folder (default: `out/codesign-sweep`).
        #[arg(long)]
        out_dir: Option<PathBuf>,
    },
    /// The cost landscape: the gait optimized at every design of an n × n grid of the design
    /// box, in parallel; writes landscape.png/.svg (a heat map with the co-design optimum and
    /// the convergence study's endpoints), landscape.csv and activity.md (which constraints
    /// hold the co-design optimum, with their multipliers).
    Landscape {
        /// Grid size n (n × n solves, at least 2), overriding `[codesign] landscape_grid`.
        #[arg(long)]
        grid: Option<usize>,
        /// Output folder (default: `out/codesign-landscape`).
        #[arg(long)]
        out_dir: Option<PathBuf>,
        /// The convergence study's sweep.json (from `adam codesign sweep`) whose endpoints to
        /// draw; without it the study is run and its sweep.json written beside the figure.
        #[arg(long)]
        sweep: Option<PathBuf>,
        /// Where each grid solve starts: ring by ring from its inner neighbour's solution
        /// (`neighbours`, the default: 16 % fewer iterations on the 9 × 9 grid), or every one
        /// from the gait at the initial design (`initial`).
        #[arg(long, value_enum, default_value = "neighbours")]
        start: StartArg,
    },
    /// The constraint audit: the gait with and without each constraint that is ours, not the
    /// paper's (swing clearance envelope, impact-velocity margin, lift-off, pitch limits), from
    /// the baseline optimum and from scratch; writes audit.md.
    Audit {
        /// The robot (default: ADAM generated at the config's initial lengths).
        #[arg(long)]
        urdf: Option<PathBuf>,
        /// Output folder (default: `out/codesign-audit`).
        #[arg(long)]
        out_dir: Option<PathBuf>,
    },
}

/// `--inertia` (no doc on the values: clap would list them with it).
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum InertiaArg {
    Exact,
    Alg1,
}

/// The planner config with the CLI's inertia coupling, if given.
pub(crate) fn codesign_config(
    config: &Path,
    inertia: Option<InertiaArg>,
) -> Result<planner::config::PlannerConfig> {
    let mut cfg = planner::config::PlannerConfig::load(shipped::input(config))?;
    if let Some(i) = inertia {
        cfg.codesign.inertia = match i {
            InertiaArg::Exact => planner::config::InertiaCoupling::Exact,
            InertiaArg::Alg1 => planner::config::InertiaCoupling::Alg1,
        };
    }
    Ok(cfg)
}

/// `adam codesign`: co-designs, writes the URDF and gait, prints the outer iterations and the
/// comparison with fixed designs, and checks the gait.
pub(crate) fn codesign(args: &CodesignArgs) -> Result<()> {
    if let Some(speeds) = &args.speeds {
        return speeds::codesign_speeds(args, speeds);
    }
    let CodesignArgs {
        config,
        inertia,
        force,
        out_gait,
        out_urdf,
        ..
    } = args;
    let out = Path::new(OUT_DIR);
    let out_gait = &out_gait
        .clone()
        .unwrap_or_else(|| out.join("gaits/adam_codesign.json"));
    let out_urdf = &out_urdf
        .clone()
        .unwrap_or_else(|| out.join("robots/adam_codesign.urdf"));
    let cfg = codesign_config(config, *inertia)?;
    // Refused before the solve, not after minutes of it.
    for path in [out_gait, out_urdf] {
        writable(path, *force)?;
    }
    let urdf_ref = relative_path(out_urdf, out_gait);
    let r = planner::codesign::codesign(&cfg, &urdf_ref, &mut progress_printer())?;
    std::fs::write(out_urdf, &r.urdf).with_context(|| format!("writing {}", out_urdf.display()))?;
    r.planned.gait.save(out_gait)?;
    let (g0, g) = (&r.initial.gait, &r.planned.gait);
    print!(
        "\n{}",
        CodesignReport {
            inertia: cfg.codesign.inertia,
            wall_time_s: r.wall_time_s,
            outer: &r.outer,
            designs: [
                DesignRow::of_gait("initial (fixed)", g0),
                DesignRow::of_gait("co-designed", g),
            ],
            converged: r.converged,
        }
    );
    // Gaits optimized at fixed designs, for comparison: the four corners of the design box and
    // the paper's optimum, each warm-started from the initial design's gait.
    let c = &cfg.codesign;
    let fixed = [
        ("box corner", [c.thigh_m[0], c.shin_m[0]]),
        ("box corner", [c.thigh_m[0], c.shin_m[1]]),
        ("box corner", [c.thigh_m[1], c.shin_m[0]]),
        ("box corner", [c.thigh_m[1], c.shin_m[1]]),
        ("paper's optimum", PAPER_OPTIMUM_M),
    ];
    let designs: Vec<[f64; 2]> = fixed.iter().map(|f| f.1).collect();
    println!("\noptimizing the gait at fixed designs for comparison ...");
    let outcomes = planner::codesign::compare_fixed_designs(&cfg, &r.initial, &designs);
    for ((name, d), o) in fixed.iter().zip(&outcomes) {
        println!("{}", DesignRow::of_outcome(name, *d, o));
    }
    println!("wrote {} and {}", out_gait.display(), out_urdf.display());
    gait_check(out_gait, 10.0, None, 0.0)
}

/// The paper's co-designed thigh and shin lengths, m (its Table II), a reference to compare with.
const PAPER_OPTIMUM_M: [f64; 2] = [0.2425, 0.2515];

/// `adam codesign sweep`: the convergence study, every run in this process (rayon) through
/// the task function of a sweep plan's task (`planner::codesign::sweep_run`), then the report
/// `adam sweep collect` writes from a plan's results ([`sweep::write_sweep_report`]).
pub(crate) fn convergence_sweep(
    args: &CodesignArgs,
    grid: Option<usize>,
    out_dir: Option<&Path>,
) -> Result<()> {
    let (config, inertia) = (&args.config, args.inertia);
    refuse_gait_outputs(args, "sweep")?;
    let mut cfg = codesign_config(config, inertia)?;
    if let Some(grid) = grid {
        check_sweep_grid(grid)?;
        cfg.codesign.sweep.grid = grid;
    }
    let grid = cfg.codesign.sweep.grid;
    let default_dir = Path::new(OUT_DIR).join("codesign-sweep");
    let out_dir = out_dir.unwrap_or(&default_dir);
    for name in sweep::SWEEP_OUTPUTS {
        writable(&out_dir.join(name), args.force)?;
    }
    let start = std::time::Instant::now();
    let model_lengths = cfg.codesign.initial_m;
    let initial = warm_start(&cfg)?;
    let warm_s = start.elapsed().as_secs_f64();
    let starts = planner::codesign::sweep_grid(&cfg, grid);
    let bar = indicatif::ProgressBar::new(starts.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} runs, {elapsed} elapsed, ETA {eta} {msg}",
        )
        .map_err(|e| anyhow::anyhow!("{e}"))?,
    );
    let runs = planner::codesign::sweep(&cfg, &initial, model_lengths, &starts, &|r| {
        bar.inc(1);
        if let Ok(o) = &r.outcome {
            bar.set_message(format!(
                "last: {:.3}/{:.3} → {:.4}/{:.4}",
                r.initial_m[0], r.initial_m[1], o.lengths_m[0], o.lengths_m[1]
            ));
        }
    });
    bar.finish();
    let wall_s = start.elapsed().as_secs_f64();
    let walls: Vec<f64> = runs.iter().map(|r| r.wall_time_s).collect();
    let md = sweep::write_sweep_report(&cfg, &runs, &walls, out_dir)?;
    print!("\n{md}");
    println!(
        "\nwarm start {warm_s:.1} s; {} runs {:.1} s wall in all on {} threads",
        runs.len(),
        wall_s,
        rayon_threads()
    );
    println!(
        "wrote {}",
        sweep::SWEEP_OUTPUTS
            .iter()
            .map(|n| out_dir.join(n).display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// Checks a `--grid` of the convergence study (n × n co-designs).
pub(crate) fn check_sweep_grid(grid: usize) -> Result<()> {
    if !(1..=planner::config::MAX_SWEEP_GRID).contains(&grid) {
        bail!(
            "--grid {grid}: must be in 1..={}",
            planner::config::MAX_SWEEP_GRID
        );
    }
    Ok(())
}

/// A study writes no gait or URDF: `--out-gait` and `--out-urdf` are refused by name.
fn refuse_gait_outputs(args: &CodesignArgs, study: &str) -> Result<()> {
    if args.speeds.is_some() {
        bail!("--speeds is not used by `adam codesign {study}` (it is a co-design of its own)");
    }
    for (flag, given) in [
        ("--out-gait", args.out_gait.is_some()),
        ("--out-urdf", args.out_urdf.is_some()),
    ] {
        if given {
            bail!("{flag} is not used by `adam codesign {study}` (its outputs go to --out-dir)");
        }
    }
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The gait planned at `[codesign] initial_m` on the robot GenerateModel makes there (with the
/// A1 drives if `[codesign] a1_drives`, the tubes' `link_density_scale`): the warm start of the sweep and the landscape.
pub(crate) fn warm_start(
    cfg: &planner::config::PlannerConfig,
) -> Result<planner::plan::PlannedGait> {
    let [thigh_m, shin_m] = cfg.codesign.initial_m;
    let (model, urdf) = model::design::generate_model_with(
        &DesignLengths {
            thigh_length_m: thigh_m,
            shin_length_m: shin_m,
        },
        &cfg.codesign.mass_model(),
    )?;
    println!("warm start: planning the gait at thigh {thigh_m} m, shin {shin_m} m");
    Ok(planner::plan::plan_gait(
        &model,
        "robot.urdf",
        &urdf,
        cfg,
        &mut |_| {},
    )?)
}
