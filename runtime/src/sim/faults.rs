//! Fault profiles for the simulated robot: what goes wrong, and when.
//!
//! A [`FaultProfile`] is checked data (TOML, `deny_unknown_fields`, [`FaultProfile::validate`]
//! names the field and value it refuses) with three parts:
//! * `wire`: CAN faults for the whole run (loss, corruption, delay), applied by
//!   [`drivers::sim::bus::SimBus`];
//! * `events`: faults at given times for given durations ([`Fault`]: a silent, hot or faulted
//!   motor, IMU dropout, spike or freeze, loop overruns, a belt-speed step, a push, a push at
//!   a phase point of the next step: `{ kind = "push_at_phase", force_x_n = -20.0,
//!   force_z_n = 0.0, phase = 0.3 }`);
//! * `random`: faults drawn from a list at exponentially distributed intervals (the soak).
//!
//! [`FaultProfile::schedule`] turns the events and the random part into one time-sorted list
//! for a run — pure and seeded: the same seed gives the same schedule. [`crate::sim::run`]
//! applies it while the loop runs. Built-in profiles have names ([`BUILT_IN`]); anything else is
//! read as a TOML file:
//!
//! ```toml
//! schema_version = 1
//! [wire]
//! loss_probability = 0.01
//! [[events]]
//! at_s = 1.0
//! duration_s = 0.1
//! fault = { kind = "push", force_x_n = 40.0, force_z_n = 0.0 }
//! [random]
//! mean_interval_s = 5.0
//! faults = [{ duration_s = 0.001, fault = { kind = "imu_spike", gyro_rad_s = 100.0 } }]
//! ```

use crate::{Result, RuntimeError};
use drivers::sim::wire::WireFaults;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Version of the fault-profile format this build reads.
pub const FAULT_PROFILE_VERSION: u32 = 1;

/// Leg motor slots a fault can name (left hip, left knee, right hip, right knee).
const LEG_MOTORS: usize = 4;

/// Faults of the CAN wire, for the whole run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireConfig {
    /// Probability that a frame (command or reply) is lost.
    #[serde(default)]
    pub loss_probability: f64,
    /// Probability that a frame arrives damaged (rejected by the decoder: a missing reply).
    #[serde(default)]
    pub corrupt_probability: f64,
    /// Probability that a reply is delayed by `delay_ms`.
    #[serde(default)]
    pub delay_probability: f64,
    /// Delay of a delayed reply, ms (more than the 1 ms period: the reply is missing).
    #[serde(default)]
    pub delay_ms: f64,
}

impl WireConfig {
    /// The simulated bus's form.
    pub fn to_wire_faults(self) -> WireFaults {
        WireFaults {
            loss_probability: self.loss_probability,
            corrupt_probability: self.corrupt_probability,
            delay_probability: self.delay_probability,
            delay_s: self.delay_ms * 1e-3,
        }
    }
}

/// One fault of the robot or the loop. Motor slots: 0 left hip, 1 left knee, 2 right hip,
/// 3 right knee.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Fault {
    /// The motor neither receives nor replies (a cut cable).
    SilentMotor {
        /// Leg motor slot.
        slot: usize,
    },
    /// The motor's winding is set to this temperature at the start; the thermal model carries
    /// on from there (the fault's duration does not cool it).
    HotMotor {
        /// Leg motor slot.
        slot: usize,
        /// Winding temperature, °C.
        temperature_c: f64,
    },
    /// The motor reports these firmware fault bits ([`drivers::a1::ErrorFlags`]).
    MotorFlags {
        /// Leg motor slot.
        slot: usize,
        /// Fault bits.
        flags: u8,
    },
    /// The IMU delivers no sample.
    ImuDropout,
    /// The gyro reads this much more than the truth.
    ImuSpike {
        /// Added pitch rate, rad/s.
        gyro_rad_s: f64,
    },
    /// The IMU repeats its last good sample.
    ImuFrozen,
    /// The loop wakes this late after every deadline (more than a period: an overrun).
    Overrun {
        /// Lateness, ms.
        late_ms: f64,
    },
    /// The belt runs at this speed, then returns to its speed before.
    BeltSpeed {
        /// Belt speed, m/s.
        speed_mps: f64,
    },
    /// A force on the torso at the hip axis (world frame), for the fault's duration.
    Push {
        /// Forward force, N.
        force_x_n: f64,
        /// Upward force, N.
        force_z_n: f64,
    },
    /// [`Fault::Push`] landing at a phase point of a step: from the fault's start, the push
    /// waits for the next step to begin and acts when the controller's phase reaches `phase`,
    /// for the fault's duration.
    PushAtPhase {
        /// Forward force, N.
        force_x_n: f64,
        /// Upward force, N.
        force_z_n: f64,
        /// Phase τ of the step at which the push starts, in `[0, 1)`.
        phase: f64,
    },
}

