//! The far end of the link: a [`SimBus`]'s simulated A1 firmware served over CAN-over-UDP
//! (what `adam emulate motors` runs, and the peer of the UDP conformance tests).
//!
//! One socket per bus. The first sender on a socket becomes that link's host; datagrams from
//! any other address are dropped and counted, never acted on, as are packets that do not
//! parse. Each host frame of a packet goes to the firmware exactly as the in-process `SimBus`
//! delivers it, and the replies go back in one packet per received packet.
//!
//! # Time: lockstep with the host
//! The simulation advances one control period at a time, driven by the host's commands, so a
//! run over the link walks the same physics as an in-process `SimBus` run whatever the wall
//! clock does. A period ends (the motors and plant advance, [`SimBus::advance_period`]) when
//! every enabled motor has received a command since the last advance (the normal tick); or,
//! lazily, just before a motor receives its second command of a period (a host that commands
//! a subset). Lifecycle frames (enable, disable) never advance time. After each advance the
//! plant's IMU sample ([`ServedPlant::imu_sample`]), if it has one, goes out with the replies
//! as [`super::imu_frames`].

use super::cannelloni::{Packet, PacketWriter, MAX_PACKET_LEN};
use super::imu_frames;
use super::socket::recv_waiting;
use crate::a1::{self, FrameKind};
use crate::bus::MAX_MOTORS;
use crate::imu::{Imu, ImuSample};
use crate::sim::bus::SimBus;
use crate::sim::plant::{InertiaDampingPlant, JointPlant};
use crate::sim::robot::RobotSim;
use core::time::Duration;
use std::io;
use std::net::{SocketAddr, UdpSocket};

/// A plant the server can put behind the link: its IMU sample after a period, if it has an IMU.
pub trait ServedPlant: JointPlant {
    /// The IMU sample after the period just simulated (`None`: no IMU).
    fn imu_sample(&mut self) -> Option<ImuSample> {
        None
    }
}

impl ServedPlant for InertiaDampingPlant {}

/// The simulated ADAM's torso IMU (noise, faults), as the in-process loop reads it.
impl ServedPlant for RobotSim {
    fn imu_sample(&mut self) -> Option<ImuSample> {
        let mut sample = ImuSample::default();
        self.read(&mut sample).ok().map(|()| sample)
    }
}

/// What the server saw (counts since it started).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ServerStats {
    /// Packets received from the hosts.
    pub packets_received: u64,
    /// Packets sent.
    pub packets_sent: u64,
    /// Datagrams from an address other than the link's host, dropped.
    pub foreign_sender: u64,
    /// Packets that did not parse, dropped.
    pub malformed: u64,
    /// Frames that are not A1 host frames (extended, remote, error, CAN FD), ignored.
    pub foreign_frames: u64,
    /// Control periods simulated.
    pub periods: u64,
}

/// A [`SimBus`] served over one UDP socket per bus.
pub struct MotorServer<P: ServedPlant> {
    sim: SimBus<P>,
    sockets: Vec<UdpSocket>,
    hosts: Vec<Option<SocketAddr>>,
    commanded: [bool; MAX_MOTORS],
    enabled: [bool; MAX_MOTORS],
    ever_enabled: bool,
    stats: ServerStats,
    seq: u8,
    recv_buf: Vec<u8>,
    send_buf: Vec<u8>,
}

impl<P: ServedPlant> MotorServer<P> {
    /// Serve `sim` on `sockets` (bus index = position; made nonblocking here).
    pub fn new(sim: SimBus<P>, sockets: Vec<UdpSocket>) -> io::Result<Self> {
        for s in &sockets {
            s.set_nonblocking(true)?;
        }
        let hosts = vec![None; sockets.len()];
        Ok(Self {
            sim,
            sockets,
            hosts,
            commanded: [false; MAX_MOTORS],
            enabled: [false; MAX_MOTORS],
            ever_enabled: false,
            stats: ServerStats::default(),
            seq: 0,
            recv_buf: vec![0; MAX_PACKET_LEN + 1],
            send_buf: vec![0; MAX_PACKET_LEN],
        })
    }

