//! `drivers::sim`: the simulated hardware, one room per concern.
//!
//! | module | what |
//! |---|---|
//! | [`bus`] | [`bus::SimBus`], a `MotorBus` over simulated motors: frames in, replies out, the exact bus time of every frame and the deadline |
//! | [`firmware`] | the A1 motor firmware model ([`firmware::A1Model`]): encoder, PD at 10 kHz, torque–speed envelope, heat, lifecycle frames |
//! | [`wire`] | the simulated CAN wire: seeded loss, corruption and delay of frames, their counts, a frame recorder |
//! | [`plant`] | the [`plant::JointPlant`] trait the firmware drives, and independent rigid joints ([`plant::InertiaDampingPlant`]) |
//! | [`robot`] | the rigid-body plant [`robot::RobotSim`]: the planar ADAM on a treadmill (optional boom), contact, impacts, falls, pushes, belt steps, IMU |
//!
//! The timing of CAN frames themselves (bits, stuffing, rates a bus can carry) is [`crate::timing`],
//! shared with the real bus's checks.

pub mod bus;
pub mod firmware;
pub mod plant;
pub mod robot;
pub mod wire;
