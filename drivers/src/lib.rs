//! # drivers: A1 motors over CAN and the VN-100 IMU, for real and simulated
//!
//! The hardware layer of adam-hzd: it turns joint commands into CAN frames for the
//! Unitree A1 actuators of ADAM and replies back into joint states, behind one trait that
//! a real SocketCAN backend and a simulated one both implement.
//!
//! | module | what |
//! |---|---|
//! | [`a1`] | sans-IO A1-over-CAN codec: frame table, ids, fixed-point fields; `a1_can.dbc` |
//! | [`timing`] | CAN bus time of A1 traffic; `validate(rate, motors per bus, bitrate)` |
//! | [`bus`] | the [`bus::MotorBus`] trait: configure → activate → exchange → deactivate, `Drop` = damping; [`bus::BusWrapper`] for a bus that wraps another |
//! | [`socketcan_bus`] | `MotorBus` on Linux SocketCAN, one interface per limb |
//! | [`udp`] | `MotorBus` over CAN-over-UDP links in cannelloni's packet format (sans-IO codec, [`udp::UdpBus`]), and [`udp::serve`]: a `SimBus` served over them (`adam emulate motors`) |
//! | [`frame_log`] | the CAN frames of a bus's last operation (bus, direction, id, data, time), which every `MotorBus` hands to the runtime's log |
//! | [`sim`] | the simulated hardware, a room per concern: |
//! | [`sim::bus`] | [`sim::bus::SimBus`]: `MotorBus` on simulated A1 firmware and a pluggable [`sim::plant::JointPlant`]; frames in, replies out, exact bus time; motor faults (silent, hot, error flags) |
//! | [`sim::firmware`] | the A1 firmware model: encoder, PD at 10 kHz, torque–speed envelope, heat, lifecycle |
//! | [`sim::wire`] | seeded wire faults (loss, corruption, delay), their counts, a frame recorder |
//! | [`sim::plant`] | the `JointPlant` trait and independent rigid joints |
//! | [`sim::robot`] | the rigid-body plant: the planar ADAM on a treadmill (optional boom): point-foot contact, impacts, falls, ground truth; a `JointPlant`; pushes, belt steps, IMU faults |
//! | [`imu`] | the [`imu::Imu`] trait (pitch rate, specific force) the simulator and the runtime share, a seeded noise model and [`imu::ImuFault`] (dropout, spike, frozen) |
//! | [`conformance`] | the checks every `MotorBus` must pass |
//! | [`vn100`] | the VectorNav VN-100 torso IMU: sans-IO binary-frame parser (sync, groups, CRC-16, resync), its configuration commands, the mounting's axes, the driver over a serial port (`serialport`, no libudev; an [`imu::Imu`]) and an emulated VN-100 on a pseudo-terminal |
//!
//! ## Data flow of one control cycle
//! ```text
//! controller ── &[Command] ──▶ MotorBus::exchange ──▶ a1::encode_command ──▶ [u8; 8] frames
//!                                                                              │
//!            SocketCanBus: write to can0..can3 ◀──────────────────────────────┤
//!            SimBus: simulated firmware decodes, runs PD at 10 kHz on the JointPlant
//!                    JointPlant = sim::robot::RobotSim: 4 leg joints (hip, knee ×2) of the planar
//!                    ADAM; D(q), H from `model`; stance/flight/impact at 10 kHz ──▶ ground truth,
//!                    events (touchdown, liftoff, fall), Imu::read (noisy pitch rate, accel)
//!                                                                              │
//! controller ◀── &mut [Reply] ◀── a1::decode_reply ◀── reply frames ◀──────────┘
//! ```
//! Nothing in `exchange` allocates, with the test plants or with [`sim::robot::RobotSim`]
//! (`tests/no_alloc.rs`). The caller sizes the command and reply slices once.
//!
//! With `SimBus<RobotSim>`, configure only the four simulated leg motors
//! ([`sim::robot::RobotSim::leg_motors`]). ADAM's other ten motors (hip yaw/roll, arms) have no joint
//! in the planar model (their mass is lumped into the torso): a `SimBus` has no firmware for
//! them, so naming one in `configure` makes `activate` fail with `MissingReply` for it, exactly
//! like an unplugged motor.
//! Time is an argument (`budget`); only `SocketCanBus` reads the clock.
//!
//! ## The torso IMU: a VectorNav VN-100
//! [`vn100::port::Vn100`] opens the serial port (`serialport`, built without libudev), turns
//! the sensor's ASCII output off and asks for binary output 1 at 800 Hz (`$VNWRG,75,3,1,01,0129`:
//! the common group's time since start-up, yaw/pitch/roll, angular rate, acceleration), then
//! each `Imu::read_at` takes the bytes waiting (never blocking, nothing allocated), parses the
//! frames (sync 0xFA, groups, fields, CRC-16-CCITT; resynchronising after garbage) and maps the
//! newest to the runtime's sample by the mounting: VN x forward, y right, z down; mounted upright
//! with x forward, the robot's pitch rate is −ω_y and its upward specific force −a_z.
//! `adam emulate imu --pty` is the same sensor emulated on a pseudo-terminal.
//!
//! ## Example
//! ```no_run
//! use core::time::Duration;
//! use drivers::a1::{Command, MotorId, Reply};
//! use drivers::bus::{MotorBus, MotorSpec};
//! use drivers::socketcan_bus::SocketCanBus;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // Both legs: hip pitch (id 1) and knee (id 2) on each leg's bus.
//! drivers::timing::validate(1000.0, 2, drivers::timing::DEFAULT_BITRATE_BPS)?;
//! let mut bus = SocketCanBus::open(&["can0", "can1"])?;
//! let ids = [1, 2, 3, 4].map(|n| MotorId::new(n).expect("id < 128"));
//! let specs = [0, 0, 1, 1].iter().zip(ids).map(|(&bus, id)| MotorSpec { bus, id });
//! bus.configure(&specs.collect::<Vec<_>>())?;
//! bus.activate()?;
//! let commands = ids.map(|id| Command::pd(id, 0.0, 0.0, 60.0, 1.5, 0.0));
//! let mut replies = ids.map(Reply::zeroed);
//! for _ in 0..1000 {
//!     bus.exchange(&commands, &mut replies, Duration::from_millis(1))?;
//! }
//! bus.deactivate()?; // every motor to damping (dropping `bus` would do the same)
//! # Ok(())
//! # }
//! ```

pub mod a1;
pub mod bus;
pub mod conformance;
pub mod frame_bus;
pub mod frame_log;
pub mod imu;
mod lifecycle;
mod noise;
pub mod sim;
pub mod socketcan_bus;
pub mod timing;
pub mod udp;
pub mod vn100;
