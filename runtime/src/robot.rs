//! The runtime on the real ADAM: the leg (and held) motors over SocketCAN, one interface per
//! bus of the runtime config.
//!
//! Today this opens the CAN interfaces and stops there: the torso IMU has no driver yet, and
//! the loop refuses to walk blind ([`RuntimeError::NoImuDriver`]). On a machine without the
//! interfaces the error is the SocketCAN one, naming the interface.

use crate::{Result, RuntimeError, Setup};
use drivers::socketcan_bus::SocketCanBus;

/// The interface names of the config's buses: `can0`, `can1`, … (`loop.bus_count` of them).
pub fn default_interfaces(setup: &Setup) -> Vec<String> {
    (0..setup.config.loop_.bus_count)
        .map(|k| format!("can{k}"))
        .collect()
}

/// Open the robot's CAN buses (bus index = position in `interfaces`).
pub fn open_can(setup: &Setup, interfaces: &[String]) -> Result<SocketCanBus> {
    if interfaces.len() != setup.config.loop_.bus_count {
        return Err(RuntimeError::InvalidField {
            origin: "CAN interfaces".into(),
            field: "loop.bus_count".into(),
            value: setup.config.loop_.bus_count.to_string(),
            reason: format!(
                "the config has that many buses, {} interfaces were given ({})",
                interfaces.len(),
                interfaces.join(",")
            ),
        });
    }
    let names: Vec<&str> = interfaces.iter().map(String::as_str).collect();
    Ok(SocketCanBus::open(&names)?)
}

/// Walk on the robot over CAN for `duration_s`: opens the buses, then needs the torso IMU.
pub fn walk(setup: &Setup, interfaces: &[String], duration_s: f64) -> Result<crate::RunSummary> {
    let _bus = open_can(setup, interfaces)?;
    let _ = duration_s;
    Err(RuntimeError::NoImuDriver)
}
