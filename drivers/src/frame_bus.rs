//! [`FrameBus`]: the one [`MotorBus`] of the hardware transports, over a [`FrameTransport`]
//! that only moves A1 frames (Linux SocketCAN: [`crate::socketcan_bus`]; CAN over UDP:
//! [`crate::udp`]).
//!
//! What every transport shares lives here once: the lifecycle (configure → activate →
//! exchange → deactivate, `Drop` = disable), the enable round that leaves nothing half enabled
//! (and keeps both rounds in the frame log), and the round trip: drain what is stale, send each
//! bus's command frames, then poll every bus until each commanded motor has replied or the
//! timeout (measured from the call with the monotonic clock) runs out, busy-polling and
//! yielding the CPU between empty polls. A reply is used once, for the motor that was asked on
//! that bus ([`Replies::offer`]); what else arrives (foreign traffic, undecodable replies, a
//! second reply) is the transport's to judge. No allocation after `open`.

use crate::a1::{self, Frame, Special};
use crate::bus::{
    BusError, ExchangeReport, Lifecycle, MotorBus, MotorSpec, MotorTable, Operation, MAX_MOTORS,
};
use crate::frame_log::{FrameDirection, FrameLog, LoggedFrame};
use core::time::Duration;
use std::time::Instant;

/// How long `activate`, `deactivate` and `Drop` wait for acknowledgements, at least.
pub const LIFECYCLE_TIMEOUT: Duration = Duration::from_millis(20);

/// An I/O error of bus `bus`'s socket, as a [`BusError`].
pub fn io_error(bus: usize, e: &std::io::Error) -> BusError {
    BusError::Io {
        bus,
        kind: e.kind(),
    }
}

/// Retries a nonblocking send on bus `bus` while the OS answers `WouldBlock` (a full transmit
/// queue), yielding the CPU between tries: still refused at `deadline` is
/// [`BusError::DeadlineExceeded`], any other error an I/O error of the bus.
pub fn send_by<T>(
    bus: usize,
    start: Instant,
    deadline: Instant,
    mut attempt: impl FnMut() -> std::io::Result<T>,
) -> Result<T, BusError> {
    loop {
        match attempt() {
            Ok(sent) => return Ok(sent),
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                if Instant::now() >= deadline {
                    return Err(BusError::DeadlineExceeded {
                        needed: start.elapsed(),
                        budget: deadline - start,
                    });
                }
                std::thread::yield_now();
            }
            Err(e) => return Err(io_error(bus, &e)),
        }
    }
}

/// What differs between the hardware transports: how frames leave and arrive.
pub trait FrameTransport {
    /// Number of buses (bus index = position).
    fn bus_count(&self) -> usize;

    /// Discards what arrived before this round trip (late replies of an earlier one); a
    /// transport error (an error frame, a socket error) is returned.
    fn drain(&mut self) -> Result<(), BusError>;

    /// Sends the frames `frames[i]` whose `buses[i] == bus`, recording each sent one as
    /// transmitted in `log` at `start.elapsed()`; a send still refused at `deadline` is
    /// [`BusError::DeadlineExceeded`].
    fn send(
        &mut self,
        bus: usize,
        frames: &[Frame],
        buses: &[usize],
        log: &mut FrameLog,
        start: Instant,
        deadline: Instant,
    ) -> Result<(), BusError>;

    /// Reads what bus `bus` has ready, without waiting, and offers each decoded reply to
    /// `replies`; `Ok(false)` when nothing was ready.
    fn poll<F: FnMut(usize, a1::Reply)>(
        &mut self,
        bus: usize,
        replies: &mut Replies<'_, F>,
    ) -> Result<bool, BusError>;

    /// How long an exchange of `budget` waits for its replies (default: the budget).
    fn reply_timeout(&self, budget: Duration) -> Duration {
        budget
    }
}

/// The replies a round trip waits for: one per commanded motor, each used once.
pub struct Replies<'a, F> {
    frames: &'a [Frame],
    buses: &'a [usize],
    table: &'a MotorTable,
    log: &'a mut FrameLog,
    start: Instant,
    got: [bool; MAX_MOTORS],
    outstanding: usize,
    on_reply: F,
}

impl<'a, F: FnMut(usize, a1::Reply)> Replies<'a, F> {
    /// Waits for the reply of each `frames[i]`'s motor on `buses[i]`; `on_reply(i, reply)` takes
    /// each one used.
    pub fn new(
        frames: &'a [Frame],
        buses: &'a [usize],
        table: &'a MotorTable,
        log: &'a mut FrameLog,
        start: Instant,
        on_reply: F,
    ) -> Self {
        Self {
            frames,
            buses,
            table,
            log,
            start,
            got: [false; MAX_MOTORS],
            outstanding: frames.len(),
            on_reply,
        }
    }

