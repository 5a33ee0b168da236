//! MCAP logging off the control thread.
//!
//! ```text
//! control thread ── LogProducer::push(LogRecord) ──▶ rtrb SPSC ring (wait-free; full → drop, counted)
//!                                                        │
//! writer thread ◀─ pop ─────────────────────────────────┘ ── JSON ──▶ mcap::Writer (zstd chunks) ──▶ file
//! ```
//! Channels (JSON messages with `jsonschema` schemas, plottable in Foxglove):
//! `/joints` (per joint q, dq, τ, temperature, commanded q, dq, τ), `/hzd` (phase, τ̇, stance,
//! steps, desired/actual outputs), `/estimator` (pitch, rate, gyro bias, raw IMU), `/state`
//! (state, trip, overruns, tick compute time), `/safety` (one message per trip, with its
//! values), `/transitions` (state changes), and for replay (`adam replay`, [`crate::telemetry::replay`])
//! `/input` (everything the controller read in a tick: time, motor replies, IMU sample,
//! operator command, overrun streak) and `/command` (every command it wrote, and its state),
//! both every tick whatever `log_every_n_ticks` says; `/speed` (one message per step while
//! treadmill speed control runs: [`crate::telemetry::speed_log`]); `/can` (every CAN frame: [`crate::telemetry::frames`]). Floats in `/input` and `/command` are
//! written in shortest round-trip form and read back bit for bit (serde_json
//! `float_roundtrip`); non-finite values are the strings `"NaN"`, `"inf"`, `"-inf"`.
//! For Foxglove's 3D panel ([`crate::telemetry::scene`]): `/tf` (`foxglove.FrameTransforms` of
//! every link, 100 Hz), `/scene` (`foxglove.SceneUpdate`: the belt, the links as lines) and
//! `/robot_description` (the URDF as `std_msgs/String`), each JSON. Schemas and the per-sample
//! messages come from [`crate::telemetry::channels`], shared with the live view.
//! The gait file, the runtime config and the robot's URDF are attached, so a log replays on
//! its own; metadata `run` describes the run (including `start_walking` and `with_held`,
//! which replay needs) and `log_stats` counts written and dropped records.

use crate::config::RuntimeConfig;
use crate::control::{CommandMode, ControlState, JointCommand, TickInput};
use crate::safety::Trip;
use crate::slots::{SlotLayout, OUTPUTS, SLOTS};
use crate::telemetry::sample::StateSample;
use crate::{Result, RuntimeError};
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

/// One record from the control thread to the writer.
// Samples dominate the queue; boxing them would allocate in the control thread.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LogRecord {
    /// The per-tick sample.
    Sample(StateSample),
    /// A safety trip.
    Trip {
        /// Time, s.
        t_s: f64,
        /// Tick.
        tick: u64,
        /// The trip.
        trip: Trip,
    },
    /// The controller's whole input and output of one tick (for replay).
    Tick(TickRecord),
    /// A state change.
    Transition {
        /// Time, s.
        t_s: f64,
        /// From.
        from: ControlState,
        /// To.
        to: ControlState,
    },
    /// Treadmill speed control at an impact.
    Speed {
        /// Time, s.
        t_s: f64,
        /// The controller's speed status after the impact.
        speed: crate::control::SpeedStatus,
        /// True position on the belt (simulator), m.
        true_position_m: Option<f64>,
    },
    /// Raw CAN frames of a bus operation ([`crate::telemetry::frames`]).
    Frames(super::frames::FrameBatch),
}

/// One tick as the controller saw it: what it read and what it commanded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickRecord {
    /// Tick counter.
    pub tick: u64,
    /// The controller's input.
    pub input: TickInput,
    /// Its commands by slot.
    pub commands: [JointCommand; SLOTS],
    /// Its state after the tick.
    pub state: ControlState,
}

/// The control thread's end: never blocks, never allocates.
pub struct LogProducer {
    ring: rtrb::Producer<LogRecord>,
    dropped: Arc<AtomicU64>,
    wait_when_full: bool,
}

