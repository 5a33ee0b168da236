//! `adam emulate motors --listen 127.0.0.1:PORT`: the simulated robot of `adam run --backend
//! sim` (same physics, seed and belt) served over CAN-over-UDP ([`runtime::sim::emulate`]).

use crate::cli::shipped;
use anyhow::{bail, Result};
use std::net::SocketAddr;
use std::path::PathBuf;

/// Arguments of `adam emulate motors`.
#[derive(clap::Args)]
pub(crate) struct MotorsArgs {
    /// Bus 0's UDP address; bus k listens at its port + k (one link per bus, as cannelloni).
    #[arg(long)]
    listen: SocketAddr,
    /// Gait file whose post-impact state the robot starts in (and whose robot it is).
    #[arg(long, default_value = runtime::DEFAULT_GAIT)]
    gait: PathBuf,
    /// Runtime config (buses, motor ids, rate).
    #[arg(long, default_value = shipped::RUNTIME_CONFIG)]
    config: PathBuf,
    /// Seed of the simulated IMU and encoder noise (default 1, as `adam run --backend sim`).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Treadmill belt speed, m/s (default: the gait's speed).
    #[arg(long, allow_negative_numbers = true)]
    belt: Option<f64>,
    /// Start standing in the gait's first pose instead of walking in its post-impact state
    /// (the runtime then needs `--start stand` too).
    #[arg(long)]
    stand: bool,
    /// Serve on after the host's run ends (default: report and exit when the host has disabled
    /// every motor).
    #[arg(long)]
    keep_serving: bool,
    /// Exit when no packet came for this many seconds after the first.
    #[arg(long, default_value_t = 10.0)]
    idle_exit: f64,
}

/// Serve until the host's run ends; print what the robot did. Fails if it fell.
pub(crate) fn motors(args: &MotorsArgs) -> Result<()> {
    let (gait, config) = (shipped::input(&args.gait), shipped::input(&args.config));
    let setup = runtime::Setup::load(&config, &gait)?;
    if let Some(v) = args.belt {
        setup.config.treadmill.check_belt_speed("--belt", v)?;
    }
    if !(args.idle_exit.is_finite() && args.idle_exit > 0.0) {
        bail!(
            "--idle-exit {}: must be a positive number of seconds",
            args.idle_exit
        );
    }
    let mut robot = runtime::sim::run::SimWalkOptions::new(1.0);
    robot.belt_speed_mps = args.belt;
    robot.seed = args.seed;
    if args.stand {
        robot.start = runtime::sim::run::SimStart::Stand;
    }
    let options = runtime::sim::emulate::EmulateOptions {
        robot,
        listen: args.listen,
        keep_serving: args.keep_serving,
        idle_exit_s: args.idle_exit,
    };
    let buses = setup.config.loop_.bus_count;
    let report = runtime::sim::emulate::serve(&setup, &options, |addr| {
        let last = addr.port() as usize + buses - 1;
        println!(
            "adam emulate motors: {} on {buses} UDP link(s) from {addr} (ports {}–{last}), cannelloni format; waiting for `adam run --backend udp --motors {addr}`",
            gait.display(),
            addr.port()
        );
    })?;
    println!("{report}");
    if let Some((t, what)) = report.fall {
        bail!("the emulated robot fell ({what}) at {t:.3} s");
    }
    Ok(())
}
