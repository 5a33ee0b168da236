//! `adam emulate imu`: an emulated VN-100 ([`drivers::vn100::emulator`]).

use crate::cli::run::parse_duration_s;
use crate::cli::shipped;
use anyhow::{bail, Context, Result};
use drivers::vn100::emulator::{serve, Emulator, EmulatorOptions, Pty};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `adam emulate imu`.
#[derive(clap::Args)]
pub(crate) struct ImuArgs {
    /// Serve on a new pseudo-terminal and print its path (`pty: /dev/pts/N`): answer the
    /// driver's configuration commands, then stream at the rate it configured.
    #[arg(long, conflicts_with = "out", required_unless_present = "out")]
    pty: bool,
    /// Write the byte stream (at --rate-hz, no commands) to this file instead; an existing
    /// file needs --force.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write --out over an existing file.
    #[arg(long, requires = "out")]
    force: bool,
    /// Stream length, e.g. `10s` (once configured).
    #[arg(long, default_value = "10s", value_parser = parse_duration_s)]
    duration: f64,
    /// Rate of the --out stream, Hz (800 or 400); on a pty the driver's command sets it.
    #[arg(long, default_value_t = 800.0, requires = "out")]
    rate_hz: f64,
    /// Probability per frame of a burst of garbage bytes before it (0–1).
    #[arg(long, default_value_t = 0.0)]
    garbage: f64,
    /// Probability per frame that one of its bytes is dropped (0–1).
    #[arg(long, default_value_t = 0.0)]
    drop: f64,
    /// Probability per frame that one of its bytes is changed (0–1).
    #[arg(long, default_value_t = 0.0)]
    flip: f64,
    /// Seed of the IMU noise and of the faults.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Torso pitch at rest, degrees (+ leaning forward).
    #[arg(long, default_value_t = 3.0, allow_negative_numbers = true)]
    pitch_deg: f64,
    /// Amplitude of a pitch sway, degrees (0: still).
    #[arg(long, default_value_t = 0.0)]
    sway_deg: f64,
    /// Frequency of the sway, Hz.
    #[arg(long, default_value_t = 1.0)]
    sway_hz: f64,
    /// Runtime config whose `[imu]` section says how the sensor is mounted.
    #[arg(long, default_value = shipped::RUNTIME_CONFIG)]
    config: PathBuf,
}

/// How long the pty stays open after the last frame, so the driver reads it all, s.
const LINGER_S: f64 = 1.0;

/// `adam emulate imu`.
pub(crate) fn emulate(args: &ImuArgs) -> Result<()> {
    for (flag, p) in [
        ("--garbage", args.garbage),
        ("--drop", args.drop),
        ("--flip", args.flip),
    ] {
        if !(0.0..=1.0).contains(&p) {
            bail!("{flag} {p}: a probability per frame must be within 0–1");
        }
    }
    for (flag, v) in [
        ("--pitch-deg", args.pitch_deg),
        ("--sway-deg", args.sway_deg),
        ("--sway-hz", args.sway_hz),
    ] {
        if !(v.is_finite() && (flag == "--pitch-deg" || v >= 0.0)) {
            bail!(
                "{flag} {v}: must be finite{}",
                if flag == "--pitch-deg" {
                    ""
                } else {
                    " and not negative"
                }
            );
        }
    }
    let config_path = shipped::input(&args.config);
    let config = runtime::config::RuntimeConfig::load(&config_path)?;
    let origin = config_path.display().to_string();
    let mounting = config.imu.vn100_options(&origin)?.mounting;
    let options = EmulatorOptions {
        seed: args.seed,
        garbage_probability: args.garbage,
        drop_probability: args.drop,
        flip_probability: args.flip,
        pitch_rad: args.pitch_deg.to_radians(),
        sway_amplitude_rad: args.sway_deg.to_radians(),
        sway_hz: args.sway_hz,
        mounting,
        ..EmulatorOptions::default()
    };
    let mut emulator = Emulator::new(options);
    if let Some(out) = &args.out {
        return write_stream(&mut emulator, out, args);
    }
    let mut pty = Pty::open().context("opening a pseudo-terminal pair")?;
    println!("pty: {}", pty.path().display());
    println!(
        "emulated VN-100 (mounted forward {}, up {}): waiting for the driver's commands; then {} s of frames",
        mounting.forward().name(),
        mounting.up().name(),
        args.duration
    );
    std::io::stdout().flush()?;
    let counts = serve(&mut pty, &mut emulator, args.duration)
        .with_context(|| format!("serving on {}", pty.path().display()))?;
    println!(
        "sent at {} Hz: {counts}",
        emulator.rate_hz().unwrap_or_default()
    );
    std::io::stdout().flush()?;
    std::thread::sleep(std::time::Duration::from_secs_f64(LINGER_S));
    Ok(())
}

/// `--out`: the stream, unpaced, into a file.
fn write_stream(emulator: &mut Emulator, out: &std::path::Path, args: &ImuArgs) -> Result<()> {
    crate::cli::paths::writable(out, args.force)?;
    let divisor = drivers::vn100::Vn100Options {
        rate_hz: args.rate_hz,
        ..Default::default()
    }
    .rate_divisor()
    .with_context(|| format!("--rate-hz {}", args.rate_hz))?;
    let command =
        drivers::vn100::ascii::binary_output(divisor, drivers::vn100::frame::Fields::DRIVER);
    let sentence = drivers::vn100::ascii::Sentence::parse(&command)
        .context("the binary output command does not parse back")?;
    emulator.reply(&sentence);
    let frames = (args.duration * args.rate_hz).round().max(1.0) as u64;
    let mut bytes = Vec::new();
    for k in 0..frames {
        emulator.next_chunk(k + 1 == frames, &mut bytes);
    }
    std::fs::write(out, &bytes).with_context(|| format!("writing {}", out.display()))?;
    println!(
        "{}: {} bytes at {} Hz: {}",
        out.display(),
        bytes.len(),
        args.rate_hz,
        emulator.counts()
    );
    Ok(())
}