impl LogProducer {
    /// Queue a record; when the ring is full the record is dropped and counted, or, after
    /// [`LogProducer::wait_when_full`], the push waits for room (drops only if the logger has
    /// stopped).
    pub fn push(&mut self, record: LogRecord) {
        let mut record = record;
        loop {
            match self.ring.push(record) {
                Ok(()) => return,
                Err(rtrb::PushError::Full(r))
                    if self.wait_when_full && !self.ring.is_abandoned() =>
                {
                    record = r;
                    // The logger drains every 2 ms.
                    std::thread::sleep(std::time::Duration::from_micros(500));
                }
                Err(_) => {
                    self.dropped.fetch_add(1, Ordering::Relaxed);
                    return;
                }
            }
        }
    }

    /// Wait for room in a full queue instead of dropping: for a loop on a simulated clock,
    /// where waiting costs no simulated time and the simulation may outrun the writer. A
    /// real-time loop never waits.
    pub fn wait_when_full(&mut self, wait: bool) {
        self.wait_when_full = wait;
    }

    /// Records dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }
}

/// What the logger wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LogStats {
    /// Records received from the control thread.
    pub records: u64,
    /// MCAP messages written (all channels).
    pub messages: u64,
    /// Records dropped because the queue was full.
    pub dropped: u64,
}

/// The writer thread.
pub struct Logger {
    path: PathBuf,
    stop: Arc<AtomicBool>,
    dropped: Arc<AtomicU64>,
    handle: JoinHandle<Result<LogStats>>,
}

/// Version of the channel layout and message fields written here. Every channel carries it as
/// channel metadata `adam_log_schema`; readers (`runtime::telemetry::log_read`) refuse any other version
/// instead of misreading it. Bump it whenever a field changes meaning or disappears.
pub const LOG_SCHEMA_VERSION: u32 = 1;

/// Channel metadata key holding [`LOG_SCHEMA_VERSION`].
pub const SCHEMA_VERSION_KEY: &str = "adam_log_schema";

pub use super::channels::CHANNELS;

/// Attachment names: the gait file, the runtime config, the robot's URDF.
pub const ATTACHMENTS: [&str; 3] = ["gait.json", "runtime.toml", "robot.urdf"];

/// The attachment of a run with a gait library: a JSON array of gait files, sorted by speed.
pub const LIBRARY_ATTACHMENT: &str = "library.json";

/// What the log describes besides the records.
#[derive(Clone, Debug)]
pub struct LogContext {
    /// Joint name per slot (`None`: slot not driven, not logged).
    pub joint_names: [Option<String>; SLOTS],
    /// Output names (stance hip, ...).
    pub output_names: [String; OUTPUTS],
    /// Gait file JSON (attachment).
    pub gait_json: String,
    /// Runtime config TOML (attachment).
    pub config_toml: String,
    /// The robot's URDF (attachment).
    pub urdf_text: String,
    /// The gait library as a JSON array (attachment [`LIBRARY_ATTACHMENT`]; `None`: none).
    pub library_json: Option<String>,
    /// Free-form run metadata.
    pub metadata: BTreeMap<String, String>,
    /// Compress chunks with zstd.
    pub zstd: bool,
    /// The robot in 3D (`/tf`, `/scene`, `/robot_description`; `None`: not logged).
    pub scene: Option<super::scene::RobotScene>,
}

/// The joint name of every driven slot of `layout` (`None`: not driven, not logged).
pub fn joint_names(config: &RuntimeConfig, layout: &SlotLayout) -> [Option<String>; SLOTS] {
    let mut names: [Option<String>; SLOTS] = Default::default();
    for (slot, name) in names.iter_mut().enumerate() {
        if !layout.present[slot] {
            continue;
        }
        *name = if slot < crate::slots::LEG_SLOTS {
            Some(config.leg_motors[slot].joint.clone())
        } else {
            config
                .held
                .get(slot - crate::slots::LEG_SLOTS)
                .map(|h| h.motor.joint.clone())
        };
    }
    names
}

