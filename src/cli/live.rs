//! `adam live`: the live view in Foxglove, in its own process ([`runtime::live`]); and `--live`
//! on `adam run` and `adam demo`, which start it beside the run as a child process of this
//! executable and stop it when the run ends (by closing its standard input).

use crate::cli::shipped;
use anyhow::{Context, Result};
use std::io::Write;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Arguments of `adam live`.
#[derive(clap::Args)]
pub(crate) struct LiveArgs {
    /// Address to serve on; loopback by default (another interface only when named here).
    #[arg(long, default_value = runtime::live::DEFAULT_ADDR)]
    addr: SocketAddr,
    /// The gait the run walks (its robot is drawn).
    #[arg(long, default_value = runtime::DEFAULT_GAIT)]
    gait: PathBuf,
    /// The run's runtime config (its telemetry service name locates the run).
    #[arg(long, default_value = shipped::RUNTIME_CONFIG)]
    config: PathBuf,
    /// Per-channel decimation over the defaults, `topic=n,…`: send every n-th sample (e.g.
    /// `/joints=5,/tf=10`; default 20 for the per-tick channels, 1000 for /scene and
    /// /robot_description). The MCAP log keeps the full rate.
    #[arg(long, default_value = "")]
    decimate: String,
    /// Accept the operator's commands (start, walk, stop, damp, estop, belt/offset/nudge)
    /// from clients, published on a client channel as `{"command": "walk"}`; each is logged
    /// with the client's address. Default: read-only.
    #[arg(long)]
    live_commands: bool,
    /// The run drives the held motors too (their joints appear in /joints).
    #[arg(long)]
    with_held: bool,
    /// End when standard input closes (how `--live` on run and demo stops its viewer).
    #[arg(long, hide = true)]
    until_stdin_closes: bool,
    /// The iceoryx2 service of the samples, instead of the config's (`adam bench live`).
    #[arg(long, hide = true)]
    service: Option<String>,
}

/// `--live` on `adam run` and `adam demo`.
#[derive(clap::Args, Clone, Debug)]
pub(crate) struct LiveFlags {
    /// Serve the run live to Foxglove (`adam live` beside the run) on ADDR, default
    /// 127.0.0.1:8765 (loopback; another interface only when named).
    #[arg(long, num_args = 0..=1, default_missing_value = runtime::live::DEFAULT_ADDR, value_name = "ADDR")]
    pub(crate) live: Option<SocketAddr>,
    /// With --live: accept operator commands from Foxglove clients (see `adam live --help`).
    #[arg(long, requires = "live")]
    pub(crate) live_commands: bool,
    /// With --live: per-channel decimation, `topic=n,…` (see `adam live --help`).
    #[arg(long, requires = "live", value_name = "TOPIC=N,…")]
    pub(crate) live_decimate: Option<String>,
}

/// `adam live`: serves until Ctrl-C (or, from `--live`, until the run ends).
pub(crate) fn live(args: &LiveArgs) -> Result<()> {
    let config = shipped::input(&args.config);
    let gait = shipped::input(&args.gait);
    let setup = runtime::Setup::load(&config, &gait)?;
    let service = args
        .service
        .clone()
        .unwrap_or_else(|| setup.config.telemetry.service_name.clone());
    if service.is_empty() {
        anyhow::bail!(
            "{}: `telemetry.service_name` is empty: the run publishes no samples to view",
            config.display()
        );
    }
    let mut options = runtime::live::LiveOptions::new(args.addr, &service);
    options.decimation = runtime::live::feed::Decimation::parse(&args.decimate, "--decimate")
        .map_err(anyhow::Error::msg)?;
    options.with_held = args.with_held;
    if args.live_commands {
        let operator = runtime::operator::operator_service_name(&service);
        options.commands = Some(Arc::new(move |command| {
            runtime::operator::send_over_iceoryx2(&operator, command).map_err(|e| e.to_string())
        }));
    }
    let stop = Arc::new(AtomicBool::new(false));
    if args.until_stdin_closes {
        let stop = stop.clone();
        // Not joined: it ends with the process.
        std::thread::spawn(move || {
            let _ = std::io::copy(&mut std::io::stdin().lock(), &mut std::io::sink());
            stop.store(true, Ordering::Release);
        });
    }
    let commands = if args.live_commands {
        "operator commands accepted (--live-commands)"
    } else {
        "read-only"
    };
    let report = runtime::live::serve(&setup, &options, &stop, |addr| {
        println!(
            "adam live: open Foxglove → Open connection → Foxglove WebSocket → ws://{addr} \
             (samples from iceoryx2 service {service}; {commands}; layout configs/foxglove/adam.json)"
        );
    })?;
    println!("{report}");
    Ok(())
}

/// A running `adam live` child: stopped (stdin closed, then killed if it lingers) on drop.
pub(crate) struct LiveChild {
    child: std::process::Child,
}

impl LiveFlags {
    /// Starts `adam live` for a run of this config and gait, if `--live` was given.
    pub(crate) fn spawn(
        &self,
        config: &Path,
        gait: &Path,
        with_held: bool,
    ) -> Result<Option<LiveChild>> {
        let Some(addr) = self.live else {
            return Ok(None);
        };
        // Refuse a port in use here, naming it, before the run starts.
        drop(
            std::net::TcpListener::bind(addr)
                .with_context(|| format!("--live {addr}: cannot listen there"))?,
        );
        let exe = std::env::current_exe().context("--live: cannot find this executable")?;
        let mut cmd = std::process::Command::new(exe);
        cmd.arg("live")
            .arg("--addr")
            .arg(addr.to_string())
            .arg("--config")
            .arg(config)
            .arg("--gait")
            .arg(gait)
            .arg("--until-stdin-closes")
            .stdin(std::process::Stdio::piped());
        if let Some(d) = &self.live_decimate {
            cmd.arg("--decimate").arg(d);
        }
        if self.live_commands {
            cmd.arg("--live-commands");
        }
        if with_held {
            cmd.arg("--with-held");
        }
        let child = cmd.spawn().context("--live: cannot start `adam live`")?;
        Ok(Some(LiveChild { child }))
    }
}

impl Drop for LiveChild {
    fn drop(&mut self) {
        if let Some(mut stdin) = self.child.stdin.take() {
            let _ = stdin.flush();
        }
        for _ in 0..50 {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
