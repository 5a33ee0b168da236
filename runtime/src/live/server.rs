//! The live view's WebSocket server on tokio: one task per client, fed by a broadcast channel.
//!
//! ```text
//! publish(Outgoing) ─▶ tokio broadcast (bounded) ─▶ client task ─▶ its subscriptions ─▶ WebSocket
//!   (any thread, never waits)                        ├─ behind by more than the queue, or a send
//!                                                    │  stuck for SEND_TIMEOUT → dropped (slow)
//!                                                    └─ malformed or oversized message → error
//!                                                       status, that connection closed (bad)
//! ```
//! The handshake must offer the subprotocol [`SUBPROTOCOL`] (the protocol version); a client
//! that does not is refused with HTTP 400 and a body that names what it offered. A subscription
//! to an unknown channel gets an error status and nothing else happens. Client publishing
//! (operator commands) is only advertised and accepted when a [`CommandSink`] is given.

use super::feed::Outgoing;
use super::protocol::{self, ClientData, ClientMessage, Level, ServerChannel, SUBPROTOCOL};
use crate::control::OperatorCommand;
use futures_util::{SinkExt, StreamExt};
use std::collections::{BTreeMap, HashMap};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::broadcast;
use tokio_tungstenite::tungstenite::handshake::server::{ErrorResponse, Request, Response};
use tokio_tungstenite::tungstenite::http::{HeaderValue, StatusCode};
use tokio_tungstenite::tungstenite::protocol::{
    frame::coding::CloseCode, CloseFrame, WebSocketConfig,
};
use tokio_tungstenite::tungstenite::Message;

/// Largest message a client may send, bytes (a subscription list or a command is far smaller).
pub const MAX_CLIENT_MESSAGE_BYTES: usize = 64 * 1024;
/// A send to a client that takes longer than this drops the client (it stopped reading).
pub const SEND_TIMEOUT: Duration = Duration::from_secs(2);

/// Where operator commands from clients go (`adam live --live-commands`): returns how many
/// runtimes received it, or why not. Called off the async threads.
pub type CommandSink =
    Arc<dyn Fn(OperatorCommand) -> Result<usize, String> + Send + Sync + 'static>;

/// How to serve.
#[derive(Clone)]
pub struct ServerOptions {
    /// The server's name in `serverInfo`.
    pub name: String,
    /// Messages queued for the clients before a client that is behind is dropped.
    pub queue_capacity: usize,
    /// Operator commands from clients (`None`: read-only, no client publishing).
    pub commands: Option<CommandSink>,
    /// Topics whose last message a new subscriber gets at once (the URDF, the scene).
    pub latched: Vec<String>,
}

impl Default for ServerOptions {
    fn default() -> Self {
        Self {
            name: "adam live".into(),
            queue_capacity: 4096,
            commands: None,
            latched: Vec::new(),
        }
    }
}

/// What the server has seen so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ServerStats {
    /// Clients connected now.
    pub connected: u64,
    /// Clients that completed the handshake, ever.
    pub accepted: u64,
    /// Clients refused at the handshake (another protocol or version).
    pub refused: u64,
    /// Clients dropped for being too slow.
    pub slow_dropped: u64,
    /// Connections closed for a malformed or oversized message.
    pub bad_closed: u64,
    /// Operator commands forwarded.
    pub commands: u64,
    /// Client publications refused (read-only server, unknown channel, not a command).
    pub commands_refused: u64,
    /// Messages sent to clients.
    pub messages_sent: u64,
}

#[derive(Default)]
struct Counters {
    connected: AtomicU64,
    accepted: AtomicU64,
    refused: AtomicU64,
    slow_dropped: AtomicU64,
    bad_closed: AtomicU64,
    commands: AtomicU64,
    commands_refused: AtomicU64,
    messages_sent: AtomicU64,
}

fn bump(c: &AtomicU64) {
    c.fetch_add(1, Ordering::Relaxed);
}

struct Hub {
    channels: Vec<ServerChannel>,
    options: ServerOptions,
    session_id: String,
    counters: Counters,
    latched: Mutex<BTreeMap<u32, Outgoing>>,
    latched_ids: Vec<u32>,
}

/// A running server: publish messages to it from any thread.
pub struct LiveServer {
    addr: SocketAddr,
    hub: Arc<Hub>,
    tx: broadcast::Sender<Outgoing>,
    accept: tokio::task::JoinHandle<()>,
}

