//! Reading our MCAP logs back: `adam logs info` and `adam logs recover`.
//!
//! ```text
//! file bytes ──▶ LinearReader (IgnoreEndMagic) ──▶ metadata, attachments (top level)
//!            └─▶ MessageStream (IgnoreEndMagic) ──▶ messages, chunk by chunk
//!                      │ first error (a chunk cut off by a crash) = end of the readable log
//!                      ▼
//!              LogInfo (channels, counts, time span, drops, safety trips, gait, design)
//!              recover(): the same records rewritten with summary and indexes
//! ```
//! Both passes stop at the first record they cannot parse, so a log cut off by SIGKILL still
//! yields every message up to its last complete chunk. Every channel must carry
//! [`LOG_SCHEMA_VERSION`] in its `adam_log_schema` metadata; any other (or none) is an error
//! naming the channel, never a silent misread.
//!
//! ```no_run
//! let info = runtime::telemetry::log_read::read_info("logs/run.mcap").unwrap();
//! println!("{info}");
//! ```

use crate::telemetry::log::{CHANNELS, LOG_SCHEMA_VERSION, SCHEMA_VERSION_KEY};
use crate::{Result, RuntimeError};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The four leg joints, in the order of the `/joints` channel's keys used here.
pub const LEG_JOINTS: [&str; 4] = [
    "left_hip_pitch",
    "left_knee_pitch",
    "right_hip_pitch",
    "right_knee_pitch",
];

/// One channel of a log.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelInfo {
    /// Topic, e.g. `/joints`.
    pub topic: String,
    /// Schema name, e.g. `adam.Joints`.
    pub schema_name: String,
    /// Messages read.
    pub messages: u64,
}

/// What a log holds, as far as it is readable.
#[derive(Clone, Debug, PartialEq)]
pub struct LogInfo {
    /// The file.
    pub path: PathBuf,
    /// File size, bytes.
    pub file_bytes: u64,
    /// `None` when the file was read to its footer; otherwise why reading stopped early
    /// (a cut-off log: `adam logs recover` rewrites it).
    pub truncated: Option<String>,
    /// Channels in order of first appearance.
    pub channels: Vec<ChannelInfo>,
    /// Log time of the first and last message, ns (`None` without messages).
    pub span_ns: Option<(u64, u64)>,
    /// Metadata records by name (`run`, `log_stats`, ...).
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Attachment names.
    pub attachments: Vec<String>,
    /// `/safety` messages (JSON text), one per trip.
    pub safety_events: Vec<String>,
    /// The gait attachment, if present and valid.
    pub gait: Option<model::gait::GaitFile>,
}

impl LogInfo {
    /// Records the logger dropped (from `log_stats`; `None` for a cut-off log, which lacks it).
    pub fn dropped(&self) -> Option<u64> {
        self.metadata
            .get("log_stats")
            .and_then(|m| m.get("dropped"))
            .and_then(|d| d.parse().ok())
    }

    /// Duration from the first to the last message, s.
    pub fn duration_s(&self) -> f64 {
        self.span_ns
            .map(|(a, b)| (b - a) as f64 * 1e-9)
            .unwrap_or(0.0)
    }

    /// Messages on `topic`.
    pub fn count(&self, topic: &str) -> u64 {
        self.channels
            .iter()
            .find(|c| c.topic == topic)
            .map_or(0, |c| c.messages)
    }
}

