//! # runtime: real-time execution of an HZD gait on ADAM
//!
//! Stands on [`model`] (kinematics, Bézier outputs, gait files) and [`drivers`] (the
//! [`drivers::bus::MotorBus`] trait, A1 codec, bus timing). It runs a planned gait on the
//! robot or on a simulated backend, at 1 kHz, with a safety monitor, zero-copy telemetry and
//! MCAP logs.
//!
//! | module | what |
//! |---|---|
//! | [`slots`] | the motor slots everyone shares: [`slots::MotorSample`], [`slots::SlotLayout`], slot counts (a leaf) |
//! | [`config`] | `configs/runtime/*.toml`: rate, buses, motors, gains, ramp, safety, held joints, treadmill speed control (`[speed]`), joint calibration (`[calibration]`), pre-flight limits and gains ramp (`[bringup]`), the torso IMU's mounting and rates (`[imu]`) |
//! | [`bringup`] | before the first gain: `adam can scan` ([`bringup::scan`]), `adam calibrate` ([`bringup::calibrate()`]: jig poses → directions and zero offsets), the pre-flight ([`bringup::preflight()`]: each refusal names motor, bus and value); `--dry-run` is [`LoopOptions::dry_run`] |
//! | [`control`] | sans-IO tick: estimator → phase τ → stance switching → y^d(τ) → PD commands; state machine ([`control::Controller`]); double support; treadmill speed control at impacts (a gait library by speed, a step-to-step regulator, the belt-position loop: [`Setup::library`], [`control::Controller::with_library`]) |
//! | [`estimator`] | torso pitch Kalman filter with gyro-bias estimation |
//! | [`safety`] | per-tick checks; a [`safety::Trip`] (small `Copy` enum) sends the controller to Damping |
//! | [`operator`] | operator commands into the loop: SPSC ring + latching e-stop flag, never blocks; belt speed and speed offset (`belt 0.25`, keys `+`/`-`) |
//! | [`backend`] | what the loop runs on: [`backend::Backend`] = [`drivers::bus::MotorBus`] + [`drivers::imu::Imu`]; [`backend::WithImu`] (pair a bus with an IMU) |
//! | [`rt_loop`] | the fixed-rate loop on its own thread, real or simulated [`rt_loop::Clock`] |
//! | [`telemetry`] | the `#[repr(C)]` [`telemetry::sample::StateSample`] over iceoryx2 (feature `iceoryx2`, default); MCAP writer ([`telemetry::log`]) and reader ([`telemetry::log_read`]: `adam logs info`, joint series; [`telemetry::salvage`]: every reader reads past damage; [`telemetry::recover`]: `adam logs recover`); deterministic [`telemetry::replay`] (`adam replay`, fixtures); the `/speed` channel ([`telemetry::speed_log`], [`telemetry::speed_read`]: `adam plot speed`); every CAN frame on `/can` ([`telemetry::frames`]: `adam logs candump`) |
//! | [`live`] | the live view (`adam live`): the Foxglove WebSocket protocol on tokio ([`live::protocol`] sans-IO, [`live::server`]), fed from the loop's iceoryx2 samples in its own process ([`live::source`]) through [`live::feed`] (the log's channels and the robot in 3D, decimated per channel) |
//! | [`tiles`] | gait tiles: stick figures at evenly spaced phases of one logged step (`adam plot tiles`) |
//! | [`robot`] | the real robot: the motors over SocketCAN and the torso IMU, a VN-100 on a serial port ([`drivers::vn100`], `--imu vn100:/dev/ttyUSB0`), one backend for the same loop; whatever is missing is named once |
//! | [`udp`] | the loop over CAN-over-UDP links ([`drivers::udp::UdpBus`]): `adam run --backend udp` against `adam emulate motors` ([`sim::emulate`]) or cannelloni gateways |
//! | [`sim`] | the loop on the simulated ADAM ([`sim::run`]: `SimBus<RobotSim>`, treadmill, walk metrics from ground truth, the soak), fault profiles ([`sim::faults`]: TOML or built-in, seeded schedule) and their injection ([`sim::inject`]); the simulated robot served over UDP to another process ([`sim::emulate`]); the robot hung on the boom for bring-up ([`sim::hung`]) |
//!
//! ## Data flow of one tick
//! ```text
//!  MotorBus::exchange(last commands) ─▶ replies ─┐
//!  Imu::read_at(t) ──────────────────────────────┤         operator ring / e-stop flag / script
//!                                                ▼                      │
//!  Controller::tick(TickInput{t, motors[14], imu, operator, overruns}) ◀┘
//!    ├─ PitchEstimator (θ̂, b̂)      ├─ SafetyMonitor ─ trip ─▶ Damping (latched)
//!    ├─ state machine: Idle → Ramp → Stand → Walk → Stop → Stand …  → Damping
//!    └─ Walk: θ(q) → τ, τ̇ → y^d(τ), ẏ^d → stance switch (τ ≥ 1 ∧ foot down, debounced)
//!  TickOutput{commands[14], status} ─▶ next exchange
//!                                   └▶ StateSample ─▶ iceoryx2 publisher (zero-copy)
//!                                                   └▶ rtrb queue ─▶ writer thread ─▶ MCAP (zstd)
//! ```
//! Only [`rt_loop`] reads a clock; the controller, estimator and safety monitor take time as
//! an argument, allocate nothing and take no lock in the tick.
//!
//! ## Example
//! ```no_run
//! use runtime::backend::{StaticImu, WithImu};
//! use runtime::control::OperatorCommand;
//! use runtime::rt_loop::{LoopOptions, SimulatedClock};
//! use runtime::Setup;
//! # fn backend() -> WithImu<drivers::sim::bus::SimBus<drivers::sim::plant::InertiaDampingPlant>, StaticImu> { unimplemented!() }
//!
//! # fn main() -> runtime::Result<()> {
//! let setup = Setup::load("configs/runtime/adam.toml", "configs/gaits/adam_codesign.json")?;
//! // Any MotorBus + Imu: a SimBus paired with an IMU here; SocketCanBus + IMU on the robot.
//! let backend = backend();
//! let mut options = LoopOptions::simulation(10.0);
//! options.script = vec![(0.1, OperatorCommand::Start), (3.0, OperatorCommand::Walk)];
//! options.log_path = Some("logs/sim.mcap".into());
//! let (summary, _backend) = runtime::run(&setup, backend, SimulatedClock::default(), options, None)?;
//! println!("{:?} after {} ticks, tick p99 {} ns", summary.final_state, summary.ticks,
//!          summary.tick_times.p99_ns);
//! # Ok(())
//! # }
//! ```

