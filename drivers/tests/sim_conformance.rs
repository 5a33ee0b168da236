//! The `MotorBus` conformance suite against `SimBus`: four motors on two buses (ADAM's
//! planar hip and knee pitch motors, one leg per bus), each joint loaded with 3 N·m.
#![allow(clippy::unwrap_used)]

use core::time::Duration;
use drivers::a1::{Command, Frame, MotorId, Reply};
use drivers::bus::{BusWrapper, MotorBus, MotorSpec};
use drivers::conformance::{Harness, HoldCheck};
use drivers::sim::bus::{SimBus, SimConfig};
use drivers::sim::firmware::{A1Model, SimMotor};
use drivers::sim::plant::{InertiaDampingPlant, RigidJoint};
use drivers::sim::wire::{Direction, WireTap};

const LOAD_NM: f64 = 3.0;

struct SimHarness {
    tap: WireTap,
}

fn spec(bus: usize, id: u8) -> MotorSpec {
    MotorSpec {
        bus,
        id: MotorId::new(id).unwrap(),
    }
}

impl Harness for SimHarness {
    type Bus = SimBus<InertiaDampingPlant>;

    fn new_bus(&mut self) -> Self::Bus {
        let motors = self
            .motors()
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
        self.tap.lock().unwrap().clear();
        bus.set_tap(Some(self.tap.clone()));
        bus
    }

    fn motors(&self) -> Vec<MotorSpec> {
        vec![spec(0, 1), spec(0, 2), spec(1, 3), spec(1, 4)]
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

fn harness() -> SimHarness {
    SimHarness {
        tap: WireTap::default(),
    }
}

drivers::motor_bus_conformance!(sim_bus, harness);

#[test]
fn run_all_reports_no_failure() {
    assert_eq!(drivers::conformance::run_all(&mut harness()), vec![]);
}

/// A bus wrapping a `SimBus` through [`BusWrapper`] (as the runtime's fault injector does),
/// counting its exchanges.
struct Counting<B> {
    bus: B,
    exchanges: usize,
}

impl<B: MotorBus> BusWrapper for Counting<B> {
    type Inner = B;
    fn inner(&self) -> &B {
        &self.bus
    }
    fn inner_mut(&mut self) -> &mut B {
        &mut self.bus
    }
    fn before_exchange(&mut self) {
        self.exchanges += 1;
    }
}

/// [`SimHarness`] with each bus wrapped in [`Counting`].
struct WrappedHarness(SimHarness);

impl Harness for WrappedHarness {
    type Bus = Counting<SimBus<InertiaDampingPlant>>;
    fn new_bus(&mut self) -> Self::Bus {
        Counting {
            bus: self.0.new_bus(),
            exchanges: 0,
        }
    }
    fn motors(&self) -> Vec<MotorSpec> {
        self.0.motors()
    }
    fn absent_motor(&self) -> MotorSpec {
        self.0.absent_motor()
    }
    fn take_sent_frames(&mut self) -> Vec<Frame> {
        self.0.take_sent_frames()
    }
    fn budget(&self) -> Duration {
        self.0.budget()
    }
    fn hold(&self) -> HoldCheck {
        self.0.hold()
    }
}

#[test]
fn a_bus_wrapper_forwards_every_method_and_passes_the_suite() {
    assert_eq!(
        drivers::conformance::run_all(&mut WrappedHarness(harness())),
        vec![]
    );
    let mut h = WrappedHarness(harness());
    let mut bus = h.new_bus();
    bus.configure(&h.motors()).unwrap();
    bus.activate().unwrap();
    assert_eq!(bus.frames(), bus.bus.frames());
    let commands = [Command::damping(h.motors()[0].id, 1.0)];
    let mut replies = [Reply::zeroed(commands[0].motor)];
    bus.exchange(&commands, &mut replies, h.budget()).unwrap();
    assert_eq!(bus.exchanges, 1);
    assert_eq!(bus.state(), bus.bus.state());
}
