//! Deterministic replay of a log through the controller: `adam replay <run.mcap>`.
//!
//! ```text
//! run.mcap ─┬─ attachments gait.json, runtime.toml, robot.urdf ─▶ Setup ─▶ Controller (as at start)
//!           ├─ metadata run: with_held, start_walking
//!           └─ /input (tick k) ─▶ Controller::tick ─▶ commands ─┐
//!              /command (tick k) ─────────────────────────────── compare bit for bit
//! ```
//! The loop ([`crate::rt_loop`]) logs, every tick, everything [`Controller::tick`] read
//! (`/input`: time, motor replies, IMU sample, operator command, overrun streak) and everything
//! it commanded (`/command`: state and one command per driven motor), floats in shortest
//! round-trip form. Replay rebuilds the controller from the attachments, feeds it the
//! recorded inputs at the recorded ticks and compares every command field and the state with
//! the logged ones, bit for bit. The first difference is reported (tick, time, joint, field,
//! logged vs replayed); a log that skips a tick (the logger dropped records) is an error, since
//! the controller's state would silently differ.
//!
//! The fixtures under `tests/fixtures/` are replayed in CI: a controller change that alters any
//! command fails them with that report. When the change is intended, re-mint them with
//! `cargo run --release -- replay --mint tests/fixtures` ([`mint_fixtures`]) and commit them.
//!
//! ```no_run
//! let report = runtime::telemetry::replay::replay("tests/fixtures/walk.mcap").unwrap();
//! assert!(report.divergence.is_none(), "{report}");
//! ```

use crate::control::{
    CommandMode, ControlState, Controller, JointCommand, OperatorCommand, TickInput, TickOutput,
};
use crate::slots::{MotorSample, SLOTS};
use crate::telemetry::log::{exact_from_json, joint_names, CHANNELS};
use crate::telemetry::log_read::{check_schema_version, log_err, read_bytes, TopLevel};
use crate::telemetry::salvage::Salvaged;
use crate::{Result, Setup};
use drivers::imu::ImuSample;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The first place where the replayed controller differs from the log.
#[derive(Clone, Debug, PartialEq)]
pub struct Divergence {
    /// Tick.
    pub tick: u64,
    /// Controller time, s.
    pub t_s: f64,
    /// Joint name, or `state`.
    pub joint: String,
    /// Field (`state`, `mode`, `q_des_rad`, …).
    pub field: &'static str,
    /// Logged value.
    pub logged: String,
    /// Replayed value.
    pub replayed: String,
}

impl std::fmt::Display for Divergence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "tick {} (t = {:.4} s), {} {}: logged {}, replayed {}",
            self.tick, self.t_s, self.joint, self.field, self.logged, self.replayed
        )
    }
}

/// What a replay found.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayReport {
    /// The log.
    pub path: PathBuf,
    /// Ticks replayed (up to and including a divergence).
    pub ticks: u64,
    /// Command fields compared (plus one state per tick).
    pub values_compared: u64,
    /// The first difference, if any.
    pub divergence: Option<Divergence>,
    /// The states the replayed controller went through, in order (consecutive repeats merged;
    /// never empty: the first is its state before the first tick).
    pub states: Vec<ControlState>,
    /// The log is cut off or damaged: where, how much was read and what was lost (replay
    /// covers every tick up to the first one lost).
    pub truncated: Option<String>,
    /// The log was rewritten by `adam logs recover`: what the recovery lost.
    pub recovered: Option<String>,
    /// Ticks missing after the last one replayed (lost to damage), where replay stopped.
    pub gap: Option<String>,
    /// Controller time of the last tick replayed, s.
    pub last_t_s: f64,
}

