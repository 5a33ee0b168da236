//! From state samples to the live view's messages: the log's channels ([`CHANNELS`]) and the
//! robot in 3D ([`SCENE_TOPICS`]), each decimated as configured ([`Decimation`]); state changes
//! (`/transitions`) and new trips (`/safety`) from every sample, never decimated. Pure logic:
//! the server ([`super::server`]) only moves the bytes.

use crate::slots::{OUTPUTS, SLOTS};
use crate::telemetry::channels::{channel_schemas, sample_messages, CHANNELS};
use crate::telemetry::sample::StateSample;
use crate::telemetry::scene::{scene_schemas, RobotScene, SCENE_TOPICS};
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// Every channel the live view advertises, in id order from 1: the log's, then the scene's.
pub fn topics() -> Vec<&'static str> {
    CHANNELS
        .iter()
        .chain(SCENE_TOPICS.iter())
        .copied()
        .collect()
}

/// The live channel id of `topic` (`None`: not a channel).
pub fn channel_id(topic: &str) -> Option<u32> {
    topics()
        .iter()
        .position(|t| *t == topic)
        .map(|i| i as u32 + 1)
}

/// Per channel: send every n-th sample (1 = every sample the viewer receives).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decimation {
    every: BTreeMap<&'static str, u32>,
}

/// Default decimation of the per-tick channels: 50 Hz at the loop's 1 kHz.
pub const DEFAULT_EVERY: u32 = 20;
/// Default decimation of `/scene` and `/robot_description`: once a second at 1 kHz.
pub const DEFAULT_SCENE_EVERY: u32 = 1000;

impl Default for Decimation {
    fn default() -> Self {
        let mut every = BTreeMap::new();
        for t in topics() {
            let n = if t == SCENE_TOPICS[1] || t == SCENE_TOPICS[2] {
                DEFAULT_SCENE_EVERY
            } else {
                DEFAULT_EVERY
            };
            every.insert(t, n);
        }
        Self { every }
    }
}

impl Decimation {
    /// Parses `topic=n,topic=n` over the defaults (`/joints=10,/tf=5`); `origin` names the
    /// flag in errors, which name the entry and why.
    pub fn parse(text: &str, origin: &str) -> Result<Self, String> {
        let mut d = Self::default();
        for entry in text.split(',').map(str::trim).filter(|e| !e.is_empty()) {
            let (topic, n) = entry
                .split_once('=')
                .ok_or_else(|| format!("{origin}: `{entry}` is not topic=n (e.g. /joints=10)"))?;
            let n: u32 = n.trim().parse().ok().filter(|&n| n >= 1).ok_or_else(|| {
                format!("{origin}: `{entry}`: n must be a whole number ≥ 1, got `{n}`")
            })?;
            let topic = topics()
                .into_iter()
                .find(|t| *t == topic.trim())
                .ok_or_else(|| {
                    format!(
                        "{origin}: `{entry}`: no channel `{topic}` (channels: {})",
                        topics().join(", ")
                    )
                })?;
            d.every.insert(topic, n);
        }
        Ok(d)
    }

    /// Every n-th sample on `topic` (1 for event channels and unknown topics).
    pub fn every(&self, topic: &str) -> u32 {
        self.every.get(topic).copied().unwrap_or(1)
    }
}

/// A message for the live view: channel id, time (ns), JSON bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct Outgoing {
    /// Live channel id ([`channel_id`]).
    pub channel: u32,
    /// Time, ns of controller time.
    pub t_ns: u64,
    /// The JSON message.
    pub payload: std::sync::Arc<Vec<u8>>,
}

/// Turns samples into messages.
#[derive(Debug)]
pub struct Feed {
    joint_names: [Option<String>; SLOTS],
    output_names: [String; OUTPUTS],
    scene: Option<RobotScene>,
    decimation: Decimation,
    samples: u64,
    last: Option<(u32, u32)>,
}

impl Feed {
    /// A feed for a run with these joints and outputs (the log's context) and robot.
    pub fn new(
        joint_names: [Option<String>; SLOTS],
        output_names: [String; OUTPUTS],
        scene: Option<RobotScene>,
        decimation: Decimation,
    ) -> Self {
        Self {
            joint_names,
            output_names,
            scene,
            decimation,
            samples: 0,
            last: None,
        }
    }

    /// Every channel with its schema name and schema text, in id order from 1.
    pub fn channels(&self) -> Vec<super::protocol::ServerChannel> {
        let log = channel_schemas(&self.joint_names, &self.output_names)
            .into_iter()
            .map(|c| (c.topic, c.schema_name, c.schema));
        let scene = SCENE_TOPICS
            .iter()
            .zip(scene_schemas())
            .map(|(t, (n, s))| (*t, n, s));
        log.chain(scene)
            .enumerate()
            .map(
                |(i, (topic, name, schema))| super::protocol::ServerChannel {
                    id: i as u32 + 1,
                    topic: topic.into(),
                    schema_name: name.into(),
                    schema: schema.to_string(),
                },
            )
            .collect()
    }