impl LiveServer {
    /// Binds `addr` and starts accepting on `runtime`; a port in use is an error naming it.
    pub fn start(
        addr: SocketAddr,
        channels: Vec<ServerChannel>,
        options: ServerOptions,
        runtime: &tokio::runtime::Handle,
    ) -> crate::Result<Self> {
        let bind_err = |error: std::io::Error| crate::RuntimeError::Live {
            addr,
            message: if error.kind() == std::io::ErrorKind::AddrInUse {
                format!("{error} (the port is in use: another `adam live`? name another address)")
            } else {
                error.to_string()
            },
        };
        let std_listener = std::net::TcpListener::bind(addr).map_err(bind_err)?;
        std_listener.set_nonblocking(true).map_err(bind_err)?;
        let local = std_listener.local_addr().map_err(bind_err)?;
        let listener = {
            let _guard = runtime.enter();
            tokio::net::TcpListener::from_std(std_listener).map_err(bind_err)?
        };
        let latched_ids = channels
            .iter()
            .filter(|c| options.latched.contains(&c.topic))
            .map(|c| c.id)
            .collect();
        let (tx, _) = broadcast::channel(options.queue_capacity.max(16));
        let session_id = format!(
            "{}",
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_millis())
        );
        let hub = Arc::new(Hub {
            channels,
            options,
            session_id,
            counters: Counters::default(),
            latched: Mutex::new(BTreeMap::new()),
            latched_ids,
        });
        let (hub_a, tx_a) = (hub.clone(), tx.clone());
        let accept = runtime.spawn(async move {
            loop {
                let Ok((stream, peer)) = listener.accept().await else {
                    // Out of file descriptors, say: wait instead of spinning.
                    tokio::time::sleep(Duration::from_millis(100)).await;
                    continue;
                };
                let _ = stream.set_nodelay(true);
                let rx = tx_a.subscribe();
                tokio::spawn(serve_client(stream, peer, hub_a.clone(), rx));
            }
        });
        eprintln!("adam live: serving Foxglove WebSocket ({SUBPROTOCOL}) on ws://{local}");
        Ok(Self {
            addr: local,
            hub,
            tx,
            accept,
        })
    }

    /// The address the server listens on (the port chosen when 0 was asked for).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Queues a message for every subscribed client; never waits.
    pub fn publish(&self, message: Outgoing) {
        if self.hub.latched_ids.contains(&message.channel) {
            if let Ok(mut l) = self.hub.latched.lock() {
                l.insert(message.channel, message.clone());
            }
        }
        // No receiver (no client) is not an error.
        let _ = self.tx.send(message);
    }

    /// The counters.
    pub fn stats(&self) -> ServerStats {
        let c = &self.hub.counters;
        let get = |a: &AtomicU64| a.load(Ordering::Relaxed);
        ServerStats {
            connected: get(&c.connected),
            accepted: get(&c.accepted),
            refused: get(&c.refused),
            slow_dropped: get(&c.slow_dropped),
            bad_closed: get(&c.bad_closed),
            commands: get(&c.commands),
            commands_refused: get(&c.commands_refused),
            messages_sent: get(&c.messages_sent),
        }
    }

    /// Stops accepting (connected clients end with the runtime).
    pub fn stop(self) {
        self.accept.abort();
    }
}

/// Accepts the handshake if the client offers [`SUBPROTOCOL`].
#[allow(clippy::result_large_err)]
fn negotiate(request: &Request, mut response: Response) -> Result<Response, ErrorResponse> {
    let offered: Vec<String> = request
        .headers()
        .get_all("Sec-WebSocket-Protocol")
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(',').map(|p| p.trim().to_string()))
        .collect();
    if offered.iter().any(|p| p == SUBPROTOCOL) {
        response.headers_mut().insert(
            "Sec-WebSocket-Protocol",
            HeaderValue::from_static(SUBPROTOCOL),
        );
        return Ok(response);
    }
    let body = format!(
        "adam live speaks the Foxglove WebSocket protocol {SUBPROTOCOL}; the client offered {}",
        if offered.is_empty() {
            "no subprotocol".to_string()
        } else {
            offered.join(", ")
        }
    );
    let mut refusal = ErrorResponse::new(Some(body));
    *refusal.status_mut() = StatusCode::BAD_REQUEST;
    Err(refusal)
}

/// Why a client's connection ends.
enum End {
    Gone,
    Slow(String),
    Bad(String),
}

