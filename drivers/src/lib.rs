//! # drivers: A1 motors over CAN
//!
//! Work in progress.

pub mod a1;
pub mod bus;
pub mod conformance;
pub mod sim_bus;
pub mod socketcan_bus;
pub mod timing;
