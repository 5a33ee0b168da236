//! `SocketCanBus`: the [`MotorBus`] over Linux SocketCAN, one raw socket per interface
//! (one interface per limb).
//!
//! This adapter only moves frames: encoding, decoding and argument checks are the codec's
//! and [`MotorTable`]'s. Sockets are nonblocking with error frames enabled. An exchange
//! drains stale frames, writes every command, then polls all sockets until every
//! commanded motor has replied or the budget (measured from the call with the monotonic
//! clock, the one place in this crate that reads a clock) runs out. It busy-polls
//! (yielding the CPU between empty polls): run the loop on a dedicated core.
//!
//! * An error frame with the bus-off class → [`BusError::BusOff`]; any other error frame
//!   → [`BusError::ErrorFrame`] with its class bits.
//! * A reply not in by the deadline → [`BusError::MissingReply`] naming the motor.
//! * A write still refused (`WouldBlock`, TX queue full) at the deadline →
//!   [`BusError::DeadlineExceeded`].
//! * Foreign traffic (other ids, extended ids, remote frames) is ignored.

use crate::a1::{self, Frame, FrameKind, Special};
use crate::bus::{
    BusError, ExchangeReport, Lifecycle, MotorBus, MotorSpec, MotorTable, Operation, MAX_MOTORS,
};
use crate::frame_log::{FrameDirection, FrameLog, LoggedFrame};
use core::time::Duration;
use socketcan::{
    CanFrame, CanSocket, EmbeddedFrame, Frame as _, Socket, SocketOptions, StandardId,
};
use std::io;
use std::time::Instant;
use thiserror::Error;

/// `CAN_ERR_BUSOFF` class bit of an error frame (`linux/can/error.h`).
pub const CAN_ERR_BUSOFF: u32 = 0x0040;
/// How long `activate`, `deactivate` and `Drop` wait for acknowledgements.
pub const LIFECYCLE_TIMEOUT: Duration = Duration::from_millis(20);

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

/// [`MotorBus`] over one or more SocketCAN interfaces.
pub struct SocketCanBus {
    interfaces: Vec<Interface>,
    table: MotorTable,
    state: Lifecycle,
    frames: FrameLog,
}

impl SocketCanBus {
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
        Ok(Self {
            interfaces: opened,
            table: MotorTable::default(),
            state: Lifecycle::Unconfigured,
            frames: FrameLog::default(),
        })
    }

    /// Interface name of bus `bus`.
    pub fn interface_name(&self, bus: usize) -> Option<&str> {
        self.interfaces.get(bus).map(|i| i.name.as_str())
    }

    fn drain(&self) -> Result<(), BusError> {
        for (bus, iface) in self.interfaces.iter().enumerate() {
            loop {
                match iface.socket.read_frame() {
                    Ok(frame) => {
                        if let Incoming::Error { class } = interpret(&frame) {
                            return Err(error_of(bus, class));
                        }
                    }
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                    Err(e) => {
                        return Err(BusError::Io {
                            bus,
                            kind: e.kind(),
                        })
                    }
                }
            }
        }
        Ok(())
    }

    fn write(
        &mut self,
        bus: usize,
        frame: &Frame,
        deadline: Instant,
        start: Instant,
    ) -> Result<(), BusError> {
        let Some(can) = to_can_frame(frame) else {
            return Ok(());
        };
        let socket = &self.interfaces[bus].socket;
        loop {
            match socket.write_frame(&can) {
                Ok(()) => {
                    self.frames.record(
                        bus,
                        FrameDirection::Tx,
                        start.elapsed(),
                        frame.id,
                        &frame.data,
                    );
                    return Ok(());
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    if Instant::now() >= deadline {
                        return Err(BusError::DeadlineExceeded {
                            needed: start.elapsed(),
                            budget: deadline - start,
                        });
                    }
                    std::thread::yield_now();
                }
                Err(e) => {
                    return Err(BusError::Io {
                        bus,
                        kind: e.kind(),
                    })
                }
            }
        }
    }

    /// Send `frames[i]` on `buses[i]` and collect the reply of `motors[i]` into
    /// `on_reply(i, reply)`, until all arrived or `budget` ran out.
    fn round_trip(
        &mut self,
        frames: &[Frame],
        buses: &[usize],
        budget: Duration,
        mut on_reply: impl FnMut(usize, a1::Reply),
    ) -> Result<Duration, BusError> {
        let start = Instant::now();
        let deadline = start + budget;
        self.frames.clear();
        self.drain()?;
        for (frame, &bus) in frames.iter().zip(buses) {
            self.write(bus, frame, deadline, start)?;
        }
        let mut got = [false; MAX_MOTORS];
        let mut outstanding = frames.len();
        while outstanding > 0 {
            let mut idle = true;
            for bus in 0..self.interfaces.len() {
                let frame = match self.interfaces[bus].socket.read_frame() {
                    Ok(frame) => frame,
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => continue,
                    Err(e) => {
                        return Err(BusError::Io {
                            bus,
                            kind: e.kind(),
                        })
                    }
                };
                idle = false;
                match interpret(&frame) {
                    Incoming::Reply(reply) => {
                        let slot = frames.iter().zip(buses).position(|(f, &b)| {
                            b == bus && a1::classify(f.id).map(|(_, m)| m) == Some(reply.motor)
                        });
                        if let Some(i) = slot.filter(|&i| !got[i]) {
                            got[i] = true;
                            outstanding -= 1;
                            self.frames.record(
                                bus,
                                FrameDirection::Rx,
                                start.elapsed(),
                                frame.raw_id(),
                                frame.data(),
                            );
                            on_reply(i, reply);
                        }
                    }
                    Incoming::BadReply(motor, error) => {
                        if self.table.get(motor).is_some() {
                            return Err(BusError::BadReply { motor, error });
                        }
                    }
                    Incoming::Error { class } => return Err(error_of(bus, class)),
                    Incoming::Foreign => {}
                }
            }
            if idle {
                if Instant::now() >= deadline {
                    break;
                }
                std::thread::yield_now();
            }
        }
        if let Some(i) = (0..frames.len()).find(|&i| !got[i]) {
            let motor = a1::classify(frames[i].id).map(|(_, m)| m);
            if let Some(motor) = motor {
                return Err(BusError::MissingReply {
                    motor,
                    bus: buses[i],
                });
            }
        }
        Ok(start.elapsed())
    }

    fn special_to_all(&mut self, special: Special) -> Result<(), BusError> {
        let mut frames = [encode_placeholder(); MAX_MOTORS];
        let mut buses = [0; MAX_MOTORS];
        let mut specs: [Option<MotorSpec>; MAX_MOTORS] = [None; MAX_MOTORS];
        let n = self.table.len();
        for (i, spec) in self.table.iter().enumerate() {
            frames[i] = a1::encode_special(spec.id, special);
            buses[i] = spec.bus;
            specs[i] = Some(spec);
        }
        let mut refused = None;
        self.round_trip(&frames[..n], &buses[..n], LIFECYCLE_TIMEOUT, |_, reply| {
            if special == Special::Enable && !reply.enabled {
                refused.get_or_insert(BusError::EnableRefused {
                    motor: reply.motor,
                    errors: reply.errors,
                });
            }
        })?;
        refused.map_or(Ok(()), Err)
    }
}