    /// Bind one socket per bus at `first` and the ports after it (bus `k` at port + `k`). Port
    /// 0: the OS picks bus 0's port, and the next ones must be free (tried up to 20 times).
    pub fn bind(first: SocketAddr, bus_count: usize) -> io::Result<Vec<UdpSocket>> {
        let consecutive = |first: SocketAddr| -> io::Result<Vec<UdpSocket>> {
            let bus0 = UdpSocket::bind(first)?;
            let base = bus0.local_addr()?.port();
            let mut sockets = vec![bus0];
            for k in 1..bus_count {
                let port = u16::try_from(usize::from(base) + k)
                    .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "port past 65535"))?;
                sockets.push(UdpSocket::bind(SocketAddr::new(first.ip(), port))?);
            }
            Ok(sockets)
        };
        let mut last = consecutive(first);
        if first.port() == 0 {
            for _ in 0..20 {
                if last.is_ok() {
                    break;
                }
                last = consecutive(first);
            }
        }
        last
    }

    /// The simulation.
    pub fn sim(&self) -> &SimBus<P> {
        &self.sim
    }

    /// The simulation, to set faults or states.
    pub fn sim_mut(&mut self) -> &mut SimBus<P> {
        &mut self.sim
    }

    /// What the server saw.
    pub fn stats(&self) -> ServerStats {
        self.stats
    }

    /// The local address of bus `bus`.
    pub fn local_addr(&self, bus: usize) -> Option<SocketAddr> {
        self.sockets.get(bus)?.local_addr().ok()
    }

    /// A host enabled motors and has since disabled every one (its run is over).
    pub fn session_over(&self) -> bool {
        self.ever_enabled && !self.enabled.iter().any(|&e| e)
    }

    /// Serve every packet waiting; if none, sleep `idle` once. Returns the packets handled.
    pub fn poll(&mut self, idle: Duration) -> io::Result<usize> {
        let mut handled = 0;
        for bus in 0..self.sockets.len() {
            while let Some((n, from)) = recv_waiting(&self.sockets[bus], &mut self.recv_buf)? {
                handled += 1;
                self.serve_packet(bus, n, from)?;
            }
        }
        if handled == 0 && !idle.is_zero() {
            std::thread::sleep(idle);
        }
        Ok(handled)
    }

    fn firmware_index(&self, motor: a1::MotorId) -> Option<usize> {
        self.sim
            .config()
            .motors
            .iter()
            .position(|m| m.spec.id == motor)
            .filter(|&i| i < MAX_MOTORS)
    }

    fn advance(&mut self) {
        self.sim.advance_period();
        self.commanded = [false; MAX_MOTORS];
        self.stats.periods += 1;
    }

    fn serve_packet(&mut self, bus: usize, n: usize, from: SocketAddr) -> io::Result<()> {
        match self.hosts[bus] {
            None => self.hosts[bus] = Some(from),
            Some(host) if host != from => {
                self.stats.foreign_sender += 1;
                return Ok(());
            }
            Some(_) => {}
        }
        // Parse from a copy of the bytes so the simulation can be borrowed mutably.
        let recv = std::mem::take(&mut self.recv_buf);
        let result = self.serve_bytes(bus, &recv[..n]);
        self.recv_buf = recv;
        let Some(len) = result else {
            return Ok(());
        };
        if let Some(host) = self.hosts[bus] {
            self.sockets[bus].send_to(&self.send_buf[..len], host)?;
            self.stats.packets_sent += 1;
        }
        Ok(())
    }

    /// Handle one packet's bytes; the length of the reply packet in `send_buf`, if any.
    fn serve_bytes(&mut self, bus: usize, bytes: &[u8]) -> Option<usize> {
        let Ok(packet) = Packet::parse(bytes) else {
            self.stats.malformed += 1;
            return None;
        };
        self.stats.packets_received += 1;
        let mut send = std::mem::take(&mut self.send_buf);
        let Some(mut writer) = PacketWriter::new(&mut send, self.seq) else {
            self.send_buf = send;
            return None;
        };
        let mut advanced = false;
        let mut any_command = false;
        for frame in packet.frames() {
            let Some((id, data)) = frame.standard_data() else {
                self.stats.foreign_frames += 1;
                continue;
            };
            let command_to = match a1::classify(id) {
                Some((FrameKind::Command, motor)) => self.firmware_index(motor),
                _ => None,
            };
            if let Some(i) = command_to {
                if self.commanded[i] {
                    self.advance();
                    advanced = true;
                }
            }
            let Some(reply) = self.sim.deliver(bus, id, data) else {
                continue;
            };
            if let Some(i) = command_to {
                self.commanded[i] = true;
                any_command = true;
            }
            if let Ok(r) = a1::decode_reply(reply.id, &reply.data) {
                if let Some(i) = self.firmware_index(r.motor) {
                    self.enabled[i] = r.enabled;
                    self.ever_enabled |= r.enabled;
                }
            }
            if let Some(can) = super::cannelloni::CanFrame::standard(reply.id, &reply.data) {
                let _ = writer.push(&can.as_ref());
            }
        }
        let motors = self.sim.config().motors.len().min(MAX_MOTORS);
        let period_done = (0..motors).all(|i| !self.enabled[i] || self.commanded[i]);
        if any_command && period_done {
            self.advance();
            advanced = true;
        }
        if advanced {
            if let Some(sample) = self.sim.plant_mut().imu_sample() {
                for f in imu_frames::encode(&sample) {
                    let _ = writer.push(&f.as_ref());
                }
            }
        }
        let len = (writer.count() > 0).then(|| writer.finish());
        self.send_buf = send;
        if len.is_some() {
            self.seq = self.seq.wrapping_add(1);
        }
        len
    }
}
