//! `adam calibrate`: measure each leg motor's direction and zero offset (checking its gear
//! ratio) with the robot hung on the boom and its legs clamped in the config's two jig poses
//! (`runtime::bringup::calibrate`), and write them into a NEW runtime config file (never the
//! input). `--backend sim` calibrates the simulated robot, whose motors can be mounted wrong
//! (`--sim-offsets`, `--sim-flip`); `--backend can` the robot, the operator clamping each pose.

use crate::cli::bringup_target::{Backend, BringupTarget};
use crate::cli::paths::writable;
use anyhow::{bail, Context, Result};
use drivers::sim::firmware::EncoderMount;
use runtime::bringup::{self, JigPose};
use runtime::config::LEG_JOINT_NAMES;
use std::io::BufRead;
use std::path::{Path, PathBuf};

/// Arguments of `adam calibrate`.
#[derive(clap::Args)]
pub(crate) struct CalibrateArgs {
    /// The robot to calibrate (`--backend sim|can`), its runtime config (the jig poses:
    /// `[calibration.<joint>] jig_rad`), gait and CAN interfaces.
    #[command(flatten)]
    target: BringupTarget,
    /// The new runtime config to write: the input with its `[calibration]` tables replaced.
    /// Never the input file; an existing file needs --force.
    #[arg(long)]
    out: PathBuf,
    /// Write --out over an existing file (never over --config).
    #[arg(long)]
    force: bool,
    /// The simulated motors' true zero offsets: the joint angle at which each reads zero, rad,
    /// in leg order (left hip, left knee, right hip, right knee), e.g. `0.5,-0.45,0.4,-0.6`
    /// (sim; default all 0).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    sim_offsets: Option<Vec<f64>>,
    /// A simulated motor mounted the other way round, by joint (e.g. `left_knee_pitch`);
    /// repeatable (sim).
    #[arg(long)]
    sim_flip: Vec<String>,
}

/// The simulated motors' mounts from `--sim-offsets` and `--sim-flip`.
pub(crate) fn sim_mounts(offsets: Option<&[f64]>, flips: &[String]) -> Result<[EncoderMount; 4]> {
    let mut mounts = [EncoderMount::default(); 4];
    if let Some(offsets) = offsets {
        if offsets.len() != 4 {
            bail!(
                "--sim-offsets has {} values: give 4, one per leg joint ({})",
                offsets.len(),
                LEG_JOINT_NAMES.join(", ")
            );
        }
        for (k, &o) in offsets.iter().enumerate() {
            if !(o.is_finite() && o.abs() <= std::f64::consts::TAU) {
                bail!(
                    "--sim-offsets value {} ({}) = {o}: must be finite and within ±2π rad",
                    k + 1,
                    LEG_JOINT_NAMES[k]
                );
            }
            mounts[k].joint_rad_at_zero = o;
        }
    }
    for joint in flips {
        let Some(k) = LEG_JOINT_NAMES.iter().position(|n| n == joint) else {
            bail!(
                "--sim-flip `{joint}` is not a leg joint (one of {})",
                LEG_JOINT_NAMES.join(", ")
            );
        };
        mounts[k].direction = -1.0;
    }
    Ok(mounts)
}

/// Refuses an output that is the input config (even with --force) or an existing file
/// without --force.
fn check_out(config: &Path, out: &Path, force: bool) -> Result<()> {
    let same = match (std::fs::canonicalize(config), std::fs::canonicalize(out)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same {
        bail!(
            "--out {} is the input config: adam calibrate never writes in place; name a new file",
            out.display()
        );
    }
    writable(out, force)
}

/// Waits for the operator to clamp the legs in `pose` (on the robot).
fn prompt_pose(setup: &runtime::Setup, pose: JigPose) -> runtime::Result<()> {
    let q = bringup::jig_angles(setup, pose);
    let angles: Vec<String> = LEG_JOINT_NAMES
        .iter()
        .zip(q)
        .map(|(n, q)| format!("{n} {q} rad"))
        .collect();
    println!(
        "Clamp the legs in jig pose {pose:?} ({}), the robot hanging still on the boom; then press Enter.",
        angles.join(", ")
    );
    let mut line = String::new();
    std::io::stdin()
        .lock()
        .read_line(&mut line)
        .map_err(|error| runtime::RuntimeError::Io {
            path: PathBuf::from("stdin"),
            error,
        })?;
    Ok(())
}

/// `adam calibrate`.
pub(crate) fn calibrate(args: CalibrateArgs) -> Result<()> {
    let CalibrateArgs {
        target,
        out,
        force,
        sim_offsets,
        sim_flip,
    } = args;
    target.refuse_unused(&[
        ("--sim-offsets", sim_offsets.is_some()),
        ("--sim-flip", !sim_flip.is_empty()),
    ])?;
    let (config, gait) = target.inputs();
    check_out(&config, &out, force)?;
    // The new config is the input's text with its [calibration] replaced: a config that extends
    // another has no whole text to write (its copy would look for its base next to --out).
    if let Some(base) = runtime::config::extends_chain(&config)?.first() {
        bail!(
            "{} extends {}: adam calibrate writes a copy of one whole config with its \
             [calibration] replaced; calibrate {} (a config that extends none)",
            config.display(),
            base.display(),
            base.display()
        );
    }
    let text = std::fs::read_to_string(&config)
        .with_context(|| format!("reading {}", config.display()))?;
    let setup = runtime::Setup::load(&config, &gait)?;
    let outcome = match target.backend {
        Backend::Sim => {
            let mounts = sim_mounts(sim_offsets.as_deref(), &sim_flip)?;
            println!(
                "adam calibrate: the simulated robot hung on the boom, legs clamped in jig pose A then B of {}",
                config.display()
            );
            let mut robot = runtime::sim::hung::hung_robot_sim(
                &setup,
                &bringup::jig_angles(&setup, JigPose::A),
                &mounts,
            )?;
            bringup::calibrate(&setup, &mut robot, |pose, r| {
                // The jig moves while the motors are off: the legs now rest at its angles.
                *r = runtime::sim::hung::hung_robot_sim(
                    &setup,
                    &bringup::jig_angles(&setup, pose),
                    &mounts,
                )?;
                Ok(())
            })?
        }
        Backend::Can => {
            let mut bus = runtime::robot::open_can(&setup, &target.interfaces(&setup))?;
            bringup::calibrate(&setup, &mut bus, |pose, _| prompt_pose(&setup, pose))?
        }
    };
    print!("{outcome}");
    let new_text = runtime::config::calibration::replace_section(&text, &outcome.calibration);
    // What is written must read back as the calibration measured.
    let check = runtime::config::RuntimeConfig::from_toml(&new_text, &out.display().to_string())?;
    if check.calibration != outcome.calibration {
        bail!("internal: the written calibration does not read back as measured");
    }
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(&out, new_text).with_context(|| format!("writing {}", out.display()))?;
    println!(
        "wrote {} ({} with the measured [calibration])",
        out.display(),
        config.display()
    );
    Ok(())
}