impl Fault {
    /// Short name (tables, logs).
    pub fn name(&self) -> &'static str {
        match self {
            Fault::SilentMotor { .. } => "silent_motor",
            Fault::HotMotor { .. } => "hot_motor",
            Fault::MotorFlags { .. } => "motor_flags",
            Fault::ImuDropout => "imu_dropout",
            Fault::ImuSpike { .. } => "imu_spike",
            Fault::ImuFrozen => "imu_frozen",
            Fault::Overrun { .. } => "overrun",
            Fault::BeltSpeed { .. } => "belt_speed",
            Fault::Push { .. } => "push",
            Fault::PushAtPhase { .. } => "push_at_phase",
        }
    }

    /// The first invalid field (name relative to the fault, value, reason).
    fn invalid(&self) -> Option<(&'static str, String, &'static str)> {
        let finite =
            |field, v: f64| (!v.is_finite()).then(|| (field, v.to_string(), "must be finite"));
        match *self {
            Fault::SilentMotor { slot }
            | Fault::HotMotor { slot, .. }
            | Fault::MotorFlags { slot, .. }
                if slot >= LEG_MOTORS =>
            {
                Some(("slot", slot.to_string(), "must be a leg motor slot 0..=3"))
            }
            Fault::HotMotor { temperature_c, .. } => finite("temperature_c", temperature_c),
            Fault::MotorFlags { flags: 0, .. } => {
                Some(("flags", "0".into(), "must set at least one fault bit"))
            }
            Fault::ImuSpike { gyro_rad_s } => finite("gyro_rad_s", gyro_rad_s),
            Fault::Overrun { late_ms } if !(late_ms.is_finite() && late_ms > 0.0) => Some((
                "late_ms",
                late_ms.to_string(),
                "must be positive and finite",
            )),
            Fault::BeltSpeed { speed_mps } => finite("speed_mps", speed_mps),
            Fault::Push {
                force_x_n,
                force_z_n,
            } => finite("force_x_n", force_x_n).or_else(|| finite("force_z_n", force_z_n)),
            Fault::PushAtPhase {
                force_x_n,
                force_z_n,
                phase,
            } => finite("force_x_n", force_x_n)
                .or_else(|| finite("force_z_n", force_z_n))
                .or_else(|| {
                    (!(0.0..1.0).contains(&phase))
                        .then(|| ("phase", phase.to_string(), "must be in [0, 1)"))
                }),
            _ => None,
        }
    }
}

/// A fault at a given time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultEvent {
    /// Start, s of simulated time.
    pub at_s: f64,
    /// How long it lasts, s (0: one control period).
    #[serde(default)]
    pub duration_s: f64,
    /// What goes wrong.
    pub fault: Fault,
}

/// A random fault of the soak: what and for how long.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomFault {
    /// How long it lasts, s.
    pub duration_s: f64,
    /// What goes wrong.
    pub fault: Fault,
}

/// Faults drawn at random: one of `faults`, uniformly, at exponentially distributed intervals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomFaults {
    /// Mean time between the end of one fault and the start of the next, s.
    pub mean_interval_s: f64,
    /// The faults to draw from.
    pub faults: Vec<RandomFault>,
}

