//! The live view end to end: a Foxglove WebSocket client (tokio-tungstenite) against
//! `runtime::live`, fed by a real loop over iceoryx2 or by synthetic samples.
//!
//! No assertion on wall-clock durations: every wait is a generous timeout that only bounds a
//! hung test (the machine may be loaded), and counts are checked, not rates.

mod common;

use common::adam;
use futures_util::{SinkExt, StreamExt};
use runtime::live::feed::{channel_id, Decimation, Feed};
use runtime::live::protocol::{parse_message_data, ClientData, SUBPROTOCOL};
use runtime::live::server::{LiveServer, ServerOptions};
use runtime::telemetry::sample::StateSample;
use serde_json::Value;
use std::collections::{BTreeMap, HashMap};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// A generous bound on any single wait: only a hung test reaches it.
const PATIENCE: Duration = Duration::from_secs(60);

fn unique(tag: &str) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .expect("clock")
        .as_nanos();
    format!("adam/test/live/{tag}/{}/{nanos}", std::process::id())
}

async fn connect_with(addr: SocketAddr, protocol: Option<&str>) -> Result<Ws, String> {
    let mut request = format!("ws://{addr}")
        .into_client_request()
        .expect("request");
    if let Some(p) = protocol {
        request
            .headers_mut()
            .insert("Sec-WebSocket-Protocol", p.parse().expect("header"));
    }
    match tokio::time::timeout(PATIENCE, tokio_tungstenite::connect_async(request)).await {
        Ok(Ok((ws, _))) => Ok(ws),
        Ok(Err(tokio_tungstenite::tungstenite::Error::Http(response))) => Err(format!(
            "HTTP {}: {}",
            response.status(),
            response
                .body()
                .as_ref()
                .map(|b| String::from_utf8_lossy(b).to_string())
                .unwrap_or_default()
        )),
        Ok(Err(e)) => Err(e.to_string()),
        Err(_) => Err("timed out".into()),
    }
}

/// Connects, reads `serverInfo` and `advertise`; returns the socket and topic → channel id.
async fn connect(addr: SocketAddr) -> (Ws, Value, HashMap<String, u32>) {
    let mut ws = connect_with(addr, Some(SUBPROTOCOL))
        .await
        .expect("connect");
    let info = next_json(&mut ws).await;
    assert_eq!(info["op"], "serverInfo", "{info}");
    let adv = next_json(&mut ws).await;
    assert_eq!(adv["op"], "advertise", "{adv}");
    let mut ids = HashMap::new();
    for c in adv["channels"].as_array().expect("channels") {
        ids.insert(
            c["topic"].as_str().expect("topic").to_string(),
            c["id"].as_u64().expect("id") as u32,
        );
        assert_eq!(c["encoding"], "json");
        assert_eq!(c["schemaEncoding"], "jsonschema");
        serde_json::from_str::<Value>(c["schema"].as_str().expect("schema")).expect("schema JSON");
    }
    (ws, info, ids)
}

async fn next_message(ws: &mut Ws) -> Option<Message> {
    match tokio::time::timeout(PATIENCE, ws.next()).await {
        Ok(Some(Ok(m))) => Some(m),
        _ => None,
    }
}

async fn next_json(ws: &mut Ws) -> Value {
    loop {
        match next_message(ws).await.expect("a message") {
            Message::Text(t) => return serde_json::from_str(t.as_str()).expect("JSON"),
            Message::Binary(_) => continue,
            other => panic!("unexpected {other:?}"),
        }
    }
}

/// The next status message (skipping data).
async fn next_status(ws: &mut Ws) -> Value {
    loop {
        let v = next_json(ws).await;
        if v["op"] == "status" {
            return v;
        }
    }
}

async fn subscribe(ws: &mut Ws, subs: &[(u32, u32)]) {
    let list: Vec<Value> = subs
        .iter()
        .map(|(id, ch)| serde_json::json!({"id": id, "channelId": ch}))
        .collect();
    let text = serde_json::json!({"op": "subscribe", "subscriptions": list}).to_string();
    ws.send(Message::text(text)).await.expect("send");
}

