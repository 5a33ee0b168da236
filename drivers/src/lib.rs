//! # drivers: A1 motors over CAN, the IMU, and the simulated ADAM
//!
//! Stands on [`model`]. Work in progress: the sans-IO A1-over-CAN codec (`drivers::a1`),
//! the `MotorBus` trait with its SocketCAN and simulated backends, and the treadmill
//! simulator (`drivers::sim`) arrive with the "Drivers" issue. Nothing here is usable yet.
