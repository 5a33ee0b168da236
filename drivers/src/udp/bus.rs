//! `UdpBus`: the [`MotorBus`] over CAN-over-UDP links (cannelloni's packet format), one link
//! per bus, and the [`Imu`] whose samples come over the same links from the emulator.
//!
//! Like `SocketCanBus`, this adapter only moves frames: the A1 codec and [`MotorTable`] encode
//! and check. Sockets are nonblocking. An exchange drains stale datagrams, sends one packet per
//! bus holding that bus's command frames, then polls every socket until each commanded motor
//! has replied or the reply timeout runs out (by default the exchange's budget, as
//! `SocketCanBus`; [`UdpBus::set_reply_timeout`] for a link to a lockstep emulator on a busy
//! host). It busy-polls, yielding the CPU between empty polls. Buffers are allocated at
//! `open`; an exchange allocates nothing.
//!
//! What arrives is judged, never trusted ([`LinkStats`] counts each case):
//! * a datagram from an address other than the link's peer is dropped, unread;
//! * a packet that does not parse ([`super::cannelloni::PacketError`]) is dropped;
//! * a reply frame from a motor that was not asked on that link in this exchange (a wrong
//!   id, a second reply, another bus's motor) is counted and not used;
//! * a reply frame whose bytes do not decode is counted and not used (the motor then misses);
//! * datagrams left from an earlier exchange (late replies) are drained and counted as stale;
//! * frames of other kinds (extended, remote, error, CAN FD, host frames) are counted as foreign;
//!   the emulator's IMU frames ([`super::imu_frames`]) become the [`Imu`] sample.

use super::cannelloni::{Packet, PacketWriter, MAX_PACKET_LEN};
use super::imu_frames::ImuAssembler;
use super::socket::recv_waiting;
use crate::a1::{self, Frame, FrameKind, Special};
use crate::bus::{
    BusError, ExchangeReport, Lifecycle, MotorBus, MotorSpec, MotorTable, Operation, MAX_MOTORS,
};
use crate::frame_log::{FrameDirection, FrameLog, LoggedFrame};
use crate::imu::{Imu, ImuError, ImuSample};
use core::time::Duration;
use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::time::Instant;
use thiserror::Error;

/// How long `activate`, `deactivate` and `Drop` wait for acknowledgements, at least.
pub const LIFECYCLE_TIMEOUT: Duration = Duration::from_millis(20);

/// Opening a link failed.
#[derive(Debug, Error)]
pub enum UdpOpenError {
    /// The OS refused to bind or set up the socket.
    #[error("cannot open the UDP link to {peer} (bus {bus}): {source}")]
    Socket {
        /// Bus index.
        bus: usize,
        /// Peer address.
        peer: SocketAddr,
        /// The OS error.
        source: io::Error,
    },
    /// No peer given.
    #[error("no UDP peer given")]
    NoPeer,
}

/// What the links saw besides the replies used (counts since `open`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Packets sent.
    pub packets_sent: u64,
    /// Packets received from the peers.
    pub packets_received: u64,
    /// Datagrams from an unexpected sender, dropped.
    pub foreign_sender: u64,
    /// Packets that did not parse, dropped.
    pub malformed: u64,
    /// Packets drained at the start of an exchange (late replies of an earlier one).
    pub stale: u64,
    /// Reply frames of a motor not asked on that link in this exchange, not used.
    pub unexpected_replies: u64,
    /// Reply frames whose bytes did not decode, not used.
    pub bad_replies: u64,
    /// Frames of other kinds (not A1 replies nor IMU frames), ignored.
    pub foreign_frames: u64,
    /// IMU samples received.
    pub imu_samples: u64,
}

struct Link {
    socket: UdpSocket,
    peer: SocketAddr,
    seq: u8,
}

/// [`MotorBus`] over one CAN-over-UDP link per bus.
pub struct UdpBus {
    links: Vec<Link>,
    table: MotorTable,
    state: Lifecycle,
    reply_timeout: Option<Duration>,
    stats: LinkStats,
    frames: FrameLog,
    imu: Option<ImuSample>,
    imu_fresh: bool,
    send_buf: Vec<u8>,
    recv_buf: Vec<u8>,
}