impl std::fmt::Display for ReplayReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "log        {}", self.path.display())?;
        writeln!(f, "ticks      {}", self.ticks)?;
        writeln!(f, "compared   {} values", self.values_compared)?;
        let states: Vec<&str> = self.states.iter().map(|s| s.name()).collect();
        writeln!(f, "states     {}", states.join(" → "))?;
        if let Some(t) = &self.truncated {
            writeln!(f, "not whole  {t}")?;
        }
        if let Some(r) = &self.recovered {
            writeln!(f, "recovered  {r}")?;
        }
        if self.truncated.is_some() || self.recovered.is_some() {
            let part = match &self.gap {
                Some(g) => format!("; {g}: replay stops there"),
                None if self.truncated.is_some() => {
                    "; every tick the log still holds (replayed every complete tick)".into()
                }
                None => "; every tick of the recovered log".into(),
            };
            writeln!(
                f,
                "checked    ticks 0–{} (t = 0–{:.3} s){part}",
                self.ticks.saturating_sub(1),
                self.last_t_s
            )?;
        }
        match &self.divergence {
            None => writeln!(f, "result     bit-identical"),
            Some(d) => writeln!(f, "result     DIVERGED at {d}"),
        }
    }
}

fn float_text(x: f64) -> String {
    format!("{x:?} (bits 0x{:016x})", x.to_bits())
}

fn mode_name(mode: CommandMode) -> &'static str {
    match mode {
        CommandMode::Pd => "pd",
        CommandMode::Damping => "damping",
    }
}

/// Reads the fields of one message, naming the log, channel, tick and field in errors.
struct Fields<'a> {
    path: &'a Path,
    topic: &'a str,
    tick: u64,
}

impl Fields<'_> {
    fn err(&self, field: &str, what: &str) -> crate::RuntimeError {
        log_err(
            self.path,
            format!("{} tick {}: field {field} {what}", self.topic, self.tick),
        )
    }
    fn float(&self, v: &Value, field: &str) -> Result<f64> {
        exact_from_json(&v[field]).ok_or_else(|| {
            self.err(
                field,
                &format!(
                    "is {} (want a number, \"NaN\", \"inf\" or \"-inf\")",
                    v[field]
                ),
            )
        })
    }
    fn uint(&self, v: &Value, field: &str) -> Result<u64> {
        v[field].as_u64().ok_or_else(|| {
            self.err(
                field,
                &format!("is {} (want an unsigned integer)", v[field]),
            )
        })
    }
    fn str<'v>(&self, v: &'v Value, field: &str) -> Result<&'v str> {
        v[field]
            .as_str()
            .ok_or_else(|| self.err(field, &format!("is {} (want a string)", v[field])))
    }
}

fn tick_of(path: &Path, topic: &str, v: &Value) -> Result<u64> {
    v["tick"].as_u64().ok_or_else(|| {
        log_err(
            path,
            format!("{topic} message without an unsigned `tick` ({})", v["tick"]),
        )
    })
}

fn parse_input(
    path: &Path,
    v: &Value,
    tick: u64,
    names: &[Option<String>; SLOTS],
) -> Result<TickInput> {
    let f = Fields {
        path,
        topic: CHANNELS[6],
        tick,
    };
    let mut input = TickInput {
        t_s: f.float(v, "t_s")?,
        overrun_streak: u32::try_from(f.uint(v, "overrun_streak")?)
            .map_err(|_| f.err("overrun_streak", "does not fit in 32 bits"))?,
        ..TickInput::default()
    };
    input.operator = match &v["operator"] {
        Value::Null => None,
        Value::String(text) => Some(
            OperatorCommand::parse(text)
                .map_err(|e| f.err("operator", &format!("is `{text}`: {e}")))?,
        ),
        other => return Err(f.err("operator", &format!("is {other} (want a name or null)"))),
    };
    input.imu = match &v["imu"] {
        Value::Null => None,
        imu @ Value::Object(_) => Some(ImuSample {
            t_s: f.float(imu, "t_s")?,
            gyro_pitch_rad_s: f.float(imu, "gyro_pitch_rad_s")?,
            accel_x_mps2: f.float(imu, "accel_x_mps2")?,
            accel_z_mps2: f.float(imu, "accel_z_mps2")?,
        }),
        other => return Err(f.err("imu", &format!("is {other} (want an object or null)"))),
    };
    for (slot, name) in names.iter().enumerate() {
        let Some(name) = name else { continue };
        let m = &v[name.as_str()];
        if !m.is_object() {
            return Err(f.err(name, "is missing"));
        }
        input.motors[slot] = MotorSample {
            fresh: m["fresh"]
                .as_bool()
                .ok_or_else(|| f.err(&format!("{name}.fresh"), "is not a boolean"))?,
            q_rad: f.float(m, "q_rad")?,
            dq_rad_s: f.float(m, "dq_rad_s")?,
            tau_nm: f.float(m, "tau_nm")?,
            temperature_c: f.float(m, "temperature_c")?,
            errors: u8::try_from(f.uint(m, "errors")?)
                .map_err(|_| f.err(&format!("{name}.errors"), "does not fit in 8 bits"))?,
        };
    }
    Ok(input)
}

