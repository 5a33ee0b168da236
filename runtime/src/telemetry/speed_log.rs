//! The `/speed` channel: one message per step while treadmill speed control runs (the
//! controller's [`SpeedStatus`] at each impact, with the simulator's true position on the belt
//! where it is known). Read back by [`crate::telemetry::speed_read`].
//!
//! Fields: `t_s`, `belt_mps` (set by the operator), `offset_mps`, `requested_mps` (before the
//! clamp to the library's range), `commanded_mps`, `clamped`, `step_speed_mps` (measured),
//! `step_length_m`, `step_duration_s`, `position_m` (estimated, + forward),
//! `true_position_m` (`null` without ground truth), `library_mps` (the gait in use for the next
//! step), `integral_mps`, `step_offset_m` (the step lever: how much longer than its gait's the
//! next step lands), `step_lean_rad` (the step lean: how far forward the next step leans the
//! torso, − back).

use crate::control::SpeedStatus;
use serde_json::{json, Value};

/// The channel's topic.
pub const SPEED_TOPIC: &str = "/speed";

/// The JSON schema of a `/speed` message.
pub fn speed_schema() -> Value {
    // One `type` per field (Foxglove's JSON-schema reader takes no type lists); null allowed.
    let number = || json!({"type": "number", "description": "null when not known"});
    json!({"type": "object", "properties": {
        "t_s": number(), "belt_mps": number(), "offset_mps": number(),
        "requested_mps": number(), "commanded_mps": number(), "clamped": {"type": "boolean"},
        "step_speed_mps": number(), "step_length_m": number(), "step_duration_s": number(),
        "position_m": number(), "true_position_m": number(), "library_mps": number(),
        "integral_mps": number(), "step_offset_m": number(), "step_lean_rad": number()}})
}

/// `x` if finite, else NaN: the value a `/speed` field reads back as (a value that is not
/// finite is written `null`, and `null` reads as NaN). The one mapping the log writer and
/// [`crate::telemetry::speed_read::SpeedRow::from_update`] share.
pub fn finite_or_nan(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        f64::NAN
    }
}

/// A finite number, or `null`.
fn num(x: f64) -> Value {
    let x = finite_or_nan(x);
    if x.is_nan() {
        Value::Null
    } else {
        json!(x)
    }
}

/// The `/speed` message of one impact.
pub fn speed_json(t_s: f64, s: &SpeedStatus, true_position_m: Option<f64>) -> Value {
    json!({
        "t_s": t_s, "belt_mps": num(s.belt_mps), "offset_mps": num(s.offset_mps),
        "requested_mps": num(s.requested_mps), "commanded_mps": num(s.commanded_mps),
        "clamped": s.clamped, "step_speed_mps": num(s.step_speed_mps),
        "step_length_m": num(s.step_length_m), "step_duration_s": num(s.step_duration_s),
        "position_m": num(s.position_m), "true_position_m": true_position_m.map_or(Value::Null, num),
        "library_mps": num(s.library_mps), "integral_mps": num(s.integral_mps),
        "step_offset_m": num(s.step_offset_m), "step_lean_rad": num(s.step_lean_rad),
    })
}
