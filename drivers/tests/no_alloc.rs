//! `MotorBus::exchange` on `SimBus` allocates nothing: a counting global allocator sees
//! zero allocations over many cycles once the bus is active. Only allocations made on
//! the test's own thread count (the test harness allocates on its threads meanwhile).
#![allow(unsafe_code, clippy::unwrap_used)] // the counting allocator must implement GlobalAlloc

use core::time::Duration;
use drivers::a1::{Command, MotorId, Reply};
use drivers::bus::{MotorBus, MotorSpec};
use drivers::sim_bus::{A1Model, InertiaDampingPlant, RigidJoint, SimBus, SimConfig, SimMotor};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

// SAFETY: forwards to the system allocator unchanged; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.try_with(Cell::get).unwrap_or(false) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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
    COUNTING.with(|c| c.set(true));
    for _ in 0..500 {
        bus.exchange(&commands, &mut replies, Duration::from_millis(1))
            .unwrap();
    }
    COUNTING.with(|c| c.set(false));
    let during = ALLOCATIONS.load(Ordering::Relaxed);
    assert_eq!(during, 0, "{during} allocations in 500 exchanges");
}
