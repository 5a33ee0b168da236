//! The `MotorBus` conformance suite against `UdpBus`: the same four motors on two buses as
//! `sim_conformance.rs`, behind a peer thread that serves `SimBus`'s firmware over
//! CAN-over-UDP (`drivers::udp::serve::MotorServer`, what `adam emulate motors` runs), one
//! loopback link per bus.
#![allow(clippy::unwrap_used)]

use core::time::Duration;
use drivers::a1::{Frame, MotorId};
use drivers::bus::MotorSpec;
use drivers::conformance::{Harness, HoldCheck};
use drivers::sim::bus::{SimBus, SimConfig};
use drivers::sim::firmware::{A1Model, SimMotor};
use drivers::sim::plant::{InertiaDampingPlant, RigidJoint};
use drivers::sim::wire::{Direction, WireTap};
use drivers::udp::serve::MotorServer;
use drivers::udp::UdpBus;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

const LOAD_NM: f64 = 3.0;
/// The peer is a thread on a shared machine: wait for its replies longer than the 1 ms period.
const REPLY_TIMEOUT: Duration = Duration::from_millis(200);

fn spec(bus: usize, id: u8) -> MotorSpec {
    MotorSpec {
        bus,
        id: MotorId::new(id).unwrap(),
    }
}

fn motors() -> Vec<MotorSpec> {
    vec![spec(0, 1), spec(0, 2), spec(1, 3), spec(1, 4)]
}

/// The simulated motors of `sim_conformance.rs`, recorded on `tap`.
fn sim(tap: &WireTap) -> SimBus<InertiaDampingPlant> {
    let motors = motors()
        .into_iter()
        .enumerate()
        .map(|(joint, spec)| SimMotor { spec, joint })
        .collect();
    let config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 2,
        motors,
        model: A1Model::default(),
        seed: 42,
    };
    let joint = RigidJoint {
        inertia_kg_m2: 0.05,
        damping_nm_s_per_rad: 0.05,
        load_torque_nm: LOAD_NM,
    };
    let plant = InertiaDampingPlant::new(vec![joint; 4]).unwrap();
    let mut bus = SimBus::new(config, plant).unwrap();
    bus.set_tap(Some(tap.clone()));
    bus
}

/// A server thread; stopped and joined on drop.
pub struct Peer {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    addrs: Vec<std::net::SocketAddr>,
}

impl Peer {
    fn start(tap: &WireTap) -> Self {
        let any: std::net::SocketAddr = "127.0.0.1:0".parse().unwrap();
        let sockets = (0..2)
            .map(|_| std::net::UdpSocket::bind(any).unwrap())
            .collect::<Vec<_>>();
        let mut server = MotorServer::new(sim(tap), sockets).unwrap();
        let addrs = (0..2).map(|b| server.local_addr(b).unwrap()).collect();
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::spawn(move || {
            while !flag.load(Ordering::Acquire) {
                server.poll(Duration::from_micros(20)).unwrap();
            }
        });
        Self {
            stop,
            thread: Some(thread),
            addrs,
        }
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

struct UdpHarness {
    tap: WireTap,
    peer: Option<Peer>,
}

impl Harness for UdpHarness {
    type Bus = UdpBus;

    fn new_bus(&mut self) -> UdpBus {
        self.peer = None;
        self.tap.lock().unwrap().clear();
        let peer = Peer::start(&self.tap);
        let mut bus = UdpBus::open(&peer.addrs).unwrap();
        bus.set_reply_timeout(Some(REPLY_TIMEOUT));
        self.peer = Some(peer);
        bus
    }

    fn motors(&self) -> Vec<MotorSpec> {
        motors()
    }

    fn absent_motor(&self) -> MotorSpec {
        spec(0, 9)
    }

    fn take_sent_frames(&mut self) -> Vec<Frame> {
        let mut log = self.tap.lock().unwrap();
        let frames = log
            .iter()
            .filter(|e| e.direction == Direction::ToMotor)
            .map(|e| e.frame)
            .collect();
        log.clear();
        frames
    }

    fn budget(&self) -> Duration {
        Duration::from_millis(1)
    }

    fn hold(&self) -> HoldCheck {
        HoldCheck {
            kp_nm_per_rad: 60.0,
            kd_nm_s_per_rad: 1.5,
            max_load_nm: LOAD_NM,
            cycles: 1000,
        }
    }
}

fn harness() -> UdpHarness {
    UdpHarness {
        tap: WireTap::default(),
        peer: None,
    }
}

drivers::motor_bus_conformance!(udp_bus, harness);