const fn encode_placeholder() -> Frame {
    Frame {
        id: 0,
        data: [0; 8],
    }
}

impl MotorBus for SocketCanBus {
    fn state(&self) -> Lifecycle {
        self.state
    }

    fn bus_count(&self) -> usize {
        self.interfaces.len()
    }

    fn configure(&mut self, motors: &[MotorSpec]) -> Result<(), BusError> {
        self.state.allows(Operation::Configure)?;
        self.table = MotorTable::new(motors, self.interfaces.len())?;
        self.state = Lifecycle::Configured;
        Ok(())
    }

    fn activate(&mut self) -> Result<(), BusError> {
        self.state.allows(Operation::Activate)?;
        if let Err(e) = self.special_to_all(Special::Enable) {
            // Leave nothing half enabled; the frame log keeps both rounds.
            let enable_frames = self.frames;
            let _ = self.special_to_all(Special::Disable);
            let disable_frames = core::mem::replace(&mut self.frames, enable_frames);
            self.frames.append(&disable_frames);
            return Err(e);
        }
        self.state = Lifecycle::Active;
        Ok(())
    }

    fn exchange(
        &mut self,
        commands: &[a1::Command],
        replies: &mut [a1::Reply],
        budget: Duration,
    ) -> Result<ExchangeReport, BusError> {
        if self.state != Lifecycle::Active {
            return Err(BusError::NotActive { state: self.state });
        }
        let (frames, buses, saturation) = self.table.prepare(commands, replies)?;
        let n = commands.len();
        let bus_time = self.round_trip(&frames[..n], &buses[..n], budget, |i, reply| {
            replies[i] = reply;
        })?;
        Ok(ExchangeReport {
            saturation,
            bus_time,
        })
    }

    fn deactivate(&mut self) -> Result<(), BusError> {
        self.state.allows(Operation::Deactivate)?;
        self.state = Lifecycle::Configured;
        self.special_to_all(Special::Disable)
    }

    fn frames(&self) -> &[LoggedFrame] {
        self.frames.frames()
    }
}

impl Drop for SocketCanBus {
    fn drop(&mut self) {
        if self.state == Lifecycle::Active {
            let _ = self.special_to_all(Special::Disable);
        }
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
