//! `adam model` and `adam generate-urdf`: a robot model's summary at a design, and ADAM's URDF
//! for any design (GenerateModel).

use crate::cli::paths::writable;
use crate::cli::shipped;
use anyhow::{bail, Context, Result};
use model::design::DesignLengths;
use model::PlanarModel;
use std::path::PathBuf;

/// Arguments of `adam model`.
#[derive(clap::Args)]
pub(crate) struct ModelArgs {
    /// URDF file.
    urdf: PathBuf,
    /// Set the design virtual joints to these total lengths, e.g. `thigh=0.24,shin=0.25`.
    #[arg(long)]
    design: Option<String>,
}

/// Arguments of `adam generate-urdf`.
#[derive(clap::Args)]
pub(crate) struct GenerateUrdfArgs {
    /// Thigh length, m.
    #[arg(long, default_value_t = model::design::ADAM_THIGH_M)]
    thigh: f64,
    /// Shin length, m.
    #[arg(long, default_value_t = model::design::ADAM_SHIN_M)]
    shin: f64,
    /// Output file (stdout if absent); an existing file needs --force.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write over an existing --out.
    #[arg(long, requires = "out")]
    force: bool,
    /// Add the A1 drives (joint damping, and a transmission per joint with the A1's gear ratio,
    /// rotor inertia, torque constant and winding resistance), as in
    /// configs/robots/adam_planar_a1.urdf.
    #[arg(long)]
    a1_drives: bool,
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

/// `adam model`: the model's summary, at a design if asked.
pub(crate) fn show_model(args: &ModelArgs) -> Result<()> {
    let (urdf, design) = (&args.urdf, args.design.as_deref());
    let robot = PlanarModel::from_urdf_file(shipped::input(urdf))?;
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

/// `adam generate-urdf`: writes the URDF to `--out` or stdout.
pub(crate) fn write_urdf(args: GenerateUrdfArgs) -> Result<()> {
    let GenerateUrdfArgs {
        thigh,
        shin,
        out,
        force,
        a1_drives,
    } = args;
    if let Some(path) = &out {
        writable(path, force)?;
    }
    let text = model::design::generate_urdf_with(
        &DesignLengths {
            thigh_length_m: thigh,
            shin_length_m: shin,
        },
        &model::design::MassModel {
            a1_drives,
            ..Default::default()
        },
    )?;
    match out {
        Some(path) => {
            std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?
        }
        None => print!("{text}"),
    }
    Ok(())
}
