//! `UdpBus` against a hostile peer: garbage, a stranger's datagrams, replies with the wrong
//! motor id or bytes that do not decode. Each is dropped and counted, never used, never a
//! panic; the frames used are the ones recorded.
#![allow(clippy::unwrap_used)]

use core::time::Duration;
use drivers::a1::{self, Command, MotorId, Reply};
use drivers::bus::{BusError, MotorBus, MotorSpec};
use drivers::frame_log::FrameDirection;
use drivers::udp::cannelloni::{CanFrame, Packet, PacketWriter, MAX_PACKET_LEN};
use drivers::udp::UdpBus;
use std::net::{SocketAddr, UdpSocket};

fn id(n: u8) -> MotorId {
    MotorId::new(n).unwrap()
}

fn packet(frames: &[CanFrame]) -> Vec<u8> {
    let mut buf = vec![0; MAX_PACKET_LEN];
    let mut w = PacketWriter::new(&mut buf, 0).unwrap();
    for f in frames {
        w.push(&f.as_ref()).unwrap();
    }
    let n = w.finish();
    buf.truncate(n);
    buf
}

fn reply_frame(motor: u8, enabled: bool) -> CanFrame {
    let reply = Reply {
        enabled,
        q_rad: 0.25,
        ..Reply::zeroed(id(motor))
    };
    let f = a1::encode_reply(&reply).unwrap().frame;
    CanFrame::standard(f.id, &f.data).unwrap()
}

/// A peer that answers the k-th packet it receives with `script(k)`: datagrams to send, each
/// from the peer (`false`) or from a stranger's socket (`true`).
fn spawn_peer(
    script: impl Fn(usize) -> Vec<(bool, Vec<u8>)> + Send + 'static,
    packets: usize,
) -> (SocketAddr, std::thread::JoinHandle<()>) {
    let any: SocketAddr = "127.0.0.1:0".parse().unwrap();
    let peer = UdpSocket::bind(any).unwrap();
    let stranger = UdpSocket::bind(any).unwrap();
    let addr = peer.local_addr().unwrap();
    let handle = std::thread::spawn(move || {
        let mut buf = vec![0; 2048];
        for k in 0..packets {
            let (n, host) = peer.recv_from(&mut buf).unwrap();
            assert!(
                Packet::parse(&buf[..n]).is_ok(),
                "the bus sent a bad packet"
            );
            for (from_stranger, bytes) in script(k) {
                let socket = if from_stranger { &stranger } else { &peer };
                socket.send_to(&bytes, host).unwrap();
            }
        }
    });
    (addr, handle)
}

#[test]
fn hostile_datagrams_are_counted_and_never_used() {
    let (addr, peer) = spawn_peer(
        |k| match k {
            // enable, and the disable of `deactivate`
            0 | 3 => vec![(false, packet(&[reply_frame(1, k == 0)]))],
            1 => {
                let mut bad = reply_frame(1, true);
                bad.data[7] |= 0x03; // reserved mode in the reply: does not decode
                vec![
                    (false, vec![0xFF; 40]),                  // garbage
                    (false, vec![2, 0, 0, 0, 1, 0, 0]),       // truncated packet
                    (true, packet(&[reply_frame(1, true)])),  // a stranger's reply
                    (false, packet(&[reply_frame(7, true)])), // wrong motor id
                    (false, packet(&[bad])),                  // undecodable reply
                    (false, packet(&[reply_frame(1, true)])), // the real one
                ]
            }
            // Only a wrong id: motor 1 misses.
            _ => vec![(false, packet(&[reply_frame(7, true)]))],
        },
        4,
    );
    let mut bus = UdpBus::open(&[addr]).unwrap();
    bus.set_reply_timeout(Some(Duration::from_millis(300)));
    bus.configure(&[MotorSpec { bus: 0, id: id(1) }]).unwrap();
    bus.activate().unwrap();
    let commands = [Command::pd(id(1), 0.1, 0.0, 20.0, 0.5, 0.0)];
    let mut replies = [Reply::zeroed(id(9))];
    bus.exchange(&commands, &mut replies, Duration::from_millis(1))
        .unwrap();
    assert_eq!(replies[0].motor, id(1));
    assert!((replies[0].q_rad - 0.25).abs() < 1e-3);
    // The frames used: the command out, the one good reply in.
    let frames = bus.frames();
    assert_eq!(frames.len(), 2, "{frames:?}");
    assert_eq!(frames[0].direction, FrameDirection::Tx);
    assert_eq!(frames[0].can_id, id(1).command_id());
    assert_eq!(frames[1].direction, FrameDirection::Rx);
    assert_eq!(frames[1].can_id, id(1).reply_id());
    // Late datagrams of this exchange may still be in flight; the counts settle below.
    let second = bus.exchange(&commands, &mut replies, Duration::from_millis(1));
    assert_eq!(
        second,
        Err(BusError::MissingReply {
            motor: id(1),
            bus: 0
        })
    );
    bus.deactivate().unwrap();
    peer.join().unwrap();
    let s = bus.stats();
    assert_eq!(s.foreign_sender, 1, "{s:?}");
    assert_eq!(s.malformed, 2, "{s:?}");
    assert_eq!(s.unexpected_replies, 2, "{s:?}");
    assert_eq!(s.bad_replies, 1, "{s:?}");
}

