//! Reading the `/can` channel back ([`crate::telemetry::frames`]): its frames, and each one as a
//! line of can-utils' candump log (`adam logs candump`).

use crate::telemetry::frames::{hex, CAN_TOPIC};
use crate::{Result, RuntimeError};
use drivers::frame_log::FrameDirection;
use serde_json::Value;
use std::path::Path;

/// One `/can` message read back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CanRow {
    /// The frame's time (`t_s`), µs.
    pub t_us: u64,
    /// Tick (`None` for a lifecycle operation).
    pub tick: Option<u64>,
    /// Bus index.
    pub bus: u8,
    /// Direction.
    pub direction: FrameDirection,
    /// Identifier without flags.
    pub id: u32,
    /// Extended identifier.
    pub extended: bool,
    /// Remote frame.
    pub remote: bool,
    /// Data.
    pub data: Vec<u8>,
}

/// Reads the `/can` messages of the log at `path` (every chunk that survives), in log order
/// (by tick; within a tick, in wire order per bus).
/// Errors name the file, the message and the field.
pub fn read_frames(path: &Path) -> Result<Vec<CanRow>> {
    let bytes = crate::telemetry::log_read::read_bytes(path)?;
    let log = crate::telemetry::salvage::Salvaged::read(path, &bytes)?;
    let mut rows = Vec::new();
    let messages = log.messages().filter(|m| m.channel.topic == CAN_TOPIC);
    for (k, m) in messages.enumerate() {
        let err = |field: &str, why: String| RuntimeError::Log {
            path: path.to_path_buf(),
            message: format!("{CAN_TOPIC} message {k}: field `{field}` {why}"),
        };
        let v: Value = serde_json::from_slice(&m.data)
            .map_err(|e| err("(the message)", format!("is not JSON: {e}")))?;
        let uint = |field: &str| {
            v[field]
                .as_u64()
                .ok_or_else(|| err(field, format!("is {} (want an integer)", v[field])))
        };
        let flag = |field: &str| {
            v[field]
                .as_bool()
                .ok_or_else(|| err(field, format!("is {} (want true or false)", v[field])))
        };
        let direction = match v["dir"].as_str() {
            Some("tx") => FrameDirection::Tx,
            Some("rx") => FrameDirection::Rx,
            _ => {
                return Err(err(
                    "dir",
                    format!("is {} (want \"tx\" or \"rx\")", v["dir"]),
                ))
            }
        };
        let text = v["data"]
            .as_str()
            .ok_or_else(|| err("data", format!("is {} (want a hex string)", v["data"])))?;
        let data = parse_hex(text)
            .filter(|d| d.len() <= 8)
            .ok_or_else(|| err("data", format!("`{text}` is not 0-8 bytes of hex")))?;
        let bus = u8::try_from(uint("bus")?).map_err(|_| err("bus", "is past 255".into()))?;
        let id = u32::try_from(uint("id")?).map_err(|_| err("id", "is past 32 bits".into()))?;
        let extended = flag("extended")?;
        if id > if extended { 0x1FFF_FFFF } else { 0x7FF } {
            return Err(err("id", format!("{id:#X} is too large for its kind")));
        }
        let t_s = v["t_s"]
            .as_f64()
            .filter(|t| t.is_finite() && *t >= 0.0)
            .ok_or_else(|| err("t_s", format!("is {} (want seconds, 0 or more)", v["t_s"])))?;
        rows.push(CanRow {
            t_us: (t_s * 1e6).round() as u64,
            tick: v["tick"].as_u64(),
            bus,
            direction,
            id,
            extended,
            remote: flag("remote")?,
            data,
        });
    }
    if rows.is_empty() {
        return Err(RuntimeError::Log {
            path: path.to_path_buf(),
            message: format!(
                "no {CAN_TOPIC} messages: the log was written before raw frames were logged, or \
                 by a backend that records none"
            ),
        });
    }
    Ok(rows)
}

fn parse_hex(text: &str) -> Option<Vec<u8>> {
    if text.len() % 2 != 0 {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect()
}

/// One line of can-utils' candump log format (`candump -l`): `(seconds.micros) canN ID#DATA`,
/// a standard id in 3 hex digits, an extended one in 8, a remote frame `ID#R`. The interface
/// is `can` + the bus index; the log format has no direction.
pub fn candump_line(row: &CanRow) -> String {
    let id = if row.extended {
        format!("{:08X}", row.id)
    } else {
        format!("{:03X}", row.id)
    };
    let data = if row.remote {
        "R".to_string()
    } else {
        hex(&row.data)
    };
    format!(
        "({:010}.{:06}) can{} {id}#{data}",
        row.t_us / 1_000_000,
        row.t_us % 1_000_000,
        row.bus
    )
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn candump_lines_have_can_utils_form() {
        let row = CanRow {
            t_us: 12_345_678,
            tick: Some(3),
            bus: 1,
            direction: FrameDirection::Rx,
            id: 0x183,
            extended: false,
            remote: false,
            data: vec![0x00, 0xAB, 0x10, 0, 0, 0, 0, 0xFF],
        };
        assert_eq!(
            candump_line(&row),
            "(0000000012.345678) can1 183#00AB1000000000FF"
        );
        let ext = CanRow {
            extended: true,
            id: 0x1AD1_0000,
            remote: true,
            data: vec![],
            ..row
        };
        assert_eq!(candump_line(&ext), "(0000000012.345678) can1 1AD10000#R");
        assert_eq!(parse_hex("00aBff"), Some(vec![0, 0xAB, 0xFF]));
        assert_eq!(parse_hex("0"), None);
        assert_eq!(parse_hex("zz"), None);
    }
}