async fn serve_client(
    stream: tokio::net::TcpStream,
    peer: SocketAddr,
    hub: Arc<Hub>,
    mut rx: broadcast::Receiver<Outgoing>,
) {
    let config = WebSocketConfig::default()
        .max_message_size(Some(MAX_CLIENT_MESSAGE_BYTES))
        .max_frame_size(Some(MAX_CLIENT_MESSAGE_BYTES));
    let mut ws = match tokio_tungstenite::accept_hdr_async_with_config(
        stream,
        negotiate,
        Some(config),
    )
    .await
    {
        Ok(ws) => ws,
        Err(e) => {
            bump(&hub.counters.refused);
            eprintln!("adam live: refused {peer}: {e}");
            return;
        }
    };
    bump(&hub.counters.accepted);
    hub.counters.connected.fetch_add(1, Ordering::Relaxed);
    eprintln!("adam live: client {peer} connected");
    let end = session(&mut ws, peer, &hub, &mut rx).await;
    hub.counters.connected.fetch_sub(1, Ordering::Relaxed);
    match end {
        End::Gone => eprintln!("adam live: client {peer} disconnected"),
        End::Slow(why) => {
            bump(&hub.counters.slow_dropped);
            eprintln!("adam live: dropped slow client {peer}: {why}");
        }
        End::Bad(why) => {
            bump(&hub.counters.bad_closed);
            eprintln!("adam live: closed client {peer}: {why}");
            let text = protocol::status(Level::Error, &why);
            let _ = tokio::time::timeout(SEND_TIMEOUT, ws.send(Message::text(text))).await;
            let frame = CloseFrame {
                code: CloseCode::Policy,
                reason: why.chars().take(100).collect::<String>().into(),
            };
            let _ = tokio::time::timeout(SEND_TIMEOUT, ws.close(Some(frame))).await;
        }
    }
}

type Ws = tokio_tungstenite::WebSocketStream<tokio::net::TcpStream>;

async fn send(ws: &mut Ws, message: Message) -> Result<(), End> {
    match tokio::time::timeout(SEND_TIMEOUT, ws.send(message)).await {
        Ok(Ok(())) => Ok(()),
        Ok(Err(_)) => Err(End::Gone),
        Err(_) => Err(End::Slow(format!(
            "a send waited more than {} s (the client stopped reading)",
            SEND_TIMEOUT.as_secs()
        ))),
    }
}

async fn session(
    ws: &mut Ws,
    peer: SocketAddr,
    hub: &Hub,
    rx: &mut broadcast::Receiver<Outgoing>,
) -> End {
    let info = protocol::server_info(
        &hub.options.name,
        hub.options.commands.is_some(),
        &hub.session_id,
    );
    if let Err(e) = send(ws, Message::text(info)).await {
        return e;
    }
    if let Err(e) = send(ws, Message::text(protocol::advertise(&hub.channels))).await {
        return e;
    }
    // channel id → subscription id; client channel id → topic.
    let mut subscriptions: HashMap<u32, u32> = HashMap::new();
    let mut client_channels: HashMap<u32, String> = HashMap::new();
    loop {
        tokio::select! {
            incoming = ws.next() => {
                let message = match incoming {
                    None | Some(Ok(Message::Close(_))) => return End::Gone,
                    Some(Err(e)) => return ended_by(e),
                    Some(Ok(m)) => m,
                };
                let replies = match message {
                    Message::Text(text) => match ClientMessage::parse(text.as_str()) {
                        Ok(m) => on_message(m, hub, &mut subscriptions, &mut client_channels),
                        Err(e) => return End::Bad(e.to_string()),
                    },
                    Message::Binary(bytes) => match ClientData::parse(&bytes) {
                        Ok(d) => on_data(d, peer, hub, &client_channels).await,
                        Err(e) => return End::Bad(e.to_string()),
                    },
                    _ => Vec::new(),
                };
                for reply in replies {
                    if let Err(e) = send(ws, reply).await {
                        return e;
                    }
                }
            }
            out = rx.recv() => match out {
                Ok(o) => {
                    if let Some(&sub) = subscriptions.get(&o.channel) {
                        let bytes = protocol::message_data(sub, o.t_ns, &o.payload);
                        if let Err(e) = send(ws, Message::binary(bytes)).await {
                            return e;
                        }
                        bump(&hub.counters.messages_sent);
                    }
                }
                Err(broadcast::error::RecvError::Lagged(n)) => {
                    return End::Slow(format!("{n} messages behind the queue of {}",
                        hub.options.queue_capacity));
                }
                Err(broadcast::error::RecvError::Closed) => return End::Gone,
            }
        }
    }
}

/// How a read error ends the session: a client that went away is gone; a message too large,
/// not UTF-8 or breaking the WebSocket protocol is a bad client.
fn ended_by(e: tokio_tungstenite::tungstenite::Error) -> End {
    use tokio_tungstenite::tungstenite::error::ProtocolError as Ws;
    use tokio_tungstenite::tungstenite::Error as E;
    match e {
        E::ConnectionClosed
        | E::AlreadyClosed
        | E::Io(_)
        | E::Protocol(Ws::ResetWithoutClosingHandshake) => End::Gone,
        E::Capacity(c) => End::Bad(format!(
            "message too large ({c}; at most {MAX_CLIENT_MESSAGE_BYTES} bytes)"
        )),
        other => End::Bad(format!("unreadable message: {other}")),
    }
}

