//! Sans-IO encoder and decoder of cannelloni's UDP packet format, version 2 (the layout is
//! in the [module docs](crate::udp)). No socket, no allocation: a [`PacketWriter`] fills a
//! buffer the caller owns, [`Packet::parse`] checks a received buffer whole and then lends its
//! frames as [`FrameRef`]s. Every malformed input is a [`PacketError`] naming what is wrong;
//! nothing panics on any input (property and fuzz tests in `tests`).

use thiserror::Error;

/// Protocol version in the first byte of every packet.
pub const VERSION: u8 = 2;
/// Op code of a data packet (the only kind the UDP transport sends).
pub const OP_DATA: u8 = 0;
/// Bytes of the packet header (version, op code, sequence number, count).
pub const HEADER_LEN: usize = 5;
/// Bytes of a frame's header (can_id, len).
pub const FRAME_HEADER_LEN: usize = 5;
/// `len` bit that marks a CAN FD frame (a flags byte follows).
pub const CANFD_FRAME: u8 = 0x80;
/// Data bytes of a classic CAN frame, at most.
pub const CLASSIC_MAX_LEN: usize = 8;
/// Data bytes of a CAN FD frame, at most.
pub const FD_MAX_LEN: usize = 64;
/// `can_id` flag: extended (29-bit) identifier.
pub const CAN_EFF_FLAG: u32 = 0x8000_0000;
/// `can_id` flag: remote transmission request (no data section on the wire).
pub const CAN_RTR_FLAG: u32 = 0x4000_0000;
/// `can_id` flag: error frame.
pub const CAN_ERR_FLAG: u32 = 0x2000_0000;
/// Identifier bits of a standard frame.
pub const CAN_SFF_MASK: u32 = 0x7FF;
/// Identifier bits of an extended frame.
pub const CAN_EFF_MASK: u32 = 0x1FFF_FFFF;
/// The largest datagram built or accepted: a UDP payload that fits an Ethernet MTU of 1500.
pub const MAX_PACKET_LEN: usize = 1472;

/// A classic CAN frame as the transport carries it (Linux `can_frame` semantics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    /// Identifier with the `CAN_*_FLAG` bits.
    pub can_id: u32,
    /// Data length code (0–8); for a remote frame the requested length.
    pub len: u8,
    /// Data (the first `len` bytes count; none for a remote frame).
    pub data: [u8; CLASSIC_MAX_LEN],
}

impl CanFrame {
    /// A standard data frame (`None` if `id` > 0x7FF or more than 8 bytes).
    pub fn standard(id: u32, data: &[u8]) -> Option<Self> {
        (id <= CAN_SFF_MASK).then_some(())?;
        Self::with_id(id, data)
    }

    /// An extended data frame (`None` if `id` > 0x1FFF_FFFF or more than 8 bytes).
    pub fn extended(id: u32, data: &[u8]) -> Option<Self> {
        (id <= CAN_EFF_MASK).then_some(())?;
        Self::with_id(id | CAN_EFF_FLAG, data)
    }

    fn with_id(can_id: u32, data: &[u8]) -> Option<Self> {
        if data.len() > CLASSIC_MAX_LEN {
            return None;
        }
        let mut bytes = [0; CLASSIC_MAX_LEN];
        bytes[..data.len()].copy_from_slice(data);
        Some(Self {
            can_id,
            len: data.len() as u8,
            data: bytes,
        })
    }

    /// The data bytes (empty for a remote frame).
    pub fn payload(&self) -> &[u8] {
        if self.can_id & CAN_RTR_FLAG != 0 {
            &[]
        } else {
            &self.data[..usize::from(self.len).min(CLASSIC_MAX_LEN)]
        }
    }

    /// As a borrowed frame (for [`PacketWriter::push`]).
    pub fn as_ref(&self) -> FrameRef<'_> {
        FrameRef {
            can_id: self.can_id,
            len: self.len,
            fd_flags: None,
            data: self.payload(),
        }
    }
}

/// One frame of a packet, borrowed from its buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRef<'a> {
    /// Identifier with the `CAN_*_FLAG` bits.
    pub can_id: u32,
    /// Data length (without the CAN FD bit); for a remote frame the requested length.
    pub len: u8,
    /// CAN FD flags; `None` for a classic frame.
    pub fd_flags: Option<u8>,
    /// Data (empty for a remote frame).
    pub data: &'a [u8],
}

