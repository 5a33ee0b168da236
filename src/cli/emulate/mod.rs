//! `adam emulate …`: emulated hardware in its own process, for the runtime's real drivers to
//! talk to: `adam emulate imu` (a VN-100 on a pseudo-terminal).

pub(crate) mod imu;

/// What to emulate.
#[derive(clap::Subcommand)]
pub(crate) enum EmulateWhat {
    /// An emulated VectorNav VN-100 on a pseudo-terminal (`--pty`: prints its path; the driver
    /// opens it as its serial port) or into a file (`--out`), fed by the simulator's IMU noise
    /// model on a torso at rest or swaying, with garbage, dropped and changed bytes on request.
    Imu(imu::ImuArgs),
}

/// Runs the emulator asked for.
pub(crate) fn run(what: &EmulateWhat) -> anyhow::Result<()> {
    match what {
        EmulateWhat::Imu(args) => imu::emulate(args),
    }
}
