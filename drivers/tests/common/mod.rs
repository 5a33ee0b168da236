//! The rig the simulator tests share: the standing ADAM (`DesignLengths::ADAM`) behind an
//! active two-bus `SimBus` at 1 kHz control, with its standing pose, the gravity feed-forward of
//! that pose and its knee joints.
#![allow(clippy::unwrap_used, dead_code)]

use core::time::Duration;
use drivers::a1::{Command, Reply};
use drivers::bus::MotorBus;
use drivers::sim::bus::{SimBus, SimConfig};
use drivers::sim::firmware::{A1Model, SimMotor};
use drivers::sim::plant::JointPlant;
use drivers::sim::robot::{LegJoint, RobotSim, RobotSimConfig};
use model::Side;

/// An active bus over the standing robot, and what the tests command it with.
pub struct StandingRig {
    /// The bus (its plant: [`RobotSim`]).
    pub bus: SimBus<RobotSim>,
    /// The four leg motors.
    pub motors: Vec<SimMotor>,
    /// The standing pose by joint, rad.
    pub target_rad: Vec<f64>,
    /// Joint torques that hold the standing pose, N·m.
    pub feedforward_nm: Vec<f64>,
    /// The knee joints (left, right).
    pub knees: [usize; 2],
    /// One zeroed reply per motor.
    pub replies: Vec<Reply>,
}

/// The rig with `config` for the robot and `seed` for the firmware noise.
pub fn standing_rig(config: RobotSimConfig, seed: u64) -> StandingRig {
    let robot = model::design::generate_model(&model::design::DesignLengths::ADAM)
        .unwrap()
        .0;
    let sim = RobotSim::new(&robot, config).unwrap();
    let target_rad: Vec<f64> = (0..sim.joint_count())
        .map(|j| sim.position_rad(j))
        .collect();
    let feedforward_nm = sim.static_torques_nm().unwrap();
    let knees = [Side::Left, Side::Right].map(|s| sim.joint_index(s, LegJoint::Knee));
    let motors = sim.leg_motors(0, 1);
    let bus_config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 2,
        motors: motors.clone(),
        model: A1Model::default(),
        seed,
    };
    let mut bus = SimBus::new(bus_config, sim).unwrap();
    let specs: Vec<_> = motors.iter().map(|m| m.spec).collect();
    bus.configure(&specs).unwrap();
    bus.activate().unwrap();
    let replies = motors.iter().map(|m| Reply::zeroed(m.spec.id)).collect();
    StandingRig {
        bus,
        motors,
        target_rad,
        feedforward_nm,
        knees,
        replies,
    }
}

impl StandingRig {
    /// Control tick `k` (1 kHz) of standing or, with `march`, marching in place: from 0.25 s on,
    /// one knee flexes by 0.35 rad for 0.15 s of every 0.25 s, alternating, both feet down in
    /// between (open loop: without balance control the robot tips over after about 1.7 s).
    /// PD 300 N·m/rad, 4 N·m·s/rad around the standing pose, gravity fed forward. `commands`
    /// is scratch space (cleared, then filled: no allocation once it has the capacity).
    pub fn stand_or_march(&mut self, k: usize, march: bool, commands: &mut Vec<Command>) {
        commands.clear();
        let lifted = (k / 250) % 2;
        for m in &self.motors {
            let mut q = self.target_rad[m.joint];
            if march && k >= 250 && k % 250 < 150 && m.joint == self.knees[lifted] {
                q += 0.35;
            }
            commands.push(Command::pd(
                m.spec.id,
                q,
                0.0,
                300.0,
                4.0,
                self.feedforward_nm[m.joint],
            ));
        }
        self.bus
            .exchange(commands, &mut self.replies, Duration::from_millis(1))
            .unwrap();
    }
}
