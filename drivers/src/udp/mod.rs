//! The motor link across processes without kernel CAN: CAN frames tunnelled over UDP in the
//! packet format of cannelloni (<https://github.com/mguentner/cannelloni>, a SocketCAN-over-
//! Ethernet tunnel used between Linux gateways), a [`MotorBus`](crate::bus::MotorBus) over it
//! ([`UdpBus`]), and the simulated A1 firmware served over it ([`serve::MotorServer`], what
//! `adam emulate motors` runs).
//!
//! ```text
//!  adam run --backend udp                         adam emulate motors --listen 127.0.0.1:PORT
//!  Controller ─▶ UdpBus::exchange                 MotorServer
//!   a1::encode_command ─▶ cannelloni packet ─UDP─▶ parse ─▶ SimBus::deliver (A1 firmware model)
//!   a1::decode_reply ◀── cannelloni packet ◀──UDP─ replies (+ IMU frames after each period)
//! ```
//!
//! # Wire format (cannelloni's UDP format, version 2, from its `doc/udp_format.md` and parser)
//! Everything is big endian (network order). One UDP datagram is one packet:
//!
//! | bytes | field | value |
//! |---|---|---|
//! | 1 | version | 2 |
//! | 1 | op code | 0 = DATA (1 ACK and 2 NACK are its TCP transport's; refused here) |
//! | 1 | sequence number | per sender, +1 per packet, wraps at 256 (informational: nobody reorders) |
//! | 2 | count | number of CAN frames that follow |
//!
//! then `count` frames, each:
//!
//! | bytes | field | value |
//! |---|---|---|
//! | 4 | `can_id` | Linux `can_id`: bits 0–28 the id (11 used for a standard frame), bit 31 `CAN_EFF_FLAG` (extended), bit 30 `CAN_RTR_FLAG` (remote), bit 29 `CAN_ERR_FLAG` (error frame) |
//! | 1 | len | data length; bit 7 set = CAN FD frame (then the length is bits 0–6) |
//! | 1 | flags | CAN FD frames only: `canfd_frame.flags` |
//! | len | data | 0–8 bytes (CAN FD: 0–64); absent for a remote frame, whose len is its DLC |
//!
//! A packet must hold exactly its `count` frames: a short packet, a length past its kind's
//! maximum, or bytes left over are refused whole ([`cannelloni::PacketError`]). Datagrams are at
//! most [`cannelloni::MAX_PACKET_LEN`] (1472) bytes. The A1 link uses only classic data frames
//! with 11-bit ids and 8 bytes ([`crate::a1`]); the others are parsed and ignored (counted).
//!
//! # Buses and addresses
//! cannelloni bridges one CAN interface per instance (one UDP port pair each), so each bus is
//! its own link: bus `k` talks to the peer at the first address's port + `k`
//! (`--motors 127.0.0.1:PORT` → bus 0 at PORT, bus 1 at PORT+1) or at the `k`-th address of a
//! list. Against real gateways, run one cannelloni per CAN interface with
//! `-R <this host> -r <UdpBus's local port>`.
//!
//! # The emulator's conventions (not cannelloni's)
//! * Lockstep time: the emulated robot advances one control period per commanded period
//!   ([`serve`]), so over the link it walks the physics of the in-process `SimBus`.
//! * The simulated torso IMU rides along as three extended frames after each period
//!   ([`imu_frames`]). On ADAM the IMU is a VN-100 on a serial port, never on the motor link.
//!
//! # What arrives is judged, never trusted
//! Datagrams from an unexpected sender, packets that do not parse, replies from a motor not
//! asked, replies whose bytes do not decode: each is dropped and counted ([`LinkStats`],
//! [`serve::ServerStats`]), never acted on, and nothing panics on any bytes (property and fuzz
//! tests in `cannelloni`, `drivers/tests/udp_link.rs`).

mod bus;
pub mod cannelloni;
pub mod imu_frames;
pub mod serve;
mod socket;

pub use bus::{LinkStats, UdpBus, UdpLinks, UdpOpenError, LIFECYCLE_TIMEOUT};

/// The peer address of every bus: `addrs` one per bus, or a single address whose port is bus
/// 0's and `port + k` bus `k`'s. `None` if the count fits neither or a port passes 65535.
pub fn bus_addresses(
    addrs: &[std::net::SocketAddr],
    bus_count: usize,
) -> Option<Vec<std::net::SocketAddr>> {
    match addrs {
        [one] => (0..bus_count)
            .map(|k| {
                let port = u16::try_from(usize::from(one.port()) + k).ok()?;
                Some(std::net::SocketAddr::new(one.ip(), port))
            })
            .collect(),
        many if many.len() == bus_count => Some(many.to_vec()),
        _ => None,
    }
}
