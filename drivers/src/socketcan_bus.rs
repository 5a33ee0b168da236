//! `SocketCanBus`: the [`MotorBus`](crate::bus::MotorBus) over Linux SocketCAN, one raw socket
//! per interface (one interface per limb): [`FrameBus`] over [`CanInterfaces`].
//!
//! This adapter only moves frames: encoding, decoding and argument checks are the codec's
//! and [`MotorTable`](crate::bus::MotorTable)'s, the lifecycle and the round trip
//! [`FrameBus`]'s. Sockets are nonblocking with error frames enabled. An exchange
//! drains stale frames, writes every command, then polls all sockets until every
//! commanded motor has replied or the budget (measured from the call with the monotonic
//! clock) runs out. It busy-polls (yielding the CPU between empty polls): run the loop on a
//! dedicated core.
//!
//! * An error frame with the bus-off class → [`BusError::BusOff`]; any other error frame
//!   → [`BusError::ErrorFrame`] with its class bits.
//! * A reply not in by the deadline → [`BusError::MissingReply`] naming the motor.
//! * A write still refused (`WouldBlock`, TX queue full) at the deadline →
//!   [`BusError::DeadlineExceeded`].
//! * Foreign traffic (other ids, extended ids, remote frames) is ignored.

use crate::a1::{self, Frame, FrameKind};
use crate::bus::BusError;
pub use crate::frame_bus::LIFECYCLE_TIMEOUT;
use crate::frame_bus::{io_error, send_by, FrameBus, FrameTransport, Replies};
use crate::frame_log::{FrameDirection, FrameLog};
use socketcan::{
    CanFrame, CanSocket, EmbeddedFrame, Frame as _, Socket, SocketOptions, StandardId,
};
use std::io;
use std::time::Instant;
use thiserror::Error;

/// `CAN_ERR_BUSOFF` class bit of an error frame (`linux/can/error.h`).
pub const CAN_ERR_BUSOFF: u32 = 0x0040;

/// Opening an interface failed.
#[derive(Debug, Error)]
pub enum OpenError {
    /// The OS refused to open or set up the socket. The OS error is part of the message, not
    /// a `source`, so that an error chain printed whole names it once.
    #[error("cannot open CAN interface `{interface}`: {os_error}")]
    Open {
        /// Interface name, e.g. `can0`.
        interface: String,
        /// The OS error.
        os_error: io::Error,
    },
    /// No interface given.
    #[error("no CAN interface given")]
    NoInterface,
}

/// What one received frame means to the bus.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Incoming {
    /// A well-formed reply.
    Reply(a1::Reply),
    /// A frame on a reply id that does not decode.
    BadReply(a1::MotorId, a1::DecodeError),
    /// A controller error frame; `class` = error class bits.
    Error {
        /// Error class bits.
        class: u32,
    },
    /// Not ours.
    Foreign,
}

/// Classify a received SocketCAN frame (pure; tested without a socket).
pub fn interpret(frame: &CanFrame) -> Incoming {
    match frame {
        CanFrame::Error(e) => Incoming::Error {
            class: e.error_bits(),
        },
        CanFrame::Remote(_) => Incoming::Foreign,
        CanFrame::Data(d) => {
            if d.is_extended() {
                return Incoming::Foreign;
            }
            let id = d.raw_id();
            match a1::classify(id) {
                Some((FrameKind::Reply, motor)) => match a1::decode_reply(id, d.data()) {
                    Ok(reply) => Incoming::Reply(reply),
                    Err(e) => Incoming::BadReply(motor, e),
                },
                _ => Incoming::Foreign,
            }
        }
    }
}

/// A codec frame as a SocketCAN frame (`None` only for an id above 0x7FF).
pub fn to_can_frame(frame: &Frame) -> Option<CanFrame> {
    let id = StandardId::new(u16::try_from(frame.id).ok()?)?;
    CanFrame::new(id, &frame.data)
}

/// The error an error frame stands for, on bus `bus`.
pub fn error_of(bus: usize, class: u32) -> BusError {
    if class & CAN_ERR_BUSOFF != 0 {
        BusError::BusOff { bus }
    } else {
        BusError::ErrorFrame { bus, class }
    }
}

struct Interface {
    name: String,
    socket: CanSocket,
}

/// The SocketCAN interfaces of a [`SocketCanBus`], one raw socket each: its [`FrameTransport`].
pub struct CanInterfaces {
    interfaces: Vec<Interface>,
}

/// [`MotorBus`](crate::bus::MotorBus) over one or more SocketCAN interfaces.
pub type SocketCanBus = FrameBus<CanInterfaces>;