    /// The messages due at sample `s`, appended to `out`.
    pub fn push(&mut self, s: &StateSample, out: &mut Vec<Outgoing>) {
        let t_ns = (s.t_s.max(0.0) * 1e9).round() as u64;
        let k = self.samples;
        self.samples += 1;
        let mut emit = |topic: &str, v: &Value| {
            if let Some(channel) = channel_id(topic) {
                out.push(Outgoing {
                    channel,
                    t_ns,
                    payload: std::sync::Arc::new(serde_json::to_vec(v).unwrap_or_default()),
                });
            }
        };
        let due = |topic: &str| k % u64::from(self.decimation.every(topic)) == 0;
        let messages = sample_messages(s, &self.joint_names, &self.output_names);
        for (topic, v) in CHANNELS.iter().zip(&messages) {
            if due(topic) {
                emit(topic, v);
            }
        }
        // State changes and trips, seen from consecutive samples.
        if let Some((state, trip)) = self.last {
            if state != s.state {
                let name = |code: u32| {
                    StateSample {
                        state: code,
                        ..StateSample::default()
                    }
                    .control_state()
                    .name()
                };
                emit(
                    CHANNELS[5],
                    &json!({"t_s": s.t_s, "from": name(state), "to": name(s.state)}),
                );
            }
            if s.trip_code != 0 && s.trip_code != trip {
                emit(
                    CHANNELS[4],
                    &json!({"t_s": s.t_s, "tick": s.tick, "code": s.trip_code,
                        "reason": trip_name(s.trip_code)}),
                );
            }
        }
        self.last = Some((s.state, s.trip_code));
        if let Some(scene) = &self.scene {
            if due(SCENE_TOPICS[0]) {
                emit(SCENE_TOPICS[0], &scene.transforms(s));
            }
            if due(SCENE_TOPICS[1]) {
                emit(SCENE_TOPICS[1], &scene.scene_update(s.t_s));
            }
            if due(SCENE_TOPICS[2]) {
                emit(SCENE_TOPICS[2], &scene.robot_description());
            }
        }
    }
}

/// The name of a trip code (as the log's `/safety` `reason`), or `trip <code>`.
fn trip_name(code: u32) -> String {
    crate::safety::Trip::name_of_code(code).map_or_else(|| format!("trip {code}"), String::from)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn decimation_parses_over_the_defaults_and_names_bad_entries() {
        let d = Decimation::parse("/joints=10, /tf=5", "--decimate").unwrap();
        assert_eq!(d.every("/joints"), 10);
        assert_eq!(d.every("/tf"), 5);
        assert_eq!(d.every("/hzd"), DEFAULT_EVERY);
        assert_eq!(d.every("/scene"), DEFAULT_SCENE_EVERY);
        let e = Decimation::parse("/joints=0", "--decimate").unwrap_err();
        assert!(e.contains("--decimate") && e.contains("/joints=0"), "{e}");
        let e = Decimation::parse("/nope=3", "--decimate").unwrap_err();
        assert!(e.contains("/nope"), "{e}");
        let e = Decimation::parse("joints", "--decimate").unwrap_err();
        assert!(e.contains("topic=n"), "{e}");
    }

    #[test]
    fn a_feed_decimates_per_channel_and_reports_every_state_change() {
        let setup = crate::Setup::shipped().unwrap();
        let layout = crate::slots::SlotLayout::new(&setup.config, false);
        let ctx = crate::telemetry::log::LogContext::new(&setup, &layout);
        let d = Decimation::parse("/joints=1,/hzd=10", "test").unwrap();
        let mut feed = Feed::new(ctx.joint_names, ctx.output_names, ctx.scene, d);
        let mut out = Vec::new();
        for k in 0..100u64 {
            let s = StateSample {
                tick: k,
                t_s: k as f64 * 1e-3,
                state: if k < 50 { 2 } else { 3 },
                ..StateSample::default()
            };
            feed.push(&s, &mut out);
        }
        let count = |topic: &str| {
            let id = channel_id(topic).unwrap();
            out.iter().filter(|o| o.channel == id).count()
        };
        assert_eq!(count("/joints"), 100);
        assert_eq!(count("/hzd"), 10);
        assert_eq!(count("/estimator"), 100 / DEFAULT_EVERY as usize);
        assert_eq!(count("/tf"), 100 / DEFAULT_EVERY as usize);
        assert_eq!(count("/scene"), 1);
        assert_eq!(count("/transitions"), 1);
        let id = channel_id("/transitions").unwrap();
        let t = out.iter().find(|o| o.channel == id).unwrap();
        let v: Value = serde_json::from_slice(&t.payload).unwrap();
        assert_eq!(
            (v["from"].as_str(), v["to"].as_str()),
            (Some("stand"), Some("walk"))
        );
        assert_eq!(t.t_ns, 50_000_000);
    }
}
