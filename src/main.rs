//! `adam`: the command-line entry point of adam-hzd. It only parses arguments and calls
//! library functions in `model`, `planner`, `drivers` and `runtime`.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use model::design::{generate_urdf, DesignLengths};
use model::PlanarModel;
use std::path::PathBuf;

mod plots;

#[derive(Parser)]
#[command(
    name = "adam",
    version,
    about = "HZD co-design and walking for the ADAM humanoid"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Walk the shipped gait for 30 s on the simulated treadmill through the CAN codec path,
    /// log to `logs/<timestamp>.mcap`, print a summary.
    Demo,
    /// Walk a gait with the real-time runtime on the simulated robot or on the robot over CAN.
    Run {
        /// Where to walk.
        #[arg(long, value_enum)]
        backend: Backend,
        /// Gait file (JSON); default: the co-designed ADAM's.
        #[arg(long, default_value = runtime::DEFAULT_GAIT)]
        gait: PathBuf,
        /// Runtime config (TOML).
        #[arg(long, default_value = "configs/runtime/adam.toml")]
        config: PathBuf,
        /// Run time, e.g. `30s`, `1500ms` or `30` (seconds).
        #[arg(long, default_value = "30s", value_parser = parse_duration_s)]
        duration: f64,
        /// Treadmill belt speed, m/s (sim; default: the gait's speed).
        #[arg(long)]
        belt: Option<f64>,
        /// MCAP log file (sim; default: no log).
        #[arg(long)]
        log: Option<PathBuf>,
        /// Seed of the simulated IMU and encoder noise (sim).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Pace the simulated run by the wall clock at the loop rate and report the loop's
        /// wake-up jitter (sim; default: as fast as the CPU allows). A wall-clock run listens
        /// for operator commands over iceoryx2 (`adam op`).
        #[arg(long)]
        real_time: bool,
        /// Read operator commands from the keyboard, one per line (s start, w walk, p stop,
        /// d damp, r reset, e e-stop); with --real-time.
        #[arg(long, requires = "real_time")]
        keyboard: bool,
        /// CAN interfaces, one per bus of the config (can; default can0,can1,…).
        #[arg(long, value_delimiter = ',')]
        can_interfaces: Option<Vec<String>>,
        /// Inject faults (sim): a profile name (none, loss-0.1, loss-1, loss-10, corrupt-1,
        /// delay-1, soak, rough) or a TOML file; seeded by --seed.
        #[arg(long)]
        faults: Option<String>,
    },
    /// Walk the simulated robot for a long time under random faults; after each trip reset and
    /// walk on. Prints ticks, overruns, trips by reason, log drops, worst tick, distance.
    Soak {
        /// Simulated minutes to walk (fractions allowed).
        #[arg(long)]
        minutes: f64,
        /// Fault profile: none, loss-0.1, loss-1, loss-10, corrupt-1, delay-1, soak, rough,
        /// or a TOML file.
        #[arg(long, default_value = "soak")]
        faults: String,
        /// Seed of the faults and the sensor noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Keep each episode's MCAP log in this folder (default: a temporary log, removed).
        #[arg(long)]
        log_dir: Option<PathBuf>,
        /// Gait file (JSON); default: the co-designed ADAM's.
        #[arg(long, default_value = runtime::DEFAULT_GAIT)]
        gait: PathBuf,
        /// Runtime config (TOML).
        #[arg(long, default_value = "configs/runtime/adam.toml")]
        config: PathBuf,
    },
    /// Figures from run logs: `adam plot portrait <run.mcap> [--compare <other.mcap>]`,
    /// `adam plot tiles <run.mcap>`.
    Plot {
        #[command(subcommand)]
        what: PlotWhat,
    },
    /// Benchmarks that print a table (medians over repeated runs).
    Bench {
        #[command(subcommand)]
        what: BenchWhat,
    },
    /// Send an operator command to a running `adam run` over iceoryx2.
    Op {
        /// start, walk, stop, damp, reset or estop.
        command: String,
        /// Runtime config (its telemetry service name locates the runtime).
        #[arg(long, default_value = "configs/runtime/adam.toml")]
        config: PathBuf,
    },
    /// Print a robot model: bodies, joints, total mass, leg lengths and D(q) at the nominal pose.
    Model {
        /// URDF file.
        urdf: PathBuf,
        /// Set the design virtual joints to these total lengths, e.g. `thigh=0.24,shin=0.25`.
        #[arg(long)]
        design: Option<String>,
    },
    /// Co-design the thigh and shin lengths with the gait (paper Sec. III): write the
    /// co-designed URDF and its gait file, verified like `adam gait check`.
    Codesign {
        /// Planner config (TOML) with its `[codesign]` section.
        #[arg(long, default_value = "configs/planner/adam.toml")]
        config: PathBuf,
        /// Inertia coupling, overriding the config: `exact` (inside the NLP) or `alg1`
        /// (the paper's Alg. 1: frozen per solve, regenerated between solves).
        #[arg(long, value_enum)]
        inertia: Option<InertiaArg>,
        /// Output gait file.
        #[arg(long, default_value = "configs/gaits/adam_codesign.json")]
        out_gait: PathBuf,
        /// Output URDF of the co-designed robot.
        #[arg(long, default_value = "configs/robots/adam_codesign.urdf")]
        out_urdf: PathBuf,
        /// `sweep`: the convergence study instead of one co-design.
        #[command(subcommand)]
        study: Option<CodesignStudy>,
    },
    /// Plan a periodic HZD walking gait (the paper's two-step solve) and write the gait file.
    Plan {
        /// Robot URDF.
        #[arg(long, default_value = "configs/robots/adam_planar.urdf")]
        robot: PathBuf,
        /// Planner config (TOML).
        #[arg(long, default_value = "configs/planner/adam.toml")]
        config: PathBuf,
        /// Output gait file (JSON).
        #[arg(long, default_value = "configs/gaits/adam_walk.json")]
        out: PathBuf,
        /// NLP backend, overriding the config's `[solver] backend`: `ripopt` or `native`.
        #[arg(long, value_parser = parse_backend)]
        backend: Option<planner::config::SolverBackend>,
    },
    /// Gait files: `adam gait check <gait.json>` verifies a gait independently of the optimizer.
    Gait {
        #[command(subcommand)]
        command: GaitCommand,
    },
    /// MCAP logs: `adam logs info <run.mcap>`, `adam logs recover <in.mcap> [--out <out.mcap>]`.
    Logs {
        #[command(subcommand)]
        command: LogsCommand,
    },
    /// Replay a log through this build's controller and compare every command with the logged
    /// one: bit-identical, or the first divergence (exit code 1). `--mint <dir>` instead records
    /// the replay fixtures (`tests/fixtures`) anew.
    Replay {
        /// The log(s) to replay.
        #[arg(required_unless_present = "mint")]
        logs: Vec<PathBuf>,
        /// Record the replay fixtures into this folder (after an intended controller change).
        #[arg(long, conflicts_with = "logs")]
        mint: Option<PathBuf>,
    },
    /// Write the URDF of ADAM for a design (GenerateModel: inertias from the cubic fits).
    GenerateUrdf {
        /// Thigh length, m.
        #[arg(long, default_value_t = model::design::ADAM_THIGH_M)]
        thigh: f64,
        /// Shin length, m.
        #[arg(long, default_value_t = model::design::ADAM_SHIN_M)]
        shin: f64,
        /// Output file (stdout if absent).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum GaitCommand {
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

#[derive(Subcommand)]
enum LogsCommand {
    /// Channels, message counts, duration, drops, safety trips, gait and design of a log.
    Info {
        /// The log.
        log: PathBuf,
    },
    /// Rewrite a log cut off by a crash with summary and indexes: every message up to the last
    /// complete chunk.
    Recover {
        /// The cut-off log.
        log: PathBuf,
        /// Output (default: `<log stem>.recovered.mcap` beside the input).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

/// Backend of `adam run`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Backend {
    /// The simulated ADAM on a treadmill behind the simulated A1 firmware and CAN codec.
    Sim,
    /// The robot over SocketCAN.
    Can,
}

/// Parses `30s`, `1500ms` or `30` into seconds.
fn parse_duration_s(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let (number, scale) = if let Some(ms) = t.strip_suffix("ms") {
        (ms, 1e-3)
    } else if let Some(s) = t.strip_suffix('s') {
        (s, 1.0)
    } else {
        (t, 1.0)
    };
    let v: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a duration (expected e.g. 30s, 1500ms)"))?;
    let seconds = v * scale;
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!("'{text}': the duration must be positive"));
    }
    Ok(seconds)
}

