//! `adam emulate …`: emulated hardware in its own process, for a runtime in another one to talk to
//! over the transports the real hardware uses: `adam emulate imu` (a VN-100 on a pseudo-terminal)
//! and `adam emulate motors` (the simulated ADAM's A1s over CAN-over-UDP).

pub(crate) mod imu;
mod motors;

/// What to emulate.
#[derive(clap::Subcommand)]
pub(crate) enum EmulateWhat {
    /// An emulated VectorNav VN-100 on a pseudo-terminal (`--pty`: prints its path; the driver
    /// opens it as its serial port) or into a file (`--out`), fed by the simulator's IMU noise
    /// model on a torso at rest or swaying, with garbage, dropped and changed bytes on request.
    Imu(imu::ImuArgs),
    /// The simulated ADAM's A1 motors (and its torso IMU) over CAN-over-UDP in cannelloni's
    /// packet format, for `adam run --backend udp --motors ADDR` in another process.
    Motors(motors::MotorsArgs),
}

/// Runs the emulator asked for.
pub(crate) fn emulate(what: EmulateWhat) -> anyhow::Result<()> {
    match what {
        EmulateWhat::Imu(args) => imu::emulate(&args),
        EmulateWhat::Motors(args) => motors::motors(&args),
    }
}
