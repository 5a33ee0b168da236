//! `UdpBus`: the [`MotorBus`](crate::bus::MotorBus) over CAN-over-UDP links (cannelloni's
//! packet format), one link per bus ([`FrameBus`] over [`UdpLinks`]), and the [`Imu`] whose
//! samples come over the same links from the emulator.
//!
//! Like `SocketCanBus`, this adapter only moves frames: the A1 codec and
//! [`MotorTable`](crate::bus::MotorTable) encode and check, [`FrameBus`] keeps the lifecycle
//! and the round trip. Sockets are nonblocking. An exchange drains stale datagrams, sends one packet per
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
use crate::a1::{self, Frame, FrameKind};
use crate::bus::BusError;
pub use crate::frame_bus::LIFECYCLE_TIMEOUT;
use crate::frame_bus::{io_error, send_by, FrameBus, FrameTransport, Replies};
use crate::frame_log::{FrameDirection, FrameLog};
use crate::imu::{Imu, ImuError, ImuSample};
use core::time::Duration;
use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::time::Instant;
use thiserror::Error;

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

/// The CAN-over-UDP links of a [`UdpBus`], one socket per bus: its [`FrameTransport`], with
/// what they saw ([`LinkStats`]) and the emulator's IMU samples that came with the replies.
pub struct UdpLinks {
    links: Vec<Link>,
    reply_timeout: Option<Duration>,
    stats: LinkStats,
    imu: Option<ImuSample>,
    imu_fresh: bool,
    send_buf: Vec<u8>,
    recv_buf: Vec<u8>,
}

/// [`MotorBus`](crate::bus::MotorBus) over one CAN-over-UDP link per bus.
pub type UdpBus = FrameBus<UdpLinks>;

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

impl FrameBus<UdpLinks> {
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
        Ok(FrameBus::new(UdpLinks {
            links,
            reply_timeout: None,
            stats: LinkStats::default(),
            imu: None,
            imu_fresh: false,
            send_buf: vec![0; MAX_PACKET_LEN],
            // One byte more than a valid packet, so an oversized datagram shows as too long.
            recv_buf: vec![0; MAX_PACKET_LEN + 1],
        }))
    }

    /// Wait this long for replies instead of the exchange's budget (`None`: the budget).
    pub fn set_reply_timeout(&mut self, timeout: Option<Duration>) {
        self.transport_mut().reply_timeout = timeout;
    }

    /// The local address of bus `bus`'s socket (where the peer must reply).
    pub fn local_addr(&self, bus: usize) -> Option<SocketAddr> {
        self.transport().links.get(bus)?.socket.local_addr().ok()
    }

    /// What the links saw.
    pub fn stats(&self) -> LinkStats {
        self.transport().stats
    }
}

impl FrameTransport for UdpLinks {
    fn bus_count(&self) -> usize {
        self.links.len()
    }

    fn drain(&mut self) -> Result<(), BusError> {
        for (bus, link) in self.links.iter().enumerate() {
            // A previous send's ICMP "port unreachable" surfaces here on Linux: nothing waits.
            while let Some((_, from)) =
                recv_waiting(&link.socket, &mut self.recv_buf).map_err(|e| io_error(bus, &e))?
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

    /// One packet holding every command frame of the bus.
    fn send(
        &mut self,
        bus: usize,
        frames: &[Frame],
        buses: &[usize],
        log: &mut FrameLog,
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
                log.record(
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
        send_by(bus, start, deadline, || {
            link.socket.send_to(&self.send_buf[..len], link.peer)
        })?;
        self.stats.packets_sent += 1;
        Ok(())
    }

    /// One datagram: its reply frames offered, its IMU frames assembled, the rest counted.
    fn poll<F: FnMut(usize, a1::Reply)>(
        &mut self,
        bus: usize,
        replies: &mut Replies<'_, F>,
    ) -> Result<bool, BusError> {
        let link = &self.links[bus];
        let (n, from) = match recv_waiting(&link.socket, &mut self.recv_buf) {
            Ok(Some(r)) => r,
            Ok(None) => return Ok(false),
            Err(e) => return Err(io_error(bus, &e)),
        };
        if from != link.peer {
            self.stats.foreign_sender += 1;
            return Ok(true);
        }
        let Ok(packet) = Packet::parse(&self.recv_buf[..n]) else {
            self.stats.malformed += 1;
            return Ok(true);
        };
        self.stats.packets_received += 1;
        let mut imu = ImuAssembler::default();
        for frame in packet.frames() {
            let Some((id, data)) = frame.standard_data() else {
                if !imu.take(&frame) {
                    self.stats.foreign_frames += 1;
                }
                continue;
            };
            if !matches!(a1::classify(id), Some((FrameKind::Reply, _))) {
                self.stats.foreign_frames += 1;
                continue;
            }
            let Ok(reply) = a1::decode_reply(id, data) else {
                self.stats.bad_replies += 1;
                continue;
            };
            if !replies.offer(bus, id, data, reply) {
                self.stats.unexpected_replies += 1;
            }
        }
        if let Some(sample) = imu.sample() {
            self.imu = Some(sample);
            self.imu_fresh = true;
            self.stats.imu_samples += 1;
        }
        Ok(true)
    }

    fn reply_timeout(&self, budget: Duration) -> Duration {
        self.reply_timeout.unwrap_or(budget)
    }
}

/// The emulator's IMU, from the frames of the last exchange: a sample is read once; a read
/// with no new sample since the last is [`ImuError::Timeout`].
impl Imu for UdpBus {
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        let links = self.transport_mut();
        match (links.imu, links.imu_fresh) {
            (Some(sample), true) => {
                *out = sample;
                links.imu_fresh = false;
                Ok(())
            }
            _ => Err(ImuError::Timeout),
        }
    }
}
