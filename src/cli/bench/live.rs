//! `adam bench live`: the loop's wake-up jitter and tick compute time on the simulated robot in
//! real time, publishing to `adam live` in its own process, with 0 and with N Foxglove clients
//! subscribed to every channel; a row per client count.

use anyhow::{bail, Context, Result};
use futures_util::{SinkExt, StreamExt};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;

/// Arguments of `adam bench live`.
#[derive(clap::Args)]
pub(crate) struct LiveBenchArgs {
    /// Client counts, one row each.
    #[arg(long, value_delimiter = ',', default_value = "0,3")]
    clients: Vec<usize>,
    /// Wall-clock seconds of walking per row.
    #[arg(long, default_value_t = 20.0)]
    seconds: f64,
    /// Runtime config (TOML).
    #[arg(long, default_value = crate::cli::shipped::RUNTIME_CONFIG)]
    config: std::path::PathBuf,
    /// Gait file (JSON).
    #[arg(long, default_value = runtime::DEFAULT_GAIT)]
    gait: std::path::PathBuf,
}

/// One row of the table.
struct Row {
    clients: usize,
    jitter: runtime::rt_loop::TickTimes,
    tick: runtime::rt_loop::TickTimes,
    overruns: u64,
    received: u64,
}

fn us(ns: u64) -> f64 {
    ns as f64 * 1e-3
}

/// `adam bench live`.
pub(crate) fn live(args: &LiveBenchArgs) -> Result<()> {
    if !(args.seconds.is_finite() && args.seconds > 0.0) {
        bail!("--seconds {}: must be more than 0", args.seconds);
    }
    let config = crate::cli::shipped::input(&args.config);
    let gait = crate::cli::shipped::input(&args.gait);
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()?;
    let mut rows = Vec::new();
    for &clients in &args.clients {
        rows.push(row(&config, &gait, clients, args.seconds, &rt)?);
    }
    println!(
        "loop at 1 kHz on the simulated robot in real time ({} s per row), `adam live` in its own \
         process (default decimation), clients subscribed to every channel",
        args.seconds
    );
    println!(
        "| clients | wake-up jitter p50 / p99 / max (µs) | tick compute p50 / p99 / max (µs) | overruns | messages received |"
    );
    println!("|---|---|---|---|---|");
    for r in rows {
        println!(
            "| {} | {:.1} / {:.1} / {:.1} | {:.1} / {:.1} / {:.1} | {} | {} |",
            r.clients,
            us(r.jitter.median_ns),
            us(r.jitter.p99_ns),
            us(r.jitter.max_ns),
            us(r.tick.median_ns),
            us(r.tick.p99_ns),
            us(r.tick.max_ns),
            r.overruns,
            r.received
        );
    }
    Ok(())
}

fn row(
    config: &Path,
    gait: &Path,
    clients: usize,
    seconds: f64,
    rt: &tokio::runtime::Runtime,
) -> Result<Row> {
    let mut setup = runtime::Setup::load(config, gait)?;
    let service = format!(
        "adam/bench/live/{}/{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos())
    );
    setup.config.telemetry.service_name = service.clone();
    // A free port for the viewer.
    let addr = std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?;
    let exe = std::env::current_exe()?;
    let mut child = std::process::Command::new(exe)
        .args(["live", "--until-stdin-closes", "--service", &service])
        .arg("--addr")
        .arg(addr.to_string())
        .arg("--config")
        .arg(config)
        .arg("--gait")
        .arg(gait)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .context("starting `adam live`")?;
    let received = Arc::new(AtomicU64::new(0));
    let result = rt.block_on(async {
        let mut tasks = Vec::new();
        for _ in 0..clients {
            let mut ws = connect(addr).await?;
            let received = received.clone();
            tasks.push(tokio::spawn(async move {
                while let Some(Ok(m)) = ws.next().await {
                    if matches!(m, Message::Binary(_)) {
                        received.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }));
        }
        let mut options = runtime::sim::run::SimWalkOptions::new(seconds);
        options.real_time = true;
        options.publish = true;
        let report = tokio::task::spawn_blocking(move || runtime::sim::run::walk(&setup, &options))
            .await??;
        for t in tasks {
            t.abort();
        }
        anyhow::Ok(report)
    });
    drop(child.stdin.take());
    let _ = child.wait();
    let report = result?;
    let s = &report.summary;
    Ok(Row {
        clients,
        jitter: s.wake_latency,
        tick: s.tick_times,
        overruns: s.overruns,
        received: received.load(Ordering::Relaxed),
    })
}

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// Connects (retrying while the viewer starts) and subscribes to every advertised channel.
async fn connect(addr: std::net::SocketAddr) -> Result<Ws> {
    let mut last = None;
    for _ in 0..300 {
        let mut request = format!("ws://{addr}").into_client_request()?;
        request.headers_mut().insert(
            "Sec-WebSocket-Protocol",
            runtime::live::protocol::SUBPROTOCOL.parse()?,
        );
        match tokio_tungstenite::connect_async(request).await {
            Ok((mut ws, _)) => {
                // serverInfo, then advertise.
                let mut channels = Vec::new();
                while channels.is_empty() {
                    let Some(Ok(Message::Text(t))) = ws.next().await else {
                        bail!("`adam live` closed before advertising");
                    };
                    let v: serde_json::Value = serde_json::from_str(t.as_str())?;
                    if v["op"] == "advertise" {
                        channels = v["channels"].as_array().cloned().unwrap_or_default();
                    }
                }
                let subs: Vec<serde_json::Value> = channels
                    .iter()
                    .map(|c| serde_json::json!({"id": c["id"], "channelId": c["id"]}))
                    .collect();
                let text = serde_json::json!({"op": "subscribe", "subscriptions": subs});
                ws.send(Message::text(text.to_string())).await?;
                return Ok(ws);
            }
            Err(e) => last = Some(e),
        }
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
    bail!("cannot connect to `adam live` on {addr}: {last:?}")
}