impl std::fmt::Display for LogInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "log       {} ({} bytes)",
            self.path.display(),
            self.file_bytes
        )?;
        match &self.truncated {
            None => writeln!(f, "complete  yes (footer read)")?,
            Some(why) => writeln!(
                f,
                "complete  NO: cut off ({why}); `adam logs recover` rewrites it"
            )?,
        }
        writeln!(f, "duration  {:.3} s", self.duration_s())?;
        match self.dropped() {
            Some(d) => writeln!(f, "dropped   {d} records")?,
            None => writeln!(f, "dropped   unknown (no log_stats record)")?,
        }
        writeln!(f, "channels")?;
        for c in &self.channels {
            writeln!(
                f,
                "  {:<13} {:<18} {:>8} msgs",
                c.topic, c.schema_name, c.messages
            )?;
        }
        if let Some(run) = self.metadata.get("run") {
            let pairs: Vec<String> = run.iter().map(|(k, v)| format!("{k}={v}")).collect();
            writeln!(f, "run       {}", pairs.join(" "))?;
        }
        if let Some(g) = &self.gait {
            writeln!(
                f,
                "gait      robot {} ({}), step {:.3} m in {:.3} s, {:.3} m/s, CoT {:.4}",
                g.robot.name,
                g.robot.urdf,
                g.step_length_m,
                g.step_duration_s,
                g.speed_mps,
                g.cost_of_transport
            )?;
            writeln!(
                f,
                "design    thigh {:.4} m, shin {:.4} m",
                g.design.thigh_length_m, g.design.shin_length_m
            )?;
        } else {
            writeln!(f, "gait      none attached")?;
        }
        writeln!(f, "attach    {}", self.attachments.join(", "))?;
        writeln!(f, "safety    {} trip(s)", self.safety_events.len())?;
        for e in &self.safety_events {
            writeln!(f, "  {e}")?;
        }
        Ok(())
    }
}

