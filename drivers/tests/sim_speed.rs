//! Speed of the simulated robot behind `SimBus` (prints, never asserts wall time):
//! simulated seconds per wall second, standing and marching in place, 10 kHz firmware and
//! plant, 1 kHz control. Run: `cargo test -p drivers --release --test sim_speed -- --nocapture`.
#![allow(clippy::unwrap_used)]

use core::time::Duration;
use drivers::a1::{Command, Reply};
use drivers::bus::MotorBus;
use drivers::sim::{LegJoint, RobotSim, RobotSimConfig};
use drivers::sim_bus::{A1Model, JointPlant, SimBus, SimConfig};
use model::Side;
use std::time::Instant;

fn run(label: &str, march: bool) {
    let robot = model::design::generate_model(&model::design::DesignLengths::ADAM)
        .unwrap()
        .0;
    let sim = RobotSim::new(&robot, RobotSimConfig::default()).unwrap();
    let target: Vec<f64> = (0..sim.joint_count())
        .map(|j| sim.position_rad(j))
        .collect();
    let ff = sim.static_torques_nm().unwrap();
    let knees = [Side::Left, Side::Right].map(|s| sim.joint_index(s, LegJoint::Knee));
    let motors = sim.leg_motors(0, 1);
    let config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 2,
        motors: motors.clone(),
        model: A1Model::default(),
        seed: 3,
    };
    let mut bus = SimBus::new(config, sim).unwrap();
    let specs: Vec<_> = motors.iter().map(|m| m.spec).collect();
    bus.configure(&specs).unwrap();
    bus.activate().unwrap();
    let mut replies: Vec<Reply> = motors.iter().map(|m| Reply::zeroed(m.spec.id)).collect();
    let mut commands: Vec<Command> = Vec::with_capacity(4);
    let ticks = 2000;
    let start = Instant::now();
    for k in 0..ticks {
        commands.clear();
        // Marching: every 0.25 s flex one knee by 0.35 rad, alternating.
        let lifted = (k / 250) % 2;
        for m in &motors {
            let mut q = target[m.joint];
            if march && (k / 250) % 4 != 0 && m.joint == knees[lifted] {
                q += 0.35;
            }
            commands.push(Command::pd(m.spec.id, q, 0.0, 300.0, 4.0, ff[m.joint]));
        }
        bus.exchange(&commands, &mut replies, Duration::from_millis(1))
            .unwrap();
    }
    let wall = start.elapsed().as_secs_f64();
    let simulated = bus.time_s();
    let plant = bus.plant();
    println!(
        "{label}: {simulated:.1} s simulated in {wall:.3} s wall = {:.0}× real time \
         ({} events, fallen: {:?}, max penetration {:.1e} m)",
        simulated / wall,
        plant.events().len(),
        plant.fallen(),
        plant.max_penetration_m()
    );
}

#[test]
fn real_time_factor() {
    run("standing", false);
    run("marching in place", true);
}
