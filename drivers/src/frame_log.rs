//! The CAN frames a [`crate::bus::MotorBus`] moved in its last operation, in fixed storage, for
//! the runtime's log (`/can` channel, `adam logs candump`).
//!
//! Every backend records each frame it sends and each frame it receives and uses (the bus,
//! the direction, the id with Linux's `can_id` flag bits, the data, and the time since the
//! operation began) into a [`FrameLog`] that it clears at the start of every `activate`,
//! `exchange` and `deactivate`; [`crate::bus::MotorBus::frames`] hands the slice out. Recording
//! is a copy into an array: nothing allocates, so the control tick may read it.
//!
//! What the offset means per backend: `SimBus` the modelled bus time of the frames before it
//! on the same bus (bits at the bitrate, stuffing included); `SocketCanBus` and `UdpBus` the
//! monotonic time since the call began, read when the frame was written or read.

use core::time::Duration;

/// Which way a frame went.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameDirection {
    /// Host → motor (sent by the host).
    Tx,
    /// Motor → host (received by the host).
    Rx,
}

impl FrameDirection {
    /// `tx` or `rx`.
    pub fn name(self) -> &'static str {
        match self {
            FrameDirection::Tx => "tx",
            FrameDirection::Rx => "rx",
        }
    }
}

/// One recorded classic CAN frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoggedFrame {
    /// Bus index (the backend's interface or UDP link).
    pub bus: u8,
    /// Direction.
    pub direction: FrameDirection,
    /// Time since the start of the operation that moved it \[ns\] (module docs).
    pub offset_ns: u32,
    /// The id with Linux `can_id` flags (`0x8000_0000` extended, `0x4000_0000` remote).
    pub can_id: u32,
    /// Data length (0–8).
    pub len: u8,
    /// Data (the first `len` bytes count).
    pub data: [u8; 8],
}

impl LoggedFrame {
    /// The data bytes.
    pub fn payload(&self) -> &[u8] {
        &self.data[..usize::from(self.len.min(8))]
    }
}

/// Most frames one operation records: a command and a reply per motor, twice over (an
/// `activate` that fails sends enable and then disable to every motor): 4 ×
/// [`crate::bus::MAX_MOTORS`] (a test in `bus` checks it).
pub const FRAME_LOG_CAPACITY: usize = 64;

const EMPTY: LoggedFrame = LoggedFrame {
    bus: 0,
    direction: FrameDirection::Tx,
    offset_ns: 0,
    can_id: 0,
    len: 0,
    data: [0; 8],
};

/// The frames of one operation, in the order they crossed the wire (fixed storage).
#[derive(Debug, Clone, Copy)]
pub struct FrameLog {
    frames: [LoggedFrame; FRAME_LOG_CAPACITY],
    len: usize,
    overflowed: u32,
}

impl Default for FrameLog {
    fn default() -> Self {
        Self {
            frames: [EMPTY; FRAME_LOG_CAPACITY],
            len: 0,
            overflowed: 0,
        }
    }
}

impl FrameLog {
    /// Forget the previous operation's frames.
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflowed = 0;
    }

    /// Record a frame; past [`FRAME_LOG_CAPACITY`] it is counted in [`FrameLog::overflowed`]
    /// instead.
    pub fn record(
        &mut self,
        bus: usize,
        direction: FrameDirection,
        offset: Duration,
        can_id: u32,
        data: &[u8],
    ) {
        let Some(slot) = self.frames.get_mut(self.len) else {
            self.overflowed = self.overflowed.saturating_add(1);
            return;
        };
        let len = data.len().min(8);
        let mut bytes = [0u8; 8];
        bytes[..len].copy_from_slice(&data[..len]);
        *slot = LoggedFrame {
            bus: u8::try_from(bus).unwrap_or(u8::MAX),
            direction,
            offset_ns: u32::try_from(offset.as_nanos()).unwrap_or(u32::MAX),
            can_id,
            len: len as u8,
            data: bytes,
        };
        self.len += 1;
    }

    /// The recorded frames.
    pub fn frames(&self) -> &[LoggedFrame] {
        &self.frames[..self.len]
    }

    /// Frames that did not fit since the last clear.
    pub fn overflowed(&self) -> u32 {
        self.overflowed
    }

    /// Appends `other`'s frames after these (what does not fit is counted as overflowed), e.g.
    /// the disable round a bus sends after a failed enable, kept beside the enable round.
    pub fn append(&mut self, other: &FrameLog) {
        for f in other.frames() {
            let offset = Duration::from_nanos(u64::from(f.offset_ns));
            self.record(
                usize::from(f.bus),
                f.direction,
                offset,
                f.can_id,
                f.payload(),
            );
        }
        self.overflowed = self.overflowed.saturating_add(other.overflowed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_in_order_and_counts_what_does_not_fit() {
        let mut log = FrameLog::default();
        log.record(
            1,
            FrameDirection::Tx,
            Duration::from_micros(3),
            0x101,
            &[1, 2, 3],
        );
        log.record(
            0,
            FrameDirection::Rx,
            Duration::from_secs(9),
            0x181,
            &[7; 12],
        );
        let f = log.frames();
        assert_eq!(f.len(), 2);
        assert_eq!(
            (f[0].bus, f[0].offset_ns, f[0].payload()),
            (1, 3000, &[1, 2, 3][..])
        );
        // A long payload is cut to 8 bytes; an offset past u32 ns saturates.
        assert_eq!((f[1].len, f[1].offset_ns), (8, u32::MAX));
        for _ in 0..FRAME_LOG_CAPACITY {
            log.record(0, FrameDirection::Tx, Duration::ZERO, 0x100, &[]);
        }
        assert_eq!(log.frames().len(), FRAME_LOG_CAPACITY);
        assert_eq!(log.overflowed(), 2);
        log.clear();
        assert!(log.frames().is_empty());
        assert_eq!(log.overflowed(), 0);
    }

    #[test]
    fn appending_keeps_both_in_order_and_counts_what_does_not_fit() {
        let mut enable = FrameLog::default();
        enable.record(0, FrameDirection::Tx, Duration::from_micros(1), 0x81, &[1]);
        let mut disable = FrameLog::default();
        disable.record(
            1,
            FrameDirection::Tx,
            Duration::from_micros(2),
            0x82,
            &[2, 3],
        );
        disable.record(1, FrameDirection::Rx, Duration::from_micros(4), 0x182, &[4]);
        let expected: Vec<LoggedFrame> = enable
            .frames()
            .iter()
            .chain(disable.frames())
            .copied()
            .collect();
        enable.append(&disable);
        assert_eq!(enable.frames(), &expected[..]);
        let mut full = FrameLog::default();
        for _ in 0..FRAME_LOG_CAPACITY - 1 {
            full.record(0, FrameDirection::Tx, Duration::ZERO, 0x100, &[]);
        }
        full.append(&disable);
        assert_eq!(full.frames().len(), FRAME_LOG_CAPACITY);
        assert_eq!(full.overflowed(), 1);
    }
}
