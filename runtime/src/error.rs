//! The runtime's error type (start-up and I/O only; the tick never returns an error).

use std::path::PathBuf;
use thiserror::Error;

/// Everything that can go wrong setting up or running the loop.
#[derive(Debug, Error)]
pub enum RuntimeError {
    /// A file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        error: std::io::Error,
    },
    /// A config file is not valid TOML of the expected shape.
    #[error("{origin}: {message}")]
    Parse {
        /// Where the text came from.
        origin: String,
        /// Parser message.
        message: String,
    },
    /// A config field has a value the runtime refuses.
    #[error("{origin}: field `{field}` = {value}: {reason}")]
    InvalidField {
        /// Where the config came from.
        origin: String,
        /// Dotted field path.
        field: String,
        /// The offending value.
        value: String,
        /// Why it is refused.
        reason: String,
    },
    /// A belt speed outside the treadmill's configured range.
    #[error(
        "{what} = {speed_mps} m/s is outside the treadmill's belt speed range [{}, {}] m/s \
         (`[treadmill] belt_speed_range_mps` of the runtime config)",
        range_mps[0],
        range_mps[1]
    )]
    BeltSpeed {
        /// Who asked for it: `--belt`, a gait file's speed, a fault profile's belt step.
        what: String,
        /// The speed asked for, m/s.
        speed_mps: f64,
        /// The treadmill's range, m/s.
        range_mps: [f64; 2],
    },
    /// The gait does not fit the robot model or the controller.
    #[error("gait does not fit: {reason}")]
    Gait {
        /// What does not fit.
        reason: String,
    },
    /// The robot model failed.
    #[error(transparent)]
    Model(#[from] model::ModelError),
    /// The buses cannot carry the configured loop rate.
    #[error(transparent)]
    Timing(#[from] drivers::timing::TimingError),
    /// The motor bus failed during start-up or shutdown.
    #[error("motor bus: {0}")]
    Bus(#[from] drivers::bus::BusError),
    /// A CAN interface of the robot could not be opened.
    #[error(transparent)]
    CanOpen(#[from] drivers::socketcan_bus::OpenError),
    /// The pre-flight checks refused to let the gains come on (`runtime::bringup`).
    #[error("pre-flight refused, no gain was turned on:{refusals}")]
    Preflight {
        /// Every refusal, one per line, each naming the motor (joint, bus, id) or the IMU and
        /// the value.
        refusals: String,
    },
    /// `adam calibrate` measured something it cannot turn into a calibration.
    #[error("calibration failed:{problems}")]
    Calibration {
        /// Every problem, one per line, each naming the joint, motor and value.
        problems: String,
    },
    /// The torso IMU could not be opened or configured.
    #[error(transparent)]
    Imu(#[from] drivers::vn100::Vn100Error),
    /// Parts of the robot are missing: each named once (CAN interfaces, the IMU's serial port).
    #[error("cannot run on the robot: {}", problems.join("; "))]
    Robot {
        /// What is missing, one entry each.
        problems: Vec<String>,
    },
    /// A log was written with another channel layout than this build reads.
    #[error("MCAP log {path}: channel `{channel}` has log schema version {found}, this build reads version {expected}: open it with the adam version that wrote it")]
    LogSchemaVersion {
        /// The log.
        path: PathBuf,
        /// The channel topic.
        channel: String,
        /// The version found (`none` when the channel carries none).
        found: String,
        /// The version this build reads.
        expected: u32,
    },
    /// The MCAP writer failed.
    #[error("MCAP log {path}: {message}")]
    Log {
        /// Log file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// Zero-copy telemetry could not be set up.
    #[error("telemetry service `{service}`: {message}")]
    Telemetry {
        /// Service name.
        service: String,
        /// What failed.
        message: String,
    },
    /// The live view's server could not start (a port in use, an address not available).
    #[error("live view: cannot listen on {addr}: {message}")]
    Live {
        /// The address asked for.
        addr: std::net::SocketAddr,
        /// What the OS said, and a hint.
        message: String,
    },
    /// A thread of the runtime panicked or could not be spawned.
    #[error("thread `{name}`: {message}")]
    Thread {
        /// Thread name.
        name: &'static str,
        /// What happened.
        message: String,
    },
}

/// Result alias of the runtime.
pub type Result<T> = core::result::Result<T, RuntimeError>;