/// The local address to bind for a peer: loopback for a loopback peer, else any address of
/// its family; an OS-chosen port.
fn local_for(peer: &SocketAddr) -> SocketAddr {
    use std::net::{IpAddr, Ipv4Addr, Ipv6Addr};
    let ip = match peer.ip() {
        IpAddr::V4(v4) if v4.is_loopback() => IpAddr::V4(Ipv4Addr::LOCALHOST),
        IpAddr::V4(_) => IpAddr::V4(Ipv4Addr::UNSPECIFIED),
        IpAddr::V6(v6) if v6.is_loopback() => IpAddr::V6(Ipv6Addr::LOCALHOST),
        IpAddr::V6(_) => IpAddr::V6(Ipv6Addr::UNSPECIFIED),
    };
    SocketAddr::new(ip, 0)
}

impl UdpBus {
    /// Open one link per peer (bus index = position), each on its own nonblocking socket at a
    /// port the OS picks.
    pub fn open(peers: &[SocketAddr]) -> Result<Self, UdpOpenError> {
        Self::open_at(peers, None)
    }

    /// [`UdpBus::open`], bus `k`'s socket bound at `local`'s port + `k` (a cannelloni gateway
    /// sends to a fixed port: its `-r`); `None`: ports the OS picks.
    pub fn open_at(peers: &[SocketAddr], local: Option<SocketAddr>) -> Result<Self, UdpOpenError> {
        if peers.is_empty() {
            return Err(UdpOpenError::NoPeer);
        }
        let links = peers
            .iter()
            .enumerate()
            .map(|(bus, &peer)| {
                let fail = |source| UdpOpenError::Socket { bus, peer, source };
                let at = match local {
                    Some(first) => {
                        let port =
                            u16::try_from(usize::from(first.port()) + bus).map_err(|_| {
                                fail(io::Error::new(
                                    io::ErrorKind::InvalidInput,
                                    "port past 65535",
                                ))
                            })?;
                        SocketAddr::new(first.ip(), port)
                    }
                    None => local_for(&peer),
                };
                let socket = UdpSocket::bind(at).map_err(fail)?;
                socket.set_nonblocking(true).map_err(fail)?;
                Ok(Link {
                    socket,
                    peer,
                    seq: 0,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            links,
            table: MotorTable::default(),
            state: Lifecycle::Unconfigured,
            reply_timeout: None,
            stats: LinkStats::default(),
            frames: FrameLog::default(),
            imu: None,
            imu_fresh: false,
            send_buf: vec![0; MAX_PACKET_LEN],
            // One byte more than a valid packet, so an oversized datagram shows as too long.
            recv_buf: vec![0; MAX_PACKET_LEN + 1],
        })
    }

    /// Wait this long for replies instead of the exchange's budget (`None`: the budget).
    pub fn set_reply_timeout(&mut self, timeout: Option<Duration>) {
        self.reply_timeout = timeout;
    }

    /// The local address of bus `bus`'s socket (where the peer must reply).
    pub fn local_addr(&self, bus: usize) -> Option<SocketAddr> {
        self.links.get(bus)?.socket.local_addr().ok()
    }

    /// What the links saw.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    fn io_error(bus: usize, e: &io::Error) -> BusError {
        BusError::Io {
            bus,
            kind: e.kind(),
        }
    }

    fn drain(&mut self) -> Result<(), BusError> {
        for (bus, link) in self.links.iter().enumerate() {
            // A previous send's ICMP "port unreachable" surfaces here on Linux: nothing waits.
            while let Some((_, from)) = recv_waiting(&link.socket, &mut self.recv_buf)
                .map_err(|e| Self::io_error(bus, &e))?
            {
                if from == link.peer {
                    self.stats.stale += 1;
                } else {
                    self.stats.foreign_sender += 1;
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
        start: Instant,
        deadline: Instant,
    ) -> Result<(), BusError> {
        let link = &mut self.links[bus];
        let Some(mut writer) = PacketWriter::new(&mut self.send_buf, link.seq) else {
            return Ok(());
        };
        for (frame, _) in frames.iter().zip(buses).filter(|(_, &b)| b == bus) {
            let Some(can) = super::cannelloni::CanFrame::standard(frame.id, &frame.data) else {
                continue;
            };
            // At most 2·MAX_MOTORS frames of 13 bytes: always fits.
            if writer.push(&can.as_ref()).is_ok() {
                self.frames.record(
                    bus,
                    FrameDirection::Tx,
                    start.elapsed(),
                    frame.id,
                    &frame.data,
                );
            }
        }
        if writer.count() == 0 {
            return Ok(());
        }
        let len = writer.finish();
        link.seq = link.seq.wrapping_add(1);
        loop {
            match link.socket.send_to(&self.send_buf[..len], link.peer) {
                Ok(_) => {
                    self.stats.packets_sent += 1;
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
                Err(e) => return Err(Self::io_error(bus, &e)),
            }
        }
    }

    /// Send `frames[i]` on `buses[i]` and collect the reply of each one's motor into
    /// `on_reply(i, reply)` until all arrived or `timeout` ran out.
    fn round_trip(
        &mut self,
        frames: &[Frame],
        buses: &[usize],
        timeout: Duration,
        mut on_reply: impl FnMut(usize, a1::Reply),
    ) -> Result<Duration, BusError> {
        let start = Instant::now();
        let deadline = start + timeout;
        self.frames.clear();
        self.drain()?;
        for bus in 0..self.links.len() {
            self.send(bus, frames, buses, start, deadline)?;
        }
        let mut got = [false; MAX_MOTORS];
        let mut outstanding = frames.len();
        while outstanding > 0 {
            let mut idle = true;
            for bus in 0..self.links.len() {
                let link = &self.links[bus];
                let (n, from) = match recv_waiting(&link.socket, &mut self.recv_buf) {
                    Ok(Some(r)) => r,
                    Ok(None) => continue,
                    Err(e) => return Err(Self::io_error(bus, &e)),
                };
                idle = false;
                if from != link.peer {
                    self.stats.foreign_sender += 1;
                    continue;
                }
                let Ok(packet) = Packet::parse(&self.recv_buf[..n]) else {
                    self.stats.malformed += 1;
                    continue;
                };
                self.stats.packets_received += 1;
                let mut imu = ImuAssembler::default();
                for frame in packet.frames() {
                    let Some((id, data)) = frame.standard_data() else {
                        if imu.take(&frame) {
                            continue;
                        }
                        self.stats.foreign_frames += 1;
                        continue;
                    };
                    if !matches!(a1::classify(id), Some((FrameKind::Reply, _))) {
                        self.stats.foreign_frames += 1;
                        continue;
                    }
                    let reply = match a1::decode_reply(id, data) {
                        Ok(reply) => reply,
                        Err(_) => {
                            self.stats.bad_replies += 1;
                            continue;
                        }
                    };
                    let slot = frames.iter().zip(buses).position(|(f, &b)| {
                        b == bus && a1::classify(f.id).map(|(_, m)| m) == Some(reply.motor)
                    });
                    match slot.filter(|&i| !got[i]) {
                        Some(i) => {
                            got[i] = true;
                            outstanding -= 1;
                            self.frames
                                .record(bus, FrameDirection::Rx, start.elapsed(), id, data);
                            on_reply(i, reply);
                        }
                        None => self.stats.unexpected_replies += 1,
                    }
                }
                if let Some(sample) = imu.sample() {
                    self.imu = Some(sample);
                    self.imu_fresh = true;
                    self.stats.imu_samples += 1;
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
            if let Some((_, motor)) = a1::classify(frames[i].id) {
                return Err(BusError::MissingReply {
                    motor,
                    bus: buses[i],
                });
            }
        }
        Ok(start.elapsed())
    }

    fn special_to_all(&mut self, special: Special) -> Result<(), BusError> {
        let mut frames = [Frame {
            id: 0,
            data: [0; 8],
        }; MAX_MOTORS];
        let mut buses = [0; MAX_MOTORS];
        let n = self.table.len();
        let table = self.table;
        for (i, spec) in table.iter().enumerate() {
            frames[i] = a1::encode_special(spec.id, special);
            buses[i] = spec.bus;
        }
        let timeout = self
            .reply_timeout
            .unwrap_or(LIFECYCLE_TIMEOUT)
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

impl MotorBus for UdpBus {
    fn state(&self) -> Lifecycle {
        self.state
    }

    fn bus_count(&self) -> usize {
        self.links.len()
    }

    fn configure(&mut self, motors: &[MotorSpec]) -> Result<(), BusError> {
        self.state.allows(Operation::Configure)?;
        self.table = MotorTable::new(motors, self.links.len())?;
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
        let timeout = self.reply_timeout.unwrap_or(budget);
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

/// The emulator's IMU, from the frames of the last exchange: a sample is read once; a read
/// with no new sample since the last is [`ImuError::Timeout`].
impl Imu for UdpBus {
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        match (self.imu, self.imu_fresh) {
            (Some(sample), true) => {
                *out = sample;
                self.imu_fresh = false;
                Ok(())
            }
            _ => Err(ImuError::Timeout),
        }
    }
}

impl Drop for UdpBus {
    fn drop(&mut self) {
        if self.state == Lifecycle::Active {
            let _ = self.special_to_all(Special::Disable);
        }
    }
}