pub(crate) fn log_err(path: &Path, e: impl std::fmt::Display) -> RuntimeError {
    RuntimeError::Log {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// MCAP's leading magic bytes.
const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// The file's bytes; a file that does not even start like an MCAP file is an error (a cut-off
/// log still has its leading magic).
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    let bytes = std::fs::read(path).map_err(|error| RuntimeError::Io {
        path: path.to_path_buf(),
        error,
    })?;
    if !bytes.starts_with(MCAP_MAGIC) {
        return Err(log_err(path, "not an MCAP file (no leading MCAP magic)"));
    }
    crate::telemetry::log_guard::check_lengths(path, &bytes)?;
    Ok(bytes)
}

/// Refuse a channel of another log schema version (or an unversioned one).
pub fn check_schema_version(path: &Path, channel: &mcap::Channel<'_>) -> Result<()> {
    let found = channel.metadata.get(SCHEMA_VERSION_KEY);
    if found.map(String::as_str) == Some(LOG_SCHEMA_VERSION.to_string().as_str()) {
        return Ok(());
    }
    Err(RuntimeError::LogSchemaVersion {
        path: path.to_path_buf(),
        channel: channel.topic.clone(),
        found: found.cloned().unwrap_or_else(|| "none".into()),
        expected: LOG_SCHEMA_VERSION,
    })
}

/// Top-level records outside chunks: metadata and attachments, up to the first unreadable one.
pub(crate) struct TopLevel {
    pub(crate) metadata: Vec<mcap::records::Metadata>,
    pub(crate) attachments: Vec<(mcap::records::AttachmentHeader, Vec<u8>)>,
    pub(crate) error: Option<String>,
    pub(crate) footer: bool,
}

impl TopLevel {
    /// The attachment `name` as text, or an error naming the log and the attachment.
    pub(crate) fn attachment_text(&self, path: &Path, name: &str) -> Result<&str> {
        let (_, data) = self
            .attachments
            .iter()
            .find(|(h, _)| h.name == name)
            .ok_or_else(|| log_err(path, format!("no attachment {name}")))?;
        std::str::from_utf8(data)
            .map_err(|e| log_err(path, format!("attachment {name} is not UTF-8: {e}")))
    }

    /// The setup a log was recorded with: its attached runtime config, gait file and URDF,
    /// cross-checked like [`crate::Setup::load`]; errors name the log and the attachment.
    pub(crate) fn setup(&self, path: &Path) -> Result<crate::Setup> {
        let origin = |name: &str| format!("{name} in {}", path.display());
        let config = crate::config::RuntimeConfig::from_toml(
            self.attachment_text(path, "runtime.toml")?,
            &origin("runtime.toml"),
        )?;
        let gait = model::gait::GaitFile::from_json(
            self.attachment_text(path, "gait.json")?,
            &origin("gait.json"),
        )?;
        let urdf = self.attachment_text(path, "robot.urdf")?.to_string();
        crate::Setup::from_parts(config, gait, urdf, &origin("robot.urdf"))
    }

    /// Metadata record `name`, key `key`.
    pub(crate) fn metadata_value(&self, name: &str, key: &str) -> Option<&str> {
        self.metadata
            .iter()
            .find(|m| m.name == name)
            .and_then(|m| m.metadata.get(key))
            .map(String::as_str)
    }
}

pub(crate) fn top_level(path: &Path, bytes: &[u8]) -> Result<TopLevel> {
    let reader = mcap::read::LinearReader::new_with_options(
        bytes,
        mcap::read::Options::IgnoreEndMagic.into(),
    )
    .map_err(|e| log_err(path, e))?;
    let mut out = TopLevel {
        metadata: Vec::new(),
        attachments: Vec::new(),
        error: None,
        footer: false,
    };
    for record in reader {
        match record {
            Ok(mcap::records::Record::Metadata(m)) => out.metadata.push(m),
            Ok(mcap::records::Record::Attachment { header, data, .. }) => {
                out.attachments.push((header, data.into_owned()))
            }
            Ok(mcap::records::Record::Footer(_)) => out.footer = true,
            Ok(_) => {}
            Err(e) => {
                out.error = Some(e.to_string());
                break;
            }
        }
    }
    Ok(out)
}

/// Read what `path` holds; stops (and says so in [`LogInfo::truncated`]) at a cut-off chunk.
pub fn read_info(path: impl AsRef<Path>) -> Result<LogInfo> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    let top = top_level(path, &bytes)?;
    let mut channels: Vec<ChannelInfo> = Vec::new();
    let mut span: Option<(u64, u64)> = None;
    let mut safety_events = Vec::new();
    let mut message_error = None;
    let stream =
        mcap::MessageStream::new_with_options(&bytes, mcap::read::Options::IgnoreEndMagic.into())
            .map_err(|e| log_err(path, e))?;
    for message in stream {
        let m = match message {
            Ok(m) => m,
            Err(e) => {
                message_error = Some(e.to_string());
                break;
            }
        };
        let topic = &m.channel.topic;
        match channels.iter_mut().find(|c| &c.topic == topic) {
            Some(c) => c.messages += 1,
            None => {
                check_schema_version(path, &m.channel)?;
                channels.push(ChannelInfo {
                    topic: topic.clone(),
                    schema_name: m
                        .channel
                        .schema
                        .as_ref()
                        .map_or_else(String::new, |s| s.name.clone()),
                    messages: 1,
                });
            }
        }
        span = Some(match span {
            None => (m.log_time, m.log_time),
            Some((a, b)) => (a.min(m.log_time), b.max(m.log_time)),
        });
        if topic == CHANNELS[4] {
            safety_events.push(String::from_utf8_lossy(&m.data).into_owned());
        }
    }
    let gait = top
        .attachments
        .iter()
        .find(|(h, _)| h.name == "gait.json")
        .and_then(|(_, d)| std::str::from_utf8(d).ok())
        .and_then(|text| model::gait::GaitFile::from_json(text, "gait.json in log").ok());
    let truncated = message_error
        .or(top.error)
        .or_else(|| (!top.footer).then(|| "no footer: the writer did not finish".to_string()));
    Ok(LogInfo {
        path: path.to_path_buf(),
        file_bytes: bytes.len() as u64,
        truncated,
        channels,
        span_ns: span,
        metadata: top
            .metadata
            .into_iter()
            .map(|m| (m.name, m.metadata))
            .collect(),
        attachments: top
            .attachments
            .iter()
            .map(|(h, _)| h.name.clone())
            .collect(),
        safety_events,
        gait,
    })
}

/// What [`recover`] rewrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RecoverStats {
    /// Messages copied.
    pub messages: u64,
    /// Attachments copied.
    pub attachments: u64,
    /// Metadata records copied (plus the added `recovery` record).
    pub metadata: u64,
    /// The input was complete (had a footer) already.
    pub input_complete: bool,
}