/// The next data message: (subscription id, time ns, JSON).
async fn next_data(ws: &mut Ws) -> Option<(u32, u64, Value)> {
    loop {
        match next_message(ws).await? {
            Message::Binary(b) => {
                let (sub, t, payload) = parse_message_data(&b).expect("messageData");
                return Some((
                    sub,
                    t,
                    serde_json::from_slice(payload).expect("JSON payload"),
                ));
            }
            Message::Close(_) => return None,
            _ => continue,
        }
    }
}

fn shipped_setup(service: &str) -> runtime::Setup {
    let mut setup = runtime::Setup::shipped().expect("shipped setup");
    setup.config.telemetry.service_name = service.to_string();
    setup
}

fn temp_log(tag: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("{}.mcap", unique(tag).replace('/', "-")))
}

/// Every message of the log by topic, with its log time (ns).
fn log_messages(path: &std::path::Path) -> BTreeMap<String, Vec<(u64, Value)>> {
    let bytes = std::fs::read(path).expect("log");
    let mut out: BTreeMap<String, Vec<(u64, Value)>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).expect("mcap") {
        let m = m.expect("message");
        let v: Value = serde_json::from_slice(&m.data).expect("JSON");
        out.entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, v));
    }
    out
}

/// The live `/joints` (subscription 1) and `/estimator` (2): at least 100 messages over at
/// least 1 s, each equal to the log's message of the same time stamp.
fn assert_live_equals_log(received: &BTreeMap<u32, Vec<(u64, Value)>>, log: &std::path::Path) {
    let logged = log_messages(log);
    for (sub, topic) in [(1, "/joints"), (2, "/estimator")] {
        let by_time: HashMap<u64, &Value> = logged[topic].iter().map(|(t, v)| (*t, v)).collect();
        let got = received.get(&sub).map(Vec::as_slice).unwrap_or_default();
        assert!(got.len() >= 100, "{topic}: {} messages", got.len());
        let span_s = (got[got.len() - 1].0 - got[0].0) as f64 * 1e-9;
        assert!(span_s >= 1.0, "{topic}: {span_s} s of samples");
        for (t, v) in got {
            let l = by_time
                .get(t)
                .unwrap_or_else(|| panic!("{topic} at {t} ns is not in the log"));
            assert_eq!(*l, v, "{topic} at {t} ns");
        }
    }
}

/// `adam live` (runtime::live::serve) on its own thread, on a port the OS picks.
fn start_live(
    setup: &runtime::Setup,
    decimate: &str,
    queue: usize,
) -> (
    SocketAddr,
    Arc<AtomicBool>,
    std::thread::JoinHandle<runtime::live::LiveReport>,
) {
    let addr: SocketAddr = "127.0.0.1:0".parse().expect("addr");
    let mut options = runtime::live::LiveOptions::new(addr, &setup.config.telemetry.service_name);
    options.decimation = Decimation::parse(decimate, "test").expect("decimation");
    options.queue_capacity = queue;
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = std::sync::mpsc::channel();
    let (setup, stop_s) = (setup.clone(), stop.clone());
    let handle = std::thread::spawn(move || {
        runtime::live::serve(&setup, &options, &stop_s, |a| {
            tx.send(a).expect("send addr")
        })
        .expect("serve")
    });
    let addr = rx.recv_timeout(PATIENCE).expect("the server started");
    (addr, stop, handle)
}