/// A fault profile (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultProfile {
    /// Format version ([`FAULT_PROFILE_VERSION`]).
    pub schema_version: u32,
    /// CAN faults for the whole run.
    #[serde(default)]
    pub wire: WireConfig,
    /// Faults at given times.
    #[serde(default)]
    pub events: Vec<FaultEvent>,
    /// Random faults.
    #[serde(default)]
    pub random: Option<RandomFaults>,
}

/// A fault active over `[start_s, end_s)` of simulated time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScheduledFault {
    /// Start, s.
    pub start_s: f64,
    /// End, s.
    pub end_s: f64,
    /// What goes wrong.
    pub fault: Fault,
}

/// Names of the built-in profiles, with what they do.
pub const BUILT_IN: [(&str, &str); 8] = [
    ("none", "no faults"),
    ("loss-0.1", "0.1 % of CAN frames lost"),
    ("loss-1", "1 % of CAN frames lost"),
    ("loss-10", "10 % of CAN frames lost"),
    (
        "corrupt-1",
        "1 % of CAN frames corrupted (rejected by the decoder)",
    ),
    (
        "delay-1",
        "1 % of replies delayed by 2 ms (past the 1 ms period)",
    ),
    (
        "soak",
        "0.1 % loss, 0.1 % corruption, and every ~4 s one of: push, IMU spike/dropout/freeze, \
         overrun burst, belt step, silent/hot/faulted motor",
    ),
    (
        "rough",
        "the soak's random faults every ~1.5 s, harder pushes, and 1 % loss",
    ),
];

fn wire(loss: f64, corrupt: f64, delay: f64) -> WireConfig {
    WireConfig {
        loss_probability: loss,
        corrupt_probability: corrupt,
        delay_probability: delay,
        delay_ms: if delay > 0.0 { 2.0 } else { 0.0 },
    }
}

fn soak_faults(push_n: f64) -> Vec<RandomFault> {
    let f = |duration_s, fault| RandomFault { duration_s, fault };
    vec![
        f(
            0.1,
            Fault::Push {
                force_x_n: push_n,
                force_z_n: 0.0,
            },
        ),
        f(
            0.1,
            Fault::Push {
                force_x_n: -push_n,
                force_z_n: 0.0,
            },
        ),
        f(0.001, Fault::ImuSpike { gyro_rad_s: 100.0 }),
        f(0.01, Fault::ImuDropout),
        f(0.05, Fault::ImuDropout),
        f(0.2, Fault::ImuFrozen),
        f(0.005, Fault::Overrun { late_ms: 1.5 }),
        f(0.05, Fault::Overrun { late_ms: 1.5 }),
        f(2.0, Fault::BeltSpeed { speed_mps: 0.25 }),
        f(0.05, Fault::SilentMotor { slot: 1 }),
        f(
            0.5,
            Fault::HotMotor {
                slot: 3,
                temperature_c: 88.0,
            },
        ),
        f(
            0.1,
            Fault::MotorFlags {
                slot: 2,
                flags: 1 << 3,
            },
        ),
    ]
}

impl FaultProfile {
    /// No faults.
    pub fn none() -> Self {
        Self {
            schema_version: FAULT_PROFILE_VERSION,
            ..Self::default()
        }
    }

    /// A built-in profile by name ([`BUILT_IN`]).
    pub fn built_in(name: &str) -> Option<Self> {
        let mut p = Self::none();
        match name {
            "none" => {}
            "loss-0.1" => p.wire = wire(0.001, 0.0, 0.0),
            "loss-1" => p.wire = wire(0.01, 0.0, 0.0),
            "loss-10" => p.wire = wire(0.1, 0.0, 0.0),
            "corrupt-1" => p.wire = wire(0.0, 0.01, 0.0),
            "delay-1" => p.wire = wire(0.0, 0.0, 0.01),
            "soak" => {
                p.wire = wire(0.001, 0.001, 0.0);
                p.random = Some(RandomFaults {
                    mean_interval_s: 4.0,
                    faults: soak_faults(40.0),
                });
            }
            "rough" => {
                p.wire = wire(0.01, 0.0, 0.0);
                p.random = Some(RandomFaults {
                    mean_interval_s: 1.5,
                    faults: soak_faults(80.0),
                });
            }
            _ => return None,
        }
        Some(p)
    }