/// Rewrite every readable record of `input` into `output` (zstd chunks, summary and indexes),
/// adding a `recovery` metadata record that says how much was recovered and why reading stopped.
pub fn recover(input: impl AsRef<Path>, output: impl AsRef<Path>) -> Result<RecoverStats> {
    let (input, output) = (input.as_ref(), output.as_ref());
    let bytes = read_bytes(input)?;
    let top = top_level(input, &bytes)?;
    let file = std::fs::File::create(output).map_err(|error| RuntimeError::Io {
        path: output.to_path_buf(),
        error,
    })?;
    let mut writer = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .profile("")
        .library(concat!(
            "adam-hzd runtime ",
            env!("CARGO_PKG_VERSION"),
            " (recovered)"
        ))
        .create(std::io::BufWriter::new(file))
        .map_err(|e| log_err(output, e))?;
    let mut stats = RecoverStats {
        input_complete: top.footer && top.error.is_none(),
        ..RecoverStats::default()
    };
    for (header, data) in &top.attachments {
        writer
            .attach(&mcap::Attachment {
                log_time: header.log_time,
                create_time: header.create_time,
                name: header.name.clone(),
                media_type: header.media_type.clone(),
                data: std::borrow::Cow::Borrowed(data),
            })
            .map_err(|e| log_err(output, e))?;
        stats.attachments += 1;
    }
    for m in &top.metadata {
        writer.write_metadata(m).map_err(|e| log_err(output, e))?;
        stats.metadata += 1;
    }
    let mut ids: BTreeMap<u16, u16> = BTreeMap::new();
    let mut stop_reason = top.error.clone();
    let stream =
        mcap::MessageStream::new_with_options(&bytes, mcap::read::Options::IgnoreEndMagic.into())
            .map_err(|e| log_err(input, e))?;
    for message in stream {
        let m = match message {
            Ok(m) => m,
            Err(e) => {
                stop_reason = Some(e.to_string());
                break;
            }
        };
        let id = match ids.get(&m.channel.id) {
            Some(id) => *id,
            None => {
                check_schema_version(input, &m.channel)?;
                let schema_id = match &m.channel.schema {
                    Some(s) => writer
                        .add_schema(&s.name, &s.encoding, &s.data)
                        .map_err(|e| log_err(output, e))?,
                    None => 0,
                };
                let id = writer
                    .add_channel(
                        schema_id,
                        &m.channel.topic,
                        &m.channel.message_encoding,
                        &m.channel.metadata,
                    )
                    .map_err(|e| log_err(output, e))?;
                ids.insert(m.channel.id, id);
                id
            }
        };
        writer
            .write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: id,
                    sequence: m.sequence,
                    log_time: m.log_time,
                    publish_time: m.publish_time,
                },
                &m.data,
            )
            .map_err(|e| log_err(output, e))?;
        stats.messages += 1;
    }
    let mut note = BTreeMap::new();
    note.insert("source".into(), input.display().to_string());
    note.insert("source_bytes".into(), bytes.len().to_string());
    note.insert("messages".into(), stats.messages.to_string());
    note.insert(
        "stopped".into(),
        stop_reason.unwrap_or_else(|| "end of data".into()),
    );
    writer
        .write_metadata(&mcap::records::Metadata {
            name: "recovery".into(),
            metadata: note,
        })
        .map_err(|e| log_err(output, e))?;
    writer.finish().map_err(|e| log_err(output, e))?;
    Ok(stats)
}

/// Joint positions and velocities of the four leg joints over a log (motor side as logged).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointSeries {
    /// Controller time, s.
    pub t_s: Vec<f64>,
    /// Position per leg joint ([`LEG_JOINTS`] order), rad.
    pub q_rad: [Vec<f64>; 4],
    /// Velocity per leg joint, rad/s.
    pub dq_rad_s: [Vec<f64>; 4],
}

