//! # drivers: A1 motors over CAN
//!
//! Work in progress.

pub mod a1;
pub mod timing;