    /// A reply arrived on `bus` (its raw `id` and `data` for the log). It is used, logged and
    /// `true` is returned when its motor was asked on that bus and has not answered yet;
    /// otherwise (not asked there, or a second reply) it is not used.
    pub fn offer(&mut self, bus: usize, id: u32, data: &[u8], reply: a1::Reply) -> bool {
        let asked = self.frames.iter().zip(self.buses).position(|(f, &b)| {
            b == bus && a1::classify(f.id).map(|(_, m)| m) == Some(reply.motor)
        });
        let Some(i) = asked.filter(|&i| !self.got[i]) else {
            return false;
        };
        self.got[i] = true;
        self.outstanding -= 1;
        self.log
            .record(bus, FrameDirection::Rx, self.start.elapsed(), id, data);
        (self.on_reply)(i, reply);
        true
    }

    /// Whether `motor` is one of the bus's configured motors (its undecodable reply is then a
    /// fault of ours, not foreign traffic).
    pub fn is_configured(&self, motor: a1::MotorId) -> bool {
        self.table.get(motor).is_some()
    }

    fn all_in(&self) -> bool {
        self.outstanding == 0
    }

    /// The first motor whose reply did not come, as [`BusError::MissingReply`].
    fn missing(&self) -> Result<(), BusError> {
        match (0..self.frames.len()).find(|&i| !self.got[i]) {
            Some(i) => match a1::classify(self.frames[i].id) {
                Some((_, motor)) => Err(BusError::MissingReply {
                    motor,
                    bus: self.buses[i],
                }),
                None => Ok(()),
            },
            None => Ok(()),
        }
    }
}

/// [`MotorBus`] over a [`FrameTransport`]: `SocketCanBus` and `UdpBus` are this over theirs.
pub struct FrameBus<T: FrameTransport> {
    transport: T,
    table: MotorTable,
    state: Lifecycle,
    frames: FrameLog,
}

impl<T: FrameTransport> FrameBus<T> {
    /// A bus over an opened transport, unconfigured.
    pub fn new(transport: T) -> Self {
        Self {
            transport,
            table: MotorTable::default(),
            state: Lifecycle::Unconfigured,
            frames: FrameLog::default(),
        }
    }

    /// The transport.
    pub fn transport(&self) -> &T {
        &self.transport
    }

    /// The transport, to change its settings.
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    /// Sends `frames[i]` on `buses[i]` and collects the reply of each one's motor into
    /// `on_reply(i, reply)` until all arrived or `timeout` ran out; the bus time taken.
    fn round_trip(
        &mut self,
        frames: &[Frame],
        buses: &[usize],
        timeout: Duration,
        on_reply: impl FnMut(usize, a1::Reply),
    ) -> Result<Duration, BusError> {
        let start = Instant::now();
        let deadline = start + timeout;
        self.frames.clear();
        self.transport.drain()?;
        for bus in 0..self.transport.bus_count() {
            self.transport
                .send(bus, frames, buses, &mut self.frames, start, deadline)?;
        }
        let mut replies = Replies::new(
            frames,
            buses,
            &self.table,
            &mut self.frames,
            start,
            on_reply,
        );
        while !replies.all_in() {
            let mut idle = true;
            for bus in 0..self.transport.bus_count() {
                if self.transport.poll(bus, &mut replies)? {
                    idle = false;
                }
            }
            if idle {
                if Instant::now() >= deadline {
                    break;
                }
                std::thread::yield_now();
            }
        }
        replies.missing()?;
        Ok(start.elapsed())
    }

    /// One special frame (enable, disable) to every configured motor; an enable a motor
    /// refuses is [`BusError::EnableRefused`].
    fn special_to_all(&mut self, special: Special) -> Result<(), BusError> {
        let mut frames = [Frame {
            id: 0,
            data: [0; 8],
        }; MAX_MOTORS];
        let mut buses = [0; MAX_MOTORS];
        let n = self.table.len();
        for (i, spec) in self.table.iter().enumerate() {
            frames[i] = a1::encode_special(spec.id, special);
            buses[i] = spec.bus;
        }
        let timeout = self
            .transport
            .reply_timeout(LIFECYCLE_TIMEOUT)
            .max(LIFECYCLE_TIMEOUT);
        let mut refused = None;
        self.round_trip(&frames[..n], &buses[..n], timeout, |_, reply| {
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

impl<T: FrameTransport> MotorBus for FrameBus<T> {
    fn state(&self) -> Lifecycle {
        self.state
    }

    fn bus_count(&self) -> usize {
        self.transport.bus_count()
    }

    fn configure(&mut self, motors: &[MotorSpec]) -> Result<(), BusError> {
        self.state.allows(Operation::Configure)?;
        self.table = MotorTable::new(motors, self.transport.bus_count())?;
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
        let timeout = self.transport.reply_timeout(budget);
        let bus_time = self.round_trip(&frames[..n], &buses[..n], timeout, |i, reply| {
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

impl<T: FrameTransport> Drop for FrameBus<T> {
    fn drop(&mut self) {
        if self.state == Lifecycle::Active {
            let _ = self.special_to_all(Special::Disable);
        }
    }
}
