//! Reading the `/speed` channel back ([`crate::telemetry::speed_log`]): the rows
//! `adam plot speed` draws.

use crate::control::SpeedStatus;
use crate::telemetry::speed_log::SPEED_TOPIC;
use crate::{Result, RuntimeError};
use serde_json::Value;
use std::path::Path;

/// One `/speed` message read back (NaN for `null`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedRow {
    /// Time of the impact, s.
    pub t_s: f64,
    /// Belt speed set, m/s.
    pub belt_mps: f64,
    /// Commanded speed, m/s.
    pub commanded_mps: f64,
    /// Requested speed before the clamp, m/s.
    pub requested_mps: f64,
    /// The step's measured speed, m/s.
    pub step_speed_mps: f64,
    /// Estimated position on the belt, m.
    pub position_m: f64,
    /// True position on the belt (simulator), m; NaN without it.
    pub true_position_m: f64,
    /// Library speed in use, m/s.
    pub library_mps: f64,
    /// The command was clamped to the library's range.
    pub clamped: bool,
}

impl SpeedRow {
    /// The row a log's `/speed` message of this update reads back as
    /// ([`crate::telemetry::speed_log::speed_json`]: a value that is not finite is `null`,
    /// read as NaN; no true position is NaN).
    pub fn from_update(t_s: f64, s: &SpeedStatus, true_position_m: Option<f64>) -> Self {
        let num = crate::telemetry::speed_log::finite_or_nan;
        Self {
            t_s,
            belt_mps: num(s.belt_mps),
            commanded_mps: num(s.commanded_mps),
            requested_mps: num(s.requested_mps),
            step_speed_mps: num(s.step_speed_mps),
            position_m: num(s.position_m),
            true_position_m: true_position_m.map_or(f64::NAN, num),
            library_mps: num(s.library_mps),
            clamped: s.clamped,
        }
    }
}

/// Reads the `/speed` messages of the log at `path` (every chunk that survives). Errors name
/// the file, the message and the field.
pub fn read_speed(path: &Path) -> Result<Vec<SpeedRow>> {
    let bytes = crate::telemetry::log_read::read_bytes(path)?;
    let log = crate::telemetry::salvage::Salvaged::read(path, &bytes)?;
    let mut rows = Vec::new();
    let speed = log.messages().filter(|m| m.channel.topic == SPEED_TOPIC);
    for (k, m) in speed.enumerate() {
        let err = |field: &str, why: &str| RuntimeError::Log {
            path: path.to_path_buf(),
            message: format!("{SPEED_TOPIC} message {k}: field `{field}` {why}"),
        };
        let v: Value = serde_json::from_slice(&m.data)
            .map_err(|e| err("(the message)", &format!("is not JSON: {e}")))?;
        let f = |field: &str| -> Result<f64> {
            match &v[field] {
                Value::Null => Ok(f64::NAN),
                Value::Number(n) => n.as_f64().ok_or_else(|| err(field, "is not a number")),
                other => Err(err(field, &format!("is {other} (want a number or null)"))),
            }
        };
        let t_s = f("t_s")?;
        if !t_s.is_finite() {
            return Err(err("t_s", "is missing"));
        }
        rows.push(SpeedRow {
            t_s,
            belt_mps: f("belt_mps")?,
            commanded_mps: f("commanded_mps")?,
            requested_mps: f("requested_mps")?,
            step_speed_mps: f("step_speed_mps")?,
            position_m: f("position_m")?,
            true_position_m: f("true_position_m")?,
            library_mps: f("library_mps")?,
            clamped: v["clamped"].as_bool().unwrap_or(false),
        });
    }
    if rows.is_empty() {
        return Err(RuntimeError::Log {
            path: path.to_path_buf(),
            message: format!(
                "no {SPEED_TOPIC} messages: speed control did not run (a gait library and a \
                 belt speed from the operator turn it on)"
            ),
        });
    }
    Ok(rows)
}