/// `logs/<UTC timestamp>.mcap`, e.g. `logs/20250101-120000.mcap`.
fn timestamped_log_path() -> PathBuf {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    PathBuf::from(format!(
        "logs/{year:04}{month:02}{day:02}-{:02}{:02}{:02}.mcap",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    ))
}

/// Walk in simulation and print the report.
/// A wall-clock simulated run that takes operator commands over iceoryx2 and, if asked, from
/// the keyboard.
fn sim_walk_operated(
    setup: &runtime::Setup,
    options: &runtime::sim_run::SimWalkOptions,
    keyboard: bool,
) -> Result<()> {
    use runtime::operator::{self, SharedHandle};
    let (handle, receiver) = operator::channel(64);
    let shared = SharedHandle::new(handle);
    let service = operator::operator_service_name(&setup.config.telemetry.service_name);
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let forwarder = operator::spawn_iceoryx2_forwarder(&service, shared.clone(), stop.clone())?;
    println!("operator commands: `adam op <command>` (iceoryx2 service {service})");
    if keyboard {
        println!("{}", operator::KEY_HELP);
        // The thread ends with stdin; it is not joined (a blocked read must not hold the exit).
        operator::spawn_keyboard(std::io::BufReader::new(std::io::stdin()), shared);
    }
    let report = runtime::sim_run::walk_with_operator(setup, options, Some(receiver));
    stop.store(true, std::sync::atomic::Ordering::Release);
    let _ = forwarder.join();
    let report = report?;
    println!("{report}");
    if let Some((t, what)) = report.fall {
        bail!("the robot fell ({what:?}) at {t:.3} s");
    }
    Ok(())
}

fn sim_walk(setup: &runtime::Setup, options: &runtime::sim_run::SimWalkOptions) -> Result<()> {
    if let Some(dir) = options.log_path.as_ref().and_then(|p| p.parent()) {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
    }
    let report = runtime::sim_run::walk(setup, options)?;
    println!("{report}");
    if let (Some(path), Some(log)) = (&options.log_path, &report.summary.log) {
        println!("log: {} ({log:?})", path.display());
    }
    if let Some((t_s, what)) = report.fall {
        bail!("the robot fell ({what:?}) at {t_s:.3} s");
    }
    Ok(())
}

/// Parses `thigh=0.24,shin=0.25`.
fn parse_design(text: &str) -> Result<DesignLengths> {
    let (mut thigh, mut shin) = (None, None);
    for part in text.split(',') {
        let (key, value) = part.split_once('=').with_context(|| {
            format!("--design: '{part}' is not key=value (expected thigh=0.24,shin=0.25)")
        })?;
        let v: f64 = value
            .trim()
            .parse()
            .with_context(|| format!("--design: {key} = '{value}' is not a number"))?;
        if !v.is_finite() || v <= 0.0 {
            bail!("--design: {key} = {v} must be a positive length in metres");
        }
        match key.trim() {
            "thigh" => thigh = Some(v),
            "shin" => shin = Some(v),
            other => bail!("--design: unknown key '{other}' (expected thigh and shin)"),
        }
    }
    match (thigh, shin) {
        (Some(thigh_length_m), Some(shin_length_m)) => Ok(DesignLengths {
            thigh_length_m,
            shin_length_m,
        }),
        _ => bail!("--design needs both thigh and shin, e.g. thigh=0.24,shin=0.25"),
    }
}