impl LogContext {
    /// The context of a run of `setup` with this slot layout.
    pub fn new(setup: &crate::Setup, layout: &SlotLayout) -> Self {
        let (config, gait) = (&setup.config, &setup.gait);
        let joint_names = joint_names(config, layout);
        let mut output_names: [String; OUTPUTS] = Default::default();
        for (i, o) in gait.outputs.iter().enumerate().take(OUTPUTS) {
            output_names[i] = o.name.clone();
        }
        let mut metadata = BTreeMap::new();
        metadata.insert("robot".into(), gait.robot.name.clone());
        metadata.insert("urdf_sha256".into(), gait.robot.sha256.clone());
        metadata.insert("rate_hz".into(), config.loop_.rate_hz.to_string());
        metadata.insert("phase".into(), format!("{:?}", config.walk.phase));
        metadata.insert("runtime_version".into(), env!("CARGO_PKG_VERSION").into());
        metadata.insert("with_held".into(), layout.with_held().to_string());
        Self {
            joint_names,
            output_names,
            gait_json: serde_json::to_string_pretty(gait).unwrap_or_default(),
            config_toml: config.to_toml(),
            urdf_text: setup.urdf_text.clone(),
            library_json: (!setup.library.is_empty())
                .then(|| serde_json::to_string(&setup.library).unwrap_or_default()),
            metadata,
            zstd: config.telemetry.log_zstd,
            scene: super::scene::RobotScene::new(setup, *layout).ok(),
        }
    }
}

