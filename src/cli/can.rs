//! `adam can scan`: every configured motor asked alone at zero torque (id, position, rate,
//! temperature, error flags), the silent ones named (`runtime::bringup::scan`); on the simulated
//! robot or over SocketCAN.

use crate::cli::bringup_target::{Backend, BringupTarget};
use anyhow::{bail, Result};
use runtime::bringup::{self, Answer};

/// `adam can …`.
#[derive(clap::Subcommand)]
pub(crate) enum CanCommand {
    /// Ask every configured motor (legs and held joints on the robot; the legs in simulation)
    /// at zero torque and print id, position, rate, temperature and error flags; the missing
    /// ones are named and the exit code is 1.
    Scan(ScanArgs),
}

/// Arguments of `adam can scan`.
#[derive(clap::Args)]
pub(crate) struct ScanArgs {
    /// The robot to scan (`--backend sim|can`), its runtime config (the buses and motors), gait
    /// and CAN interfaces.
    #[command(flatten)]
    target: BringupTarget,
    /// A simulated motor that does not answer (a cut cable), by id; repeatable (sim).
    #[arg(long)]
    sim_silent: Vec<u8>,
}

/// `adam can scan`.
pub(crate) fn scan(args: ScanArgs) -> Result<()> {
    let ScanArgs { target, sim_silent } = args;
    target.refuse_unused(&[("--sim-silent", !sim_silent.is_empty())])?;
    let (config, gait) = target.inputs();
    let setup = runtime::Setup::load(&config, &gait)?;
    let budget = std::time::Duration::from_secs_f64(setup.config.period_s());
    let scanned = match target.backend {
        Backend::Sim => {
            let targets = bringup::preflight::targets(&setup.config, false)?;
            let mut options = runtime::sim::run::SimWalkOptions::new(1.0);
            options.start = runtime::sim::run::SimStart::Stand;
            let mut bus = runtime::sim::run::sim_backend(&setup, &options)?;
            for id in sim_silent {
                let found = drivers::a1::MotorId::new(id).is_some_and(|m| bus.set_silent(m, true));
                if !found {
                    bail!(
                        "--sim-silent {id}: no simulated motor has that id (the leg motors are {})",
                        targets
                            .iter()
                            .map(|t| t.spec.id.get().to_string())
                            .collect::<Vec<_>>()
                            .join(", ")
                    );
                }
            }
            println!(
                "adam can scan: the simulated robot's leg motors ({} buses at {} bit/s)",
                setup.config.loop_.bus_count, setup.config.loop_.bitrate_bps
            );
            bringup::scan(&mut bus, &targets, budget)?
        }
        Backend::Can => {
            let targets = bringup::preflight::targets(&setup.config, true)?;
            let interfaces = target.interfaces(&setup);
            let mut bus = runtime::robot::open_can(&setup, &interfaces)?;
            println!(
                "adam can scan: {} over {}",
                config.display(),
                interfaces.join(",")
            );
            bringup::scan(&mut bus, &targets, budget)?
        }
    };
    print!("{}", bringup::preflight::ScanTable(&scanned));
    let missing: Vec<String> = scanned
        .iter()
        .filter(|s| !matches!(s.answer, Answer::Reply(_)))
        .map(|s| s.target.to_string())
        .collect();
    if !missing.is_empty() {
        bail!(
            "{} of {} motors did not answer or refused to enable: {}",
            missing.len(),
            scanned.len(),
            missing.join(", ")
        );
    }
    Ok(())
}
