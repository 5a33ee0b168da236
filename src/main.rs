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
