//! `UdpBus::exchange` allocates nothing: a counting global allocator sees zero allocations on
//! the test's thread over 2000 exchanges with a peer thread serving `SimBus`'s firmware (the
//! peer's allocations, on its own thread, do not count), reading `frames()` and the IMU too.
#![allow(unsafe_code, clippy::unwrap_used)] // the counting allocator must implement GlobalAlloc

use core::time::Duration;
use drivers::a1::{Command, MotorId, Reply};
use drivers::bus::{MotorBus, MotorSpec};
use drivers::imu::{Imu, ImuSample};
use drivers::sim::bus::{SimBus, SimConfig};
use drivers::sim::firmware::{A1Model, SimMotor};
use drivers::sim::plant::{InertiaDampingPlant, RigidJoint};
use drivers::udp::serve::MotorServer;
use drivers::udp::UdpBus;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

#[global_allocator]
static GLOBAL: counting_alloc::Counting = counting_alloc::Counting;

#[test]
fn udp_exchange_allocates_nothing() {
    let specs: Vec<MotorSpec> = (1..=4)
        .map(|n| MotorSpec {
            bus: usize::from(n > 2),
            id: MotorId::new(n).unwrap(),
        })
        .collect();
    let motors = specs
        .iter()
        .enumerate()
        .map(|(joint, &spec)| SimMotor { spec, joint })
        .collect();
    let config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 2,
        motors,
        model: A1Model::default(),
        seed: 7,
    };
    let joint = RigidJoint {
        inertia_kg_m2: 0.05,
        damping_nm_s_per_rad: 0.05,
        load_torque_nm: 1.0,
    };
    let sim = SimBus::new(config, InertiaDampingPlant::new(vec![joint; 4]).unwrap()).unwrap();
    let sockets =
        MotorServer::<InertiaDampingPlant>::bind("127.0.0.1:0".parse().unwrap(), 2).unwrap();
    let mut server = MotorServer::new(sim, sockets).unwrap();
    let peers = [server.local_addr(0).unwrap(), server.local_addr(1).unwrap()];
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let peer = std::thread::spawn(move || {
        while !flag.load(Ordering::Acquire) {
            server.poll(Duration::from_micros(20)).unwrap();
        }
        server.stats()
    });
    let mut bus = UdpBus::open(&peers).unwrap();
    bus.set_reply_timeout(Some(Duration::from_millis(200)));
    bus.configure(&specs).unwrap();
    bus.activate().unwrap();
    let commands: Vec<Command> = specs
        .iter()
        .map(|s| Command::pd(s.id, 0.1, 0.0, 30.0, 1.0, 0.0))
        .collect();
    let mut replies: Vec<Reply> = specs.iter().map(|s| Reply::zeroed(s.id)).collect();
    let mut frames_seen = 0;
    let mut sample = ImuSample::default();
    counting_alloc::start();
    for _ in 0..2000 {
        bus.exchange(&commands, &mut replies, Duration::from_millis(1))
            .unwrap();
        frames_seen += bus.frames().len();
        let _ = bus.read(&mut sample);
    }
    let allocations = counting_alloc::stop();
    bus.deactivate().unwrap();
    stop.store(true, Ordering::Release);
    let stats = peer.join().unwrap();
    assert_eq!(allocations, 0, "UdpBus::exchange allocated");
    assert_eq!(frames_seen, 2000 * 8, "a command and a reply per motor");
    assert_eq!(stats.periods, 2000, "one simulated period per exchange");
    assert!(replies
        .iter()
        .all(|r| r.enabled && (r.q_rad - 0.1).abs() < 0.05));
}