/// Handles a text message; returns the replies to send.
fn on_message(
    message: ClientMessage,
    hub: &Hub,
    subscriptions: &mut HashMap<u32, u32>,
    client_channels: &mut HashMap<u32, String>,
) -> Vec<Message> {
    let mut replies = Vec::new();
    let error = |text: String| Message::text(protocol::status(Level::Error, &text));
    match message {
        ClientMessage::Subscribe(list) => {
            for s in list {
                if !hub.channels.iter().any(|c| c.id == s.channel_id) {
                    replies.push(error(format!(
                        "subscribe: no channel {} (subscription {}); channels are 1..={}",
                        s.channel_id,
                        s.id,
                        hub.channels.len()
                    )));
                    continue;
                }
                subscriptions.insert(s.channel_id, s.id);
                let latched = hub
                    .latched
                    .lock()
                    .ok()
                    .and_then(|l| l.get(&s.channel_id).cloned());
                if let Some(o) = latched {
                    replies.push(Message::binary(protocol::message_data(
                        s.id, o.t_ns, &o.payload,
                    )));
                }
            }
        }
        ClientMessage::Unsubscribe(ids) => subscriptions.retain(|_, sub| !ids.contains(sub)),
        ClientMessage::Advertise(channels) => {
            if hub.options.commands.is_none() {
                replies.push(error(
                    "read-only: this viewer takes no commands (start it with --live-commands)"
                        .into(),
                ));
            } else {
                for c in channels {
                    if c.encoding != "json" {
                        replies.push(error(format!(
                            "advertise: channel {} ({}) has encoding `{}`; only json is accepted",
                            c.id, c.topic, c.encoding
                        )));
                        continue;
                    }
                    client_channels.insert(c.id, c.topic);
                }
            }
        }
        ClientMessage::Unadvertise(ids) => client_channels.retain(|id, _| !ids.contains(id)),
    }
    replies
}

/// The operator command in a client's JSON message: `{"command": "walk"}` (or `"belt 0.25"`).
pub fn command_of(payload: &[u8]) -> Result<OperatorCommand, String> {
    let v: serde_json::Value = serde_json::from_slice(payload)
        .map_err(|e| format!("not JSON ({e}); send {{\"command\": \"walk\"}}"))?;
    let text = v["command"]
        .as_str()
        .ok_or("no `command` string; send {\"command\": \"walk\"}")?;
    let command = OperatorCommand::parse(text).map_err(|e| format!("`{text}`: {e}"))?;
    if command == OperatorCommand::Reset {
        return Err(
            "`reset` clears a latched trip: only at the robot (keyboard or adam op)".into(),
        );
    }
    Ok(command)
}

/// Handles client message data: an operator command, if allowed.
async fn on_data(
    data: ClientData<'_>,
    peer: SocketAddr,
    hub: &Hub,
    client_channels: &HashMap<u32, String>,
) -> Vec<Message> {
    let status = |level, text: String| vec![Message::text(protocol::status(level, &text))];
    let Some(sink) = hub.options.commands.clone() else {
        bump(&hub.counters.commands_refused);
        eprintln!("adam live: refused a command from {peer}: read-only");
        return status(
            Level::Error,
            "read-only: this viewer takes no commands (start it with --live-commands)".into(),
        );
    };
    let Some(topic) = client_channels.get(&data.channel_id) else {
        bump(&hub.counters.commands_refused);
        return status(
            Level::Error,
            format!(
                "message on channel {} that was not advertised",
                data.channel_id
            ),
        );
    };
    let command = match command_of(data.payload) {
        Ok(c) => c,
        Err(e) => {
            bump(&hub.counters.commands_refused);
            eprintln!("adam live: refused a command from {peer} on {topic}: {e}");
            return status(Level::Error, format!("command refused: {e}"));
        }
    };
    let sent = tokio::task::spawn_blocking(move || sink(command))
        .await
        .unwrap_or_else(|e| Err(e.to_string()));
    match sent {
        Ok(n) => {
            bump(&hub.counters.commands);
            eprintln!(
                "adam live: command `{}` from {peer} on {topic} → {n} runtime(s)",
                command.text()
            );
            status(
                Level::Info,
                format!("`{}` sent to {n} runtime(s)", command.text()),
            )
        }
        Err(e) => {
            bump(&hub.counters.commands_refused);
            eprintln!(
                "adam live: command `{}` from {peer} failed: {e}",
                command.text()
            );
            status(Level::Error, format!("`{}` not sent: {e}", command.text()))
        }
    }
}
