//! Reading our MCAP logs back: `adam logs info`, and the joint series of `adam plot portrait`.
//!
//! ```text
//! file bytes ──▶ salvage (every whole record; damage stepped over and accounted for)
//!                  ├─▶ metadata, attachments (top level)
//!                  └─▶ messages of every kept chunk, in file order
//!                        ▼
//!              LogInfo (channels, counts, time span, drops, safety trips, gait, design,
//!                       and what a damaged or cut-off log lost)
//! ```
//! Every reader ([`read_info`], [`joint_series`], [`crate::telemetry::replay`], [`crate::tiles`])
//! reads the same way: a log cut off by SIGKILL or damaged in the middle yields every message of
//! every intact chunk, and says what it could not read ([`crate::telemetry::salvage`]);
//! `adam logs recover` ([`crate::telemetry::recover`]) rewrites such a log whole. Every channel
//! must carry [`crate::telemetry::log::LOG_SCHEMA_VERSION`] in its `adam_log_schema` metadata;
//! any other (or none) is an error naming the channel, never a silent misread.
//!
//! ```no_run
//! let info = runtime::telemetry::log_read::read_info("logs/run.mcap").unwrap();
//! println!("{info}");
//! ```

use crate::telemetry::log::CHANNELS;
pub use crate::telemetry::recover::{recover, RecoverStats};
pub use crate::telemetry::salvage::check_schema_version;
use crate::telemetry::salvage::Salvaged;
pub(crate) use crate::telemetry::salvage::{log_err, read_bytes};
use crate::Result;
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
    /// `None` when the file was read whole to its footer; otherwise where it is cut off or
    /// damaged, how much was read and what was lost (`adam logs recover` rewrites it).
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
            Some(why) => writeln!(f, "complete  NO: {why}; `adam logs recover` rewrites it")?,
        }
        if let Some(r) = self.metadata.get("recovery") {
            writeln!(
                f,
                "recovered from {}: {}",
                r.get("source").map_or("?", String::as_str),
                r.get("summary")
                    .or_else(|| r.get("stopped"))
                    .map_or("?", String::as_str)
            )?;
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

/// Top-level records outside chunks: metadata and attachments, every one that reads.
pub(crate) struct TopLevel {
    pub(crate) metadata: Vec<mcap::records::Metadata>,
    pub(crate) attachments: Vec<(mcap::records::AttachmentHeader, Vec<u8>)>,
    /// Where the log is cut off or damaged (`None`: read whole).
    pub(crate) error: Option<String>,
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
        let setup = crate::Setup::from_parts(config, gait, urdf, &origin("robot.urdf"))?;
        let name = crate::telemetry::log::LIBRARY_ATTACHMENT;
        if !self.attachments.iter().any(|(h, _)| h.name == name) {
            return Ok(setup);
        }
        let text = self.attachment_text(path, name)?;
        let entries: Vec<serde_json::Value> = serde_json::from_str(text)
            .map_err(|e| log_err(path, format!("attachment {name} is not a JSON array: {e}")))?;
        let mut library = Vec::with_capacity(entries.len());
        let mut origins = Vec::with_capacity(entries.len());
        for (k, entry) in entries.iter().enumerate() {
            let o = origin(&format!("{name}[{k}]"));
            library.push(model::gait::GaitFile::from_json(&entry.to_string(), &o)?);
            origins.push(o);
        }
        setup.with_library(library, &origins)
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

impl TopLevel {
    /// The top-level records of a salvaged log.
    pub(crate) fn of(log: &Salvaged<'_>) -> Self {
        Self {
            metadata: log.metadata.clone(),
            attachments: log.attachments.clone(),
            error: log.loss.summary(),
        }
    }
}

/// The top-level records of the log `bytes` (the file `path`).
#[cfg(test)]
pub(crate) fn top_level(path: &Path, bytes: &[u8]) -> Result<TopLevel> {
    Ok(TopLevel::of(&Salvaged::read(path, bytes)?))
}

/// Read what `path` holds; a cut-off or damaged log is read past its damage and says so in
/// [`LogInfo::truncated`].
pub fn read_info(path: impl AsRef<Path>) -> Result<LogInfo> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    let log = Salvaged::read(path, &bytes)?;
    let top = TopLevel::of(&log);
    let mut channels: Vec<ChannelInfo> = Vec::new();
    let mut span: Option<(u64, u64)> = None;
    let mut safety_events = Vec::new();
    for m in log.messages() {
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
    let truncated = top.error;
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

/// Joint positions and velocities of the four leg joints over a log (motor side as logged).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointSeries {
    /// Controller time, s.
    pub t_s: Vec<f64>,
    /// Position per leg joint ([`LEG_JOINTS`] order), rad.
    pub q_rad: [Vec<f64>; 4],
    /// Velocity per leg joint, rad/s.
    pub dq_rad_s: [Vec<f64>; 4],
    /// Where the log is cut off or damaged, how much was read and what was lost (`None`: read
    /// whole).
    pub damage: Option<String>,
}

/// The `/joints` channel's leg-joint positions and velocities, of every intact chunk of a
/// damaged or cut-off log too ([`JointSeries::damage`] says what was lost).
pub fn joint_series(path: &Path) -> Result<JointSeries> {
    let bytes = read_bytes(path)?;
    let log = Salvaged::read(path, &bytes)?;
    let mut out = JointSeries {
        damage: log.loss.summary(),
        ..JointSeries::default()
    };
    for m in log.messages() {
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
        return Err(log_err(
            path,
            match &out.damage {
                Some(d) => format!("no /joints messages left to read ({d})"),
                None => "no /joints messages".into(),
            },
        ));
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
    use crate::telemetry::log::{
        start, LogContext, LogRecord, LOG_SCHEMA_VERSION, SCHEMA_VERSION_KEY,
    };
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
        // A file that is not MCAP gives an error naming the file; a truncated log gives the
        // series up to its cut, a prefix of the whole one, and says it was cut off (issue #27).
        let bad = path.with_extension("txt");
        std::fs::write(&bad, "not a log").unwrap();
        let e = read_info(&bad).unwrap_err().to_string();
        assert!(e.contains(&bad.display().to_string()), "{e}");
        let e = joint_series(&bad).unwrap_err().to_string();
        assert!(e.contains(&bad.display().to_string()), "{e}");
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
        let cut = joint_series(&bad).unwrap();
        assert!(
            !cut.t_s.is_empty() && cut.t_s.len() < 2000,
            "{}",
            cut.t_s.len()
        );
        assert_eq!(cut.t_s[..], s.t_s[..cut.t_s.len()]);
        assert_eq!(cut.q_rad[1][..], s.q_rad[1][..cut.t_s.len()]);
        assert!(
            cut.damage.as_ref().is_some_and(|d| d.contains("cut off")),
            "{cut:?}"
        );
        // Nothing readable left: an error that names the file and says why.
        std::fs::write(&bad, &bytes[..200]).unwrap();
        let e = joint_series(&bad).unwrap_err().to_string();
        assert!(
            e.contains(&bad.display().to_string()) && e.contains("no /joints"),
            "{e}"
        );
        std::fs::remove_file(&bad).ok();
        std::fs::remove_file(&path).ok();
    }
}