fn paced_walk(
    setup: &runtime::Setup,
    duration_s: f64,
    log: &std::path::Path,
) -> std::thread::JoinHandle<runtime::sim::run::SimWalkReport> {
    let mut options = runtime::sim::run::SimWalkOptions::new(duration_s);
    options.real_time = true;
    options.publish = true;
    options.log_path = Some(log.to_path_buf());
    let setup = setup.clone();
    std::thread::spawn(move || runtime::sim::run::walk(&setup, &options).expect("walk"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn live_samples_match_the_mcap_log_of_the_same_run() {
    let setup = shipped_setup(&unique("match"));
    let (addr, stop, live) = start_live(&setup, "/joints=1,/estimator=1,/tf=10", 65536);
    let (mut ws, info, ids) = connect(addr).await;
    assert!(
        info["capabilities"].as_array().expect("caps").is_empty(),
        "read-only: {info}"
    );
    for topic in runtime::live::feed::topics() {
        assert!(ids.contains_key(topic), "{topic} advertised");
    }
    subscribe(
        &mut ws,
        &[
            (1, ids["/joints"]),
            (2, ids["/estimator"]),
            (3, ids["/tf"]),
            (4, ids["/robot_description"]),
            (5, ids["/scene"]),
        ],
    )
    .await;
    let log = temp_log("match");
    let walk = paced_walk(&setup, 3.0, &log);
    let mut received: BTreeMap<u32, Vec<(u64, Value)>> = BTreeMap::new();
    // Until the walk ends and the stream goes quiet.
    loop {
        let done = walk.is_finished();
        match tokio::time::timeout(Duration::from_secs(3), next_data(&mut ws)).await {
            Ok(Some((sub, t, v))) => received.entry(sub).or_default().push((t, v)),
            _ if done => break,
            Ok(None) => panic!("connection closed"),
            Err(_) => {}
        }
    }
    let report = walk.join().expect("walk");
    stop.store(true, Ordering::Release);
    let live = live.join().expect("live");
    assert_eq!(report.summary.publish_failures, 0);
    assert_eq!(live.server.slow_dropped, 0);

    assert_live_equals_log(&received, &log);
    // The robot in 3D: both trees, every transform finite; the URDF and the belt.
    let tf = &received[&3];
    assert!(tf.len() >= 10, "{} /tf messages", tf.len());
    let (_, last) = &tf[tf.len() - 1];
    let transforms = last["transforms"].as_array().expect("transforms");
    let children: Vec<&str> = transforms
        .iter()
        .map(|t| t["child_frame_id"].as_str().expect("child"))
        .collect();
    assert!(
        children.contains(&"torso") && children.contains(&"truth/torso"),
        "{children:?}"
    );
    assert!(children.contains(&"left_shin") && children.contains(&"truth/right_shin"));
    for t in transforms {
        for k in ["x", "y", "z"] {
            assert!(t["translation"][k].as_f64().expect("number").is_finite());
        }
    }
    assert!(received[&4][0].1["data"]
        .as_str()
        .expect("urdf")
        .contains("<robot name=\"adam_planar\">"));
    let belt = &received[&5][0].1["entities"][0];
    assert_eq!(belt["id"], "belt");
    // The same scene channels are in the log.
    let logged = log_messages(&log);
    for topic in ["/tf", "/scene", "/robot_description"] {
        assert!(!logged[topic].is_empty(), "{topic} logged");
    }
    std::fs::remove_file(&log).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_that_stops_reading_is_dropped_and_the_loop_is_not_disturbed() {
    let setup = shipped_setup(&unique("slow"));
    // The URDF every tick: about 6 MB/s for the stalled client to fall behind on.
    let (addr, stop, live) = start_live(&setup, "/robot_description=1,/state=10", 16384);
    let (mut stalled, _, ids) = connect(addr).await;
    subscribe(&mut stalled, &[(1, ids["/robot_description"])]).await;
    let (mut reader, _, _) = connect(addr).await;
    subscribe(&mut reader, &[(7, ids["/state"])]).await;
    let log = temp_log("slow");
    let walk = paced_walk(&setup, 8.0, &log);
    let mut last_t_s = 0.0f64;
    let mut count = 0u64;
    loop {
        let done = walk.is_finished();
        match tokio::time::timeout(Duration::from_secs(3), next_data(&mut reader)).await {
            Ok(Some((7, _, v))) => {
                count += 1;
                last_t_s = v["t_s"].as_f64().expect("t_s");
            }
            Ok(Some(_)) => {}
            _ if done => break,
            Ok(None) => panic!("the reading client was closed"),
            Err(_) => {}
        }
    }
    let report = walk.join().expect("walk");
    // The loop ran every tick and published every sample: it never waited for the viewer.
    assert_eq!(report.summary.ticks, 8000);
    assert_eq!(report.summary.publish_failures, 0);
    assert!(count >= 100, "{count} /state messages");
    assert!(
        last_t_s > 7.0,
        "the reader kept receiving: last at {last_t_s} s"
    );
    // The stalled client, reading again, finds its connection closed by the server.
    let closed = tokio::time::timeout(PATIENCE, async {
        while let Some(Ok(m)) = stalled.next().await {
            if matches!(m, Message::Close(_)) {
                break;
            }
        }
    })
    .await;
    assert!(closed.is_ok(), "the stalled client was not dropped");
    stop.store(true, Ordering::Release);
    let live = live.join().expect("live");
    assert_eq!(live.server.slow_dropped, 1, "{live}");
    std::fs::remove_file(&log).ok();
}

/// A server fed synthetic samples (no loop): 1 kHz of Walk samples on a tokio task.
fn synthetic_server(
    rt: &tokio::runtime::Handle,
    options: ServerOptions,
) -> (Arc<LiveServer>, tokio::task::JoinHandle<()>) {
    let setup = runtime::Setup::shipped().expect("setup");
    let layout = runtime::slots::SlotLayout::new(&setup.config, false);
    let ctx = runtime::telemetry::log::LogContext::new(&setup, &layout);
    let mut feed = Feed::new(
        ctx.joint_names,
        ctx.output_names,
        ctx.scene,
        Decimation::parse("/state=1", "test").expect("decimation"),
    );
    let server = Arc::new(
        LiveServer::start(
            "127.0.0.1:0".parse().expect("addr"),
            feed.channels(),
            options,
            rt,
        )
        .expect("start"),
    );
    let s = server.clone();
    let pump = rt.spawn(async move {
        let mut out = Vec::new();
        for tick in 0u64.. {
            let sample = StateSample {
                tick,
                t_s: tick as f64 * 1e-3,
                state: 3,
                ..StateSample::default()
            };
            out.clear();
            feed.push(&sample, &mut out);
            for o in out.drain(..) {
                s.publish(o);
            }
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
    });
    (server, pump)
}

/// Receives /state (subscription `sub`) until one arrives.
async fn receives_state(ws: &mut Ws, sub: u32) -> bool {
    while let Some((s, _, v)) = next_data(ws).await {
        if s == sub {
            return v["state"] == "walk";
        }
    }
    false
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_clients_are_closed_or_told_and_the_others_keep_receiving() {
    let rt = tokio::runtime::Handle::current();
    let (server, pump) = synthetic_server(&rt, ServerOptions::default());
    let addr = server.local_addr();
    let state = channel_id("/state").expect("/state");

    let (mut good, _, _) = connect(addr).await;
    subscribe(&mut good, &[(1, state)]).await;
    assert!(receives_state(&mut good, 1).await);

    // Malformed JSON: an error status naming it, then that connection is closed.
    let (mut garbage, _, _) = connect(addr).await;
    garbage
        .send(Message::text("{not json"))
        .await
        .expect("send");
    let status = next_status(&mut garbage).await;
    assert_eq!(status["level"], 2);
    assert!(
        status["message"]
            .as_str()
            .expect("msg")
            .contains("malformed"),
        "{status}"
    );
    assert!(
        next_data(&mut garbage).await.is_none(),
        "closed after garbage"
    );

    // An oversized message: closed.
    let (mut big, _, _) = connect(addr).await;
    let huge = "x".repeat(runtime::live::server::MAX_CLIENT_MESSAGE_BYTES + 1);
    let _ = big.send(Message::text(huge)).await;
    assert!(
        next_data(&mut big).await.is_none(),
        "closed after an oversized message"
    );

    // A subscription to an unknown channel: an error to that client, which stays connected.
    let (mut unknown, _, _) = connect(addr).await;
    subscribe(&mut unknown, &[(5, 999)]).await;
    let status = next_status(&mut unknown).await;
    assert!(
        status["message"]
            .as_str()
            .expect("msg")
            .contains("no channel 999"),
        "{status}"
    );
    subscribe(&mut unknown, &[(6, state)]).await;
    assert!(receives_state(&mut unknown, 6).await);

    // Another protocol version: refused at the handshake with a body that says why.
    let refused = connect_with(addr, Some("foxglove.websocket.v2"))
        .await
        .expect_err("refused");
    assert!(
        refused.contains("400") && refused.contains(SUBPROTOCOL),
        "{refused}"
    );
    let refused = connect_with(addr, None).await.expect_err("refused");
    assert!(refused.contains("no subprotocol"), "{refused}");

    // A read-only server refuses client publishing.
    good.send(Message::text(
        r#"{"op":"advertise","channels":[{"id":1,"topic":"/operator","encoding":"json","schemaName":"adam.Command"}]}"#,
    ))
    .await
    .expect("send");
    let status = next_status(&mut good).await;
    assert!(
        status["message"]
            .as_str()
            .expect("msg")
            .contains("read-only"),
        "{status}"
    );

    // The first client never noticed; a client that reconnects is served again.
    assert!(receives_state(&mut good, 1).await);
    drop(good);
    let (mut again, _, _) = connect(addr).await;
    subscribe(&mut again, &[(2, state)]).await;
    assert!(receives_state(&mut again, 2).await);

    let stats = server.stats();
    assert_eq!(stats.bad_closed, 2, "{stats:?}");
    assert_eq!(stats.refused, 2, "{stats:?}");
    assert_eq!(stats.slow_dropped, 0, "{stats:?}");

    // A port in use: an error naming it.
    let err = LiveServer::start(addr, Vec::new(), ServerOptions::default(), &rt)
        .err()
        .expect("the port is taken");
    let text = err.to_string();
    assert!(
        text.contains(&addr.to_string()) && text.contains("in use"),
        "{text}"
    );
    pump.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn with_live_commands_only_operator_commands_pass_each_logged() {
    let rt = tokio::runtime::Handle::current();
    let sent: Arc<Mutex<Vec<runtime::control::OperatorCommand>>> = Arc::default();
    let sink = sent.clone();
    let options = ServerOptions {
        commands: Some(Arc::new(move |c| {
            sink.lock().expect("lock").push(c);
            Ok(1)
        })),
        ..ServerOptions::default()
    };
    let (server, pump) = synthetic_server(&rt, options);
    let (mut ws, info, _) = connect(server.local_addr()).await;
    assert_eq!(info["capabilities"][0], "clientPublish");
    ws.send(Message::text(
        r#"{"op":"advertise","channels":[{"id":9,"topic":"/operator","encoding":"json","schemaName":"adam.Command"}]}"#,
    ))
    .await
    .expect("send");
    for (command, accepted) in [
        (r#"{"command":"walk"}"#, true),
        (r#"{"command":"belt 0.25"}"#, true),
        (r#"{"command":"reset"}"#, false),
        (r#"{"command":"fly"}"#, false),
        (r#"{"speed": 3}"#, false),
    ] {
        let bytes = ClientData::encode(9, command.as_bytes());
        ws.send(Message::binary(bytes)).await.expect("send");
        let status = next_status(&mut ws).await;
        assert_eq!(status["level"] == 0, accepted, "{command}: {status}");
    }
    // Data on a channel never advertised.
    ws.send(Message::binary(ClientData::encode(
        4,
        br#"{"command":"walk"}"#,
    )))
    .await
    .expect("send");
    let status = next_status(&mut ws).await;
    assert!(
        status["message"]
            .as_str()
            .expect("msg")
            .contains("not advertised"),
        "{status}"
    );
    use runtime::control::OperatorCommand as C;
    assert_eq!(
        *sent.lock().expect("lock"),
        vec![C::Walk, C::Belt { speed_mps: 0.25 }]
    );
    let stats = server.stats();
    assert_eq!(
        (stats.commands, stats.commands_refused),
        (2, 4),
        "{stats:?}"
    );
    pump.abort();
}

/// Every topic and field the shipped layout names exists in a log of a walk and in the live
/// server's advertisement.
#[test]
fn the_layout_names_only_topics_and_fields_of_a_log_and_of_the_live_server() {
    let setup = runtime::Setup::shipped().expect("setup");
    let log = temp_log("layout");
    let mut options = runtime::sim::run::SimWalkOptions::new(2.0);
    options.log_path = Some(log.clone());
    runtime::sim::run::walk(&setup, &options).expect("walk");
    let logged = log_messages(&log);
    let bytes = std::fs::read(&log).expect("log");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("summary");
    let log_topics: Vec<String> = summary.channels.values().map(|c| c.topic.clone()).collect();
    let live_topics = runtime::live::feed::topics();

    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/foxglove/adam.json"),
    )
    .expect("layout");
    let layout: Value = serde_json::from_str(&text).expect("layout JSON");
    let mut paths = Vec::new();
    fn collect(v: &Value, out: &mut Vec<String>) {
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    if let (true, Some(s)) = (
                        ["value", "topicPath", "topic"].contains(&k.as_str()),
                        x.as_str(),
                    ) {
                        if s.starts_with('/') {
                            out.push(s.to_string());
                        }
                    }
                    collect(x, out);
                }
            }
            Value::Array(a) => a.iter().for_each(|x| collect(x, out)),
            _ => {}
        }
    }
    collect(&layout, &mut paths);
    // The topics the 3D panel shows (the URDF, the scene) are keys of its `topics`.
    let panel_topics = layout["configById"]["3D!robot"]["topics"]
        .as_object()
        .expect("the 3D panel's topics");
    paths.extend(panel_topics.keys().cloned());
    assert!(paths.contains(&"/robot_description".to_string()));
    assert!(paths.len() >= 15, "{paths:?}");
    for path in &paths {
        let (topic, fields) = path.split_once('.').unwrap_or((path, ""));
        assert!(
            log_topics.iter().any(|t| t == topic),
            "{path}: {topic} not in the log"
        );
        assert!(
            live_topics.contains(&topic),
            "{path}: {topic} not advertised live"
        );
        if fields.is_empty() {
            continue;
        }
        let (_, last) = logged[topic].last().expect("messages");
        let mut v = last;
        for f in fields.split('.') {
            v = &v[f];
        }
        assert!(v.is_number() || v.is_string(), "{path}: {v} in {last}");
    }
    std::fs::remove_file(&log).ok();
}

/// `adam run --backend udp --live` against `adam emulate motors` in another process: the same
/// loop publishes its samples, `adam live` (its child) serves them, and every `/joints` and
/// `/estimator` message a client decodes is the log's at the same time; the robot's tree is in
/// `/tf` and, with no ground truth over UDP, no `truth/` tree.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn live_view_of_a_udp_run_matches_its_log() {
    let dir = std::env::temp_dir().join(unique("udp").replace('/', "-"));
    std::fs::create_dir_all(&dir).expect("temp dir");
    // The shipped config on a service of this test's own (runs in parallel must not meet).
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let shipped = std::fs::read_to_string(root.join("configs/runtime/adam.toml")).expect("config");
    let service = unique("udp-run");
    let text = shipped.replace(
        "service_name = \"adam/runtime/state\"",
        &format!("service_name = \"{service}\""),
    );
    assert_ne!(text, shipped, "the shipped config names its service");
    let config = dir.join("adam.toml");
    std::fs::write(&config, text).expect("write config");
    let log = dir.join("udp.mcap");

    let (mut emulator, mut emulator_out, motors) = common::spawn_emulator();
    let addr = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port");
    let run = adam()
        .args([
            "run",
            "--backend",
            "udp",
            "--motors",
            &motors,
            "--duration",
            "20s",
        ])
        .arg("--live")
        .arg(addr.to_string())
        .args(["--live-decimate", "/joints=5,/estimator=5,/tf=50"])
        .arg("--config")
        .arg(&config)
        .arg("--log")
        .arg(&log)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run");
    let run = tokio::task::spawn_blocking(move || run.wait_with_output());

    // The run starts once `adam live` serves; connect as soon as it listens.
    let mut attempt = 0;
    let mut ws = loop {
        match connect_with(addr, Some(SUBPROTOCOL)).await {
            Ok(ws) => break ws,
            Err(e) => {
                attempt += 1;
                assert!(attempt < 600, "adam live never listened on {addr}: {e}");
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
        }
    };
    assert_eq!(next_json(&mut ws).await["op"], "serverInfo");
    let adv = next_json(&mut ws).await;
    let ids: HashMap<String, u32> = adv["channels"]
        .as_array()
        .expect("channels")
        .iter()
        .map(|c| {
            let topic = c["topic"].as_str().expect("topic").to_string();
            (topic, c["id"].as_u64().expect("id") as u32)
        })
        .collect();
    subscribe(
        &mut ws,
        &[(1, ids["/joints"]), (2, ids["/estimator"]), (3, ids["/tf"])],
    )
    .await;
    let mut received: BTreeMap<u32, Vec<(u64, Value)>> = BTreeMap::new();
    // Until the run ends: its viewer then stops and closes the connection.
    while let Some((sub, t, v)) = next_data(&mut ws).await {
        received.entry(sub).or_default().push((t, v));
    }
    let output = run.await.expect("join").expect("run output");
    // Read the emulator to its end (it reports the walk when the host lets go).
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut emulator_out, &mut rest).expect("emulator output");
    assert!(emulator.wait().expect("emulator").success(), "{rest}");
    assert!(rest.contains("fall: none"), "{rest}");
    let stdout = String::from_utf8_lossy(&output.stdout).to_string();
    eprintln!("{stdout}\n{}", String::from_utf8_lossy(&output.stderr));
    assert!(output.status.success());
    assert!(stdout.contains("ran 20000 ticks"), "{stdout}");
    assert!(stdout.contains("adam live: open Foxglove"), "{stdout}");
    assert!(
        stdout.contains("1 accepted"),
        "the viewer's report: {stdout}"
    );

    assert_live_equals_log(&received, &log);
    let tf = received.get(&3).map(Vec::as_slice).unwrap_or_default();
    assert!(tf.len() >= 10, "{} /tf messages", tf.len());
    for (_, m) in tf {
        let children: Vec<&str> = m["transforms"]
            .as_array()
            .expect("transforms")
            .iter()
            .map(|t| t["child_frame_id"].as_str().expect("child"))
            .collect();
        assert!(children.contains(&"torso") && children.contains(&"left_shin"));
        assert!(
            children.iter().all(|c| !c.starts_with("truth/")),
            "no ground truth over UDP: {children:?}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Foxglove's indexed MCAP reader refuses a file with a chunk that has no message index
/// ("Chunks without message indexes are not currently supported"): the writer once closed a
/// chunk of schemas and channels alone (by writing its attachments after them), and Foxglove
/// opened no demo log. Every chunk of a log now holds messages and has their index.
#[test]
fn every_chunk_of_a_log_has_a_message_index_as_foxglove_requires() {
    let setup = runtime::Setup::shipped().expect("setup");
    let log = temp_log("chunks");
    let mut options = runtime::sim::run::SimWalkOptions::new(2.0);
    options.log_path = Some(log.clone());
    runtime::sim::run::walk(&setup, &options).expect("walk");
    let bytes = std::fs::read(&log).expect("log");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("summary");
    assert!(
        summary.chunk_indexes.len() >= 2,
        "{} chunks",
        summary.chunk_indexes.len()
    );
    for (i, c) in summary.chunk_indexes.iter().enumerate() {
        assert!(
            c.message_index_length > 0 && !c.message_index_offsets.is_empty(),
            "chunk {i} at {} has no message index",
            c.chunk_start_offset
        );
    }
    assert_eq!(summary.attachment_indexes.len(), 3, "gait, config, URDF");
    std::fs::remove_file(&log).ok();
}
