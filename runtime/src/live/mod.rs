//! The live view: `adam live` serves a running loop to Foxglove over WebSocket, in its own
//! process, so that nothing the viewer does (a crash, a slow client) reaches the control
//! thread.
//!
//! ```text
//! control process                          adam live (this module)
//! rt_loop ─ StateSample ─▶ iceoryx2 ──────▶ source (subscriber, SUBSCRIBER_BUFFER samples;
//!   (publisher never waits: the oldest     │          the loop overwrites what it has not read)
//!    sample is overwritten when full)      ▼
//!                                          feed: the log's channels + /tf, /scene,
//!                                          │     /robot_description, decimated per channel
//!                                          ▼
//!                                          server (tokio): Foxglove WebSocket protocol
//!                                          │  ├─ slow client → dropped, counted, logged
//!                                          │  └─ malformed or oversized message → closed
//! adam op / operator forwarder ◀─ iceoryx2 ◀┘  operator commands, only with --live-commands
//! ```
//! The channels and schemas are the MCAP log's ([`crate::telemetry::channels`],
//! [`crate::telemetry::scene`]), so a Foxglove layout made on a log works live and the other
//! way round (`configs/foxglove/adam.json`). `/input`, `/command`, `/speed` and `/can` are
//! advertised but carry nothing live (they are the log's replay and diagnostic channels);
//! `/safety` live carries the trip's reason and code (its values are in the log).

pub mod feed;
pub mod protocol;
pub mod server;
#[cfg(feature = "iceoryx2")]
pub mod source;

use crate::Result;
use feed::{Decimation, Feed};
use server::{CommandSink, LiveServer, ServerOptions, ServerStats};
use std::net::SocketAddr;
#[cfg(feature = "iceoryx2")]
use std::sync::atomic::{AtomicBool, Ordering};

/// The default address: loopback only; another address must be given explicitly.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8765";

/// How `adam live` runs.
#[derive(Clone)]
pub struct LiveOptions {
    /// Where to listen.
    pub addr: SocketAddr,
    /// Per-channel decimation.
    pub decimation: Decimation,
    /// iceoryx2 service of the state samples (`telemetry.service_name` of the runtime config).
    pub service: String,
    /// Forward operator commands from clients (`--live-commands`); `None`: read-only.
    pub commands: Option<CommandSink>,
    /// The run drives the held motors too (their joints appear in `/joints`).
    pub with_held: bool,
    /// Messages queued per server before a client that is behind is dropped.
    pub queue_capacity: usize,
}

impl LiveOptions {
    /// Read-only, default decimation, on `addr`, for the samples of `service`.
    pub fn new(addr: SocketAddr, service: &str) -> Self {
        Self {
            addr,
            decimation: Decimation::default(),
            service: service.to_string(),
            commands: None,
            with_held: false,
            queue_capacity: ServerOptions::default().queue_capacity,
        }
    }
}

/// What a live session did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LiveReport {
    /// Samples received from the loop.
    pub samples: u64,
    /// Samples the loop published that the viewer never saw (it was behind).
    pub missed: u64,
    /// Messages handed to the server.
    pub messages: u64,
    /// The server's counters at the end.
    pub server: ServerStats,
}

impl std::fmt::Display for LiveReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.server;
        write!(
            f,
            "adam live: {} samples ({} missed), {} messages queued, {} sent; clients: {} \
             accepted, {} refused at the handshake, {} dropped as slow, {} closed for bad \
             messages; commands: {} forwarded, {} refused",
            self.samples,
            self.missed,
            self.messages,
            s.messages_sent,
            s.accepted,
            s.refused,
            s.slow_dropped,
            s.bad_closed,
            s.commands,
            s.commands_refused
        )
    }
}

/// A live server for `setup`'s robot with the feed's channels, started on `runtime`.
pub fn start_server(
    setup: &crate::Setup,
    options: &LiveOptions,
    runtime: &tokio::runtime::Handle,
) -> Result<(LiveServer, Feed)> {
    let layout = crate::slots::SlotLayout::new(&setup.config, options.with_held);
    let ctx = crate::telemetry::log::LogContext::new(setup, &layout);
    let feed = Feed::new(
        ctx.joint_names,
        ctx.output_names,
        ctx.scene,
        options.decimation.clone(),
    );
    let server_options = ServerOptions {
        name: format!("adam live ({})", setup.gait.robot.name),
        queue_capacity: options.queue_capacity,
        commands: options.commands.clone(),
        latched: vec![
            crate::telemetry::scene::SCENE_TOPIC.into(),
            crate::telemetry::scene::ROBOT_DESCRIPTION_TOPIC.into(),
        ],
    };
    let server = LiveServer::start(options.addr, feed.channels(), server_options, runtime)?;
    Ok((server, feed))
}

/// Serves the samples of `options.service` until `stop` is set: opens the server (calling
/// `started` with its address), then moves samples from iceoryx2 to the clients.
#[cfg(feature = "iceoryx2")]
pub fn serve(
    setup: &crate::Setup,
    options: &LiveOptions,
    stop: &AtomicBool,
    started: impl FnOnce(SocketAddr),
) -> Result<LiveReport> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .thread_name("adam-live")
        .enable_all()
        .build()
        .map_err(|e| crate::RuntimeError::Thread {
            name: "adam-live",
            message: e.to_string(),
        })?;
    let (server, mut feed) = start_server(setup, options, runtime.handle())?;
    // Subscribed before `started`: a run started after it loses no sample to a late viewer.
    let mut source = source::SampleSource::open(&options.service)?;
    started(server.local_addr());
    let mut report = LiveReport::default();
    let mut samples = Vec::with_capacity(crate::telemetry::sample::SUBSCRIBER_BUFFER);
    let mut out = Vec::new();
    while !stop.load(Ordering::Acquire) {
        samples.clear();
        if source.drain(&mut samples)? == 0 {
            std::thread::sleep(std::time::Duration::from_millis(1));
            continue;
        }
        for s in &samples {
            out.clear();
            feed.push(s, &mut out);
            report.messages += out.len() as u64;
            for o in out.drain(..) {
                server.publish(o);
            }
        }
        report.samples += samples.len() as u64;
    }
    report.missed = source.missed();
    report.server = server.stats();
    server.stop();
    runtime.shutdown_timeout(std::time::Duration::from_secs(1));
    Ok(report)
}