pub mod backend;
pub mod bringup;
pub mod config;
pub mod control;
mod error;
pub mod estimator;
pub mod live;
pub mod operator;
pub mod robot;
pub mod rt_loop;
mod rt_sys;
pub mod safety;
pub mod sim;
pub mod slots;
pub mod telemetry;
pub mod tiles;
pub mod udp;

pub use backend::Backend;
pub use drivers::imu::{Imu, ImuSample};
pub use error::{Result, RuntimeError};
pub use rt_loop::{run, LoopOptions, RunSummary};

/// The runtime's default gait (repository-relative): the co-designed ADAM's (`adam codesign`).
pub const DEFAULT_GAIT: &str = "configs/gaits/adam_codesign.json";

/// Everything [`run`] needs besides the backend: config, gait and robot model, loaded and
/// cross-checked.
#[derive(Clone, Debug)]
pub struct Setup {
    /// Runtime config.
    pub config: config::RuntimeConfig,
    /// The gait to walk.
    pub gait: model::gait::GaitFile,
    /// The robot model the gait was planned for.
    pub model: model::PlanarModel,
    /// The URDF text of that model (attached to every log, so a log replays on its own).
    pub urdf_text: String,
    /// Gaits of the same robot sorted by speed, for treadmill speed control (empty: walk
    /// [`Setup::gait`] only). Attached to the log when not empty.
    pub library: Vec<model::gait::GaitFile>,
}

impl Setup {
    /// Loads the runtime config, the gait file and the URDF the gait names (relative to the gait
    /// file's folder), checking the URDF's SHA-256 and the gait against the robot
    /// ([`model::gait::GaitFile::check_against`]: state lengths, Bézier coefficients within the
    /// joint limits); and the gait library of the config's `speed.library` (relative to the
    /// config file's folder), if set ([`Setup::load_library`]).
    pub fn load(
        config_path: impl AsRef<std::path::Path>,
        gait_path: impl AsRef<std::path::Path>,
    ) -> Result<Self> {
        let config_path = config_path.as_ref();
        let config = config::RuntimeConfig::load(config_path)?;
        let gait_path = gait_path.as_ref();
        let gait = model::gait::GaitFile::load_unchecked(gait_path)?;
        let (urdf_path, text) = gait.read_urdf(gait_path)?;
        let library = config.speed.library.clone();
        let setup = Self::assemble(
            config,
            &config_path.display().to_string(),
            gait,
            &gait_path.display().to_string(),
            text,
            &urdf_path.display().to_string(),
        )?;
        match library {
            // Relative to the config file's folder.
            Some(rel) => setup.load_library(
                config_path
                    .parent()
                    .unwrap_or_else(|| std::path::Path::new("."))
                    .join(rel),
            ),
            None => Ok(setup),
        }
    }

    /// A setup from an already-parsed config and gait and the URDF text the gait names
    /// (`urdf_origin` names that text in errors), checking the URDF's SHA-256 and the gait
    /// against the robot.
    pub fn from_parts(
        config: config::RuntimeConfig,
        gait: model::gait::GaitFile,
        urdf_text: String,
        urdf_origin: &str,
    ) -> Result<Self> {
        Self::assemble(
            config,
            "the runtime config",
            gait,
            "the gait file",
            urdf_text,
            urdf_origin,
        )
    }