/// The `/joints` channel's leg-joint positions and velocities.
pub fn joint_series(path: &Path) -> Result<JointSeries> {
    let bytes = read_bytes(path)?;
    let mut out = JointSeries::default();
    let stream = mcap::MessageStream::new(&bytes)
        .map_err(|e| log_err(path, format!("not an MCAP file: {e}")))?;
    for message in stream {
        let m = message.map_err(|e| log_err(path, format!("unreadable message: {e}")))?;
        if m.channel.topic != "/joints" {
            continue;
        }
        let v: Value = serde_json::from_slice(&m.data)
            .map_err(|e| log_err(path, format!("/joints message is not JSON: {e}")))?;
        let mut row = [(0.0, 0.0); 4];
        for (k, name) in LEG_JOINTS.iter().enumerate() {
            let j = &v[*name];
            match (j["q_rad"].as_f64(), j["dq_rad_s"].as_f64()) {
                (Some(q), Some(dq)) => row[k] = (q, dq),
                _ => {
                    return Err(log_err(
                        path,
                        format!("/joints message without {name}.q_rad / dq_rad_s"),
                    ))
                }
            }
        }
        out.t_s.push(m.log_time as f64 * 1e-9);
        for (k, (q, dq)) in row.into_iter().enumerate() {
            out.q_rad[k].push(q);
            out.dq_rad_s[k].push(dq);
        }
    }
    if out.t_s.is_empty() {
        return Err(log_err(path, "no /joints messages"));
    }
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::control::ControlState;
    use crate::safety::Trip;
    use crate::sim::run::{walk, SimWalkOptions};
    use crate::slots::SlotLayout;
    use crate::telemetry::log::{start, LogContext, LogRecord};
    use crate::telemetry::sample::StateSample;
    use crate::Setup;

    fn temp_path(tag: &str) -> PathBuf {
        std::env::temp_dir().join(format!(
            "adam-log-read-{tag}-{}-{:?}.mcap",
            std::process::id(),
            std::thread::current().id()
        ))
    }

    /// A log of `n` ticks at 1 kHz with one transition and one trip, small chunks so that
    /// truncation lands in many different places.
    fn write_log(path: &Path, n: u64) {
        let setup = Setup::shipped().unwrap();
        let layout = SlotLayout::new(&setup.config, false);
        let ctx = LogContext::new(&setup, &layout);
        let (mut tx, logger) = start(path, ctx, 4096).unwrap();
        for k in 0..n {
            let mut s = StateSample {
                tick: k,
                t_s: k as f64 * 1e-3,
                ..StateSample::default()
            };
            s.q_rad[1] = 0.001 * k as f64;
            tx.push(LogRecord::Sample(s));
            if k == 10 {
                tx.push(LogRecord::Transition {
                    t_s: 0.01,
                    from: ControlState::Idle,
                    to: ControlState::Ramp,
                });
            }
            if k == 20 {
                tx.push(LogRecord::Trip {
                    t_s: 0.02,
                    tick: k,
                    trip: Trip::Fall {
                        pitch_rad: 0.7,
                        limit_rad: 0.6,
                    },
                });
            }
        }
        let stats = logger.finish().unwrap();
        assert_eq!(stats.dropped, 0);
    }

    #[test]
    fn info_reports_channels_counts_span_trips_and_gait() {
        let path = temp_path("info");
        write_log(&path, 300);
        let info = read_info(&path).unwrap();
        assert_eq!(info.truncated, None);
        for topic in ["/joints", "/hzd", "/estimator", "/state"] {
            assert_eq!(info.count(topic), 300, "{topic}");
        }
        assert_eq!(info.count("/safety"), 1);
        assert_eq!(info.count("/transitions"), 1);
        assert_eq!(info.span_ns, Some((0, 299_000_000)));
        assert_eq!(info.dropped(), Some(0));
        assert!(info.safety_events[0].contains("\"fall\""));
        let setup = Setup::shipped().unwrap();
        let gait = info.gait.as_ref().unwrap();
        assert_eq!(gait.step_length_m, setup.gait.step_length_m);
        assert_eq!(info.attachments, crate::telemetry::log::ATTACHMENTS);
        let text = info.to_string();
        assert!(text.contains("duration  0.299 s"), "{text}");
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn a_log_of_another_schema_version_is_refused_naming_the_channel() {
        let path = temp_path("version");
        {
            let file = std::fs::File::create(&path).unwrap();
            let mut w = mcap::Writer::new(std::io::BufWriter::new(file)).unwrap();
            let sid = w.add_schema("adam.Joints", "jsonschema", b"{}").unwrap();
            let meta = BTreeMap::from([(SCHEMA_VERSION_KEY.to_string(), "0".to_string())]);
            let ch = w.add_channel(sid, "/joints", "json", &meta).unwrap();
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: 0,
                    log_time: 0,
                    publish_time: 0,
                },
                b"{}",
            )
            .unwrap();
            w.finish().unwrap();
        }
        let err = read_info(&path).unwrap_err().to_string();
        assert!(err.contains("`/joints`"), "{err}");
        assert!(err.contains("version 0"), "{err}");
        assert!(
            err.contains(&format!("reads version {LOG_SCHEMA_VERSION}")),
            "{err}"
        );
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn a_log_cut_at_any_offset_recovers_every_complete_message_in_order() {
        let path = temp_path("full");
        write_log(&path, 3000);
        let bytes = std::fs::read(&path).unwrap();
        let full = read_info(&path).unwrap();
        let total: u64 = full.channels.iter().map(|c| c.messages).sum();
        let cut = temp_path("cut");
        let out = temp_path("recovered");
        let mut previous = 0;
        let mut partial = 0;
        // Offsets spread over the whole file, plus the very start and end.
        let mut offsets: Vec<usize> = (1..40).map(|i| i * bytes.len() / 40 + i * 7).collect();
        offsets.extend([9, bytes.len() - 1, bytes.len()]);
        offsets.sort_unstable();
        for &offset in offsets.iter().filter(|&&o| o <= bytes.len()) {
            std::fs::write(&cut, &bytes[..offset]).unwrap();
            let stats = recover(&cut, &out).unwrap();
            let info = read_info(&out).unwrap();
            assert_eq!(
                info.truncated, None,
                "recovered file complete at cut {offset}"
            );
            let n: u64 = info.channels.iter().map(|c| c.messages).sum();
            assert_eq!(n, stats.messages);
            // More bytes never recover fewer messages, and never more than were written.
            assert!(n >= previous && n <= total, "cut {offset}: {n} of {total}");
            previous = n;
            partial += u64::from(n > 0 && n < total);
            // The recovered /joints stream is a prefix of the original one.
            let rec = std::fs::read(&out).unwrap();
            let knee: Vec<f64> = mcap::MessageStream::new(&rec)
                .unwrap()
                .map(|m| m.unwrap())
                .filter(|m| m.channel.topic == "/joints")
                .map(|m| {
                    let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
                    v["left_knee_pitch"]["q_rad"].as_f64().unwrap()
                })
                .collect();
            for (k, q) in knee.iter().enumerate() {
                assert!(
                    (q - 0.001 * k as f64).abs() < 1e-12,
                    "cut {offset} tick {k}"
                );
            }
            assert!(info.metadata.contains_key("recovery"));
        }
        // The uncut file recovers everything, and some cuts recover part of it.
        assert_eq!(previous, total);
        assert!(
            partial >= 3,
            "only {partial} cuts recovered part of the log"
        );
        for p in [&path, &cut, &out] {
            std::fs::remove_file(p).unwrap();
        }
    }

    #[test]
    fn a_simulated_run_reads_back_with_counts_gait_and_joint_series() {
        let path = std::env::temp_dir().join(format!("adam-logread-{}.mcap", std::process::id()));
        let setup = Setup::shipped().unwrap();
        let mut options = SimWalkOptions::new(2.0);
        options.log_path = Some(path.clone());
        walk(&setup, &options).unwrap();
        let summary = read_info(&path).unwrap();
        let count = |t: &str| {
            summary
                .channels
                .iter()
                .find(|c| c.topic == t)
                .map(|c| c.messages)
        };
        assert_eq!(count("/joints"), Some(2000), "{summary}");
        assert_eq!(count("/hzd"), Some(2000), "{summary}");
        assert!(summary.truncated.is_none(), "{summary}");
        assert_eq!(summary.metadata["log_stats"]["dropped"], "0");
        assert_eq!(summary.gait.as_ref().unwrap(), &setup.gait);
        assert!((summary.duration_s() - 1.999).abs() < 1e-6, "{summary}");
        let s = joint_series(&path).unwrap();
        assert_eq!(s.t_s.len(), 2000);
        // Knees stay bent forward (0..2.4 rad) while walking.
        assert!(s.q_rad[1].iter().all(|&q| (-0.1..2.5).contains(&q)));
        // A file that is not MCAP, and a truncated log, give errors naming the file.
        let bad = path.with_extension("txt");
        std::fs::write(&bad, "not a log").unwrap();
        let e = read_info(&bad).unwrap_err().to_string();
        assert!(e.contains(&bad.display().to_string()), "{e}");
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
        assert!(joint_series(&bad).is_err());
        std::fs::remove_file(&bad).ok();
        std::fs::remove_file(&path).ok();
    }
}
