//! The simulated robot hung on the boom, for bring-up: its legs free (or clamped in a jig) on
//! the joint bench behind the simulated A1 firmware and CAN codec, the torso upright and still;
//! its motors can be mounted wrong (`EncoderMount`: flipped, zero elsewhere) for calibration.
//! `adam calibrate --backend sim`, the pre-flight of a simulated run from Stand, `adam run
//! --backend sim --dry-run` and the bring-up tests run on it ([`crate::bringup`]).

use crate::bringup::{preflight, PreflightReport};
use crate::slots::LEG_SLOTS;
use crate::{Result, RuntimeError, Setup};
use drivers::sim::bus::{SimBus, SimConfig};
use drivers::sim::firmware::{A1Model, EncoderMount, SimMotor};
use drivers::sim::plant::JointPlant;

/// Mount the simulated leg motors of `setup` as `mounts` says (leg slot order): a simulated
/// robot whose calibration is not the identity.
pub fn mount_sim_motors<P: JointPlant>(
    bus: &mut SimBus<P>,
    setup: &Setup,
    mounts: &[EncoderMount; LEG_SLOTS],
) -> Result<()> {
    for (k, (m, mount)) in setup.config.leg_motors.iter().zip(mounts).enumerate() {
        let spec = m.spec(&format!("leg_motors[{k}]"))?;
        if !bus.set_encoder_mount(spec.id, *mount) {
            return Err(RuntimeError::InvalidField {
                origin: "simulated motors".into(),
                field: format!("encoder mount of {}", m.joint),
                value: format!(
                    "direction {}, zero at {} rad",
                    mount.direction, mount.joint_rad_at_zero
                ),
                reason: "the direction must be ±1 and the angle finite".into(),
            });
        }
    }
    Ok(())
}

/// The joint bench as a robot hung on the boom with its legs clamped in a jig: the four leg
/// joints at `joint_rad` (true joint angles, leg slot order) at rest, the torso upright and
/// still, the leg motors mounted as `mounts` says. `adam calibrate --backend sim` and the
/// calibration tests measure on it.
pub fn hung_robot_sim(
    setup: &Setup,
    joint_rad: &[f64; LEG_SLOTS],
    mounts: &[EncoderMount; LEG_SLOTS],
) -> Result<
    crate::backend::WithImu<
        SimBus<drivers::sim::plant::InertiaDampingPlant>,
        crate::backend::StaticImu,
    >,
> {
    let imu = crate::backend::StaticImu {
        pitch_rad: 0.0,
        gyro_bias_rad_s: 0.0,
    };
    let mut backend = joint_bench_backend(setup, joint_rad, imu)?;
    mount_sim_motors(&mut backend.bus, setup, mounts)?;
    Ok(backend)
}

/// The pre-flight of a simulated run from Stand, made as on the robot: hung on the boom. The
/// simulated robot standing at zero torque would sag and tilt within the listening periods, so
/// the checks run on its hung twin ([`hung_robot_sim`]: the same leg angles and motor mounts,
/// the IMU at the standing robot's torso pitch), after which the robot stands on the treadmill
/// as it was. Refusals are in the report.
pub fn preflight_hung<P: JointPlant>(
    setup: &Setup,
    standing: &SimBus<P>,
    torso_pitch_rad: f64,
    mounts: &[EncoderMount; LEG_SLOTS],
) -> Result<PreflightReport> {
    let mut q = [0.0; LEG_SLOTS];
    for (k, m) in standing.config().motors.iter().take(LEG_SLOTS).enumerate() {
        q[k] = standing.plant().position_rad(m.joint);
    }
    let mut twin = hung_robot_sim(setup, &q, mounts)?;
    twin.imu.pitch_rad = torso_pitch_rad;
    preflight(
        setup,
        &mut twin,
        &mut crate::rt_loop::SimulatedClock::default(),
        false,
    )
}

/// How far from the gait's first pose a simulated dry run hangs each leg joint (alternating
/// signs), rad.
pub const DRY_RUN_START_OFFSET_RAD: f64 = 0.1;

/// What a dry run did.
#[derive(Debug)]
pub struct DryRun {
    /// The pre-flight that preceded it (passed).
    pub preflight: PreflightReport,
    /// The loop's summary.
    pub summary: crate::RunSummary,
    /// The largest distance any leg joint moved from where the run began, rad (zero torque on
    /// a still robot: the legs stay put).
    pub largest_motion_rad: f64,
}

