//! # runtime: real-time execution of an HZD gait on ADAM
//!
//! (crate docs: see below)

pub mod config;
pub mod controller;
mod error;
pub mod estimator;
pub mod io;
pub mod log;
pub mod operator;
pub mod rt_loop;
mod rt_sys;
pub mod safety;
pub mod telemetry;

pub use error::{Result, RuntimeError};
pub use io::{Imu, ImuSample};

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
}

impl Setup {
    /// Loads the runtime config, the gait file and the URDF the gait names (relative to the gait
    /// file's folder), checking the URDF's SHA-256 against the gait.
    pub fn load(
        config_path: impl AsRef<std::path::Path>,
        gait_path: impl AsRef<std::path::Path>,
    ) -> Result<Self> {
        let config = config::RuntimeConfig::load(config_path)?;
        let gait_path = gait_path.as_ref();
        let gait = model::gait::GaitFile::load(gait_path)?;
        let urdf_path = gait_path
            .parent()
            .unwrap_or_else(|| std::path::Path::new("."))
            .join(&gait.robot.urdf);
        let text = std::fs::read_to_string(&urdf_path).map_err(|error| RuntimeError::Io {
            path: urdf_path.clone(),
            error,
        })?;
        let sha = model::gait::sha256_hex(&text);
        if sha != gait.robot.sha256 {
            return Err(RuntimeError::Gait {
                reason: format!(
                    "{} has SHA-256 {sha}, the gait was planned for {}",
                    urdf_path.display(),
                    gait.robot.sha256
                ),
            });
        }
        let model = model::PlanarModel::from_urdf_file(&urdf_path)?;
        Ok(Self {
            config,
            gait,
            model,
        })
    }

    /// The shipped ADAM config and gait of this repository (tests, examples, benchmarks).
    pub fn shipped() -> Result<Self> {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        Self::load(
            root.join("configs/runtime/adam.toml"),
            root.join("configs/gaits/adam_walk.json"),
        )
    }

    /// A controller for this setup.
    pub fn controller(&self, with_held: bool) -> Result<controller::Controller> {
        controller::Controller::new(&self.config, &self.gait, self.model.clone(), with_held)
    }
}
