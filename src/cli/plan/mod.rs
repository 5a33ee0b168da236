//! `adam plan` and `adam gait check`: the HZD gait planned with live progress and a summary
//! table, and a gait file verified on its own (Newton on the Poincaré map, eigenvalues);
//! `adam plan library` (in `library`): a gait per speed, written as one library file.

pub(crate) mod library;
mod report;

pub(crate) use report::{CommandTimes, GaitFigures, PhaseSeconds};

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
        /// Also walk the gait under this runtime config's joint PD (its gains, its scale of the
        /// plan's feed-forward, its reference lead) with references `--latency-s` late, and
        /// print the speed it settles at: what the robot walks, not the plan.
        #[arg(long)]
        runtime: Option<PathBuf>,
        /// Sample-to-action latency of the joint commands, s (with `--runtime`): 3 ms makes
        /// the prediction match the simulated robot's walked speeds (docs/planning.md).
        #[arg(long, default_value_t = DEFAULT_LATENCY_S, requires = "runtime")]
        latency_s: f64,
    },
}

/// `adam gait check --latency-s` by default, s: the simulated bus applies a command about
/// 2.5 ms after the sample it was computed from (one period on the wire, then the period it
/// acts over), and the pitch estimate lags a little more; fitted to the simulator's walked
/// speeds (docs/planning.md, "The gait under the runtime's controller").
pub(crate) const DEFAULT_LATENCY_S: f64 = 0.003;

/// Steps walked by `adam gait check --runtime`, and how many of the last are measured.
const RUNTIME_WALK_STEPS: (usize, usize) = (30, 10);

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

/// `adam plan`: plans the gait, writes it, prints the summary, its verification and the
/// command's time by phase.
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
    let (times, _) = plan_command(robot, config, out, *force, *backend, true)?;
    println!("{times}");
    Ok(())
}

/// The CPU time of this process so far (all its threads, and its waited-for children), s,
/// from `/proc/self/stat` (Linux; in USER_HZ = 100 ticks per second, so to 10 ms); `None`
/// where that file is missing or unreadable.
pub(crate) fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name in parentheses: state is field 3, utime 14, stime 15,
    // cutime 16, cstime 17.
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields
        .get(11..15)?
        .iter()
        .map(|f| f.parse::<f64>().ok())
        .sum::<Option<f64>>()?;
    Some(ticks / 100.0)
}

