//! `adam emulate`: hardware emulated in this process for a runtime in another one, over the
//! same transports the real hardware uses (`motors`: the A1s over CAN-over-UDP).

mod motors;

/// What `adam emulate` emulates.
#[derive(clap::Subcommand)]
pub(crate) enum EmulateWhat {
    /// The simulated ADAM's A1 motors (and its torso IMU) over CAN-over-UDP in cannelloni's
    /// packet format, for `adam run --backend udp --motors ADDR` in another process.
    Motors(motors::MotorsArgs),
}

/// Runs the emulator asked for.
pub(crate) fn emulate(what: EmulateWhat) -> anyhow::Result<()> {
    match what {
        EmulateWhat::Motors(args) => motors::motors(&args),
    }
}