/// A dry run on the simulated robot hung on the boom (legs free near the gait's first pose,
/// [`DRY_RUN_START_OFFSET_RAD`] off it, torso upright and still; [`hung_robot_sim`]): the pre-flight, then the whole loop with Start at
/// 0 s and `script` after it, every command sent as zero torque, the controller's commands
/// logged to `log_path` (`adam run --backend sim --dry-run`).
pub fn dry_run_sim(
    setup: &Setup,
    duration_s: f64,
    script: &[(f64, crate::control::OperatorCommand)],
    log_path: Option<std::path::PathBuf>,
) -> Result<DryRun> {
    use crate::rt_loop::{LoopOptions, SimulatedClock};
    use drivers::sim::plant::JointPlant as _;
    let controller = setup.controller(false)?;
    let first = controller.first_pose();
    let layout = *controller.layout();
    let mut start = [0.0; LEG_SLOTS];
    // A little off the first pose, as legs hanging from the boom are: the Ramp's commands
    // would move them (they do not: every command sent is zero torque).
    for (k, q) in start.iter_mut().enumerate() {
        *q = layout.model_rad(k, first[k]) + DRY_RUN_START_OFFSET_RAD * (-1f64).powi(k as i32);
    }
    let mut backend = hung_robot_sim(setup, &start, &Default::default())?;
    let report = preflight(setup, &mut backend, &mut SimulatedClock::default(), false)?;
    report.refuse()?;
    let mut options = LoopOptions::simulation(duration_s);
    options.dry_run = true;
    options
        .script
        .push((0.0, crate::control::OperatorCommand::Start));
    options.script.extend_from_slice(script);
    options.script.sort_by(|a, b| a.0.total_cmp(&b.0));
    options.log_path = log_path;
    let (summary, backend) = crate::run(setup, backend, SimulatedClock::default(), options, None)?;
    let plant = backend.bus.plant();
    let largest_motion_rad = (0..LEG_SLOTS)
        .map(|k| (plant.position_rad(k) - start[k]).abs())
        .fold(0.0, f64::max);
    Ok(DryRun {
        preflight: report,
        summary,
        largest_motion_rad,
    })
}

/// The leg motors of `setup` on four free joints (inertia 0.05 kg·m², damping 0.1 N·m·s/rad, no
/// robot dynamics) starting at `start_rad`, behind the simulated A1 firmware (seed 7), paired
/// with a static IMU: a backend for the state machine and loop tests without a robot.
pub fn joint_bench_backend(
    setup: &Setup,
    start_rad: &[f64],
    imu: crate::backend::StaticImu,
) -> Result<
    crate::backend::WithImu<
        SimBus<drivers::sim::plant::InertiaDampingPlant>,
        crate::backend::StaticImu,
    >,
> {
    use drivers::sim::plant::{InertiaDampingPlant, RigidJoint};
    let joint = RigidJoint {
        inertia_kg_m2: 0.05,
        damping_nm_s_per_rad: 0.1,
        load_torque_nm: 0.0,
    };
    let invalid = |reason: String| RuntimeError::Gait { reason };
    let n = setup.config.leg_motors.len();
    let mut plant = InertiaDampingPlant::new(vec![joint; n])
        .ok_or_else(|| invalid("joint bench: invalid plant".into()))?;
    for (j, q) in start_rad.iter().take(n).enumerate() {
        plant.set_state(j, *q, 0.0);
    }
    let mut motors = Vec::with_capacity(n);
    for (joint, m) in setup.config.leg_motors.iter().enumerate() {
        motors.push(SimMotor {
            spec: m.spec(&format!("leg_motors[{joint}]"))?,
            joint,
        });
    }
    let config = SimConfig {
        control_rate_hz: setup.config.loop_.rate_hz,
        bitrate_bps: setup.config.loop_.bitrate_bps,
        bus_count: setup.config.loop_.bus_count,
        motors,
        model: A1Model::default(),
        seed: 7,
    };
    Ok(crate::backend::WithImu {
        bus: SimBus::new(config, plant).map_err(|e| invalid(format!("joint bench bus: {e}")))?,
        imu,
    })
}