fn show_model(urdf: &PathBuf, design: Option<&str>) -> Result<()> {
    let robot = PlanarModel::from_urdf_file(urdf)?;
    let mut q = robot.nominal_pose()?;
    if let Some(text) = design {
        let d = parse_design(text)?;
        q = robot.with_design(&q, d.thigh_length_m, d.shin_length_m)?;
        for j in robot.design_joints() {
            let joint = &robot.joints[j];
            let v = q[joint.coordinate];
            if v < joint.lower - 1e-12 || v > joint.upper + 1e-12 {
                bail!(
                    "--design {text}: design joint '{}' would be {v:.4} m, outside its limits [{:.4}, {:.4}] m",
                    joint.name,
                    joint.lower,
                    joint.upper
                );
            }
        }
        // Re-place the feet on the ground for the new lengths.
        let legs = robot.legs()?;
        let lf = robot.frame_position(&q, legs.left.foot)?;
        q[1] -= lf[1];
        println!("design joints set for thigh {} m, shin {} m (link inertias as in the URDF; `adam generate-urdf` regenerates them)\n", d.thigh_length_m, d.shin_length_m);
    }
    print!("{}", robot.summary(&q)?);
    Ok(())
}

#[derive(Subcommand)]
enum PlotWhat {
    /// Phase portraits (q vs q̇) of the hips and knees, like the paper's Fig. 4, as PNG and SVG.
    Portrait {
        /// The run.
        log: PathBuf,
        /// A second run to overlay (e.g. another gait, seed or the hardware).
        #[arg(long)]
        compare: Option<PathBuf>,
        /// Output prefix (default: the log's path without extension, + `-portrait`).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Gait tiles, like the paper's Fig. 5: stick figures at evenly spaced phases of one step
    /// of a logged walk, as PNG and SVG.
    Tiles {
        /// The run (a walk of at least two steps).
        log: PathBuf,
        /// Number of figures (phases 0, 1/(n−1), …, 1).
        #[arg(long, default_value_t = 8)]
        count: usize,
        /// Output prefix (default: the log's path without extension, + `-tiles`).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum BenchWhat {
    /// Plan the default ADAM gait `--runs` times (fresh problem each time): set-up, iterations
    /// and solve time per stage, and the median.
    Plan {
        /// Number of plans.
        #[arg(long, default_value_t = 3)]
        runs: usize,
        /// Robot.
        #[arg(long, default_value = "configs/robots/adam_planar.urdf")]
        robot: PathBuf,
        /// Planner config.
        #[arg(long, default_value = "configs/planner/adam.toml")]
        config: PathBuf,
        /// NLP backend, overriding the config's `[solver] backend`: `ripopt` or `native`.
        #[arg(long, value_parser = parse_backend)]
        backend: Option<planner::config::SolverBackend>,
    },
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
}

fn bench_check(runs: usize, gait_path: &std::path::Path) -> Result<()> {
    if runs == 0 {
        bail!("--runs must be at least 1");
    }
    let (gait, robot) = planner::verify::load_gait_and_robot(gait_path)?;
    let options = planner::verify::VerifyOptions::default();
    println!(
        "{:>3} {:>8} {:>7} {:>12} {:>10}",
        "run", "wall s", "newton", "residual", "|λ|max"
    );
    let mut times = Vec::with_capacity(runs);
    let mut first: Option<planner::verify::VerifyReport> = None;
    let mut identical = true;
    for run in 1..=runs {
        let t0 = std::time::Instant::now();
        let r = planner::verify::verify_gait(&robot, &gait, options)?;
        let wall = t0.elapsed().as_secs_f64();
        println!(
            "{run:>3} {wall:>8.3} {:>7} {:>12.3e} {:>10.6}",
            r.newton_iterations, r.fixed_point_residual, r.spectral_radius
        );
        times.push(wall);
        match &first {
            None => first = Some(r),
            Some(f) => identical &= *f == r,
        }
    }
    times.sort_by(f64::total_cmp);
    println!(
        "\n{}: median {:.2} s over {runs} checks; the reports are {}",
        gait_path.display(),
        times[runs / 2],
        if identical {
            "identical"
        } else {
            "NOT identical"
        }
    );
    Ok(())
}

/// `--backend ripopt|native`.
fn parse_backend(text: &str) -> std::result::Result<planner::config::SolverBackend, String> {
    match text {
        "ripopt" => Ok(planner::config::SolverBackend::Ripopt),
        "native" => Ok(planner::config::SolverBackend::Native),
        other => Err(format!(
            "unknown backend `{other}`: expected `ripopt` or `native`"
        )),
    }
}

fn bench_plan(
    runs: usize,
    robot: &PathBuf,
    config: &PathBuf,
    backend: Option<planner::config::SolverBackend>,
) -> Result<()> {
    if runs == 0 {
        bail!("--runs must be at least 1");
    }
    let text =
        std::fs::read_to_string(robot).with_context(|| format!("reading {}", robot.display()))?;
    let model = PlanarModel::from_urdf_str(&text, &robot.display().to_string())?;
    let mut cfg = planner::config::PlannerConfig::load(config)?;
    if let Some(backend) = backend {
        cfg.solver.backend = backend;
    }
    println!(
        "{:>3} {:>9} {:>10} {:>11} {:>10} {:>11} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "run",
        "set-up s",
        "feas. iter",
        "feas. solve",
        "cost iter",
        "cost solve",
        "eval",
        "factor",
        "kkt sol",
        "other",
        "total s"
    );
    let mut phases = Vec::with_capacity(runs);
    let mut totals = Vec::with_capacity(runs);
    let mut iterations = Vec::with_capacity(runs);
    let mut size = (0, 0);
    let mut first_x: Option<Vec<f64>> = None;
    let mut identical = true;
    for run in 1..=runs {
        let t0 = std::time::Instant::now();
        let p = planner::plan::plan_gait(&model, "robot.urdf", &text, &cfg, &mut |_| {})?;
        let total = t0.elapsed().as_secs_f64();
        let (f, c) = (&p.stages[0], &p.stages[1]);
        let phase = PhaseSeconds::of_plan(&p.stages);
        println!(
            "{:>3} {:>9.3} {:>10} {:>10.3}s {:>10} {:>10.3}s {:>8.3} {} {:>8.3}",
            run,
            p.setup_time_s,
            f.iterations,
            f.solve_time_s,
            c.iterations,
            c.solve_time_s,
            phase.evaluation,
            phase.columns(),
            total
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
    totals.sort_by(f64::total_cmp);
    iterations.sort_unstable();
    println!(
        "\nADAM, {} variables, {} constraints, {:?} backend: median {:.2} s and {} iterations over \
         {runs} plan{} (set-up, both solves and the feed-forward table); {}",
        size.0,
        size.1,
        cfg.solver.backend,
        totals[runs / 2],
        iterations[runs / 2],
        if runs == 1 { "" } else { "s" },
        match (runs, identical) {
            (1, _) => "one run, no solutions to compare",
            (_, true) => "the solutions are bit-identical",
            (_, false) => "the solutions are NOT bit-identical",
        }
    );
    // Each phase's median over the runs (so they need not add up to the median total).
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[runs / 2]
    };
    let mut evaluation: Vec<f64> = phases.iter().map(|p| p.evaluation).collect();
    let backend: Option<Vec<[f64; 3]>> = phases.iter().map(PhaseSeconds::split).collect();
    let split = match backend {
        Some(b) => {
            let column = |k: usize| median(&mut b.iter().map(|p| p[k]).collect());
            format!(
                "factorizations {:.3} s, solves with the factors {:.3} s, other {:.3} s",
                column(0),
                column(1),
                column(2)
            )
        }
        None => "the backend's own time is not split (ripopt does not time its phases)".into(),
    };
    println!(
        "time by phase (medians): problem evaluation {:.3} s, {split}",
        median(&mut evaluation)
    );
    println!(
        "anchors: CasADi + IPOPT + MUMPS on the same kind of problem (PLANNER-NOTES) 1.19 s solve \
         + 1.96 s set-up; a published five-link optimization (571 variables) 143 IPOPT iterations, ~12 s in MATLAB"
    );
    Ok(())
}

#[derive(Subcommand)]
enum CodesignStudy {
    /// The paper's convergence study: co-design from an n × n grid of initial thigh and shin
    /// lengths over the config's bounds, in parallel on all cores; writes sweep.csv, table.md
    /// (like the paper's Table II) and convergence.png/.svg (like its Fig. 3).
    Sweep {
        /// Grid size n (n × n runs).
        #[arg(long, default_value_t = 5)]
        grid: usize,
        /// Output folder.
        #[arg(long, default_value = "logs/codesign-sweep")]
        out_dir: PathBuf,
    },
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum InertiaArg {
    Exact,
    Alg1,
}

/// The planner config with the CLI's inertia coupling, if given.
fn codesign_config(
    config: &PathBuf,
    inertia: Option<InertiaArg>,
) -> Result<planner::config::PlannerConfig> {
    let mut cfg = planner::config::PlannerConfig::load(config)?;
    if let Some(i) = inertia {
        cfg.codesign.inertia = match i {
            InertiaArg::Exact => planner::config::InertiaCoupling::Exact,
            InertiaArg::Alg1 => planner::config::InertiaCoupling::Alg1,
        };
    }
    Ok(cfg)
}

fn progress_printer() -> impl FnMut(planner::plan::Progress<'_>) {
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

fn codesign(
    config: &PathBuf,
    inertia: Option<InertiaArg>,
    out_gait: &PathBuf,
    out_urdf: &PathBuf,
) -> Result<()> {
    let cfg = codesign_config(config, inertia)?;
    for path in [out_gait, out_urdf] {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
    }
    let urdf_ref = relative_path(out_urdf, out_gait);
    let r = planner::codesign::codesign(&cfg, &urdf_ref, &mut progress_printer())?;
    std::fs::write(out_urdf, &r.urdf).with_context(|| format!("writing {}", out_urdf.display()))?;
    r.planned.gait.save(out_gait)?;
    println!(
        "\nco-design ({:?} inertia coupling), {:.1} s in all",
        cfg.codesign.inertia, r.wall_time_s
    );
    println!(
        "{:>5} {:>16} {:>16} {:>8} {:>6} {:>9}",
        "outer", "start thigh/shin", "found thigh/shin", "CoT", "iter", "solve s"
    );
    for (j, o) in r.outer.iter().enumerate() {
        println!(
            "{:>5} {:>7.4}/{:<8.4} {:>7.4}/{:<8.4} {:>8.5} {:>6} {:>9.2}",
            j + 1,
            o.start_m[0],
            o.start_m[1],
            o.lengths_m[0],
            o.lengths_m[1],
            o.cost_of_transport,
            o.report.iterations,
            o.report.solve_time_s
        );
    }
    let (g0, g) = (&r.initial.gait, &r.planned.gait);
    println!(
        "\n{:<22} {:>8} {:>8} {:>9} {:>9} {:>9} {:>8}",
        "design", "thigh m", "shin m", "step m", "period s", "speed m/s", "CoT"
    );
    for (name, gg) in [("initial (fixed)", g0), ("co-designed", g)] {
        println!(
            "{:<22} {:>8.4} {:>8.4} {:>9.4} {:>9.4} {:>9.4} {:>8.5}",
            name,
            gg.design.thigh_length_m,
            gg.design.shin_length_m,
            gg.step_length_m,
            gg.step_duration_s,
            gg.speed_mps,
            gg.cost_of_transport
        );
    }
    if !r.converged {
        println!("warning: the outer loop stopped at its iteration limit before ‖ΔL‖ < δ");
    }
    // Gaits optimized at fixed designs, for comparison: the four corners of the design box and
    // the paper's optimum, each warm-started from the initial design's gait.
    let c = &cfg.codesign;
    let fixed = [
        ("box corner", [c.thigh_m[0], c.shin_m[0]]),
        ("box corner", [c.thigh_m[0], c.shin_m[1]]),
        ("box corner", [c.thigh_m[1], c.shin_m[0]]),
        ("box corner", [c.thigh_m[1], c.shin_m[1]]),
        ("paper's optimum", [0.2425, 0.2515]),
    ];
    let designs: Vec<[f64; 2]> = fixed.iter().map(|f| f.1).collect();
    println!("\noptimizing the gait at fixed designs for comparison ...");
    let outcomes = planner::codesign::compare_fixed_designs(&cfg, &r.initial, &designs);
    for ((name, d), o) in fixed.iter().zip(&outcomes) {
        match o {
            Ok(o) => println!(
                "{:<22} {:>8.4} {:>8.4} {:>9.4} {:>9.4} {:>9.4} {:>8.5}",
                name,
                d[0],
                d[1],
                o.step_length_m,
                o.step_duration_s,
                o.speed_mps,
                o.cost_of_transport
            ),
            Err(e) => println!("{:<22} {:>8.4} {:>8.4} failed: {e}", name, d[0], d[1]),
        }
    }
    println!("wrote {} and {}", out_gait.display(), out_urdf.display());
    gait_check(out_gait, 10.0)
}

/// Relative cost of transport above the best run that marks a worse local minimum.
const LOCAL_MINIMUM_MARGIN: f64 = 0.01;

fn codesign_sweep(
    config: &PathBuf,
    inertia: Option<InertiaArg>,
    grid: usize,
    out_dir: &PathBuf,
) -> Result<()> {
    use planner::codesign::{local_minima, mean_std, sweep, sweep_grid};
    if !(1..=20).contains(&grid) {
        bail!("--grid {grid}: must be in 1..=20");
    }
    let cfg = codesign_config(config, inertia)?;
    std::fs::create_dir_all(out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let start = std::time::Instant::now();
    let model_lengths = cfg.codesign.initial_m;
    let (model, urdf) = model::design::generate_model(&DesignLengths {
        thigh_length_m: model_lengths[0],
        shin_length_m: model_lengths[1],
    })?;
    println!(
        "warm start: planning the gait at thigh {} m, shin {} m",
        model_lengths[0], model_lengths[1]
    );
    let initial = planner::plan::plan_gait(&model, "robot.urdf", &urdf, &cfg, &mut |_| {})?;
    let warm_s = start.elapsed().as_secs_f64();
    let starts = sweep_grid(&cfg, grid);
    let bar = indicatif::ProgressBar::new(starts.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} runs, {elapsed} elapsed, ETA {eta} {msg}",
        )
        .map_err(|e| anyhow::anyhow!("{e}"))?,
    );
    let runs = sweep(&cfg, &initial, model_lengths, &starts, &|r| {
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
    let minima = local_minima(&runs, LOCAL_MINIMUM_MARGIN);
    // CSV of every run.
    let mut csv = String::from("initial_thigh_m,initial_shin_m,status,thigh_m,shin_m,step_length_m,step_duration_s,speed_mps,cost_of_transport,iterations,solve_time_s,wall_time_s,local_minimum\n");
    for (r, &lm) in runs.iter().zip(&minima) {
        match &r.outcome {
            Ok(o) => {
                csv += &format!(
                    "{},{},ok,{},{},{},{},{},{},{},{},{},{}\n",
                    r.initial_m[0],
                    r.initial_m[1],
                    o.lengths_m[0],
                    o.lengths_m[1],
                    o.step_length_m,
                    o.step_duration_s,
                    o.speed_mps,
                    o.cost_of_transport,
                    o.iterations,
                    o.solve_time_s,
                    r.wall_time_s,
                    lm
                )
            }
            Err(e) => {
                csv += &format!(
                    "{},{},\"failed: {}\",,,,,,,,,{},\n",
                    r.initial_m[0],
                    r.initial_m[1],
                    e.replace('"', "'"),
                    r.wall_time_s
                )
            }
        }
    }
    std::fs::write(out_dir.join("sweep.csv"), csv)?;
    // Table II: mean ± std over the runs that are not local minima.
    let good: Vec<&planner::codesign::SweepOutcome> = runs
        .iter()
        .zip(&minima)
        .filter(|(_, &lm)| !lm)
        .filter_map(|(r, _)| r.outcome.as_ref().ok())
        .collect();
    let col = |f: fn(&planner::codesign::SweepOutcome) -> f64| {
        mean_std(&good.iter().map(|o| f(o)).collect::<Vec<_>>())
    };
    let rows = [
        ("thigh length (m)", col(|o| o.lengths_m[0]), "0.2425"),
        ("shin length (m)", col(|o| o.lengths_m[1]), "0.2515"),
        ("step length (m)", col(|o| o.step_length_m), "—"),
        ("step duration (s)", col(|o| o.step_duration_s), "—"),
        ("speed (m/s)", col(|o| o.speed_mps), "—"),
        ("cost of transport", col(|o| o.cost_of_transport), "—"),
        ("solve time (s)", col(|o| o.solve_time_s), "—"),
    ];
    let failed = runs.iter().filter(|r| r.outcome.is_err()).count();
    let n_minima = minima.iter().filter(|&&m| m).count();
    let mut md = format!(
        "# Co-design convergence study\n\n{} runs from a {grid}×{grid} grid of initial thigh/shin lengths over [{}, {}] × [{}, {}] m, {:?} inertia coupling; warm start planned at {}/{} m in {:.1} s; {:.1} s wall time in all on {} threads.\n\n{} runs converged to the best design, {} ended in a worse local minimum (cost of transport more than {:.0} % above the best), {} failed.\n\n| quantity | mean | std | paper |\n|---|---|---|---|\n",
        runs.len(), cfg.codesign.thigh_m[0], cfg.codesign.thigh_m[1], cfg.codesign.shin_m[0],
        cfg.codesign.shin_m[1], cfg.codesign.inertia, model_lengths[0], model_lengths[1], warm_s,
        wall_s, rayon_threads(), good.len(), n_minima, LOCAL_MINIMUM_MARGIN * 100.0, failed
    );
    for (name, (m, sd), paper) in rows {
        md += &format!("| {name} | {m:.4} | {sd:.4} | {paper} |\n");
    }
    std::fs::write(out_dir.join("table.md"), &md)?;
    print!("\n{md}");
    let arrows: Vec<plots::ConvergenceArrow> = runs
        .iter()
        .zip(&minima)
        .filter_map(|(r, &lm)| {
            r.outcome.as_ref().ok().map(|o| plots::ConvergenceArrow {
                from_m: (r.initial_m[0], r.initial_m[1]),
                to_m: (o.lengths_m[0], o.lengths_m[1]),
                local_minimum: lm,
            })
        })
        .collect();
    plots::convergence(
        &out_dir.join("convergence"),
        &arrows,
        [cfg.codesign.thigh_m, cfg.codesign.shin_m],
        (0.2425, 0.2515),
    )?;
    println!(
        "\nwrote {0}/sweep.csv, {0}/table.md, {0}/convergence.png and {0}/convergence.svg",
        out_dir.display()
    );
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

fn plan(
    robot: &PathBuf,
    config: &PathBuf,
    out: &PathBuf,
    backend: Option<planner::config::SolverBackend>,
) -> Result<()> {
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
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    planned.gait.save(out)?;
    let g = &planned.gait;
    let feasibility = planned
        .feasibility_size
        .map(|(n, m)| format!(" (feasibility stage: {n} and {m}, no power slacks)"))
        .unwrap_or_default();
    println!(
        "\nNLP: {} variables, {} constraints{feasibility}, set-up {:.3} s",
        planned.size.0, planned.size.1, planned.setup_time_s
    );
    println!(
        "{:<18} {:>8} {:>6} {:>6} {:>12} {:>10} {:>9} {:>8} {:>8} {:>8} {:>8}",
        "stage",
        "status",
        "iter",
        "resto",
        "objective",
        "violation",
        "solve s",
        "eval",
        "factor",
        "kkt sol",
        "other"
    );
    for s in &planned.stages {
        let phases = PhaseSeconds::of(s);
        println!(
            "{:<18} {:>8} {:>6} {:>6} {:>12.6} {:>10.1e} {:>9.3} {:>8.3} {}",
            s.stage,
            s.status,
            s.iterations,
            s.restoration_iterations
                .map_or("-".to_string(), |n| n.to_string()),
            s.objective,
            s.violation,
            s.solve_time_s,
            s.evaluation_time_s,
            phases.columns()
        );
    }
    let factorizations: Option<Vec<String>> = planned
        .stages
        .iter()
        .map(|s| s.phases.map(|p| p.factorizations.to_string()))
        .collect();
    println!(
        "(resto: iterations in feasibility restoration; eval: problem functions and derivatives; \
         factor: KKT assembly and LDLᵀ factorizations{}; kkt sol: solves with the factors; \
         other: the rest of the solver{})",
        factorizations.map_or(String::new(), |f| format!(", {} in all", f.join(" + "))),
        if planned.stages.iter().any(|s| s.phases.is_none()) {
            "; -: not measured by the ripopt backend"
        } else {
            ""
        }
    );
    println!(
        "\nstep length {:.4} m | duration {:.4} s | speed {:.4} m/s | cost of transport {:.4}",
        g.step_length_m, g.step_duration_s, g.speed_mps, g.cost_of_transport
    );
    println!("wrote {}", out.display());
    let report =
        planner::verify::verify_gait(&model, g, planner::verify::VerifyOptions::default())?;
    let failures = report.failures(planner::verify::VerifyOptions::default().fixed_point_tolerance);
    println!(
        "verification (adam gait check): |λ|max {:.4}, fixed-point residual {:.1e}, orbit steps \
         {:.4} m in {:.4} s, {}",
        report.spectral_radius,
        report.fixed_point_residual,
        report.step_length_m,
        report.step_duration_s,
        if failures.is_empty() {
            "stable periodic orbit".to_string()
        } else {
            format!("NOT a stable orbit of the plan: {}", failures.join("; "))
        }
    );
    Ok(())
}

/// A solve's time by phase: evaluation, s, then the backend's own split (`None` where the
/// backend does not measure it: ripopt).
#[derive(Clone, Copy)]
struct PhaseSeconds {
    evaluation: f64,
    backend: Option<planner::nlp::PhaseTimes>,
}

impl PhaseSeconds {
    fn of(stage: &planner::plan::StageReport) -> Self {
        Self {
            evaluation: stage.evaluation_time_s,
            backend: stage.phases,
        }
    }

    /// Both stages of a plan together.
    fn of_plan(stages: &[planner::plan::StageReport]) -> Self {
        let start = Self {
            evaluation: 0.0,
            backend: Some(Default::default()),
        };
        stages.iter().map(Self::of).fold(start, |a, b| Self {
            evaluation: a.evaluation + b.evaluation,
            backend: planner::nlp::sum_if_both(a.backend, b.backend),
        })
    }

    /// The backend's factorization, solve and other times, s.
    fn split(&self) -> Option<[f64; 3]> {
        self.backend.map(|p| {
            [p.factorization_time, p.linear_solve_time, p.other_time].map(|t| t.as_secs_f64())
        })
    }

    /// The backend's three columns, 8 wide, `-` where it does not measure them.
    fn columns(&self) -> String {
        match self.split() {
            Some([f, s, o]) => format!("{f:>8.3} {s:>8.3} {o:>8.3}"),
            None => format!("{:>8} {:>8} {:>8}", "-", "-", "-"),
        }
    }
}

/// `target` as seen from the folder of `from` (for the gait file's robot reference).
fn relative_path(target: &std::path::Path, from: &std::path::Path) -> String {
    // A file that does not exist yet: its folder's canonical path joined with its name.
    let abs = |p: &std::path::Path| {
        std::fs::canonicalize(p)
            .or_else(|_| {
                let dir = match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => std::path::Path::new("."),
                };
                std::fs::canonicalize(dir).map(|d| d.join(p.file_name().unwrap_or_default()))
            })
            .unwrap_or_else(|_| p.to_path_buf())
    };
    let t = abs(target);
    let f = from.parent().map(abs).unwrap_or_default();
    let (tc, fc): (Vec<_>, Vec<_>) = (t.components().collect(), f.components().collect());
    let common = tc.iter().zip(&fc).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = vec!["..".to_string(); fc.len().saturating_sub(common)];
    parts.extend(
        tc[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    parts.join("/")
}

fn gait_check(path: &std::path::Path, epsilon: f64) -> Result<()> {
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

/// `dir/stem.ext` → `dir/stem<suffix>` (an output prefix beside an input file).
fn with_suffix(path: &std::path::Path, suffix: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}{suffix}"))
}

fn replay(logs: &[PathBuf], mint: Option<&std::path::Path>) -> Result<()> {
    if let Some(dir) = mint {
        let setup = runtime::Setup::load("configs/runtime/adam.toml", runtime::DEFAULT_GAIT)?;
        let paths = runtime::replay::mint_fixtures(&setup, dir)?;
        for (path, (_, what)) in paths.iter().zip(runtime::replay::FIXTURES) {
            let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            println!("wrote {} ({bytes} bytes): {what}", path.display());
        }
        return Ok(());
    }
    let mut diverged = 0;
    for log in logs {
        let report = runtime::replay::replay(log)?;
        print!("{report}");
        diverged += usize::from(report.divergence.is_some());
    }
    if diverged > 0 {
        bail!("{diverged} of {} log(s) diverged", logs.len());
    }
    Ok(())
}

fn demo() -> Result<()> {
    let gait = PathBuf::from(runtime::DEFAULT_GAIT);
    let config = PathBuf::from("configs/runtime/adam.toml");
    let setup = runtime::Setup::load(&config, &gait)?;
    let g = &setup.gait;
    println!(
        "adam demo: {} (step {:.4} m, {:.4} s, {:.4} m/s) with {}, 30 s on the simulated treadmill via SimBus (A1 CAN codec)",
        gait.display(),
        g.step_length_m,
        g.step_duration_s,
        g.speed_mps,
        config.display()
    );
    let mut options = runtime::sim_run::SimWalkOptions::new(30.0);
    options.log_path = Some(timestamped_log_path());
    sim_walk(&setup, &options)
}

fn soak(
    minutes: f64,
    faults: &str,
    seed: u64,
    log_dir: Option<PathBuf>,
    config: &std::path::Path,
    gait: &std::path::Path,
) -> Result<()> {
    let profile = runtime::faults::FaultProfile::resolve(faults)?;
    let setup = runtime::Setup::load(config, gait)?;
    let options = runtime::sim_run::SoakOptions {
        duration_s: minutes * 60.0,
        profile,
        seed,
        log_dir,
    };
    println!("adam soak: {minutes} min of simulated walking, faults `{faults}`, seed {seed}");
    let wall = std::time::Instant::now();
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let report = runtime::sim_run::soak(&setup, &options, |r| {
        if tty {
            eprint!("\r{:.1} s simulated, {} episodes", r.sim_time_s, r.episodes);
        }
    })?;
    if tty {
        eprintln!();
    }
    print!("{report}");
    println!(
        "wall time                    {:.1} s",
        wall.elapsed().as_secs_f64()
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Demo => demo(),
        Command::Run {
            backend,
            gait,
            config,
            duration,
            belt,
            log,
            seed,
            real_time,
            keyboard,
            can_interfaces,
            faults,
        } => {
            let setup = runtime::Setup::load(&config, &gait)?;
            if faults.is_some() && matches!(backend, Backend::Can) {
                bail!("--faults injects faults into the simulated backend only");
            }
            match backend {
                Backend::Sim => {
                    let mut options = runtime::sim_run::SimWalkOptions::new(duration);
                    options.belt_speed_mps = belt;
                    options.log_path = log;
                    options.seed = seed;
                    options.real_time = real_time;
                    options.faults = faults
                        .as_deref()
                        .map(runtime::faults::FaultProfile::resolve)
                        .transpose()?;
                    if real_time {
                        sim_walk_operated(&setup, &options, keyboard)
                    } else {
                        sim_walk(&setup, &options)
                    }
                }
                Backend::Can => {
                    let interfaces = can_interfaces
                        .unwrap_or_else(|| runtime::robot::default_interfaces(&setup));
                    let summary = runtime::robot::walk(&setup, &interfaces, duration)?;
                    println!("{summary:?}");
                    Ok(())
                }
            }
        }
        Command::Soak {
            minutes,
            faults,
            seed,
            log_dir,
            gait,
            config,
        } => soak(minutes, &faults, seed, log_dir, &config, &gait),
        Command::Plan {
            robot,
            config,
            out,
            backend,
        } => plan(&robot, &config, &out, backend),
        Command::Gait {
            command: GaitCommand::Check { gait, epsilon },
        } => gait_check(&gait, epsilon),
        Command::Logs {
            command: LogsCommand::Info { log },
        } => {
            print!("{}", runtime::log_read::read_info(&log)?);
            Ok(())
        }
        Command::Logs {
            command: LogsCommand::Recover { log, out },
        } => {
            let out = out.unwrap_or_else(|| log.with_extension("recovered.mcap"));
            let stats = runtime::log_read::recover(&log, &out)?;
            println!(
                "{} -> {}: {} messages, {} attachments, {} metadata records{}",
                log.display(),
                out.display(),
                stats.messages,
                stats.attachments,
                stats.metadata,
                if stats.input_complete {
                    " (the input was complete already)"
                } else {
                    ""
                }
            );
            Ok(())
        }
        Command::Replay { logs, mint } => replay(&logs, mint.as_deref()),
        Command::Model { urdf, design } => show_model(&urdf, design.as_deref()),
        Command::Bench {
            what:
                BenchWhat::Plan {
                    runs,
                    robot,
                    config,
                    backend,
                },
        } => bench_plan(runs, &robot, &config, backend),
        Command::Bench {
            what: BenchWhat::Check { runs, gait },
        } => bench_check(runs, &gait),
        Command::Plot {
            what: PlotWhat::Portrait { log, compare, out },
        } => {
            let a = runtime::log_read::joint_series(&log)?;
            let b = compare
                .as_ref()
                .map(|p| runtime::log_read::joint_series(p))
                .transpose()?;
            let mut runs = vec![plots::PortraitRun {
                label: log.display().to_string(),
                series: &a,
            }];
            if let (Some(p), Some(b)) = (&compare, &b) {
                runs.push(plots::PortraitRun {
                    label: p.display().to_string(),
                    series: b,
                });
            }
            let prefix = out.unwrap_or_else(|| with_suffix(&log, "-portrait"));
            plots::portraits(&prefix, &runs)?;
            println!(
                "wrote {} and {}",
                prefix.with_extension("png").display(),
                prefix.with_extension("svg").display()
            );
            Ok(())
        }
        Command::Plot {
            what: PlotWhat::Tiles { log, count, out },
        } => {
            let tiles = runtime::tiles::gait_tiles(&log, count)?;
            let prefix = out.unwrap_or_else(|| with_suffix(&log, "-tiles"));
            let name = log
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            plots::tiles(&prefix, &tiles, &name)?;
            println!(
                "step {} ({:.3} m in {:.3} s), {} figures: wrote {} and {}",
                tiles.step,
                tiles.step_length_m,
                tiles.step_duration_s,
                tiles.figures.len(),
                prefix.with_extension("png").display(),
                prefix.with_extension("svg").display()
            );
            Ok(())
        }
        Command::Op { command, config } => {
            let cmd = runtime::operator::parse_key(&command).ok_or_else(|| {
                anyhow::anyhow!(
                    "unknown operator command {command:?}: start, walk, stop, damp, reset or estop"
                )
            })?;
            let cfg = runtime::config::RuntimeConfig::load(&config)?;
            let service = runtime::operator::operator_service_name(&cfg.telemetry.service_name);
            let receivers = runtime::operator::send_over_iceoryx2(&service, cmd)?;
            println!("sent {cmd:?} on {service} to {receivers} runtime(s)");
            if receivers == 0 {
                bail!("no runtime is listening on {service}");
            }
            Ok(())
        }
        Command::Codesign {
            config,
            inertia,
            out_gait,
            out_urdf,
            study,
        } => match study {
            None => codesign(&config, inertia, &out_gait, &out_urdf),
            Some(CodesignStudy::Sweep { grid, out_dir }) => {
                codesign_sweep(&config, inertia, grid, &out_dir)
            }
        },
        Command::GenerateUrdf { thigh, shin, out } => {
            let text = generate_urdf(&DesignLengths {
                thigh_length_m: thigh,
                shin_length_m: shin,
            })?;
            match out {
                Some(path) => std::fs::write(&path, text)
                    .with_context(|| format!("writing {}", path.display()))?,
                None => print!("{text}"),
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::relative_path;
    use std::path::Path;

    #[test]
    fn relative_paths_between_config_folders_even_for_files_not_written_yet() {
        let dir = std::env::temp_dir().join(format!("adam-rel-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("configs/robots")).expect("dir");
        std::fs::create_dir_all(dir.join("configs/gaits")).expect("dir");
        let urdf = dir.join("configs/robots/new.urdf");
        let gait = dir.join("configs/gaits/new.json");
        assert_eq!(relative_path(&urdf, &gait), "../robots/new.urdf");
        std::fs::write(&urdf, "x").expect("write");
        assert_eq!(relative_path(&urdf, &gait), "../robots/new.urdf");
        assert_eq!(
            relative_path(
                Path::new("configs/robots/adam_planar.urdf"),
                Path::new("configs/gaits/g.json")
            ),
            "../robots/adam_planar.urdf"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
