//! Reading the runtime's MCAP logs back: a summary for `adam logs info` and the joint series for
//! phase portraits (`adam plot portrait`). Every failure names the file; nothing panics on a
//! truncated or foreign file.

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

/// What a log holds.
#[derive(Clone, Debug, PartialEq)]
pub struct LogInfo {
    /// The file.
    pub path: PathBuf,
    /// Per channel: (topic, schema name, messages).
    pub channels: Vec<(String, String, u64)>,
    /// Time of the first and last message, s (controller time).
    pub span_s: Option<(f64, f64)>,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Attachments: (name, bytes).
    pub attachments: Vec<(String, usize)>,
    /// `/safety` messages (one per trip), as JSON text.
    pub safety_events: Vec<String>,
    /// The gait file attached to the log, if it parses.
    pub gait: Option<model::gait::GaitFile>,
    /// Whether the file has a summary section (false: cut off, e.g. by a crash).
    pub has_summary: bool,
}

fn log_error(path: &Path, message: impl Into<String>) -> RuntimeError {
    RuntimeError::Log {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|error| RuntimeError::Io {
        path: path.to_path_buf(),
        error,
    })
}

/// Summarizes a log: channels with message counts, time span, metadata (run, drops),
/// attachments (gait and config), safety events and the gait used.
pub fn info(path: &Path) -> Result<LogInfo> {
    let bytes = read(path)?;
    let mut counts: BTreeMap<String, (String, u64)> = BTreeMap::new();
    let mut span: Option<(f64, f64)> = None;
    let mut safety_events = Vec::new();
    let stream = mcap::MessageStream::new(&bytes)
        .map_err(|e| log_error(path, format!("not an MCAP file: {e}")))?;
    for message in stream {
        let m = message.map_err(|e| log_error(path, format!("unreadable message: {e}")))?;
        let schema = m
            .channel
            .schema
            .as_ref()
            .map_or_else(String::new, |s| s.name.clone());
        let entry = counts.entry(m.channel.topic.clone()).or_insert((schema, 0));
        entry.1 += 1;
        let t = m.log_time as f64 * 1e-9;
        span = Some(span.map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
        if m.channel.topic == "/safety" {
            safety_events.push(String::from_utf8_lossy(&m.data).into_owned());
        }
    }
    let summary =
        mcap::Summary::read(&bytes).map_err(|e| log_error(path, format!("summary: {e}")))?;
    let mut metadata = BTreeMap::new();
    let mut attachments = Vec::new();
    let mut gait = None;
    let has_summary = summary.is_some();
    if let Some(summary) = summary {
        for index in &summary.metadata_indexes {
            let meta = mcap::read::metadata(&bytes, index)
                .map_err(|e| log_error(path, format!("metadata {}: {e}", index.name)))?;
            metadata.insert(meta.name.clone(), meta.metadata.clone());
        }
        for index in &summary.attachment_indexes {
            let a = mcap::read::attachment(&bytes, index)
                .map_err(|e| log_error(path, format!("attachment {}: {e}", index.name)))?;
            if a.name == "gait.json" {
                gait = std::str::from_utf8(&a.data)
                    .ok()
                    .and_then(|t| model::gait::GaitFile::from_json(t, "gait.json").ok());
            }
            attachments.push((a.name.clone(), a.data.len()));
        }
    }
    Ok(LogInfo {
        path: path.to_path_buf(),
        channels: counts
            .into_iter()
            .map(|(topic, (schema, n))| (topic, schema, n))
            .collect(),
        span_s: span,
        metadata,
        attachments,
        safety_events,
        gait,
        has_summary,
    })
}

impl std::fmt::Display for LogInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "log {}", self.path.display())?;
        if let Some((a, b)) = self.span_s {
            writeln!(f, "time span       {a:.3} s to {b:.3} s ({:.3} s)", b - a)?;
        }
        writeln!(
            f,
            "summary section {}",
            if self.has_summary {
                "present"
            } else {
                "missing (the file was cut off)"
            }
        )?;
        writeln!(f, "channels:")?;
        for (topic, schema, n) in &self.channels {
            writeln!(f, "  {topic:<14} {n:>8} messages  schema {schema}")?;
        }
        for (name, meta) in &self.metadata {
            let fields: Vec<String> = meta.iter().map(|(k, v)| format!("{k}={v}")).collect();
            writeln!(f, "metadata {name}: {}", fields.join(", "))?;
        }
        for (name, len) in &self.attachments {
            writeln!(f, "attachment {name} ({len} bytes)")?;
        }
        if let Some(g) = &self.gait {
            writeln!(
                f,
                "gait: robot {} (thigh {:.4} m, shin {:.4} m), step {:.4} m in {:.4} s, cost of transport {:.4}",
                g.robot.name,
                g.design.thigh_length_m,
                g.design.shin_length_m,
                g.step_length_m,
                g.step_duration_s,
                g.cost_of_transport
            )?;
        }
        write!(f, "safety events: {}", self.safety_events.len())?;
        for e in &self.safety_events {
            write!(f, "\n  {e}")?;
        }
        Ok(())
    }
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
    let bytes = read(path)?;
    let mut out = JointSeries::default();
    let stream = mcap::MessageStream::new(&bytes)
        .map_err(|e| log_error(path, format!("not an MCAP file: {e}")))?;
    for message in stream {
        let m = message.map_err(|e| log_error(path, format!("unreadable message: {e}")))?;
        if m.channel.topic != "/joints" {
            continue;
        }
        let v: Value = serde_json::from_slice(&m.data)
            .map_err(|e| log_error(path, format!("/joints message is not JSON: {e}")))?;
        let mut row = [(0.0, 0.0); 4];
        for (k, name) in LEG_JOINTS.iter().enumerate() {
            let j = &v[*name];
            match (j["q_rad"].as_f64(), j["dq_rad_s"].as_f64()) {
                (Some(q), Some(dq)) => row[k] = (q, dq),
                _ => {
                    return Err(log_error(
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
        return Err(log_error(path, "no /joints messages"));
    }
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::sim_run::{walk, SimWalkOptions};
    use crate::Setup;

    #[test]
    fn a_simulated_run_reads_back_with_counts_gait_and_joint_series() {
        let path = std::env::temp_dir().join(format!("adam-logread-{}.mcap", std::process::id()));
        let setup = Setup::shipped().unwrap();
        let mut options = SimWalkOptions::new(2.0);
        options.log_path = Some(path.clone());
        walk(&setup, &options).unwrap();
        let summary = info(&path).unwrap();
        let count = |t: &str| summary.channels.iter().find(|c| c.0 == t).map(|c| c.2);
        assert_eq!(count("/joints"), Some(2000), "{summary}");
        assert_eq!(count("/hzd"), Some(2000), "{summary}");
        assert!(summary.has_summary);
        assert_eq!(summary.metadata["log_stats"]["dropped"], "0");
        assert_eq!(summary.gait.as_ref().unwrap(), &setup.gait);
        let (a, b) = summary.span_s.unwrap();
        assert!((b - a - 1.999).abs() < 1e-6, "{a} {b}");
        let s = joint_series(&path).unwrap();
        assert_eq!(s.t_s.len(), 2000);
        // Knees stay bent forward (0..2.4 rad) while walking.
        assert!(s.q_rad[1].iter().all(|&q| (-0.1..2.5).contains(&q)));
        // A file that is not MCAP, and a truncated log, give errors naming the file.
        let bad = path.with_extension("txt");
        std::fs::write(&bad, "not a log").unwrap();
        let e = info(&bad).unwrap_err().to_string();
        assert!(e.contains(&bad.display().to_string()), "{e}");
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
        assert!(info(&bad).is_err());
        std::fs::remove_file(&bad).ok();
        std::fs::remove_file(&path).ok();
    }
}
