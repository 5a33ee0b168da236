//! What a bring-up command (`adam calibrate`, `adam can scan`) talks to: the backend, the runtime
//! config and gait that describe the robot, and the CAN interfaces of the real one. One struct,
//! flattened into each command's arguments, so the flags read and check the same everywhere.

use crate::cli::shipped;
use anyhow::{bail, Result};
use std::path::PathBuf;

/// The robot a bring-up command works on (`#[command(flatten)]` into its arguments).
#[derive(clap::Args)]
pub(crate) struct BringupTarget {
    /// The simulated robot (hung on the boom), or the robot over SocketCAN.
    #[arg(long, value_enum)]
    pub(crate) backend: Backend,
    /// Runtime config (TOML): the buses, the motors, the calibration and its jig poses.
    #[arg(long, default_value = shipped::RUNTIME_CONFIG)]
    pub(crate) config: PathBuf,
    /// Gait file (JSON) whose robot (URDF) the config drives; default: the co-designed ADAM's.
    #[arg(long, default_value = runtime::DEFAULT_GAIT)]
    pub(crate) gait: PathBuf,
    /// CAN interfaces, one per bus of the config (can; default can0,can1,…).
    #[arg(long, value_delimiter = ',')]
    pub(crate) can_interfaces: Option<Vec<String>>,
}

/// Backend of a bring-up command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Backend {
    /// The simulated robot behind the simulated A1 firmware.
    Sim,
    /// The robot over SocketCAN.
    Can,
}

impl BringupTarget {
    /// Refuses the flags the chosen backend does not use: `--can-interfaces` with `sim`, and each
    /// of the command's simulator-only flags (`(flag, given)`) with `can`, naming them all.
    pub(crate) fn refuse_unused(&self, sim_only: &[(&str, bool)]) -> Result<()> {
        let unused: Vec<&str> = match self.backend {
            Backend::Sim => [("--can-interfaces", self.can_interfaces.is_some())]
                .iter()
                .filter_map(|&(flag, given)| given.then_some(flag))
                .collect(),
            Backend::Can => sim_only
                .iter()
                .filter_map(|&(flag, given)| given.then_some(flag))
                .collect(),
        };
        if unused.is_empty() {
            return Ok(());
        }
        let backend = match self.backend {
            Backend::Sim => "sim",
            Backend::Can => "can",
        };
        bail!(
            "{} {} not used by --backend {backend}: remove {}",
            unused.join(", "),
            if unused.len() == 1 { "is" } else { "are" },
            if unused.len() == 1 { "it" } else { "them" },
        )
    }

    /// The config and gait paths as given, or the shipped copies when run from elsewhere.
    pub(crate) fn inputs(&self) -> (PathBuf, PathBuf) {
        (shipped::input(&self.config), shipped::input(&self.gait))
    }

    /// The CAN interfaces given, or the config's default (`can0`, `can1`, …).
    pub(crate) fn interfaces(&self, setup: &runtime::Setup) -> Vec<String> {
        self.can_interfaces
            .clone()
            .unwrap_or_else(|| runtime::robot::default_interfaces(setup))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        target: BringupTarget,
    }

    fn parse(args: &[&str]) -> BringupTarget {
        let mut all = vec!["test"];
        all.extend_from_slice(args);
        Cli::try_parse_from(all).expect("valid flags").target
    }

    #[test]
    fn each_backend_refuses_the_other_backends_flags_by_name() {
        let sim = parse(&["--backend", "sim", "--can-interfaces", "can0,can1"]);
        assert_eq!(
            sim.can_interfaces.as_deref(),
            Some(&["can0".to_string(), "can1".to_string()][..])
        );
        let err = sim
            .refuse_unused(&[("--sim-flip", false)])
            .expect_err("sim refuses --can-interfaces");
        assert_eq!(
            err.to_string(),
            "--can-interfaces is not used by --backend sim: remove it"
        );
        let can = parse(&["--backend", "can"]);
        let err = can
            .refuse_unused(&[
                ("--sim-offsets", true),
                ("--sim-flip", true),
                ("--x", false),
            ])
            .expect_err("can refuses the sim flags");
        assert_eq!(
            err.to_string(),
            "--sim-offsets, --sim-flip are not used by --backend can: remove them"
        );
        assert!(can.refuse_unused(&[("--sim-flip", false)]).is_ok());
        assert!(parse(&["--backend", "sim"]).refuse_unused(&[]).is_ok());
    }
}