impl FrameBus<CanInterfaces> {
    /// Open `interfaces` (bus index = position), nonblocking, with error frames on.
    pub fn open(interfaces: &[&str]) -> Result<Self, OpenError> {
        if interfaces.is_empty() {
            return Err(OpenError::NoInterface);
        }
        let opened = interfaces
            .iter()
            .map(|&name| {
                let fail = |os_error| OpenError::Open {
                    interface: name.to_owned(),
                    os_error,
                };
                let socket = CanSocket::open(name).map_err(fail)?;
                socket.set_nonblocking(true).map_err(fail)?;
                socket
                    .set_error_filter(socketcan::id::ERR_MASK_ALL)
                    .map_err(fail)?;
                Ok(Interface {
                    name: name.to_owned(),
                    socket,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(FrameBus::new(CanInterfaces { interfaces: opened }))
    }

    /// Interface name of bus `bus`.
    pub fn interface_name(&self, bus: usize) -> Option<&str> {
        self.transport()
            .interfaces
            .get(bus)
            .map(|i| i.name.as_str())
    }
}

impl FrameTransport for CanInterfaces {
    fn bus_count(&self) -> usize {
        self.interfaces.len()
    }

    fn drain(&mut self) -> Result<(), BusError> {
        for (bus, iface) in self.interfaces.iter().enumerate() {
            loop {
                match iface.socket.read_frame() {
                    Ok(frame) => {
                        if let Incoming::Error { class } = interpret(&frame) {
                            return Err(error_of(bus, class));
                        }
                    }
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                    Err(e) => return Err(io_error(bus, &e)),
                }
            }
        }
        Ok(())
    }

    fn send(
        &mut self,
        bus: usize,
        frames: &[Frame],
        buses: &[usize],
        log: &mut FrameLog,
        start: Instant,
        deadline: Instant,
    ) -> Result<(), BusError> {
        let socket = &self.interfaces[bus].socket;
        for (frame, _) in frames.iter().zip(buses).filter(|(_, &b)| b == bus) {
            let Some(can) = to_can_frame(frame) else {
                continue;
            };
            send_by(bus, start, deadline, || socket.write_frame(&can))?;
            log.record(
                bus,
                FrameDirection::Tx,
                start.elapsed(),
                frame.id,
                &frame.data,
            );
        }
        Ok(())
    }

    fn poll<F: FnMut(usize, a1::Reply)>(
        &mut self,
        bus: usize,
        replies: &mut Replies<'_, F>,
    ) -> Result<bool, BusError> {
        let frame = match self.interfaces[bus].socket.read_frame() {
            Ok(frame) => frame,
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(false),
            Err(e) => return Err(io_error(bus, &e)),
        };
        match interpret(&frame) {
            Incoming::Reply(reply) => {
                // A reply of a motor not asked (or a second one) is not used.
                replies.offer(bus, frame.raw_id(), frame.data(), reply);
            }
            Incoming::BadReply(motor, error) => {
                if replies.is_configured(motor) {
                    return Err(BusError::BadReply { motor, error });
                }
            }
            Incoming::Error { class } => return Err(error_of(bus, class)),
            Incoming::Foreign => {}
        }
        Ok(true)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::a1::{Command, MotorId, Reply};
    use socketcan::{CanErrorFrame, CanRemoteFrame};

    #[test]
    fn opening_a_missing_interface_names_it_and_the_os_error() {
        // No AF_CAN on CI machines; on a machine with can0 up this test is skipped.
        match SocketCanBus::open(&["can0"]) {
            Ok(_) => eprintln!("can0 exists here; nothing to check"),
            Err(e) => {
                let text = e.to_string();
                eprintln!("{text}");
                assert!(text.contains("`can0`"), "{text}");
                assert!(text.contains("os error"), "{text}");
                // Printed as a chain (`{:#}`, as the CLI does), the OS error still appears once.
                assert!(std::error::Error::source(&e).is_none(), "{text}");
                assert_eq!(text.matches("os error").count(), 1, "{text}");
            }
        }
        assert!(matches!(
            SocketCanBus::open(&[]),
            Err(OpenError::NoInterface)
        ));
    }

    #[test]
    fn frames_convert_and_replies_are_recognised() {
        let m = MotorId::new(3).unwrap();
        let reply = Reply {
            q_rad: 0.5,
            enabled: true,
            ..Reply::zeroed(m)
        };
        let frame = a1::encode_reply(&reply).unwrap().frame;
        let can = to_can_frame(&frame).unwrap();
        assert_eq!(can.raw_id(), 0x183);
        assert_eq!(can.data(), &frame.data);
        match interpret(&can) {
            Incoming::Reply(r) => {
                assert_eq!(r.motor, m);
                assert!((r.q_rad - 0.5).abs() < 2e-4);
            }
            other => panic!("{other:?}"),
        }
        // A command (our own id range, but not a reply) and a remote frame are foreign.
        let cmd = a1::encode_command(&Command::brake(m)).unwrap().frame;
        assert_eq!(interpret(&to_can_frame(&cmd).unwrap()), Incoming::Foreign);
        let remote = CanRemoteFrame::new_remote(StandardId::new(0x183).unwrap(), 8).unwrap();
        assert_eq!(interpret(&CanFrame::Remote(remote)), Incoming::Foreign);
        // A short frame on a reply id is a bad reply, with the codec's error.
        let short = CanFrame::new(StandardId::new(0x183).unwrap(), &[0; 4]).unwrap();
        assert_eq!(
            interpret(&short),
            Incoming::BadReply(m, a1::DecodeError::WrongLength { id: 0x183, len: 4 })
        );
    }

    #[test]
    fn error_frames_become_typed_errors() {
        let bus_off = CanErrorFrame::new_error(CAN_ERR_BUSOFF, &[]).unwrap();
        let Incoming::Error { class } = interpret(&CanFrame::Error(bus_off)) else {
            panic!("not an error frame");
        };
        assert_eq!(error_of(2, class), BusError::BusOff { bus: 2 });
        let no_ack = CanErrorFrame::new_error(0x0020, &[]).unwrap(); // CAN_ERR_ACK
        let Incoming::Error { class } = interpret(&CanFrame::Error(no_ack)) else {
            panic!("not an error frame");
        };
        assert_eq!(
            error_of(1, class),
            BusError::ErrorFrame {
                bus: 1,
                class: 0x20
            }
        );
    }
}
