//! The simulated CAN wire: its faults ([`WireFaults`]: loss, corruption, delay), the damage a
//! corrupted frame carries ([`corrupt`]), what it did ([`WireStats`]) and a recorder ([`WireTap`]).
//!
//! With [`WireFaults`] set on a [`crate::sim::bus::SimBus`], each frame, in each direction, is lost
//! with `loss_probability` or corrupted with `corrupt_probability`; each reply is delayed by
//! `delay_s` with `delay_probability`. A corrupted frame carries damage the A1 codec can see
//! (a cut data length, a reserved mode, an id outside its kind's range: bit flips inside the
//! payload are caught by the CAN CRC in the controller and become a loss); the firmware and
//! the host decoder reject it, so its reply is missing. A delayed reply that arrives after the
//! exchange budget is missing too (the real bus drains it at the next exchange). The fault
//! generator has its own seeded stream: enabling faults leaves the sensor noise unchanged.

use crate::a1::{self, Frame};
use std::sync::{Arc, Mutex};

/// Direction of a frame on the simulated wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Host → motor.
    ToMotor,
    /// Motor → host.
    ToHost,
}

/// One frame seen on the simulated wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TapEntry {
    /// Bus index.
    pub bus: usize,
    /// Direction.
    pub direction: Direction,
    /// The frame.
    pub frame: Frame,
}

/// Faults of the simulated CAN wire (probabilities per frame, in `[0, 1]`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WireFaults {
    /// A frame (command or reply) vanishes.
    pub loss_probability: f64,
    /// A frame (command or reply) arrives damaged and is rejected by its decoder.
    pub corrupt_probability: f64,
    /// A reply is delayed by `delay_s`.
    pub delay_probability: f64,
    /// Delay of a delayed reply \[s\].
    pub delay_s: f64,
}

impl WireFaults {
    /// A clean wire.
    pub const NONE: Self = Self {
        loss_probability: 0.0,
        corrupt_probability: 0.0,
        delay_probability: 0.0,
        delay_s: 0.0,
    };

    /// The first field out of range, as (name, value).
    pub fn invalid_field(&self) -> Option<(&'static str, f64)> {
        let probabilities = [
            ("loss_probability", self.loss_probability),
            ("corrupt_probability", self.corrupt_probability),
            ("delay_probability", self.delay_probability),
        ];
        probabilities
            .into_iter()
            .find(|(_, p)| !(0.0..=1.0).contains(p))
            .or_else(|| {
                (!(self.delay_s.is_finite() && self.delay_s >= 0.0))
                    .then_some(("delay_s", self.delay_s))
            })
    }
}

/// Damage a corrupted frame carries, each one a distinct codec rejection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Corruption {
    /// The data length code is cut to this many bytes (`DecodeError::WrongLength`).
    Length(usize),
    /// The mode field holds the reserved value (`DecodeError::UnknownMode`); on a special frame
    /// the opcode byte is garbled instead (`DecodeError::UnknownOpcode`).
    ReservedMode,
    /// The id is moved out of its kind's range (`DecodeError::WrongId`).
    Id,
}

/// Apply `damage` to `frame`: the id and the bytes as received (pure; the decoders reject them).
pub fn corrupt(frame: &Frame, damage: Corruption) -> (u32, [u8; a1::codec::FRAME_LEN], usize) {
    let mut data = frame.data;
    let mut id = frame.id;
    let mut len = data.len();
    match damage {
        Corruption::Length(n) => len = n.min(data.len() - 1),
        Corruption::ReservedMode => match a1::codec::classify(frame.id) {
            Some((a1::codec::FrameKind::Special, _)) => data[0] = 0xEE,
            Some((a1::codec::FrameKind::Command, _)) => {
                let payload = u64::from_le_bytes(data) | (0b11 << a1::codec::CMD_MODE_START_BIT);
                data = payload.to_le_bytes();
            }
            _ => {
                let payload = u64::from_le_bytes(data) | (0b11 << a1::codec::REPLY_MODE_START_BIT);
                data = payload.to_le_bytes();
            }
        },
        // Bit 10 set: above every A1 id range (standard ids are 11 bits).
        Corruption::Id => id |= 0x700,
    }
    (id, data, len)
}

/// What the simulated wire did (counts of frames).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WireStats {
    /// Frames lost (either direction).
    pub lost: u64,
    /// Frames corrupted and rejected by a decoder (either direction).
    pub corrupted: u64,
    /// Replies delayed.
    pub delayed: u64,
    /// Delayed replies that arrived after the exchange budget (missing).
    pub delayed_late: u64,
}

impl core::ops::AddAssign for WireStats {
    fn add_assign(&mut self, other: Self) {
        self.lost += other.lost;
        self.corrupted += other.corrupted;
        self.delayed += other.delayed;
        self.delayed_late += other.delayed_late;
    }
}

/// A shared recorder of the simulated wire (diagnostics and conformance tests only: it
/// locks and grows a `Vec`, so leave it off in real-time use).
pub type WireTap = Arc<Mutex<Vec<TapEntry>>>;

/// What the wire did to one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum WireFault {
    Lost,
    Corrupted(Corruption),
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::a1::{decode_host_frame, encode_reply, Command, MotorId, Reply, Special};

    fn id(n: u8) -> MotorId {
        MotorId::new(n).unwrap()
    }

    #[test]
    fn every_corruption_is_rejected_by_the_decoders() {
        let m = id(5);
        let reply = encode_reply(&Reply::zeroed(m)).unwrap().frame;
        let command = a1::encode_command(&Command::pd(m, 0.1, 0.0, 10.0, 0.5, 0.0))
            .unwrap()
            .frame;
        let special = a1::encode_special(m, Special::Enable);
        let damages = [
            Corruption::Length(0),
            Corruption::Length(7),
            Corruption::ReservedMode,
            Corruption::Id,
        ];
        for damage in damages {
            let (id, data, len) = corrupt(&reply, damage);
            assert!(a1::decode_reply(id, &data[..len]).is_err(), "{damage:?}");
            for host in [command, special] {
                let (id, data, len) = corrupt(&host, damage);
                assert!(decode_host_frame(id, &data[..len]).is_err(), "{damage:?}");
            }
        }
        // Length(n) never delivers all 8 bytes.
        assert_eq!(corrupt(&reply, Corruption::Length(99)).2, 7);
    }
}
