//! The `/can` channel: every CAN frame the loop's motor bus sent and received, one MCAP message
//! per frame, whatever the backend (`SimBus`, `UdpBus`, `SocketCanBus`: each records its frames,
//! [`drivers::frame_log`]); and reading them back as can-utils' candump log
//! (`adam logs candump`).
//!
//! ```text
//! MotorBus::frames() (fixed array) ─▶ FrameBatch::batches (Copy, ≤ 32 frames) ─▶ LogProducer::push
//!   (the tick's wait-free ring; a full ring drops and counts the batch like any record)
//!   ─▶ writer thread ─▶ one `/can` message per frame
//! ```
//! Fields: `t_s` (the tick's time plus the frame's offset in its bus operation, s), `tick`
//! (`null` for `activate` and `deactivate`), `op` (`activate`, `exchange`, `deactivate`),
//! `bus`, `dir` (`tx` host → motor, `rx` motor → host), `id` (without flags), `extended`,
//! `remote`, `len`, `data` (upper-case hex). The MCAP log time of a message is its operation's
//! start (the tick's time), so frames sort with their tick and never past the run's last tick;
//! `t_s` adds the frame's own offset.

use drivers::frame_log::LoggedFrame;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The channel's topic.
pub const CAN_TOPIC: &str = "/can";

/// Frames one [`FrameBatch`] carries (more are split over several records).
pub const FRAMES_PER_BATCH: usize = 2 * drivers::bus::MAX_MOTORS;

/// `can_id` flag of an extended id.
const EFF_FLAG: u32 = 0x8000_0000;
/// `can_id` flag of a remote frame.
const RTR_FLAG: u32 = 0x4000_0000;

/// The bus operation that moved the frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BusOp {
    /// `MotorBus::activate`.
    Activate,
    /// `MotorBus::exchange` of a tick.
    Exchange,
    /// `MotorBus::deactivate`.
    Deactivate,
}

impl BusOp {
    /// As logged.
    pub fn name(self) -> &'static str {
        match self {
            BusOp::Activate => "activate",
            BusOp::Exchange => "exchange",
            BusOp::Deactivate => "deactivate",
        }
    }
}

/// The frames of one bus operation (or part of one), as the control thread queues them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameBatch {
    /// Time of the operation's start, s (loop time).
    pub t_s: f64,
    /// Tick of an exchange.
    pub tick: Option<u64>,
    /// The operation.
    pub op: BusOp,
    frames: [LoggedFrame; FRAMES_PER_BATCH],
    len: usize,
}

impl FrameBatch {
    /// The frames.
    pub fn frames(&self) -> &[LoggedFrame] {
        &self.frames[..self.len]
    }
}

impl FrameBatch {
    /// `frames` (a bus's last operation) in batches of at most [`FRAMES_PER_BATCH`], each to be
    /// queued as a [`crate::telemetry::log::LogRecord::Frames`]. Allocates nothing.
    pub fn batches(
        op: BusOp,
        t_s: f64,
        tick: Option<u64>,
        frames: &[LoggedFrame],
    ) -> impl Iterator<Item = FrameBatch> + '_ {
        frames.chunks(FRAMES_PER_BATCH).map(move |chunk| {
            let mut batch = FrameBatch {
                t_s,
                tick,
                op,
                frames: [chunk[0]; FRAMES_PER_BATCH],
                len: chunk.len(),
            };
            batch.frames[..chunk.len()].copy_from_slice(chunk);
            batch
        })
    }
}

/// The JSON schema of a `/can` message.
pub fn frame_schema() -> Value {
    let int = || json!({"type": "integer"});
    json!({"type": "object", "properties": {
        "t_s": {"type": "number"}, "tick": {"type": "integer",
            "description": "null: outside the loop's ticks (activate, deactivate)"},
        "op": {"type": "string", "enum": ["activate", "exchange", "deactivate"]},
        "bus": int(), "dir": {"type": "string", "enum": ["tx", "rx"]}, "id": int(),
        "extended": {"type": "boolean"}, "remote": {"type": "boolean"}, "len": int(),
        "data": {"type": "string"}}})
}

/// Upper-case hex of `data`.
pub fn hex(data: &[u8]) -> String {
    let mut s = String::with_capacity(2 * data.len());
    for b in data {
        let _ = write!(s, "{b:02X}");
    }
    s
}

/// The `/can` messages of a batch: (log time: the operation's start, message) per frame.
pub fn batch_json(batch: &FrameBatch) -> impl Iterator<Item = (f64, Value)> + '_ {
    batch.frames().iter().map(move |f| {
        let t_s = batch.t_s + f64::from(f.offset_ns) * 1e-9;
        let extended = f.can_id & EFF_FLAG != 0;
        let id = if extended {
            f.can_id & 0x1FFF_FFFF
        } else {
            f.can_id & 0x7FF
        };
        let v = json!({
            "t_s": t_s, "tick": batch.tick, "op": batch.op.name(), "bus": f.bus,
            "dir": f.direction.name(), "id": id, "extended": extended,
            "remote": f.can_id & RTR_FLAG != 0, "len": f.len, "data": hex(f.payload()),
        });
        (batch.t_s, v)
    })
}