    fn assemble(
        config: config::RuntimeConfig,
        config_origin: &str,
        gait: model::gait::GaitFile,
        gait_origin: &str,
        urdf_text: String,
        urdf_origin: &str,
    ) -> Result<Self> {
        let sha = model::gait::sha256_hex(&urdf_text);
        if sha != gait.robot.sha256 {
            return Err(RuntimeError::InvalidField {
                origin: gait_origin.to_string(),
                field: "robot.sha256".into(),
                value: gait.robot.sha256.clone(),
                reason: format!(
                    "{urdf_origin} has SHA-256 {sha}: the robot changed since the gait was planned"
                ),
            });
        }
        let model = model::PlanarModel::from_urdf_str(&urdf_text, urdf_origin)?;
        gait.check_against(&model, gait_origin, urdf_origin)?;
        config.calibration.check_against(&model, config_origin)?;
        Ok(Self {
            config,
            gait,
            model,
            urdf_text,
            library: Vec::new(),
        })
    }

    /// The shipped ADAM config and default gait of this repository, the co-designed one
    /// (tests, examples, benchmarks).
    pub fn shipped() -> Result<Self> {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        Self::load(
            root.join("configs/runtime/adam.toml"),
            root.join(DEFAULT_GAIT),
        )
    }

    /// A controller for this setup (with its gait library, if any).
    pub fn controller(&self, with_held: bool) -> Result<control::Controller> {
        control::Controller::with_library(
            &self.config,
            &self.gait,
            &self.library,
            self.model.clone(),
            with_held,
        )
    }

    /// Adds the gait library file at `path` ([`model::library::GaitLibrary`]: gaits by speed,
    /// of this setup's robot: the check names both robots otherwise) for treadmill speed
    /// control. Errors name the file, the entry and the field.
    pub fn load_library(self, path: impl AsRef<std::path::Path>) -> Result<Self> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let library = model::library::GaitLibrary::load(path)?;
        library.check_against(
            &self.model,
            &self.urdf_text,
            &origin,
            &format!("the URDF of the gait ({})", self.gait.robot.name),
        )?;
        let origins: Vec<String> = (0..library.entries.len())
            .map(|k| format!("{origin}: entries[{k}].gait"))
            .collect();
        let gaits = library.entries.into_iter().map(|e| e.gait).collect();
        self.with_library(gaits, &origins)
    }

    /// Adds a gait library (gaits sorted by speed, each checked against the robot like the
    /// gait; `origins` name them in errors) for treadmill speed control.
    pub fn with_library(
        mut self,
        library: Vec<model::gait::GaitFile>,
        origins: &[String],
    ) -> Result<Self> {
        let urdf_origin = format!("the URDF of {}", self.gait.robot.name);
        for (k, g) in library.iter().enumerate() {
            let origin = origins
                .get(k)
                .cloned()
                .unwrap_or_else(|| format!("gait library entry {k}"));
            g.validate(&origin)?;
            g.check_against(&self.model, &origin, &urdf_origin)?;
        }
        self.library = library;
        // Built once here so a bad library fails at load, not at the first walk.
        self.controller(false)?;
        Ok(self)
    }

    /// The library gait whose speed is nearest `speed_mps` (`None` without a library).
    pub fn library_gait_nearest(&self, speed_mps: f64) -> Option<&model::gait::GaitFile> {
        self.library.iter().min_by(|a, b| {
            (a.speed_mps - speed_mps)
                .abs()
                .total_cmp(&(b.speed_mps - speed_mps).abs())
        })
    }

    /// This setup walking from the library gait nearest `speed_mps` (unchanged without a
    /// library): a simulated walk on a belt at that speed starts in that gait's state, so speed
    /// control does not have to pull a mismatched first step onto the belt.
    pub fn starting_near(mut self, speed_mps: f64) -> Self {
        if let Some(g) = self.library_gait_nearest(speed_mps) {
            self.gait = g.clone();
        }
        self
    }

    /// This setup starting on a belt at rest (unchanged without a library): from the library
    /// gait whose step is nearest the runtime gait's, so that the robot stands in the runtime
    /// gait's stance. (Nearest the belt's speed, 0, would be the slowest gait, whose shorter
    /// step a library reaching below 0.15 m/s makes a narrower stance to launch from.)
    pub fn starting_at_rest(mut self) -> Self {
        let step_m = self.gait.step_length_m;
        let nearest = self.library.iter().min_by(|a, b| {
            (a.step_length_m - step_m)
                .abs()
                .total_cmp(&(b.step_length_m - step_m).abs())
        });
        if let Some(g) = nearest {
            self.gait = g.clone();
        }
        self
    }
}