/// The whole of `adam plan` as a user runs it (read the robot and config, plan with both solves
/// and the feed-forward table, write the gait file, verify it like `adam gait check`), printing
/// progress and reports if `verbose`; returns its time by phase and the plan.
pub(crate) fn plan_command(
    robot: &std::path::Path,
    config: &std::path::Path,
    out: &std::path::Path,
    force: bool,
    backend: Option<planner::config::SolverBackend>,
    verbose: bool,
) -> Result<(CommandTimes, planner::plan::PlannedGait)> {
    let start = std::time::Instant::now();
    let cpu_start = process_cpu_s();
    let (robot, config) = (&shipped::input(robot), &shipped::input(config));
    // Refused before the solve, not after it.
    writable(out, force)?;
    let text =
        std::fs::read_to_string(robot).with_context(|| format!("reading {}", robot.display()))?;
    let model = PlanarModel::from_urdf_str(&text, &robot.display().to_string())?;
    let mut cfg = planner::config::PlannerConfig::load(config)?;
    if let Some(backend) = backend {
        cfg.solver.backend = backend;
    }
    let urdf_ref = relative_path(robot, out);
    let load_s = start.elapsed().as_secs_f64();
    let mut printer = progress_printer();
    let mut quiet = |_: planner::plan::Progress<'_>| {};
    let progress: &mut dyn FnMut(planner::plan::Progress<'_>) =
        if verbose { &mut printer } else { &mut quiet };
    let (planned, plan_times) =
        planner::plan::plan_gait_timed(&model, &urdf_ref, &text, &cfg, progress)?;
    let writing = std::time::Instant::now();
    planned.gait.save(out)?;
    let write_s = writing.elapsed().as_secs_f64() + plan_times.gait_s;
    let g = &planned.gait;
    if verbose {
        println!("\n{}", PlanSummary::of(&planned));
        println!("wrote {}", out.display());
    }
    let checking = std::time::Instant::now();
    let options = planner::verify::VerifyOptions::default();
    let report = planner::verify::verify_gait(&model, g, options)?;
    let mut failures = report.failures(options.fixed_point_tolerance);
    failures.extend(report.accuracy_failures());
    let verify_s = checking.elapsed().as_secs_f64();
    if verbose {
        println!("{}", OrbitCheck::of(&report, failures));
    }
    let times = CommandTimes {
        load_s,
        problems_s: plan_times.problems_s,
        feasibility_s: plan_times.feasibility_s,
        cost_s: plan_times.cost_s,
        feedforward_s: plan_times.feedforward_s,
        write_s,
        verify_s,
        total_s: start.elapsed().as_secs_f64(),
        cpu_s: cpu_start.zip(process_cpu_s()).map(|(a, b)| b - a),
    };
    Ok((times, planned))
}

/// `adam gait check`: prints the verification report; fails naming what failed.
pub(crate) fn gait_check(
    path: &std::path::Path,
    epsilon: f64,
    runtime: Option<&std::path::Path>,
    latency_s: f64,
) -> Result<()> {
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
    let mut failed = report.failures(options.fixed_point_tolerance);
    failed.extend(report.accuracy_failures());
    if !failed.is_empty() {
        bail!("{} fails its check: {}", path.display(), failed.join("; "));
    }
    println!("stable periodic orbit");
    if let Some(config) = runtime {
        walk_under_runtime(&robot, &gait, config, latency_s)?;
    }
    Ok(())
}

/// `adam gait check --runtime CONFIG`: walks the gait from its planned post-impact state under
/// the config's joint PD with the plan's feed-forward (times its scale), the references
/// `latency_s` less the config's lead late ([`planner::verify::Law::JointPd`]), and prints the
/// speed of the last steps. Informational: a gait that does not keep walking is reported, not
/// failed (the check above is about the plan).
fn walk_under_runtime(
    robot: &PlanarModel,
    gait: &model::gait::GaitFile,
    config_path: &std::path::Path,
    latency_s: f64,
) -> Result<()> {
    if !(latency_s.is_finite() && latency_s >= 0.0) {
        bail!("--latency-s = {latency_s}: must be finite and at least 0");
    }
    let config = runtime::config::RuntimeConfig::load(config_path)?;
    let g = &config.gains;
    let same = |v: &[f64; 4], field: &str| -> Result<f64> {
        if v.iter().all(|&x| x == v[0]) {
            Ok(v[0])
        } else {
            bail!(
                "{}: gains.{field} = {v:?}: `adam gait check --runtime` walks one gain for every \
                 joint",
                config_path.display()
            )
        }
    };
    let kp = same(&g.kp_nm_per_rad, "kp_nm_per_rad")?;
    let kd = same(&g.kd_nm_s_per_rad, "kd_nm_s_per_rad")?;
    let scale = g.plan_feedforward_scale;
    let lead_s = config.walk.reference_lead_s;
    let delay_s = (latency_s - lead_s).max(0.0);
    let law = planner::verify::Law::runtime_pd(gait, kp, kd, scale, delay_s);
    let cl = planner::verify::ClosedLoop::new(robot, gait, Default::default())?.with_law(law);
    let x0 = cl.planned_state(gait, "walk from")?;
    println!(
        "under the joint PD of {} ({kp} N·m/rad, {kd} N·m·s/rad, the plan's feed-forward ×{scale}), \
         references {:.1} ms late (latency {:.1} ms, lead {:.1} ms):",
        config_path.display(),
        1e3 * delay_s,
        1e3 * latency_s,
        1e3 * lead_s
    );
    let (steps, measured) = RUNTIME_WALK_STEPS;
    match cl.walk(&x0, steps, measured) {
        Ok(w) => {
            let plan = gait.step_length_m / gait.step_duration_s;
            println!(
                "  steps {}–{steps} from the planned x⁺: {:.4} m in {:.4} s, {:.4} m/s ({:.1} % of \
                 the plan's {plan:.4} m/s)",
                steps - measured + 1,
                w.length_m,
                w.duration_s,
                w.speed_mps(),
                100.0 * w.speed_mps() / plan
            );
        }
        Err(e) => println!("  the robot does not keep walking: {e}"),
    }
    Ok(())
}
