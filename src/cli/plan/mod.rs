//! `adam plan` and `adam gait check`: the HZD gait planned with live progress and a summary
//! table, and a gait file verified on its own (Newton on the Poincaré map, eigenvalues);
//! `adam plan library` (in `library`): a gait per speed, written as one library file.

pub(crate) mod library;
mod report;

pub(crate) use report::{GaitFigures, PhaseSeconds};

use crate::cli::paths::{relative_path, writable};
use crate::cli::shipped;
use anyhow::{bail, Context, Result};
use model::PlanarModel;
use report::{OrbitCheck, PlanSummary};
use std::path::PathBuf;

/// Arguments of `adam plan` (or its subcommand, `adam plan library`).
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct PlanArgs {
    /// `library`: a gait per speed instead of one gait.
    #[command(subcommand)]
    command: Option<PlanCommand>,
    /// Robot URDF.
    #[arg(long, default_value = "configs/robots/adam_planar.urdf")]
    robot: PathBuf,
    /// Planner config (TOML).
    #[arg(long, default_value = "configs/planner/adam.toml")]
    config: PathBuf,
    /// Output gait file (JSON); an existing file needs --force.
    #[arg(long, default_value = "out/gaits/adam_walk.json")]
    out: PathBuf,
    /// Write over an existing --out.
    #[arg(long)]
    force: bool,
    /// NLP backend, overriding the config's `[solver] backend`: `ripopt` or `native`.
    #[arg(long, value_parser = parse_backend)]
    backend: Option<planner::config::SolverBackend>,
}

/// The subcommands of `adam plan`.
#[derive(clap::Subcommand)]
pub(crate) enum PlanCommand {
    /// Plan a gait per walking speed for one robot (each warm-started from its neighbour),
    /// verify each (Poincaré eigenvalues, the step it walks) and write one gait library file;
    /// fails if the gaits left out leave a hole wider than 0.05 m/s.
    Library(library::LibraryArgs),
}

/// The subcommands of `adam gait`.
#[derive(clap::Subcommand)]
pub(crate) enum GaitCommand {
    /// Simulate the closed loop, find the periodic orbit (Newton on the Poincaré map), print its
    /// eigenvalues; exit non-zero for an unstable or inconsistent gait.
    Check {
        /// Gait file.
        gait: PathBuf,
        /// ε of the output controller, 1/s.
        #[arg(long, default_value_t = 10.0)]
        epsilon: f64,
    },
}

/// `--backend ripopt|native`.
pub(crate) fn parse_backend(
    text: &str,
) -> std::result::Result<planner::config::SolverBackend, String> {
    match text {
        "ripopt" => Ok(planner::config::SolverBackend::Ripopt),
        "native" => Ok(planner::config::SolverBackend::Native),
        other => Err(format!(
            "unknown backend `{other}`: expected `ripopt` or `native`"
        )),
    }
}

/// Prints each solve's start and every tenth iteration (or one a second).
pub(crate) fn progress_printer() -> impl FnMut(planner::plan::Progress<'_>) {
    let mut last_print = std::time::Instant::now();
    move |p| match p {
        planner::plan::Progress::Stage(s) => println!("solve: {s}"),
        planner::plan::Progress::Iteration(_, r) => {
            if r.iteration % 10 == 0 || last_print.elapsed().as_secs_f64() > 1.0 {
                println!(
                    "  iter {:>4}  objective {:>12.6e}  infeasibility {:>9.2e}  dual {:>9.2e}",
                    r.iteration, r.objective, r.primal_infeasibility, r.dual_infeasibility
                );
                last_print = std::time::Instant::now();
            }
        }
    }
}

/// `adam plan`: plans the gait, writes it, prints the summary and its verification.
pub(crate) fn plan(args: &PlanArgs) -> Result<()> {
    if let Some(PlanCommand::Library(library)) = &args.command {
        return library::plan_library(library);
    }
    let PlanArgs {
        command: _,
        robot,
        config,
        out,
        force,
        backend,
    } = args;
    let backend = *backend;
    let (robot, config) = (&shipped::input(robot), &shipped::input(config));
    // Refused before the solve, not after it.
    writable(out, *force)?;
    let text =
        std::fs::read_to_string(robot).with_context(|| format!("reading {}", robot.display()))?;
    let model = PlanarModel::from_urdf_str(&text, &robot.display().to_string())?;
    let mut cfg = planner::config::PlannerConfig::load(config)?;
    if let Some(backend) = backend {
        cfg.solver.backend = backend;
    }
    let urdf_ref = relative_path(robot, out);
    let planned =
        planner::plan::plan_gait(&model, &urdf_ref, &text, &cfg, &mut progress_printer())?;
    planned.gait.save(out)?;
    let g = &planned.gait;
    println!("\n{}", PlanSummary::of(&planned));
    println!("wrote {}", out.display());
    let report =
        planner::verify::verify_gait(&model, g, planner::verify::VerifyOptions::default())?;
    let failures = report.failures(planner::verify::VerifyOptions::default().fixed_point_tolerance);
    println!("{}", OrbitCheck::of(&report, failures));
    Ok(())
}

/// `adam gait check`: prints the verification report; fails naming what failed.
pub(crate) fn gait_check(path: &std::path::Path, epsilon: f64) -> Result<()> {
    let path = &shipped::input(path);
    let (gait, robot) = planner::verify::load_gait_and_robot(path)?;
    let options = planner::verify::VerifyOptions {
        epsilon_per_s: epsilon,
        ..Default::default()
    };
    let report = planner::verify::verify_gait(&robot, &gait, options)
        .with_context(|| format!("{} fails its check", path.display()))?;
    println!(
        "gait {} (planned: {:.4} m in {:.4} s)",
        path.display(),
        gait.step_length_m,
        gait.step_duration_s
    );
    print!("{report}");
    let failed = report.failures(options.fixed_point_tolerance);
    if !failed.is_empty() {
        bail!("{} fails its check: {}", path.display(), failed.join("; "));
    }
    println!("stable periodic orbit");
    Ok(())
}