fn log_err(path: &Path, e: impl std::fmt::Display) -> RuntimeError {
    RuntimeError::Log {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Open `path`, write the header, schemas, channels and attachments, and start the writer
/// thread; returns the control thread's end and the logger.
pub fn start(
    path: impl AsRef<Path>,
    context: LogContext,
    queue_capacity: usize,
) -> Result<(LogProducer, Logger)> {
    let path = path.as_ref().to_path_buf();
    let file = std::fs::File::create(&path).map_err(|error| RuntimeError::Io {
        path: path.clone(),
        error,
    })?;
    let options = mcap::WriteOptions::new()
        .compression(context.zstd.then_some(mcap::Compression::Zstd))
        .profile("")
        .library(concat!("adam-hzd runtime ", env!("CARGO_PKG_VERSION")));
    let mut writer = options
        .create(BufWriter::new(file))
        .map_err(|e| log_err(&path, e))?;
    let ids = Channels::add(&mut writer, &context).map_err(|e| log_err(&path, e))?;
    for (name, media, data) in [
        (
            ATTACHMENTS[0],
            "application/json",
            context.gait_json.as_bytes(),
        ),
        (
            ATTACHMENTS[1],
            "application/toml",
            context.config_toml.as_bytes(),
        ),
        (
            ATTACHMENTS[2],
            "application/xml",
            context.urdf_text.as_bytes(),
        ),
    ]
    .into_iter()
    .chain(
        context
            .library_json
            .as_ref()
            .map(|l| (LIBRARY_ATTACHMENT, "application/json", l.as_bytes())),
    ) {
        writer
            .attach(&mcap::Attachment {
                log_time: 0,
                create_time: 0,
                name: name.into(),
                media_type: media.into(),
                data: std::borrow::Cow::Borrowed(data),
            })
            .map_err(|e| log_err(&path, e))?;
    }
    writer
        .write_metadata(&mcap::records::Metadata {
            name: "run".into(),
            metadata: context.metadata.clone(),
        })
        .map_err(|e| log_err(&path, e))?;
    let (producer, mut consumer) = rtrb::RingBuffer::new(queue_capacity.max(2));
    let stop = Arc::new(AtomicBool::new(false));
    let dropped = Arc::new(AtomicU64::new(0));
    let (stop_w, dropped_w, path_w) = (stop.clone(), dropped.clone(), path.clone());
    let handle = std::thread::Builder::new()
        .name("adam-log".into())
        .spawn(move || -> Result<LogStats> {
            let mut stats = LogStats::default();
            let mut w = RecordWriter {
                writer,
                scene: super::scene::SceneLog::default(),
                ids,
                context,
                seq: 0,
            };
            loop {
                // Read `stop` before draining so nothing pushed before the stop is missed.
                let stopping = stop_w.load(Ordering::Acquire);
                while let Ok(record) = consumer.pop() {
                    stats.records += 1;
                    stats.messages += w.write(&record).map_err(|e| log_err(&path_w, e))?;
                }
                if stopping {
                    break;
                }
                std::thread::sleep(std::time::Duration::from_millis(2));
            }
            stats.dropped = dropped_w.load(Ordering::Relaxed);
            let mut meta = BTreeMap::new();
            meta.insert("records".into(), stats.records.to_string());
            meta.insert("messages".into(), stats.messages.to_string());
            meta.insert("dropped".into(), stats.dropped.to_string());
            w.writer
                .write_metadata(&mcap::records::Metadata {
                    name: "log_stats".into(),
                    metadata: meta,
                })
                .map_err(|e| log_err(&path_w, e))?;
            w.writer.finish().map_err(|e| log_err(&path_w, e))?;
            Ok(stats)
        })
        .map_err(|e| RuntimeError::Thread {
            name: "adam-log",
            message: e.to_string(),
        })?;
    Ok((
        LogProducer {
            ring: producer,
            dropped: dropped.clone(),
            wait_when_full: false,
        },
        Logger {
            path,
            stop,
            dropped,
            handle,
        },
    ))
}

impl Logger {
    /// Records dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Drain the queue, finish the file and join the writer.
    pub fn finish(self) -> Result<LogStats> {
        self.stop.store(true, Ordering::Release);
        self.handle.join().map_err(|_| RuntimeError::Log {
            path: self.path.clone(),
            message: "writer thread panicked".into(),
        })?
    }
}

#[derive(Clone, Copy, Debug)]
struct Channels {
    joints: u16,
    hzd: u16,
    estimator: u16,
    state: u16,
    safety: u16,
    transitions: u16,
    input: u16,
    command: u16,
    speed: u16,
    can: u16,
    scene: super::scene::SceneChannels,
}

impl Channels {
    fn add<W: std::io::Write + std::io::Seek>(
        w: &mut mcap::Writer<W>,
        ctx: &LogContext,
    ) -> mcap::McapResult<Self> {
        let meta = BTreeMap::from([(
            SCHEMA_VERSION_KEY.to_string(),
            LOG_SCHEMA_VERSION.to_string(),
        )]);
        let mut ids = Vec::with_capacity(CHANNELS.len());
        for c in super::channels::channel_schemas(&ctx.joint_names, &ctx.output_names) {
            let text = serde_json::to_vec(&c.schema).unwrap_or_default();
            let sid = w.add_schema(c.schema_name, "jsonschema", &text)?;
            ids.push(w.add_channel(sid, c.topic, "json", &meta)?);
        }
        let scene = super::scene::add_scene_channels(w, &meta)?;
        Ok(Self {
            joints: ids[0],
            hzd: ids[1],
            estimator: ids[2],
            state: ids[3],
            safety: ids[4],
            transitions: ids[5],
            input: ids[6],
            command: ids[7],
            speed: ids[8],
            can: ids[9],
            scene,
        })
    }
}

struct RecordWriter<W: std::io::Write + std::io::Seek> {
    writer: mcap::Writer<W>,
    ids: Channels,
    context: LogContext,
    seq: u32,
    scene: super::scene::SceneLog,
}

/// Seconds to MCAP nanoseconds (negative times clamp to 0).
fn ns(t_s: f64) -> u64 {
    (t_s.max(0.0) * 1e9).round() as u64
}

/// A float as JSON that reads back bit for bit: a number, or `"NaN"`, `"inf"`, `"-inf"`.
pub fn exact_json(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else if x.is_nan() {
        json!("NaN")
    } else if x > 0.0 {
        json!("inf")
    } else {
        json!("-inf")
    }
}

/// The inverse of [`exact_json`] (`None`: neither a number nor one of the three strings).
pub fn exact_from_json(v: &Value) -> Option<f64> {
    match v {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => match s.as_str() {
            "NaN" => Some(f64::NAN),
            "inf" => Some(f64::INFINITY),
            "-inf" => Some(f64::NEG_INFINITY),
            _ => None,
        },
        _ => None,
    }
}

/// `/input` message of one tick (joints named by slot).
pub fn input_json(record: &TickRecord, joint_names: &[Option<String>; SLOTS]) -> Value {
    let input = &record.input;
    let mut m = Map::new();
    m.insert("t_s".into(), exact_json(input.t_s));
    m.insert("tick".into(), json!(record.tick));
    m.insert("overrun_streak".into(), json!(input.overrun_streak));
    m.insert(
        "operator".into(),
        input.operator.map_or(Value::Null, |c| json!(c.text())),
    );
    m.insert(
        "imu".into(),
        input.imu.map_or(Value::Null, |i| {
            json!({
                "t_s": exact_json(i.t_s), "gyro_pitch_rad_s": exact_json(i.gyro_pitch_rad_s),
                "accel_x_mps2": exact_json(i.accel_x_mps2),
                "accel_z_mps2": exact_json(i.accel_z_mps2),
            })
        }),
    );
    for (slot, name) in joint_names.iter().enumerate() {
        let Some(name) = name else { continue };
        let s = &input.motors[slot];
        m.insert(
            name.clone(),
            json!({
                "fresh": s.fresh, "q_rad": exact_json(s.q_rad),
                "dq_rad_s": exact_json(s.dq_rad_s), "tau_nm": exact_json(s.tau_nm),
                "temperature_c": exact_json(s.temperature_c), "errors": s.errors,
            }),
        );
    }
    Value::Object(m)
}

/// `/command` message of one tick.
pub fn command_json(record: &TickRecord, joint_names: &[Option<String>; SLOTS]) -> Value {
    let mut m = Map::new();
    m.insert("t_s".into(), exact_json(record.input.t_s));
    m.insert("tick".into(), json!(record.tick));
    m.insert("state".into(), json!(record.state.name()));
    for (slot, name) in joint_names.iter().enumerate() {
        let Some(name) = name else { continue };
        let c = &record.commands[slot];
        m.insert(
            name.clone(),
            json!({
                "mode": match c.mode { CommandMode::Pd => "pd", CommandMode::Damping => "damping" },
                "q_des_rad": exact_json(c.q_des_rad), "dq_des_rad_s": exact_json(c.dq_des_rad_s),
                "kp_nm_per_rad": exact_json(c.kp_nm_per_rad),
                "kd_nm_s_per_rad": exact_json(c.kd_nm_s_per_rad),
                "tau_ff_nm": exact_json(c.tau_ff_nm),
            }),
        );
    }
    Value::Object(m)
}

/// A trip as a JSON object with its reason and values.
pub fn trip_json(trip: &Trip) -> Value {
    let mut v = match *trip {
        Trip::EStop => json!({}),
        Trip::JointLimit {
            slot,
            q_rad,
            lower_rad,
            upper_rad,
        } => json!({"slot": slot, "q_rad": q_rad, "lower_rad": lower_rad, "upper_rad": upper_rad}),
        Trip::TorqueSaturation {
            slot,
            tau_nm,
            limit_nm,
            ticks,
        } => json!({"slot": slot, "tau_nm": tau_nm, "limit_nm": limit_nm, "ticks": ticks}),
        Trip::Fall {
            pitch_rad,
            limit_rad,
        } => json!({"pitch_rad": pitch_rad, "limit_rad": limit_rad}),
        Trip::OverTemperature {
            slot,
            temperature_c,
            limit_c,
        } => json!({"slot": slot, "temperature_c": temperature_c, "limit_c": limit_c}),
        Trip::MotorFault { slot, flags } => json!({"slot": slot, "flags": flags}),
        Trip::MissingReplies { slot, consecutive } => {
            json!({"slot": slot, "consecutive": consecutive})
        }
        Trip::ImuStale { age_s, limit_s } => json!({"age_s": age_s, "limit_s": limit_s}),
        Trip::ImuImplausible {
            gyro_rad_s,
            accel_norm_mps2,
        } => json!({"gyro_rad_s": gyro_rad_s, "accel_norm_mps2": accel_norm_mps2}),
        Trip::OverrunStreak { streak, limit } => json!({"streak": streak, "limit": limit}),
        Trip::StepTimeout { elapsed_s, limit_s } => {
            json!({"elapsed_s": elapsed_s, "limit_s": limit_s})
        }
    };
    v["reason"] = json!(trip.name());
    v["code"] = json!(trip.code());
    v
}

impl<W: std::io::Write + std::io::Seek> RecordWriter<W> {
    fn put(&mut self, channel: u16, t_s: f64, v: &Value) -> mcap::McapResult<()> {
        let data = serde_json::to_vec(v).unwrap_or_default();
        self.seq = self.seq.wrapping_add(1);
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: channel,
                sequence: self.seq,
                log_time: ns(t_s),
                publish_time: ns(t_s),
            },
            &data,
        )
    }

    /// Write one record; returns the number of MCAP messages written.
    fn write(&mut self, record: &LogRecord) -> mcap::McapResult<u64> {
        match record {
            LogRecord::Sample(s) => {
                let t = s.t_s;
                let [joints, hzd, estimator, state] = super::channels::sample_messages(
                    s,
                    &self.context.joint_names,
                    &self.context.output_names,
                );
                let ids = self.ids;
                self.put(ids.joints, t, &joints)?;
                self.put(ids.hzd, t, &hzd)?;
                self.put(ids.estimator, t, &estimator)?;
                self.put(ids.state, t, &state)?;
                let scene = self.context.scene.as_ref();
                Ok(4 + self
                    .scene
                    .write(&mut self.writer, scene, &ids.scene, s, &mut self.seq)?)
            }
            LogRecord::Tick(record) => {
                let t = record.input.t_s;
                let ids = self.ids;
                let input = input_json(record, &self.context.joint_names);
                self.put(ids.input, t, &input)?;
                let command = command_json(record, &self.context.joint_names);
                self.put(ids.command, t, &command)?;
                Ok(2)
            }
            LogRecord::Trip { t_s, tick, trip } => {
                let mut v = trip_json(trip);
                v["t_s"] = json!(t_s);
                v["tick"] = json!(tick);
                self.put(self.ids.safety, *t_s, &v)?;
                Ok(1)
            }
            LogRecord::Transition { t_s, from, to } => {
                let v = json!({"t_s": t_s, "from": from.name(), "to": to.name()});
                self.put(self.ids.transitions, *t_s, &v)?;
                Ok(1)
            }
            LogRecord::Speed {
                t_s,
                speed,
                true_position_m,
            } => {
                let v = super::speed_log::speed_json(*t_s, speed, *true_position_m);
                self.put(self.ids.speed, *t_s, &v)?;
                Ok(1)
            }
            LogRecord::Frames(batch) => super::frames::batch_json(batch)
                .try_fold(0, |n, (t, v)| self.put(self.ids.can, t, &v).map(|()| n + 1)),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::Setup;
    use std::collections::HashMap;

    /// A unique temporary file path (no tempfile crate: the test removes it).
    pub(crate) fn temp_path(tag: &str) -> PathBuf {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos();
        std::env::temp_dir().join(format!("adam-{tag}-{}-{nanos}.mcap", std::process::id()))
    }

    #[test]
    fn written_log_rereads_with_the_expected_channels_counts_and_attachments() {
        let setup = Setup::shipped().unwrap();
        let layout = SlotLayout::new(&setup.config, false);
        let ctx = LogContext::new(&setup, &layout);
        let path = temp_path("log");
        // A queue that holds the whole run: this test is about content, not drops (which a
        // busy machine could cause with a small queue; see the next test).
        let (mut tx, logger) = start(&path, ctx, 1024).unwrap();
        let n = 500;
        for k in 0..n {
            let mut s = StateSample {
                tick: k,
                t_s: k as f64 * 1e-3,
                ..StateSample::default()
            };
            s.q_rad[1] = 0.001 * k as f64;
            tx.push(LogRecord::Sample(s));
            if k == 100 {
                tx.push(LogRecord::Transition {
                    t_s: 0.1,
                    from: ControlState::Idle,
                    to: ControlState::Ramp,
                });
            }
            if k == 200 {
                tx.push(LogRecord::Trip {
                    t_s: 0.2,
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
        assert_eq!(stats.records, n + 2);
        // 4 per sample, a transition, a trip; and the scene: /tf every 10 ms of the 0.5 s,
        // /scene and /robot_description at the first sample.
        let tf = n / 10;
        assert_eq!(stats.messages, 4 * n + 2 + tf + 2);

        let bytes = std::fs::read(&path).unwrap();
        let mut counts: HashMap<String, u64> = HashMap::new();
        let mut knee = Vec::new();
        let mut trip = None;
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            let schema = m.channel.schema.as_ref().unwrap();
            assert_eq!(schema.encoding, "jsonschema");
            assert_eq!(m.channel.message_encoding, "json");
            *counts.entry(m.channel.topic.clone()).or_default() += 1;
            let v: Value = serde_json::from_slice(&m.data).unwrap();
            match m.channel.topic.as_str() {
                "/joints" => knee.push(v["left_knee_pitch"]["q_rad"].as_f64().unwrap()),
                "/safety" => trip = Some(v),
                _ => {}
            }
        }
        for topic in ["/joints", "/hzd", "/estimator", "/state"] {
            assert_eq!(counts[topic], n, "{topic}");
        }
        assert_eq!(counts["/safety"], 1);
        assert_eq!(counts["/transitions"], 1);
        assert_eq!(counts["/tf"], tf);
        assert_eq!((counts["/scene"], counts["/robot_description"]), (1, 1));
        assert!((knee[123] - 0.123).abs() < 1e-12);
        let trip = trip.unwrap();
        assert_eq!(trip["reason"], "fall");
        assert_eq!(trip["pitch_rad"], 0.7);
        // Attachments and metadata are indexed in the summary.
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let names: Vec<_> = summary
            .attachment_indexes
            .iter()
            .map(|a| a.name.clone())
            .collect();
        assert_eq!(names, ATTACHMENTS);
        let gait = mcap::read::attachment(&bytes, &summary.attachment_indexes[0]).unwrap();
        assert!(
            model::gait::GaitFile::from_json(std::str::from_utf8(&gait.data).unwrap(), "log")
                .is_ok()
        );
        let stats_index = summary
            .metadata_indexes
            .iter()
            .find(|m| m.name == "log_stats")
            .unwrap();
        let meta = mcap::read::metadata(&bytes, stats_index).unwrap();
        assert_eq!(meta.metadata["dropped"], "0");
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn a_full_queue_drops_and_counts_instead_of_blocking() {
        let setup = Setup::shipped().unwrap();
        let layout = SlotLayout::new(&setup.config, false);
        let ctx = LogContext::new(&setup, &layout);
        let path = temp_path("drops");
        let (mut tx, logger) = start(&path, ctx, 16).unwrap();
        // 10 000 pushes in a burst far outrun a writer that sleeps 2 ms between drains.
        for k in 0..10_000u64 {
            tx.push(LogRecord::Sample(StateSample {
                tick: k,
                ..StateSample::default()
            }));
        }
        let dropped = tx.dropped();
        let stats = logger.finish().unwrap();
        assert!(dropped > 0);
        assert_eq!(stats.dropped, dropped);
        assert_eq!(stats.records + stats.dropped, 10_000);
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn a_producer_that_waits_when_full_drops_nothing() {
        let setup = Setup::shipped().unwrap();
        let layout = SlotLayout::new(&setup.config, false);
        let ctx = LogContext::new(&setup, &layout);
        let path = temp_path("waits");
        let (mut tx, logger) = start(&path, ctx, 16).unwrap();
        tx.wait_when_full(true);
        // The same burst as above: every push now waits for the writer.
        for k in 0..10_000u64 {
            tx.push(LogRecord::Sample(StateSample {
                tick: k,
                ..StateSample::default()
            }));
        }
        assert_eq!(tx.dropped(), 0);
        let stats = logger.finish().unwrap();
        assert_eq!((stats.records, stats.dropped), (10_000, 0));
        std::fs::remove_file(&path).unwrap();
    }
}
