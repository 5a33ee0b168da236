//! Bring-up: from power-on to the first gain. Everything here runs before the loop, with every
//! motor at zero torque.
//!
//! ```text
//! adam can scan     scan: each configured motor alone — configure, enable, one zero-torque
//!                   exchange (id, position, temperature, error flags), disable; the silent ones named
//! adam calibrate    calibrate: the legs clamped in jig pose A, then B (the config's
//!                   `calibration.<joint>.jig_rad`); the motors' angles in each → direction, gear
//!                   ratio check, zero offset → a NEW config file
//! adam run          preflight: scan, then listen `bringup.samples` periods to every motor and
//!                   the IMU at zero torque → refusals (each naming motor, bus and value), or
//!                   the loop; Start then ramps the gains in over `bringup.gains_ramp_s`
//! adam run --dry-run  the whole loop, every command sent as zero torque, the controller's
//!                   commands logged (`LoopOptions::dry_run`)
//! ```
//! On the simulated robot (`runtime::sim::hung`): the robot hung on the boom (legs free behind
//! the simulated A1 firmware, motors mountable wrong for calibration), the pre-flight of a run
//! from Stand, and the dry run.
//!
//! The checks are pure functions of what was heard ([`preflight::check`]), so every refusal is
//! tested without a robot; `runtime/tests/calibration.rs` and `runtime/tests/preflight.rs`
//! make each one happen on the simulator (a silent motor, a joint far from the start pose, a
//! dead IMU, an IMU reading an implausible pitch, wrong offsets and a flipped motor).
//!
//! Why two jig poses: one pose gives one equation `q_A = d·m_A/N + o` for two unknowns, the
//! direction `d = ±1` and the offset `o`; two poses give `d = sign((m_B − m_A)/(q_B − q_A))`,
//! a check of the gear ratio `N = |m_B − m_A| / |q_B − q_A|`, and two estimates of the offset,
//! whose difference is the jig's play.

pub mod calibrate;
pub mod preflight;

pub use calibrate::{calibrate, CalibrationOutcome, JigPose, JointOutcome};
pub use preflight::{preflight, scan, Answer, MotorScan, MotorTarget, PreflightReport, Refusal};

use crate::slots::LEG_SLOTS;
use crate::Setup;

/// The jig's joint angles of `pose` from the config's calibration (leg slot order), rad.
pub fn jig_angles(setup: &Setup, pose: JigPose) -> [f64; LEG_SLOTS] {
    let mut q = [0.0; LEG_SLOTS];
    for (k, (_, j)) in setup.config.calibration.joints().into_iter().enumerate() {
        q[k] = j.jig_rad[pose.index()];
    }
    q
}

/// How a run on the robot goes after the bring-up ([`run_on_robot`]).
#[derive(Clone, Debug)]
pub struct RobotRun {
    /// Run time, s.
    pub duration_s: f64,
    /// Send every motor zero torque, logging what the controller would have sent.
    pub dry_run: bool,
    /// Drive the held motors too (the robot: yes).
    pub with_held: bool,
    /// Write an MCAP log here.
    pub log_path: Option<std::path::PathBuf>,
}

/// A run on hardware (any [`crate::Backend`]: SocketCAN or UDP motors with an IMU driver): the
/// pre-flight under the wall clock, which refuses before any gain comes on; then the loop in
/// real time (mlockall, SCHED_FIFO as the config says) with operator commands from `operator`.
pub fn run_on_robot<B>(
    setup: &Setup,
    mut backend: B,
    run: &RobotRun,
    operator: Option<crate::operator::OperatorReceiver>,
) -> crate::Result<(PreflightReport, crate::RunSummary, B)>
where
    B: crate::Backend + Send + 'static,
{
    use crate::rt_loop::{LoopOptions, MonotonicClock};
    let report = preflight(setup, &mut backend, &mut MonotonicClock, run.with_held)?;
    report.refuse()?;
    let mut options = LoopOptions::simulation(run.duration_s);
    options.with_held = run.with_held;
    options.dry_run = run.dry_run;
    options.realtime = true;
    options.publish = true;
    options.log_path = run.log_path.clone();
    let (summary, backend) = crate::run(setup, backend, MonotonicClock, options, operator)?;
    Ok((report, summary, backend))
}
