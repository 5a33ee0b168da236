//! `adam op`: one operator command (start, walk, stop, damp, reset, estop; `belt 0.25`, `offset
//! 0.05`, `nudge -0.025` for treadmill speed control, m/s) sent over iceoryx2 to a running
//! `adam run --real-time`.

use anyhow::{bail, Result};
use std::path::PathBuf;

/// Arguments of `adam op`.
#[derive(clap::Args)]
pub(crate) struct OpArgs {
    /// start, walk, stop, damp, reset, estop, or belt / offset / nudge followed by a speed in m/s
    /// (`adam op belt 0.25`).
    #[arg(num_args = 1..=2, required = true)]
    command: Vec<String>,
    /// Runtime config (its telemetry service name locates the runtime).
    #[arg(long, default_value = crate::cli::shipped::RUNTIME_CONFIG)]
    config: PathBuf,
}

/// `adam op`: sends the command to every runtime listening on the config's service.
pub(crate) fn send(args: &OpArgs) -> Result<()> {
    let OpArgs { command, config } = args;
    let command = command.join(" ");
    let cmd = runtime::control::OperatorCommand::parse(&command)
        .map_err(|e| anyhow::anyhow!("operator command `{command}`: {e}"))?;
    let cfg = runtime::config::RuntimeConfig::load(crate::cli::shipped::input(config))?;
    let service = runtime::operator::operator_service_name(&cfg.telemetry.service_name);
    let receivers = runtime::operator::send_over_iceoryx2(&service, cmd)?;
    println!(
        "sent `{}` on {service} to {receivers} runtime(s)",
        cmd.text()
    );
    if receivers == 0 {
        bail!("no runtime is listening on {service}");
    }
    Ok(())
}