/// Compare the logged `/command` message with the replayed output; the first difference.
fn compare(
    path: &Path,
    logged: &Value,
    tick: u64,
    t_s: f64,
    out: &TickOutput,
    names: &[Option<String>; SLOTS],
    compared: &mut u64,
) -> Result<Option<Divergence>> {
    let f = Fields {
        path,
        topic: CHANNELS[7],
        tick,
    };
    let differ = |joint: &str, field: &'static str, logged: String, replayed: String| {
        Some(Divergence {
            tick,
            t_s,
            joint: joint.to_string(),
            field,
            logged,
            replayed,
        })
    };
    let state = f.str(logged, "state")?;
    *compared += 1;
    if state != out.status.state.name() {
        return Ok(differ(
            "state",
            "state",
            state.into(),
            out.status.state.name().into(),
        ));
    }
    for (slot, name) in names.iter().enumerate() {
        let Some(name) = name else { continue };
        let c = &logged[name.as_str()];
        if !c.is_object() {
            return Err(f.err(name, "is missing"));
        }
        let r: &JointCommand = &out.commands[slot];
        let mode = f.str(c, "mode")?;
        *compared += 1;
        if mode != mode_name(r.mode) {
            return Ok(differ(name, "mode", mode.into(), mode_name(r.mode).into()));
        }
        for (field, replayed) in [
            ("q_des_rad", r.q_des_rad),
            ("dq_des_rad_s", r.dq_des_rad_s),
            ("kp_nm_per_rad", r.kp_nm_per_rad),
            ("kd_nm_s_per_rad", r.kd_nm_s_per_rad),
            ("tau_ff_nm", r.tau_ff_nm),
        ] {
            let logged = f.float(c, field)?;
            *compared += 1;
            if logged.to_bits() != replayed.to_bits() {
                return Ok(differ(
                    name,
                    field,
                    float_text(logged),
                    float_text(replayed),
                ));
            }
        }
    }
    Ok(None)
}

fn metadata_bool(path: &Path, value: Option<&str>, key: &str) -> Result<bool> {
    match value {
        Some("true") => Ok(true),
        Some("false") => Ok(false),
        Some(other) => Err(log_err(
            path,
            format!("metadata run.{key} is {other:?} (want true or false)"),
        )),
        None => Err(log_err(
            path,
            format!("metadata run.{key} is missing (a log written before replay support?)"),
        )),
    }
}

/// The controller the log `path` (top-level records `top`) was recorded with, as it was before
/// its first tick, with the output the loop starts from.
fn controller_of_log(path: &Path, top: &TopLevel) -> Result<(Setup, Controller, TickOutput)> {
    let setup = top.setup(path)?;
    let with_held = metadata_bool(path, top.metadata_value("run", "with_held"), "with_held")?;
    let start_walking = metadata_bool(
        path,
        top.metadata_value("run", "start_walking"),
        "start_walking",
    )?;
    let mut controller = setup.controller(with_held)?;
    let mut out = TickOutput::default();
    if start_walking {
        // As the loop does before its first tick.
        controller.begin_walk_at_step_start(0.0, &mut out.status);
    }
    Ok((setup, controller, out))
}

