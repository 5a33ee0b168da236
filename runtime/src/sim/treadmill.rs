//! What a simulated run is told from outside, in time: the belt's speed profile
//! ([`BeltProfile`], `--belt "0:0.20,20:0.30,40:0.25"`), pushes on the torso ([`parse_push`],
//! `--push "10.5:-20:0.2"`) and scripted operator commands ([`parse_script`], `--script
//! "3:stop,10:walk"`). Each parser names the pair at fault, its field and value.
//!
//! A profile's pairs are `time s : speed m/s`: at each time the belt starts toward the speed,
//! ramping at the simulator's `belt_acceleration_mps2` (default 0.5 m/s²); a pair at time 0
//! sets the speed the belt starts at (without one the belt starts at rest).

use crate::config::TreadmillConfig;
use crate::control::OperatorCommand;
use crate::sim::faults::{Fault, FaultEvent};
use crate::{Result, RuntimeError};

/// A belt-speed profile: target speeds at times, ramped at the simulator's acceleration.
#[derive(Clone, Debug, PartialEq)]
pub struct BeltProfile {
    /// `(time s, speed m/s)`, times increasing from ≥ 0.
    pub points: Vec<(f64, f64)>,
}

fn invalid(origin: &str, field: String, value: String, reason: &str) -> RuntimeError {
    RuntimeError::InvalidField {
        origin: origin.into(),
        field,
        value,
        reason: reason.into(),
    }
}

/// A number of a `a:b:c` list, or an error naming `field` of pair `k` (from 1).
fn number(origin: &str, what: &str, k: usize, field: &str, text: &str) -> Result<f64> {
    text.trim().parse::<f64>().map_err(|_| {
        invalid(
            origin,
            format!("{what} {k} ({field})"),
            format!("`{}`", text.trim()),
            "not a number",
        )
    })
}

impl BeltProfile {
    /// A constant belt at `speed_mps` from the start.
    pub fn constant(speed_mps: f64) -> Self {
        Self {
            points: vec![(0.0, speed_mps)],
        }
    }

    /// Parse `time:speed` pairs separated by commas; `origin` (e.g. `--belt`) names the source
    /// in errors, which name the pair (from 1), the field and the value.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let mut points = Vec::new();
        for (i, pair) in text.split(',').enumerate() {
            let k = i + 1;
            let parts: Vec<&str> = pair.split(':').collect();
            if parts.len() != 2 {
                return Err(invalid(
                    origin,
                    format!("pair {k}"),
                    format!("`{}`", pair.trim()),
                    "expected time:speed, e.g. 20:0.30 (s, m/s)",
                ));
            }
            let t = number(origin, "pair", k, "time", parts[0])?;
            let v = number(origin, "pair", k, "speed", parts[1])?;
            points.push((t, v));
        }
        let profile = Self { points };
        profile.validate(origin)?;
        Ok(profile)
    }

    /// Refuse an empty profile, a negative, non-finite or non-increasing time, a non-finite or
    /// negative speed, naming the pair (from 1), the field and the value.
    pub fn validate(&self, origin: &str) -> Result<()> {
        if self.points.is_empty() {
            return Err(invalid(
                origin,
                "pairs".into(),
                "none".into(),
                "a belt profile needs at least one time:speed pair",
            ));
        }
        let mut last_t = f64::NEG_INFINITY;
        for (i, &(t, v)) in self.points.iter().enumerate() {
            let k = i + 1;
            if !(t.is_finite() && t >= 0.0) {
                return Err(invalid(
                    origin,
                    format!("pair {k} (time)"),
                    format!("{t} s"),
                    "must be ≥ 0 and finite",
                ));
            }
            if t <= last_t {
                return Err(invalid(
                    origin,
                    format!("pair {k} (time)"),
                    format!("{t} s"),
                    "must be later than the pair before",
                ));
            }
            if !(v.is_finite() && v >= 0.0) {
                return Err(invalid(
                    origin,
                    format!("pair {k} (speed)"),
                    format!("{v} m/s"),
                    "must be ≥ 0 and finite",
                ));
            }
            last_t = t;
        }
        Ok(())
    }

    /// Check every speed against the treadmill's range, naming the pair.
    pub fn check_range(&self, treadmill: &TreadmillConfig, origin: &str) -> Result<()> {
        for (i, &(t, v)) in self.points.iter().enumerate() {
            treadmill.check_belt_speed(&format!("{origin} pair {} ({t}:{v})", i + 1), v)?;
        }
        Ok(())
    }

    /// The speed the belt starts at: that of a pair at time 0, else at rest, m/s.
    pub fn initial_speed_mps(&self) -> f64 {
        match self.points.first() {
            Some(&(0.0, v)) => v,
            _ => 0.0,
        }
    }
}