impl FrameRef<'_> {
    /// Extended identifier.
    pub fn is_extended(&self) -> bool {
        self.can_id & CAN_EFF_FLAG != 0
    }
    /// Remote frame.
    pub fn is_remote(&self) -> bool {
        self.can_id & CAN_RTR_FLAG != 0
    }
    /// Error frame.
    pub fn is_error(&self) -> bool {
        self.can_id & CAN_ERR_FLAG != 0
    }
    /// The identifier without flags (11 or 29 bits).
    pub fn id(&self) -> u32 {
        if self.is_extended() {
            self.can_id & CAN_EFF_MASK
        } else {
            self.can_id & CAN_SFF_MASK
        }
    }
    /// A classic data frame with a standard id: the only kind the A1 link uses (`None` for
    /// extended, remote, error and CAN FD frames).
    pub fn standard_data(&self) -> Option<(u32, &[u8])> {
        let plain = self.fd_flags.is_none() && self.can_id & !CAN_SFF_MASK == 0;
        plain.then_some((self.can_id, self.data))
    }
    /// As an owned classic frame (`None` for a CAN FD frame).
    pub fn to_classic(&self) -> Option<CanFrame> {
        if self.fd_flags.is_some() {
            return None;
        }
        let mut data = [0; CLASSIC_MAX_LEN];
        data[..self.data.len()].copy_from_slice(self.data);
        Some(CanFrame {
            can_id: self.can_id,
            len: self.len,
            data,
        })
    }
}

/// What is wrong with a received packet. `Copy`, no heap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum PacketError {
    /// Fewer bytes than the header.
    #[error("packet of {len} bytes is shorter than the {HEADER_LEN}-byte header")]
    TooShort {
        /// Bytes received.
        len: usize,
    },
    /// Longer than [`MAX_PACKET_LEN`].
    #[error("packet of {len} bytes is longer than {MAX_PACKET_LEN}")]
    TooLong {
        /// Bytes received.
        len: usize,
    },
    /// Another protocol version.
    #[error("packet version {version}, expected {VERSION}")]
    WrongVersion {
        /// Version byte.
        version: u8,
    },
    /// Not a data packet.
    #[error("packet op code {op_code}, expected {OP_DATA} (data)")]
    WrongOpCode {
        /// Op code byte.
        op_code: u8,
    },
    /// The packet ends inside frame `frame` (0-based) of `count`.
    #[error("packet ends inside frame {frame} of {count}")]
    Truncated {
        /// Frame index.
        frame: u16,
        /// Frames announced.
        count: u16,
    },
    /// Frame `frame` has a data length its kind cannot have (classic > 8, FD > 64).
    #[error("frame {frame} has length {len} (classic CAN: 0-8, CAN FD: 0-64)")]
    BadLength {
        /// Frame index.
        frame: u16,
        /// Length as received (CAN FD bit removed).
        len: u8,
    },
    /// Bytes left after the announced frames.
    #[error("{extra} bytes after the {count} frames the header announces")]
    Trailing {
        /// Extra bytes.
        extra: usize,
        /// Frames announced.
        count: u16,
    },
}

/// A received packet whose every frame has been checked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Packet<'a> {
    /// Sequence number (wraps at 256).
    pub seq: u8,
    /// Frames in the packet.
    pub count: u16,
    body: &'a [u8],
}

/// Reads one frame at `at`; its view and the offset after it.
fn read_frame(
    body: &[u8],
    at: usize,
    frame: u16,
    count: u16,
) -> Result<(FrameRef<'_>, usize), PacketError> {
    let truncated = PacketError::Truncated { frame, count };
    let header = body.get(at..at + FRAME_HEADER_LEN).ok_or(truncated)?;
    let can_id = u32::from_be_bytes([header[0], header[1], header[2], header[3]]);
    let raw_len = header[4];
    let mut at = at + FRAME_HEADER_LEN;
    let (len, fd_flags) = if raw_len & CANFD_FRAME != 0 {
        let flags = *body.get(at).ok_or(truncated)?;
        at += 1;
        (raw_len & !CANFD_FRAME, Some(flags))
    } else {
        (raw_len, None)
    };
    let max = if fd_flags.is_some() {
        FD_MAX_LEN
    } else {
        CLASSIC_MAX_LEN
    };
    if usize::from(len) > max {
        return Err(PacketError::BadLength { frame, len });
    }
    let data_len = if can_id & CAN_RTR_FLAG != 0 {
        0
    } else {
        usize::from(len)
    };
    let data = body.get(at..at + data_len).ok_or(truncated)?;
    Ok((
        FrameRef {
            can_id,
            len,
            fd_flags,
            data,
        },
        at + data_len,
    ))
}