/// Replay `path` through the controller of this build; see the module docs.
pub fn replay(path: impl AsRef<Path>) -> Result<ReplayReport> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    let log = Salvaged::read(path, &bytes)?;
    let top = TopLevel::of(&log);
    let (setup, mut controller, mut out) = controller_of_log(path, &top)?;
    let names = joint_names(&setup.config, controller.layout());
    let recovered = top.metadata.iter().find(|m| m.name == "recovery").map(|m| {
        let source = m.metadata.get("source").map_or("?", String::as_str);
        let what = m
            .metadata
            .get("summary")
            .or_else(|| m.metadata.get("stopped"));
        format!("from {source}: {}", what.map_or("?", String::as_str))
    });
    // Ticks may be missing where chunks were lost; anywhere else a jump is an error.
    let lossy = log.loss.summary().is_some()
        || top
            .metadata_value("recovery", "lost_chunks")
            .is_some_and(|n| n != "0");
    let mut report = ReplayReport {
        path: path.to_path_buf(),
        ticks: 0,
        values_compared: 0,
        divergence: None,
        states: vec![controller.state()],
        truncated: log.loss.summary(),
        recovered,
        gap: None,
        last_t_s: 0.0,
    };
    let mut pending: Option<(u64, TickInput)> = None;
    let mut checked = [false; 2];
    for m in log.messages() {
        let topic = m.channel.topic.as_str();
        let which = match topic {
            t if t == CHANNELS[6] => 0,
            t if t == CHANNELS[7] => 1,
            _ => continue,
        };
        if !checked[which] {
            check_schema_version(path, &m.channel)?;
            checked[which] = true;
        }
        let v: Value = serde_json::from_slice(&m.data)
            .map_err(|e| log_err(path, format!("{topic} message is not JSON: {e}")))?;
        let tick = tick_of(path, topic, &v)?;
        if lossy && tick != report.ticks && (which == 0 || pending.is_none()) {
            report.gap = Some(format!(
                "ticks {}–{} are missing (lost to damage)",
                report.ticks,
                tick.saturating_sub(1)
            ));
            break;
        }
        if which == 0 {
            if let Some((k, _)) = pending {
                return Err(log_err(
                    path,
                    format!("{topic} tick {tick} follows tick {k}, which has no /command"),
                ));
            }
            if tick != report.ticks {
                return Err(log_err(
                    path,
                    format!(
                        "{topic} jumps from tick {} to tick {tick}: ticks are missing (the \
                         logger dropped records?) and replay needs every tick",
                        report.ticks
                    ),
                ));
            }
            pending = Some((tick, parse_input(path, &v, tick, &names)?));
            continue;
        }
        let Some((k, input)) = pending.take() else {
            return Err(log_err(
                path,
                format!("{topic} tick {tick} without its /input"),
            ));
        };
        if k != tick {
            return Err(log_err(
                path,
                format!("{topic} tick {tick} after /input tick {k}"),
            ));
        }
        controller.tick(&input, &mut out);
        report.ticks += 1;
        report.last_t_s = input.t_s;
        if report.states.last() != Some(&out.status.state) {
            report.states.push(out.status.state);
        }
        report.divergence = compare(
            path,
            &v,
            tick,
            input.t_s,
            &out,
            &names,
            &mut report.values_compared,
        )?;
        if report.divergence.is_some() {
            break;
        }
    }
    if report.ticks == 0 {
        return Err(log_err(
            path,
            match &report.truncated {
                Some(t) => format!("no complete tick left to replay ({t})"),
                None => {
                    "no /input and /command messages (a log written before replay support?)".into()
                }
            },
        ));
    }
    Ok(report)
}

/// The replay fixtures [`mint_fixtures`] writes: file name and what it covers.
pub const FIXTURES: [(&str, &str); 3] = [
    (
        "walk.mcap",
        "2.0 s of walking on the simulated treadmill (robot simulator, seed 3): phase, stance \
         switches, pitch fusion, feed-forward",
    ),
    (
        "state_machine.mcap",
        "1.6 s on four free joints (no robot dynamics) with a static IMU: Idle, Start → Ramp → \
         Stand, Walk, Stop, e-stop → Damping, Reset",
    ),
    (
        "estop.mcap",
        "0.8 s of walking on the simulated treadmill, e-stop at 0.6 s: the trip and Damping",
    ),
];