/// Parse a push `time:force:duration` (s, N with + forward, s) with an optional `:phase`
/// (the push then lands at that phase of the first step that begins after the time, in
/// `[0, 1)`), into a fault event ([`Fault::Push`] or [`Fault::PushAtPhase`]). Errors name
/// `origin`, the field and the value.
pub fn parse_push(text: &str, origin: &str) -> Result<FaultEvent> {
    let parts: Vec<&str> = text.split(':').collect();
    if !(3..=4).contains(&parts.len()) {
        return Err(invalid(
            origin,
            "push".into(),
            format!("`{}`", text.trim()),
            "expected time:force:duration[:phase], e.g. 10.5:-20:0.2 (s, N, s)",
        ));
    }
    let field = |name: &str, k: usize| -> Result<f64> {
        let v = parts[k].trim().parse::<f64>().map_err(|_| {
            invalid(
                origin,
                format!("push {name}"),
                format!("`{}`", parts[k].trim()),
                "not a number",
            )
        })?;
        if !v.is_finite() {
            return Err(invalid(
                origin,
                format!("push {name}"),
                v.to_string(),
                "must be finite",
            ));
        }
        Ok(v)
    };
    let (at_s, force_x_n, duration_s) =
        (field("time", 0)?, field("force", 1)?, field("duration", 2)?);
    if at_s < 0.0 {
        return Err(invalid(
            origin,
            "push time".into(),
            format!("{at_s} s"),
            "must be ≥ 0",
        ));
    }
    if duration_s <= 0.0 {
        return Err(invalid(
            origin,
            "push duration".into(),
            format!("{duration_s} s"),
            "must be positive",
        ));
    }
    let fault = if parts.len() == 4 {
        let phase = field("phase", 3)?;
        if !(0.0..1.0).contains(&phase) {
            return Err(invalid(
                origin,
                "push phase".into(),
                phase.to_string(),
                "must be in [0, 1)",
            ));
        }
        Fault::PushAtPhase {
            force_x_n,
            force_z_n: 0.0,
            phase,
        }
    } else {
        Fault::Push {
            force_x_n,
            force_z_n: 0.0,
        }
    };
    Ok(FaultEvent {
        at_s,
        duration_s,
        fault,
    })
}

/// An operator command of a script by name, with its argument (`name=value`) if it takes one.
type ScriptCommand = fn(Option<&str>) -> core::result::Result<OperatorCommand, &'static str>;

/// A command that takes no value.
fn no_value(
    arg: Option<&str>,
    command: OperatorCommand,
) -> core::result::Result<OperatorCommand, &'static str> {
    match arg {
        None => Ok(command),
        Some(_) => Err("takes no value"),
    }
}

/// The script's command names: [`OperatorCommand::name`] of every command. A command with a
/// value (`speed=0.25`) adds a row here whose function parses it.
pub const SCRIPT_COMMANDS: [(&str, ScriptCommand); 6] = [
    ("start", |a| no_value(a, OperatorCommand::Start)),
    ("walk", |a| no_value(a, OperatorCommand::Walk)),
    ("stop", |a| no_value(a, OperatorCommand::Stop)),
    ("damp", |a| no_value(a, OperatorCommand::Damp)),
    ("reset", |a| no_value(a, OperatorCommand::Reset)),
    ("estop", |a| no_value(a, OperatorCommand::EStop)),
];

