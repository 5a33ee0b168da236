//! The runtime over CAN-over-UDP links ([`drivers::udp::UdpBus`], cannelloni's packet format):
//! against `adam emulate motors` (the simulated robot served in another process) or, through
//! cannelloni gateways, against CAN buses on another machine.
//!
//! The motors and, from the emulator, the torso IMU come over the links; the loop is the one
//! every backend runs ([`crate::run`]), and it logs the links' raw frames like any other bus.
//! Two clocks: [`UdpRunOptions::real_time`] paces the loop by the wall clock at the config's rate
//! (what gateways to real motors need); without it the loop runs under the simulated clock,
//! as fast as the link answers, which against the lockstep emulator walks the very run the
//! in-process simulator walks (the emulator advances one period per commanded period whatever
//! the wall clock does). With the simulated clock a reply may take up to
//! [`UdpRunOptions::reply_timeout`] of wall time (the emulator shares the machine); with the
//! wall clock the exchange's budget, one period, as on CAN (20 ms for enable and disable).
//! The wall-clock loop asks for SCHED_FIFO and busy-polls its sockets, like the CAN loop: give
//! it a core of its own. An emulator on the same busy machine may then not get the CPU in time
//! (seen on 2 shared cores at a load of 7–11, as root: the enable's 20 ms passed without a
//! reply); against `adam emulate motors` use the default lockstep clock.

use crate::backend::Backend;
use crate::control::OperatorCommand;
use crate::rt_loop::{LoopOptions, MonotonicClock, RunSummary, SimulatedClock};
use crate::{Result, RuntimeError, Setup};
use core::time::Duration;
use drivers::udp::UdpBus;
use std::net::SocketAddr;
use std::path::PathBuf;

/// The UDP links have no ground truth; the emulator's IMU comes with the replies.
impl Backend for UdpBus {}

/// How to run over UDP.
#[derive(Clone, Debug)]
pub struct UdpRunOptions {
    /// Run time, s (loop time).
    pub duration_s: f64,
    /// Begin in Walk at the first tick (the emulator starts the robot in the gait's
    /// post-impact state); otherwise a Start at 0 s ramps to Stand and `script` walks.
    pub start_walking: bool,
    /// Operator commands at loop times, s (sorted by time).
    pub script: Vec<(f64, OperatorCommand)>,
    /// Pace by the wall clock (see the module docs).
    pub real_time: bool,
    /// Longest wait for the replies of one exchange under the simulated clock.
    pub reply_timeout: Duration,
    /// Write an MCAP log here.
    pub log_path: Option<PathBuf>,
    /// Bind bus 0's socket here, bus `k`'s at its port + `k` (what a gateway's cannelloni
    /// sends to); `None`: ports the OS picks.
    pub bind: Option<SocketAddr>,
    /// Publish each tick's state sample over iceoryx2 (`telemetry.service_name`), for
    /// `adam live` and `adam op`.
    pub publish: bool,
}

impl UdpRunOptions {
    /// `duration_s` walking from the first tick, simulated clock, a 100 ms reply timeout, no log,
    /// no publishing.
    pub fn new(duration_s: f64) -> Self {
        Self {
            duration_s,
            start_walking: true,
            script: Vec::new(),
            real_time: false,
            reply_timeout: Duration::from_millis(100),
            log_path: None,
            bind: None,
            publish: false,
        }
    }
}

/// Open one link per bus of the config: `addrs` one per bus, or one address whose port + `k`
/// is bus `k`'s ([`drivers::udp::bus_addresses`]).
pub fn open_udp(
    setup: &Setup,
    addrs: &[SocketAddr],
    bind: Option<SocketAddr>,
    origin: &str,
) -> Result<UdpBus> {
    let bus_count = setup.config.loop_.bus_count;
    let peers = drivers::udp::bus_addresses(addrs, bus_count).ok_or_else(|| {
        RuntimeError::InvalidField {
            origin: origin.into(),
            field: "loop.bus_count".into(),
            value: bus_count.to_string(),
            reason: format!(
                "the config has that many buses; give one address (bus k at its port + k, at \
                 most 65535) or one per bus ({} given: {})",
                addrs.len(),
                addrs
                    .iter()
                    .map(SocketAddr::to_string)
                    .collect::<Vec<_>>()
                    .join(",")
            ),
        }
    })?;
    UdpBus::open_at(&peers, bind).map_err(|e| RuntimeError::InvalidField {
        origin: origin.into(),
        field: "address".into(),
        value: addrs
            .iter()
            .map(SocketAddr::to_string)
            .collect::<Vec<_>>()
            .join(","),
        reason: e.to_string(),
    })
}

/// Walk over the UDP links at `addrs` (leg motors only, as the simulated robot has); the run's
/// summary and the links' counts.
pub fn walk(
    setup: &Setup,
    addrs: &[SocketAddr],
    options: &UdpRunOptions,
) -> Result<(RunSummary, drivers::udp::LinkStats)> {
    let mut bus = open_udp(setup, addrs, options.bind, "--motors")?;
    if !options.real_time {
        bus.set_reply_timeout(Some(options.reply_timeout));
    }
    let mut loop_options = LoopOptions::simulation(options.duration_s);
    loop_options.start_walking = options.start_walking;
    if !options.start_walking {
        loop_options.script.push((0.0, OperatorCommand::Start));
    }
    loop_options.script.extend_from_slice(&options.script);
    loop_options.script.sort_by(|a, b| a.0.total_cmp(&b.0));
    loop_options.log_path = options.log_path.clone();
    loop_options.realtime = options.real_time;
    loop_options.publish = options.publish;
    let (summary, bus) = if options.real_time {
        crate::run(setup, bus, MonotonicClock, loop_options, None)?
    } else {
        crate::run(setup, bus, SimulatedClock::default(), loop_options, None)?
    };
    Ok((summary, bus.stats()))
}