/// Record the [`FIXTURES`] into `dir` with `setup` (the shipped config and default gait);
/// returns the files written. To keep them small, the per-tick sample channels are logged at
/// 50 Hz (`/input` and `/command` are logged every tick regardless; the walk at 100 Hz, below)
/// and the state machine's ramp lasts at least 0.5 s instead of the config's value.
pub fn mint_fixtures(setup: &Setup, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut setup = setup.clone();
    // The walk's gait tiles (tests/replay.rs) need a sample in the last 5 % of the step's phase;
    // near the impact the phase advances up to 0.055 per 20 ms, so 50 Hz can miss it.
    setup.config.telemetry.log_every_n_ticks = 10;
    let walk_setup = setup.clone();
    setup.config.telemetry.log_every_n_ticks = 20;
    let setup = &setup;
    use crate::rt_loop::{LoopOptions, SimulatedClock};
    use crate::sim::run::{sim_backend, walk, SimWalkOptions};
    std::fs::create_dir_all(dir).map_err(|error| crate::RuntimeError::Io {
        path: dir.to_path_buf(),
        error,
    })?;
    let paths: Vec<PathBuf> = FIXTURES.iter().map(|(name, _)| dir.join(name)).collect();

    let mut options = SimWalkOptions::new(2.0);
    options.seed = 3;
    options.log_path = Some(paths[0].clone());
    walk(&walk_setup, &options)?;

    let mut quick_ramp = setup.clone();
    quick_ramp.config.ramp.min_duration_s = 0.5;
    let mut options = LoopOptions::simulation(1.6);
    options.script = vec![
        (0.02, OperatorCommand::Start),
        (0.8, OperatorCommand::Walk),
        (1.2, OperatorCommand::Stop),
        (1.4, OperatorCommand::EStop),
        (1.5, OperatorCommand::Reset),
    ];
    options.log_path = Some(paths[1].clone());
    // A little off the gait's first pose, as a robot hung in its stand would be.
    let first = setup.controller(false)?.first_pose();
    let start: Vec<f64> = (0..setup.config.leg_motors.len())
        .map(|j| first[j] + 0.1 * (-1f64).powi(j as i32))
        .collect();
    let imu = crate::backend::StaticImu {
        pitch_rad: 0.02,
        gyro_bias_rad_s: 0.002,
    };
    crate::run(
        &quick_ramp,
        crate::sim::run::joint_bench_backend(setup, &start, imu)?,
        SimulatedClock::default(),
        options,
        None,
    )?;

    let walk_options = SimWalkOptions::new(0.8);
    let mut options = LoopOptions::simulation(walk_options.duration_s);
    options.start_walking = true;
    options.script = vec![(0.6, OperatorCommand::EStop)];
    options.log_path = Some(paths[2].clone());
    crate::run(
        setup,
        sim_backend(setup, &walk_options)?,
        SimulatedClock::default(),
        options,
        None,
    )?;
    Ok(paths)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::sim::run::{walk, SimWalkOptions};
    use crate::telemetry::log_read::top_level;
    use std::collections::BTreeMap;

    fn temp_path(tag: &str) -> PathBuf {
        std::env::temp_dir().join(format!(
            "adam-replay-{tag}-{}-{:?}.mcap",
            std::process::id(),
            std::thread::current().id()
        ))
    }

    /// Copy `input` to `output`, letting `edit` change (or drop, by returning false) each
    /// message and `attach` change each attachment.
    fn rewrite(
        input: &Path,
        output: &Path,
        mut edit: impl FnMut(&str, &mut Value) -> bool,
        mut attach: impl FnMut(&str, &mut Vec<u8>),
    ) {
        let bytes = std::fs::read(input).unwrap();
        let top = top_level(input, &bytes).unwrap();
        let file = std::fs::File::create(output).unwrap();
        let mut w = mcap::WriteOptions::new()
            .create(std::io::BufWriter::new(file))
            .unwrap();
        for (h, data) in &top.attachments {
            let mut data = data.clone();
            attach(&h.name, &mut data);
            w.attach(&mcap::Attachment {
                log_time: 0,
                create_time: 0,
                name: h.name.clone(),
                media_type: h.media_type.clone(),
                data: std::borrow::Cow::Owned(data),
            })
            .unwrap();
        }
        for m in &top.metadata {
            w.write_metadata(m).unwrap();
        }
        let mut ids: BTreeMap<u16, u16> = BTreeMap::new();
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            let id = *ids.entry(m.channel.id).or_insert_with(|| {
                let s = m.channel.schema.as_ref().unwrap();
                let sid = w.add_schema(&s.name, &s.encoding, &s.data).unwrap();
                w.add_channel(
                    sid,
                    &m.channel.topic,
                    &m.channel.message_encoding,
                    &m.channel.metadata,
                )
                .unwrap()
            });
            let mut v: Value = serde_json::from_slice(&m.data).unwrap();
            if !edit(&m.channel.topic, &mut v) {
                continue;
            }
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: id,
                    sequence: m.sequence,
                    log_time: m.log_time,
                    publish_time: m.publish_time,
                },
                &serde_json::to_vec(&v).unwrap(),
            )
            .unwrap();
        }
        w.finish().unwrap();
    }

    #[test]
    fn exact_floats_round_trip_through_json_bit_for_bit() {
        let mut x = 0.1f64;
        for k in 0..2000 {
            // Awkward values: long mantissas, subnormals, huge and tiny exponents, signs.
            x = (x * 1.618_033_988_749_895 + 0.3).fract() * 10f64.powi(k % 40 - 20);
            let v = if k % 2 == 0 { x } else { -x };
            for y in [v, f64::from_bits(v.to_bits() + 1), 5e-324, -0.0] {
                let text = serde_json::to_string(&crate::telemetry::log::exact_json(y)).unwrap();
                let back: Value = serde_json::from_str(&text).unwrap();
                let z = exact_from_json(&back).unwrap();
                assert_eq!(z.to_bits(), y.to_bits(), "{y:e} → {text}");
            }
        }
        for y in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let z = exact_from_json(&crate::telemetry::log::exact_json(y)).unwrap();
            assert!(z.is_nan() == y.is_nan() && (y.is_nan() || z == y));
        }
    }

    #[test]
    fn a_sim_log_replays_bit_identically_and_every_kind_of_change_is_reported() {
        let setup = Setup::shipped().unwrap();
        let path = temp_path("walk");
        let mut options = SimWalkOptions::new(0.6);
        options.log_path = Some(path.clone());
        let walked = walk(&setup, &options).unwrap();
        assert_eq!(walked.summary.log.unwrap().dropped, 0);

        let report = replay(&path).unwrap();
        assert_eq!(report.divergence, None, "{report}");
        assert_eq!(report.ticks, 600);
        assert_eq!(report.states, [ControlState::Walk]);
        // One state plus six fields for each of the four leg motors, every tick.
        assert_eq!(report.values_compared, 600 * (1 + 4 * 6));
        assert!(report.to_string().contains("bit-identical"), "{report}");

        // A logged command off by one unit in the last place is found, with where and what.
        let edited = temp_path("edited");
        rewrite(
            &path,
            &edited,
            |topic, v| {
                if topic == "/command" && v["tick"] == 250 {
                    let x = v["left_knee_pitch"]["q_des_rad"].as_f64().unwrap();
                    v["left_knee_pitch"]["q_des_rad"] =
                        serde_json::json!(f64::from_bits(x.to_bits() + 1));
                }
                true
            },
            |_, _| {},
        );
        let d = replay(&edited).unwrap().divergence.unwrap();
        assert_eq!(
            (d.tick, d.joint.as_str(), d.field),
            (250, "left_knee_pitch", "q_des_rad")
        );
        assert!(d.to_string().contains("tick 250"), "{d}");

        // A different controller (here: its gains in the attached config) diverges at once.
        rewrite(
            &path,
            &edited,
            |_, _| true,
            |name, data| {
                if name == "runtime.toml" {
                    let mut doc: toml::Table =
                        toml::from_str(std::str::from_utf8(data).unwrap()).unwrap();
                    let kp = &mut doc["gains"]["kp_nm_per_rad"][0];
                    *kp = toml::Value::Float(kp.as_float().unwrap() * 1.01);
                    *data = toml::to_string(&doc).unwrap().into_bytes();
                }
            },
        );
        let d = replay(&edited).unwrap().divergence.unwrap();
        assert_eq!(d.tick, 0, "{d}");

        // A tick missing from the log (a dropped record) is an error, not a silent misreplay.
        rewrite(
            &path,
            &edited,
            |topic, v| !(matches!(topic, "/input" | "/command") && v["tick"] == 100),
            |_, _| {},
        );
        let e = replay(&edited).unwrap_err().to_string();
        assert!(
            e.contains("ticks are missing") && e.contains("tick 101"),
            "{e}"
        );
        std::fs::remove_file(&edited).unwrap();
        std::fs::remove_file(&path).unwrap();
    }
}
