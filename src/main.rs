//! `adam`: the command-line entry point of adam-hzd. It only parses arguments and calls
//! library functions in `model`, `planner`, `drivers` and `runtime`.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use model::design::{generate_urdf, DesignLengths};
use model::PlanarModel;
use std::path::PathBuf;

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
    /// The main job on the simulated robot (today: the parts that exist, and what does not yet).
    Demo,
    /// Print a robot model: bodies, joints, total mass, leg lengths and D(q) at the nominal pose.
    Model {
        /// URDF file.
        urdf: PathBuf,
        /// Set the design virtual joints to these total lengths, e.g. `thigh=0.24,shin=0.25`.
        #[arg(long)]
        design: Option<String>,
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
    },
    /// Gait files: `adam gait check <gait.json>` verifies a gait independently of the optimizer.
    Gait {
        #[command(subcommand)]
        command: GaitCommand,
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

fn plan(robot: &PathBuf, config: &PathBuf, out: &PathBuf) -> Result<()> {
    let text =
        std::fs::read_to_string(robot).with_context(|| format!("reading {}", robot.display()))?;
    let model = PlanarModel::from_urdf_str(&text, &robot.display().to_string())?;
    let cfg = planner::config::PlannerConfig::load(config)?;
    let urdf_ref = relative_path(robot, out);
    let mut last_print = std::time::Instant::now();
    let planned = planner::plan::plan_gait(&model, &urdf_ref, &text, &cfg, &mut |p| match p {
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
    })?;
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    planned.gait.save(out)?;
    let g = &planned.gait;
    println!(
        "\nNLP: {} variables, {} constraints, set-up {:.3} s",
        planned.size.0, planned.size.1, planned.setup_time_s
    );
    println!(
        "{:<18} {:>8} {:>6} {:>12} {:>10} {:>9} {:>9}",
        "stage", "status", "iter", "objective", "violation", "solve s", "eval s"
    );
    for s in &planned.stages {
        println!(
            "{:<18} {:>8} {:>6} {:>12.6} {:>10.1e} {:>9.3} {:>9.3}",
            s.stage,
            s.status,
            s.iterations,
            s.objective,
            s.violation,
            s.solve_time_s,
            s.evaluation_time_s
        );
    }
    println!(
        "\nstep length {:.4} m | duration {:.4} s | speed {:.4} m/s | cost of transport {:.4}",
        g.step_length_m, g.step_duration_s, g.speed_mps, g.cost_of_transport
    );
    println!("wrote {}", out.display());
    Ok(())
}

/// `target` as seen from the folder of `from` (for the gait file's robot reference).
fn relative_path(target: &std::path::Path, from: &std::path::Path) -> String {
    let abs = |p: &std::path::Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
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

fn gait_check(path: &PathBuf, epsilon: f64) -> Result<()> {
    let (gait, robot) = planner::verify::load_gait_and_robot(path)?;
    let options = planner::verify::VerifyOptions {
        epsilon_per_s: epsilon,
        ..Default::default()
    };
    let report = planner::verify::verify_gait(&robot, &gait, options)?;
    println!(
        "gait {} (planned: {:.4} m in {:.4} s)",
        path.display(),
        gait.step_length_m,
        gait.step_duration_s
    );
    print!("{report}");
    if !report.passed(options.fixed_point_tolerance) {
        bail!(
            "the gait is unstable or has no periodic orbit (|λ|max {:.4}, residual {:.2e})",
            report.spectral_radius,
            report.fixed_point_residual
        );
    }
    println!("stable periodic orbit");
    Ok(())
}

fn demo() -> Result<()> {
    let path = PathBuf::from("configs/robots/adam_planar.urdf");
    println!("adam demo: loading {}\n", path.display());
    show_model(&path, None)?;
    println!(
        "\nNot built yet: the gait planner (issue \"Planner I\"), the CAN drivers and the simulated\n\
         treadmill (\"Drivers\"), and the real-time runtime (\"Runtime\"). When they land, `demo`\n\
         plans or loads the shipped gait and walks it for 30 s on the simulated robot."
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
        Command::Plan { robot, config, out } => plan(&robot, &config, &out),
        Command::Gait {
            command: GaitCommand::Check { gait, epsilon },
        } => gait_check(&gait, epsilon),
        Command::Model { urdf, design } => show_model(&urdf, design.as_deref()),
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