/// Parse operator commands scripted in time, `time:command` pairs separated by commas (e.g.
/// `3:stop,10:walk`; a command with a value as `time:name=value`), sorted by time. Errors
/// name `origin`, the pair (from 1), the field and the value.
pub fn parse_script(text: &str, origin: &str) -> Result<Vec<(f64, OperatorCommand)>> {
    let mut out = Vec::new();
    for (i, pair) in text.split(',').enumerate() {
        let k = i + 1;
        let Some((t, command)) = pair.split_once(':') else {
            return Err(invalid(
                origin,
                format!("pair {k}"),
                format!("`{}`", pair.trim()),
                "expected time:command, e.g. 3:stop",
            ));
        };
        let t = number(origin, "pair", k, "time", t)?;
        if !(t.is_finite() && t >= 0.0) {
            return Err(invalid(
                origin,
                format!("pair {k} (time)"),
                format!("{t} s"),
                "must be ≥ 0 and finite",
            ));
        }
        let command = command.trim();
        let (name, arg) = match command.split_once('=') {
            Some((n, a)) => (n.trim(), Some(a.trim())),
            None => (command, None),
        };
        let names: Vec<&str> = SCRIPT_COMMANDS.iter().map(|(n, _)| *n).collect();
        let Some((_, make)) = SCRIPT_COMMANDS.iter().find(|(n, _)| *n == name) else {
            return Err(invalid(
                origin,
                format!("pair {k} (command)"),
                format!("`{name}`"),
                &format!("unknown command: expected one of {}", names.join(", ")),
            ));
        };
        let cmd = make(arg).map_err(|reason| {
            invalid(
                origin,
                format!("pair {k} (command {name})"),
                format!("`{command}`"),
                reason,
            )
        })?;
        out.push((t, cmd));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn a_belt_profile_parses_and_a_bad_pair_is_named_with_its_value() {
        let p = BeltProfile::parse("0:0.20, 20:0.30,40:0.25", "--belt").unwrap();
        assert_eq!(p.points, [(0.0, 0.2), (20.0, 0.3), (40.0, 0.25)]);
        assert_eq!(p.initial_speed_mps(), 0.2);
        assert_eq!(
            BeltProfile::parse("5:0.25", "--belt")
                .unwrap()
                .initial_speed_mps(),
            0.0
        );
        for (text, field, value) in [
            ("0:0.2,-1:0.3", "pair 2 (time)", "-1 s"),
            ("0:0.2,20:0.3,10:0.25", "pair 3 (time)", "10 s"),
            ("0:0.2,20:0.3,20:0.25", "pair 3 (time)", "20 s"),
            ("0:NaN", "pair 1 (speed)", "NaN m/s"),
            ("0:inf", "pair 1 (speed)", "inf m/s"),
            ("0:-0.1", "pair 1 (speed)", "-0.1 m/s"),
            ("0:0.2,x:0.3", "pair 2 (time)", "`x`"),
            ("0:0.2,20", "pair 2", "`20`"),
        ] {
            let e = BeltProfile::parse(text, "--belt").unwrap_err().to_string();
            assert!(
                e.contains("--belt") && e.contains(field) && e.contains(value),
                "{text}: {e}"
            );
        }
        let treadmill = TreadmillConfig::default();
        let e = BeltProfile::parse("0:0.2,10:0.7", "--belt")
            .unwrap()
            .check_range(&treadmill, "--belt")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--belt pair 2 (10:0.7)") && e.contains("0.7"),
            "{e}"
        );
    }

    #[test]
    fn pushes_parse_and_bad_ones_name_the_field() {
        let e = parse_push("10.5:-20:0.2", "--push").unwrap();
        assert_eq!((e.at_s, e.duration_s), (10.5, 0.2));
        assert_eq!(
            e.fault,
            Fault::Push {
                force_x_n: -20.0,
                force_z_n: 0.0
            }
        );
        let e = parse_push("3:40:0.2:0.3", "--push").unwrap();
        assert_eq!(
            e.fault,
            Fault::PushAtPhase {
                force_x_n: 40.0,
                force_z_n: 0.0,
                phase: 0.3
            }
        );
        for (text, field, value) in [
            ("1:inf:0.2", "push force", "inf"),
            ("1:NaN:0.2", "push force", "NaN"),
            ("1:20:0", "push duration", "0 s"),
            ("-1:20:0.2", "push time", "-1 s"),
            ("1:20:0.2:1.5", "push phase", "1.5"),
            ("1:20", "push", "`1:20`"),
            ("1:x:0.2", "push force", "`x`"),
        ] {
            let e = parse_push(text, "--push").unwrap_err().to_string();
            assert!(
                e.contains("--push") && e.contains(field) && e.contains(value),
                "{text}: {e}"
            );
        }
    }

    #[test]
    fn scripts_parse_by_name_sorted_and_unknown_commands_are_named() {
        let s = parse_script("10:walk,3:stop", "--script").unwrap();
        assert_eq!(
            s,
            [(3.0, OperatorCommand::Stop), (10.0, OperatorCommand::Walk)]
        );
        for (name, _) in SCRIPT_COMMANDS {
            let c = parse_script(&format!("1:{name}"), "--script").unwrap()[0].1;
            assert_eq!(c.name(), name);
        }
        for (text, field, value) in [
            ("3:jump", "pair 1 (command)", "`jump`"),
            ("3:stop,x:walk", "pair 2 (time)", "`x`"),
            ("3:stop,-2:walk", "pair 2 (time)", "-2 s"),
            ("3", "pair 1", "`3`"),
            ("3:stop=1", "pair 1 (command stop)", "`stop=1`"),
        ] {
            let e = parse_script(text, "--script").unwrap_err().to_string();
            assert!(
                e.contains("--script") && e.contains(field) && e.contains(value),
                "{text}: {e}"
            );
        }
        let e = parse_script("3:jump", "--script").unwrap_err().to_string();
        assert!(e.contains("walk") && e.contains("estop"), "{e}");
    }
}