    /// A built-in profile's name, or else the path of a TOML profile.
    pub fn resolve(name_or_path: &str) -> Result<Self> {
        if let Some(p) = Self::built_in(name_or_path) {
            return Ok(p);
        }
        let path = Path::new(name_or_path);
        if path.extension().and_then(|e| e.to_str()) == Some("toml") {
            return Self::load(path);
        }
        Err(RuntimeError::InvalidField {
            origin: "command line".into(),
            field: "faults".into(),
            value: format!("`{name_or_path}`"),
            reason: format!(
                "unknown fault profile: expected one of {} or a .toml file",
                BUILT_IN.map(|(n, _)| n).join(", ")
            ),
        })
    }

    /// Read and validate a TOML profile.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|error| RuntimeError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Parse and validate TOML; `origin` names the source in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self> {
        let profile: Self = toml::from_str(text).map_err(|e| RuntimeError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        profile.validate(origin)?;
        Ok(profile)
    }

    /// Refuse a wrong version, probabilities outside `[0, 1]`, negative or non-finite times,
    /// unknown motor slots and non-finite magnitudes, naming the field and value.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let bad = |field: String, value: String, reason: &str| {
            Err(RuntimeError::InvalidField {
                origin: origin.to_string(),
                field,
                value,
                reason: reason.to_string(),
            })
        };
        if self.schema_version != FAULT_PROFILE_VERSION {
            return bad(
                "schema_version".into(),
                self.schema_version.to_string(),
                "this build reads fault profile version 1",
            );
        }
        let w = self.wire;
        for (field, p) in [
            ("wire.loss_probability", w.loss_probability),
            ("wire.corrupt_probability", w.corrupt_probability),
            ("wire.delay_probability", w.delay_probability),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return bad(field.into(), p.to_string(), "must be in [0, 1]");
            }
        }
        if !(w.delay_ms.is_finite() && w.delay_ms >= 0.0) {
            return bad(
                "wire.delay_ms".into(),
                w.delay_ms.to_string(),
                "must be ≥ 0 and finite",
            );
        }
        let time = |v: f64| v.is_finite() && v >= 0.0;
        for (i, e) in self.events.iter().enumerate() {
            if !time(e.at_s) {
                return bad(
                    format!("events[{i}].at_s"),
                    e.at_s.to_string(),
                    "must be ≥ 0 and finite",
                );
            }
            if !time(e.duration_s) {
                return bad(
                    format!("events[{i}].duration_s"),
                    e.duration_s.to_string(),
                    "must be ≥ 0 and finite",
                );
            }
            if let Some((field, value, reason)) = e.fault.invalid() {
                return bad(format!("events[{i}].fault.{field}"), value, reason);
            }
        }
        if let Some(r) = &self.random {
            if !(r.mean_interval_s.is_finite() && r.mean_interval_s > 0.0) {
                return bad(
                    "random.mean_interval_s".into(),
                    r.mean_interval_s.to_string(),
                    "must be positive and finite",
                );
            }
            if r.faults.is_empty() {
                return bad("random.faults".into(), "[]".into(), "must list a fault");
            }
            for (i, f) in r.faults.iter().enumerate() {
                if !time(f.duration_s) {
                    return bad(
                        format!("random.faults[{i}].duration_s"),
                        f.duration_s.to_string(),
                        "must be ≥ 0 and finite",
                    );
                }
                if let Some((field, value, reason)) = f.fault.invalid() {
                    return bad(format!("random.faults[{i}].fault.{field}"), value, reason);
                }
            }
        }
        Ok(())
    }

    /// The faults of a run of `duration_s`, sorted by start: the events, then random faults
    /// (one at a time, separated by exponential gaps) from a generator seeded with `seed`.
    /// A zero duration lasts one control period of `period_s`.
    pub fn schedule(&self, duration_s: f64, period_s: f64, seed: u64) -> Vec<ScheduledFault> {
        let span = |start_s: f64, d: f64, fault| ScheduledFault {
            start_s,
            end_s: start_s + d.max(period_s),
            fault,
        };
        let mut out: Vec<ScheduledFault> = self
            .events
            .iter()
            .filter(|e| e.at_s < duration_s)
            .map(|e| span(e.at_s, e.duration_s, e.fault))
            .collect();
        if let Some(r) = &self.random {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5EED_FA17_0000_0002);
            let mut t = 0.0;
            loop {
                let u: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
                t += -r.mean_interval_s * u.ln();
                if t >= duration_s {
                    break;
                }
                let f = r.faults[rng.random_range(0..r.faults.len())];
                let s = span(t, f.duration_s, f.fault);
                t = s.end_s;
                out.push(s);
            }
        }
        out.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
        out
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn built_in_profiles_validate_and_unknown_names_are_refused_by_name() {
        for (name, _) in BUILT_IN {
            let p = FaultProfile::built_in(name).unwrap();
            p.validate(name).unwrap();
        }
        let e = FaultProfile::resolve("los-1").unwrap_err().to_string();
        assert!(e.contains("`los-1`") && e.contains("loss-1"), "{e}");
    }

    #[test]
    fn toml_round_trips_and_bad_fields_are_named() {
        let text = r#"
            schema_version = 1
            [wire]
            loss_probability = 0.01
            [[events]]
            at_s = 1.0
            duration_s = 0.1
            fault = { kind = "push", force_x_n = 40.0, force_z_n = 0.0 }
            [[events]]
            at_s = 2.0
            fault = { kind = "silent_motor", slot = 2 }
            [random]
            mean_interval_s = 5.0
            faults = [{ duration_s = 0.001, fault = { kind = "imu_spike", gyro_rad_s = 100.0 } }]
        "#;
        let p = FaultProfile::from_toml(text, "t.toml").unwrap();
        assert_eq!(p.events.len(), 2);
        assert_eq!(p.events[1].fault, Fault::SilentMotor { slot: 2 });
        let back = FaultProfile::from_toml(&toml::to_string(&p).unwrap(), "back").unwrap();
        assert_eq!(back, p);
        for (edit, field, value) in [
            ("slot = 2", "events[1].fault.slot", "7"),
            ("loss_probability = 0.01", "wire.loss_probability", "1.5"),
            ("at_s = 2.0", "events[1].at_s", "-1"),
            ("mean_interval_s = 5.0", "random.mean_interval_s", "0"),
        ] {
            let key = edit.split(" = ").next().unwrap();
            let bad = text.replace(edit, &format!("{key} = {value}"));
            let e = FaultProfile::from_toml(&bad, "t.toml")
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("t.toml") && e.contains(field) && e.contains(value),
                "{e}"
            );
        }
        // Unknown fields and kinds: the parser names them.
        let e = FaultProfile::from_toml(&text.replace("slot = 2", "slott = 2"), "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("slott"), "{e}");
        let e = FaultProfile::from_toml(&text.replace("\"push\"", "\"shove\""), "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("shove"), "{e}");
    }

    #[test]
    fn schedules_are_seeded_sorted_and_non_overlapping() {
        let p = FaultProfile::built_in("soak").unwrap();
        let a = p.schedule(120.0, 1e-3, 7);
        assert_eq!(a, p.schedule(120.0, 1e-3, 7));
        assert_ne!(a, p.schedule(120.0, 1e-3, 8));
        // Mean gap 4 s plus durations: about 120 / 4.3 ≈ 28 faults; Poisson sd ≈ 5.
        assert!((12..=45).contains(&a.len()), "{}", a.len());
        for w in a.windows(2) {
            assert!(w[0].end_s <= w[1].start_s);
        }
        assert!(a.iter().all(|s| s.start_s < 120.0 && s.end_s > s.start_s));
        // A zero duration lasts one period.
        let mut q = FaultProfile::none();
        q.events.push(FaultEvent {
            at_s: 1.0,
            duration_s: 0.0,
            fault: Fault::ImuDropout,
        });
        assert_eq!(q.schedule(2.0, 1e-3, 0)[0].end_s, 1.001);
        assert!(q.schedule(0.5, 1e-3, 0).is_empty());
    }
}