impl<'a> Packet<'a> {
    /// Check a received datagram: header, every frame, no trailing bytes.
    pub fn parse(buf: &'a [u8]) -> Result<Self, PacketError> {
        if buf.len() < HEADER_LEN {
            return Err(PacketError::TooShort { len: buf.len() });
        }
        if buf.len() > MAX_PACKET_LEN {
            return Err(PacketError::TooLong { len: buf.len() });
        }
        if buf[0] != VERSION {
            return Err(PacketError::WrongVersion { version: buf[0] });
        }
        if buf[1] != OP_DATA {
            return Err(PacketError::WrongOpCode { op_code: buf[1] });
        }
        let count = u16::from_be_bytes([buf[3], buf[4]]);
        let body = &buf[HEADER_LEN..];
        let mut at = 0;
        for frame in 0..count {
            at = read_frame(body, at, frame, count)?.1;
        }
        if at != body.len() {
            return Err(PacketError::Trailing {
                extra: body.len() - at,
                count,
            });
        }
        Ok(Self {
            seq: buf[2],
            count,
            body,
        })
    }

    /// The frames, in packet order.
    pub fn frames(&self) -> Frames<'a> {
        Frames {
            body: self.body,
            at: 0,
            next: 0,
            count: self.count,
        }
    }
}

/// Iterator over a checked packet's frames.
#[derive(Debug, Clone)]
pub struct Frames<'a> {
    body: &'a [u8],
    at: usize,
    next: u16,
    count: u16,
}

impl<'a> Iterator for Frames<'a> {
    type Item = FrameRef<'a>;
    fn next(&mut self) -> Option<FrameRef<'a>> {
        if self.next >= self.count {
            return None;
        }
        // The packet was checked whole by `Packet::parse`; a failure here cannot happen and
        // ends the iteration rather than panicking.
        let (frame, at) = read_frame(self.body, self.at, self.next, self.count).ok()?;
        self.at = at;
        self.next += 1;
        Some(frame)
    }
}

/// A frame does not fit: the packet is full, or the frame is not valid to send.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum WriteError {
    /// The buffer (or [`MAX_PACKET_LEN`]) has no room for it.
    #[error("no room for the frame: {needed} bytes needed, {free} free")]
    Full {
        /// Bytes the frame needs.
        needed: usize,
        /// Bytes free.
        free: usize,
    },
    /// The frame's length exceeds its kind's (classic 8, CAN FD 64) or its data slice
    /// disagrees with `len`.
    #[error("frame length {len} with {data} data bytes is not valid")]
    BadFrame {
        /// `len`.
        len: u8,
        /// Data bytes given.
        data: usize,
    },
    /// More than 65535 frames.
    #[error("more than 65535 frames in one packet")]
    TooManyFrames,
}

/// Builds one data packet in a caller-owned buffer.
#[derive(Debug)]
pub struct PacketWriter<'b> {
    buf: &'b mut [u8],
    at: usize,
    count: u16,
}

impl<'b> PacketWriter<'b> {
    /// Start a packet with sequence number `seq` (`None` if the buffer cannot hold a header).
    pub fn new(buf: &'b mut [u8], seq: u8) -> Option<Self> {
        let header = buf.get_mut(..HEADER_LEN)?;
        header.copy_from_slice(&[VERSION, OP_DATA, seq, 0, 0]);
        Some(Self {
            buf,
            at: HEADER_LEN,
            count: 0,
        })
    }

    /// Append a frame.
    pub fn push(&mut self, frame: &FrameRef<'_>) -> Result<(), WriteError> {
        let max = if frame.fd_flags.is_some() {
            FD_MAX_LEN
        } else {
            CLASSIC_MAX_LEN
        };
        let remote = frame.can_id & CAN_RTR_FLAG != 0;
        let data_len = if remote { 0 } else { usize::from(frame.len) };
        if usize::from(frame.len) > max || frame.data.len() != data_len {
            return Err(WriteError::BadFrame {
                len: frame.len,
                data: frame.data.len(),
            });
        }
        let count = self.count.checked_add(1).ok_or(WriteError::TooManyFrames)?;
        let needed = FRAME_HEADER_LEN + usize::from(frame.fd_flags.is_some()) + data_len;
        let limit = self.buf.len().min(MAX_PACKET_LEN);
        let free = limit.saturating_sub(self.at);
        if needed > free {
            return Err(WriteError::Full { needed, free });
        }
        let out = &mut self.buf[self.at..self.at + needed];
        out[..4].copy_from_slice(&frame.can_id.to_be_bytes());
        match frame.fd_flags {
            Some(flags) => {
                out[4] = frame.len | CANFD_FRAME;
                out[5] = flags;
                out[6..].copy_from_slice(frame.data);
            }
            None => {
                out[4] = frame.len;
                out[5..].copy_from_slice(frame.data);
            }
        }
        self.at += needed;
        self.count = count;
        Ok(())
    }

    /// Frames so far.
    pub fn count(&self) -> u16 {
        self.count
    }

    /// Write the frame count into the header; the packet's length in the buffer.
    pub fn finish(self) -> usize {
        self.buf[3..HEADER_LEN].copy_from_slice(&self.count.to_be_bytes());
        self.at
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests;
