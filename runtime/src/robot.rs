//! The runtime on the real ADAM: the leg (and held) motors over SocketCAN, one interface per
//! bus of the runtime config, and the torso IMU, a VectorNav VN-100 on a serial port
//! ([`drivers::vn100`], mounted as the config's `[imu]` says), paired into one
//! [`crate::backend::WithImu`] backend that runs the same controller as the simulator, on the
//! wall clock.
//!
//! [`open`] opens both before anything moves; whatever is missing (a CAN interface, the serial
//! port, no `--imu` at all) is reported in one error that names each.

use crate::backend::WithImu;
use crate::bringup::{run_on_robot, PreflightReport, RobotRun};
use crate::operator::OperatorReceiver;
use crate::{Result, RuntimeError, Setup};
use drivers::socketcan_bus::SocketCanBus;
use drivers::vn100::port::Vn100;

/// The interface names of the config's buses: `can0`, `can1`, … (`loop.bus_count` of them).
pub fn default_interfaces(setup: &Setup) -> Vec<String> {
    (0..setup.config.loop_.bus_count)
        .map(|k| format!("can{k}"))
        .collect()
}

/// Where the torso IMU is: `adam run --imu <driver>:<path>`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ImuSource {
    /// A VectorNav VN-100 on the serial port at `path` (`vn100:/dev/ttyUSB0`).
    Vn100 {
        /// The serial port's path.
        path: String,
    },
}

impl ImuSource {
    /// Parses `vn100:PATH`; `flag` names the option in the error.
    pub fn parse(text: &str, flag: &str) -> Result<Self> {
        match text.split_once(':') {
            Some(("vn100", path)) if !path.is_empty() => Ok(Self::Vn100 {
                path: path.to_string(),
            }),
            _ => Err(RuntimeError::InvalidField {
                origin: "the command line".into(),
                field: flag.to_string(),
                value: format!("`{text}`"),
                reason: "must be <driver>:<serial port>, e.g. vn100:/dev/ttyUSB0 (drivers: vn100)"
                    .into(),
            }),
        }
    }

    /// Opens and configures the IMU with the config's `[imu]` section.
    pub fn open(&self, setup: &Setup) -> Result<Vn100> {
        let options = setup.config.imu.vn100_options("runtime config")?;
        match self {
            Self::Vn100 { path } => Ok(Vn100::open(path, &options)?),
        }
    }
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

/// Opens the CAN buses and the IMU, both before anything moves; every one missing is named in
/// one [`RuntimeError::Robot`].
pub fn open(
    setup: &Setup,
    interfaces: &[String],
    imu: Option<&ImuSource>,
) -> Result<WithImu<SocketCanBus, Vn100>> {
    let bus = open_can(setup, interfaces);
    let imu = imu.map(|source| source.open(setup));
    match (bus, imu) {
        (Ok(bus), Some(Ok(imu))) => Ok(WithImu { bus, imu }),
        (bus, imu) => {
            let mut problems = Vec::new();
            if let Err(e) = bus {
                problems.push(e.to_string());
            }
            match imu {
                None => problems.push(
                    "no torso IMU given: the loop needs pitch and pitch rate (--imu vn100:/dev/ttyUSB0)"
                        .into(),
                ),
                Some(Err(e)) => problems.push(e.to_string()),
                Some(Ok(_)) => {}
            }
            Err(RuntimeError::Robot { problems })
        }
    }
}

/// Walk on the robot on the buses and IMU [`open`] gave, as [`crate::bringup::run_on_robot`]
/// runs it: first the pre-flight (every motor answers, the IMU is alive and upright, the joints
/// are near the start pose, the buses have room; a refusal names motor, bus and value and no gain
/// comes on), then the loop on the wall clock with every configured motor (held ones too),
/// real-time set-up, telemetry, the log (`run.log_path`), `run.dry_run`, and the operator's
/// commands from `operator` (the robot waits in Idle for Start).
pub fn walk(
    setup: &Setup,
    backend: WithImu<SocketCanBus, Vn100>,
    run: &RobotRun,
    operator: Option<OperatorReceiver>,
) -> Result<(crate::RunSummary, PreflightReport)> {
    let (preflight, summary, _backend) = run_on_robot(setup, backend, run, operator)?;
    Ok((summary, preflight))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn imu_sources_parse_or_name_the_flag() {
        assert_eq!(
            ImuSource::parse("vn100:/dev/ttyUSB0", "--imu").ok(),
            Some(ImuSource::Vn100 {
                path: "/dev/ttyUSB0".into()
            })
        );
        for bad in ["vn100", "vn100:", "bno055:/dev/ttyS0", ""] {
            let e = ImuSource::parse(bad, "--imu")
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            assert!(e.contains("--imu") && e.contains(bad), "{bad}: {e}");
        }
    }

    #[test]
    fn a_machine_without_the_robot_names_every_missing_part_once() {
        let setup = Setup::shipped().expect("shipped setup");
        let source = ImuSource::Vn100 {
            path: "/dev/no-such-imu".into(),
        };
        let e = open(&setup, &default_interfaces(&setup), Some(&source))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("cannot open CAN interface `can0`"), "{e}");
        assert!(e.contains("`/dev/no-such-imu`"), "{e}");
        assert_eq!(e.matches("can0").count(), 1, "{e}");
        let e = open(&setup, &default_interfaces(&setup), None)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("--imu vn100:"), "{e}");
    }
}
