//! `MotorBus::exchange` on `SimBus` allocates nothing, over a simple plant and over the
//! simulated robot standing and stepping: a counting global allocator sees zero allocations
//! over many cycles once the bus is active. Only allocations made on the test's own thread
//! count (the test harness allocates on its threads meanwhile).
#![allow(unsafe_code, clippy::unwrap_used)] // the counting allocator must implement GlobalAlloc

mod common;

use core::time::Duration;
use drivers::a1::{Command, MotorId, Reply};
use drivers::bus::{MotorBus, MotorSpec};
use drivers::sim::bus::{SimBus, SimConfig};
use drivers::sim::firmware::{A1Model, SimMotor};
use drivers::sim::plant::{InertiaDampingPlant, RigidJoint};
use drivers::sim::robot::{RobotSimConfig, SimEvent};

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

#[global_allocator]
static GLOBAL: counting_alloc::Counting = counting_alloc::Counting;

#[test]
fn exchange_allocates_nothing() {
    let specs: Vec<_> = (0..4)
        .map(|j| MotorSpec {
            bus: j / 2,
            id: MotorId::new(j as u8 + 1).unwrap(),
        })
        .collect();
    let config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 2,
        motors: specs
            .iter()
            .enumerate()
            .map(|(joint, &spec)| SimMotor { spec, joint })
            .collect(),
        model: A1Model::default(),
        seed: 1,
    };
    let joint = RigidJoint {
        inertia_kg_m2: 0.05,
        damping_nm_s_per_rad: 0.05,
        load_torque_nm: 2.0,
    };
    let plant = InertiaDampingPlant::new(vec![joint; 4]).unwrap();
    let mut bus = SimBus::new(config, plant).unwrap();
    bus.configure(&specs).unwrap();
    bus.activate().unwrap();
    let commands: Vec<_> = specs
        .iter()
        .map(|s| Command::pd(s.id, 0.1, 0.0, 60.0, 1.5, 0.0))
        .collect();
    let mut replies: Vec<_> = specs.iter().map(|s| Reply::zeroed(s.id)).collect();
    counting_alloc::start();
    for _ in 0..500 {
        bus.exchange(&commands, &mut replies, Duration::from_millis(1))
            .unwrap();
    }
    let during = counting_alloc::stop();
    assert_eq!(during, 0, "{during} allocations in 500 exchanges");
}

#[test]
fn exchange_with_the_simulated_robot_allocates_nothing() {
    let common::StandingRig {
        mut bus,
        motors,
        target_rad: target,
        feedforward_nm: ff,
        knees,
        mut replies,
    } = common::standing_rig(RobotSimConfig::default(), 1);
    let knee = knees[0];
    let mut commands = Vec::with_capacity(motors.len());
    counting_alloc::start();
    // Stand for 0.25 s, then lift the left foot for 0.15 s and put it down: held and fresh
    // dynamics, a liftoff and a touchdown.
    for k in 0..600 {
        commands.clear();
        for m in &motors {
            let lift = if (250..400).contains(&k) && m.joint == knee {
                0.35
            } else {
                0.0
            };
            commands.push(Command::pd(
                m.spec.id,
                target[m.joint] + lift,
                0.0,
                300.0,
                4.0,
                ff[m.joint],
            ));
        }
        bus.exchange(&commands, &mut replies, Duration::from_millis(1))
            .unwrap();
    }
    let during = counting_alloc::stop();
    let events = bus.plant().events();
    assert!(
        events.iter().any(|e| matches!(e, SimEvent::Liftoff { .. })),
        "{events:?}"
    );
    assert!(
        events.iter().any(|e| matches!(e, SimEvent::Touchdown(_))),
        "{events:?}"
    );
    assert_eq!(during, 0, "{during} allocations in 600 exchanges");
}