#[test]
fn random_bytes_from_the_peer_never_panic_and_never_reply() {
    use rand::{Rng, SeedableRng};
    let (addr, peer) = spawn_peer(
        |k| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(k as u64);
            let mut out = Vec::new();
            for _ in 0..50 {
                let len = rng.random_range(0..64);
                let mut bytes: Vec<u8> = (0..len).map(|_| rng.random()).collect();
                // Half of them look like packets of the right version and op code.
                if len >= 2 && rng.random() {
                    bytes[0] = 2;
                    bytes[1] = 0;
                }
                out.push((false, bytes));
            }
            out
        },
        1,
    );
    let mut bus = UdpBus::open(&[addr]).unwrap();
    bus.set_reply_timeout(Some(Duration::from_millis(200)));
    bus.configure(&[MotorSpec { bus: 0, id: id(1) }]).unwrap();
    assert_eq!(
        bus.activate(),
        Err(BusError::MissingReply {
            motor: id(1),
            bus: 0
        })
    );
    peer.join().unwrap();
    let s = bus.stats();
    // Every datagram was judged: malformed, or a well-formed packet whose frames were not a
    // reply of motor 1 (an enabled reply of motor 1 from random bytes is all but impossible).
    assert!(s.malformed + s.packets_received >= 40, "{s:?}");
}

#[test]
fn opening_names_the_peer_and_bus_and_addresses_follow_the_port_rule() {
    assert!(matches!(
        UdpBus::open(&[]),
        Err(drivers::udp::UdpOpenError::NoPeer)
    ));
    let a: SocketAddr = "127.0.0.1:9000".parse().unwrap();
    let b: SocketAddr = "10.0.0.2:20000".parse().unwrap();
    let ports: Vec<u16> = drivers::udp::bus_addresses(&[a], 3)
        .unwrap()
        .iter()
        .map(SocketAddr::port)
        .collect();
    assert_eq!(ports, [9000, 9001, 9002]);
    assert_eq!(drivers::udp::bus_addresses(&[a, b], 2).unwrap(), vec![a, b]);
    assert!(drivers::udp::bus_addresses(&[a, b], 3).is_none());
    let top: SocketAddr = "127.0.0.1:65535".parse().unwrap();
    assert!(drivers::udp::bus_addresses(&[top], 2).is_none());
    // A fixed local port (what a gateway's cannelloni sends to): bus k at its port + k.
    // (A port the OS just freed, and the one after it; another try if that one is taken.)
    let (bus, local) = (0..20)
        .find_map(|_| {
            let free = UdpSocket::bind("127.0.0.1:0")
                .unwrap()
                .local_addr()
                .unwrap();
            UdpBus::open_at(&[a, a], Some(free)).ok().map(|b| (b, free))
        })
        .unwrap();
    assert_eq!(bus.local_addr(0).unwrap(), local);
    assert_eq!(bus.local_addr(1).unwrap().port(), local.port() + 1);
    let taken = UdpBus::open_at(&[a], Some(local))
        .err()
        .unwrap()
        .to_string();
    assert!(
        taken.contains("bus 0") && taken.contains("127.0.0.1:9000"),
        "{taken}"
    );
}

/// The emulator's side: a stranger's datagram (here a *disable* to every motor) is dropped and
/// counted, never acted on (the host's motors stay enabled), and so is a stranger's garbage.
#[test]
fn the_server_ignores_strangers_and_garbage() {
    use drivers::sim::bus::{SimBus, SimConfig};
    use drivers::sim::firmware::{A1Model, SimMotor};
    use drivers::sim::plant::{InertiaDampingPlant, RigidJoint};
    use drivers::udp::serve::MotorServer;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    let spec = MotorSpec { bus: 0, id: id(1) };
    let config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 1,
        motors: vec![SimMotor { spec, joint: 0 }],
        model: A1Model::default(),
        seed: 1,
    };
    let joint = RigidJoint {
        inertia_kg_m2: 0.05,
        damping_nm_s_per_rad: 0.05,
        load_torque_nm: 0.0,
    };
    let sim = SimBus::new(config, InertiaDampingPlant::new(vec![joint]).unwrap()).unwrap();
    let any: SocketAddr = "127.0.0.1:0".parse().unwrap();
    let mut server = MotorServer::new(sim, vec![UdpSocket::bind(any).unwrap()]).unwrap();
    let addr = server.local_addr(0).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let thread = std::thread::spawn(move || {
        while !flag.load(Ordering::Acquire) {
            server.poll(Duration::from_micros(20)).unwrap();
        }
        server.stats()
    });
    let mut bus = UdpBus::open(&[addr]).unwrap();
    bus.set_reply_timeout(Some(Duration::from_millis(300)));
    bus.configure(&[spec]).unwrap();
    bus.activate().unwrap();
    let stranger = UdpSocket::bind(any).unwrap();
    let disable = a1::encode_special(id(1), a1::Special::Disable);
    stranger
        .send_to(
            &packet(&[CanFrame::standard(disable.id, &disable.data).unwrap()]),
            addr,
        )
        .unwrap();
    stranger.send_to(&[0xAB; 7], addr).unwrap();
    let host_socket_addr = bus.local_addr(0).unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let commands = [Command::damping(id(1), 1.0)];
    let mut replies = [Reply::zeroed(id(9))];
    for _ in 0..5 {
        bus.exchange(&commands, &mut replies, Duration::from_millis(1))
            .unwrap();
        assert!(replies[0].enabled, "a stranger's disable was obeyed");
    }
    bus.deactivate().unwrap();
    stop.store(true, Ordering::Release);
    let stats = thread.join().unwrap();
    assert_eq!(
        stats.foreign_sender, 2,
        "{stats:?} (host {host_socket_addr})"
    );
    assert_eq!(stats.malformed, 0, "{stats:?}");
}
