//! `Controller::tick` allocates nothing: a counting global allocator watches this test
//! thread over thousands of ticks through Ramp, Stand, Walk (its launch in double support,
//! both phase sources, stance switches included), Stop (the braking step) and Stand again; and
//! with treadmill speed control (a gait library, operator `belt` and `nudge` commands, the
//! regulator switching to interpolated library gaits at each impact). No locks: by construction `Controller` owns only plain data (no `Mutex`,
//! `RwLock`, channel or `Arc` in `control/`, `estimator.rs`, `safety.rs`);
//! `controller_is_owned_plain_data` checks it is `'static + Clone + Send + Sync` (no borrowed
//! shared state).

// The counting allocator is the drivers' no-allocation tests' own (one copy in the workspace).
#![allow(unsafe_code)]

#[path = "../../drivers/tests/common/counting_alloc.rs"]
mod counting_alloc;

use runtime::config::PhaseSource;
use runtime::control::{CommandMode, ControlState, OperatorCommand, TickInput, TickOutput};
use runtime::estimator::GRAVITY_MPS2;
use runtime::{ImuSample, Setup};

#[global_allocator]
static GLOBAL: counting_alloc::Counting = counting_alloc::Counting;

/// Runs `f` with this thread's allocations counted: its result and the count.
fn counted<R>(f: impl FnOnce() -> R) -> (R, usize) {
    counting_alloc::start();
    let r = f();
    (r, counting_alloc::stop())
}

/// A still IMU pitched `pitch_rad` at `t_s`: gravity alone, the gyro reading `bias_rad_s` plus
/// the backends' dither.
fn still_imu(t_s: f64, pitch_rad: f64, bias_rad_s: f64) -> ImuSample {
    ImuSample {
        t_s,
        gyro_pitch_rad_s: bias_rad_s + runtime::backend::test_dither_rad_s(t_s),
        accel_x_mps2: -GRAVITY_MPS2 * pitch_rad.sin(),
        accel_z_mps2: GRAVITY_MPS2 * pitch_rad.cos(),
    }
}

/// The test gait library (`tests/fixtures/library/`), sorted by speed.
fn library(setup: Setup) -> Setup {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/library");
    let mut gaits: Vec<model::gait::GaitFile> = std::fs::read_dir(&dir)
        .expect("library fixtures")
        .map(|e| model::gait::GaitFile::load(e.expect("entry").path()).expect("gait"))
        .collect();
    gaits.sort_by(|a, b| a.speed_mps.total_cmp(&b.speed_mps));
    let origins: Vec<String> = (0..gaits.len()).map(|k| format!("library {k}")).collect();
    setup.with_library(gaits, &origins).expect("library")
}

fn walk_without_allocating(phase: PhaseSource) {
    walk_without_allocating_with(phase, false);
}

fn walk_without_allocating_with(phase: PhaseSource, with_library: bool) {
    let mut setup = Setup::shipped().expect("shipped setup");
    if with_library {
        setup = library(setup);
    }
    setup.config.walk.phase = phase;
    // The touchdown gate (the treadmill config's; off as shipped) runs at every impact.
    setup.config.estimator.touchdown_gate_rad = 0.01;
    // The orbit lever (off as shipped) runs in the tick too.
    setup.config.orbit.enabled = true;
    // No robot here: with the state-based phase the step never ends; the stall check
    // (step timeout) is not what this test is about.
    setup.config.safety.stall_timeout_s = 1e9;
    let mut c = setup.controller(false).expect("controller");
    let mut input = TickInput::default();
    for m in input.motors.iter_mut().take(4) {
        m.fresh = true;
        m.temperature_c = 30.0;
    }
    let mut out = TickOutput::default();
    let pitch: f64 = 0.0237;
    let mut steps = 0;
    let mut walk_ticks = 0;
    let mut stood_after_stop = false;
    let mut speed_updates = 0;
    let ((), allocations) = counted(|| {
        for k in 0..10_000u32 {
            for slot in 0..4 {
                let cmd = out.commands[slot];
                if cmd.mode == CommandMode::Pd {
                    input.motors[slot].q_rad = cmd.q_des_rad;
                    input.motors[slot].dq_rad_s = cmd.dq_des_rad_s;
                }
            }
            input.t_s = f64::from(k) * 1e-3;
            input.imu = Some(still_imu(input.t_s, pitch, 0.001));
            input.operator = match k {
                1 => Some(OperatorCommand::Start),
                2 if with_library => Some(OperatorCommand::Belt { speed_mps: 0.3 }),
                2500 => Some(OperatorCommand::Walk),
                4000 if with_library => Some(OperatorCommand::Nudge { delta_mps: 0.025 }),
                7000 => Some(OperatorCommand::Stop),
                _ => None,
            };
            c.tick(&input, &mut out);
            if out.status.state == ControlState::Walk {
                walk_ticks += 1;
            }
            if out.status.transition == Some((ControlState::Stop, ControlState::Stand)) {
                stood_after_stop = true;
            }
            steps = out.status.steps;
            speed_updates += u32::from(out.status.speed_update);
        }
    });
    assert_eq!(out.status.trip, None);
    assert!(walk_ticks >= 3400, "{walk_ticks} ticks in Walk");
    if phase == PhaseSource::TimeBased {
        // Several stance switches (each relabels the legs) happen inside the counted ticks.
        // The launch (1 s), several stance switches (each relabels the legs), the braking
        // step and Stand happen inside the counted ticks.
        assert!(steps >= 3, "stance switches exercised: {steps}");
        assert!(stood_after_stop);
    }
    if with_library {
        // Impacts ran the regulator and switched to interpolated library gaits.
        assert!(speed_updates >= 3, "{speed_updates} speed updates");
        assert!(out.status.speed.library_mps.is_finite());
        assert_eq!(out.status.speed.offset_mps, 0.025);
    }
    assert_eq!(allocations, 0, "Controller::tick allocated");
}

#[test]
fn tick_allocates_nothing_with_speed_control_switching_library_gaits() {
    walk_without_allocating_with(PhaseSource::TimeBased, true);
}

#[test]
fn tick_allocates_nothing_with_the_time_based_phase() {
    walk_without_allocating(PhaseSource::TimeBased);
}

#[test]
fn tick_allocates_nothing_with_the_state_based_phase() {
    walk_without_allocating(PhaseSource::StateBased);
}

#[test]
fn the_counter_sees_allocations() {
    let (v, n) = counted(|| vec![1u8; 100]);
    assert_eq!(v.len(), 100);
    assert!(n >= 1);
}

#[test]
fn controller_is_owned_plain_data() {
    fn owned<T: Send + Sync + Clone + 'static>() {}
    owned::<runtime::control::Controller>();
}

/// The tick's raw CAN frames reach the log without allocating: a `SimBus` exchange records
/// its frames in fixed storage and `FrameBatch::batches` copies them into the log's wait-free ring
/// (the writer thread, which formats them, does not count). Then the log holds them all.
#[test]
fn logging_the_ticks_can_frames_allocates_nothing() {
    use drivers::a1::{Command, MotorId, Reply};
    use drivers::bus::{MotorBus, MotorSpec};
    use drivers::sim::bus::{SimBus, SimConfig};
    use drivers::sim::firmware::{A1Model, SimMotor};
    use drivers::sim::plant::{InertiaDampingPlant, RigidJoint};
    use runtime::telemetry::frames::{BusOp, FrameBatch};
    use runtime::telemetry::frames_read::read_frames;
    use runtime::telemetry::log::{start, LogContext, LogRecord};

    let setup = Setup::shipped().expect("shipped setup");
    let layout = runtime::slots::SlotLayout::new(&setup.config, false);
    let path = std::env::temp_dir().join(format!("adam-can-noalloc-{}.mcap", std::process::id()));
    let (mut tx, logger) = start(&path, LogContext::new(&setup, &layout), 8192).expect("log");
    let specs: Vec<MotorSpec> = (1..=4u8)
        .map(|n| MotorSpec {
            bus: usize::from(n > 2),
            id: MotorId::new(n).expect("id"),
        })
        .collect();
    let config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 2,
        motors: specs
            .iter()
            .enumerate()
            .map(|(joint, &spec)| SimMotor { spec, joint })
            .collect(),
        model: A1Model::default(),
        seed: 3,
    };
    let joint = RigidJoint {
        inertia_kg_m2: 0.05,
        damping_nm_s_per_rad: 0.05,
        load_torque_nm: 0.0,
    };
    let plant = InertiaDampingPlant::new(vec![joint; 4]).expect("plant");
    let mut bus = SimBus::new(config, plant).expect("bus");
    bus.configure(&specs).expect("configure");
    bus.activate().expect("activate");
    let commands: Vec<Command> = specs.iter().map(|s| Command::damping(s.id, 1.0)).collect();
    let mut replies: Vec<Reply> = specs.iter().map(|s| Reply::zeroed(s.id)).collect();
    let ticks = 500u64;
    let ((), allocations) = counted(|| {
        for tick in 0..ticks {
            bus.exchange(&commands, &mut replies, std::time::Duration::from_millis(1))
                .expect("exchange");
            let t_s = tick as f64 * 1e-3;
            for batch in FrameBatch::batches(BusOp::Exchange, t_s, Some(tick), bus.frames()) {
                tx.push(LogRecord::Frames(batch));
            }
        }
    });
    let stats = logger.finish().expect("finish");
    assert_eq!(allocations, 0, "logging the frames allocated");
    assert_eq!(stats.dropped, 0);
    let rows = read_frames(&path).expect("frames");
    assert_eq!(
        rows.len() as u64,
        8 * ticks,
        "a command and a reply per motor and tick"
    );
    assert_eq!(rows[0].id, 0x101);
    assert_eq!(rows[1].id, 0x181);
    let _ = std::fs::remove_file(&path);
}

/// The shipped setup with its speed settings changed by `speed` and the safety's stall timeout
/// off (the recovery tests hold the robot still for longer than it allows), and its gait's
/// initial coordinates.
fn no_stall_timeout(speed: impl FnOnce(&mut runtime::config::SpeedConfig)) -> (Setup, Vec<f64>) {
    let mut setup = Setup::shipped().expect("shipped setup");
    speed(&mut setup.config.speed);
    setup.config.safety.stall_timeout_s = 1e9;
    let q0 = setup
        .gait
        .initial_state
        .clone()
        .expect("an initial state")
        .q;
    (setup, q0)
}

/// The stall relaunch (`speed.stall_relaunch_s`) allocates nothing either: a walk held rigidly in
/// the gait's post-impact pose (both feet down, no progress) relaunches from double support
/// inside the counted ticks, then hands over to the step.
#[test]
fn the_stall_relaunch_allocates_nothing() {
    let (setup, q0) = no_stall_timeout(|speed| speed.stall_relaunch_s = 0.3);
    let pitch = q0[2];
    let held: Vec<f64> = runtime::config::LEG_JOINT_NAMES
        .iter()
        .map(|name| {
            let j = setup.model.require_joint(name).expect("a leg joint");
            q0[setup.model.joints[j].coordinate]
        })
        .collect();
    let mut c = setup.controller(false).expect("controller");
    let mut input = TickInput::default();
    for (m, &q) in input.motors.iter_mut().zip(&held) {
        (m.fresh, m.temperature_c, m.q_rad) = (true, 30.0, q);
    }
    let mut out = TickOutput::default();
    assert!(c.begin_walk_at_step_start(0.0, &mut out.status));
    let ((), allocations) = counted(|| {
        for k in 1..2000u32 {
            input.t_s = f64::from(k) * 1e-3;
            input.imu = Some(still_imu(input.t_s, pitch, 0.0));
            c.tick(&input, &mut out);
        }
    });
    assert_eq!(out.status.trip, None);
    assert_eq!(out.status.state, ControlState::Walk);
    assert_eq!(out.status.recoveries, 1, "the relaunch ran");
    assert_eq!(allocations, 0, "Controller::tick allocated");
}

/// The step-back catch (`speed.step_back_catch_m`) allocates nothing either: the joints follow
/// the gait's outputs forward to τ = 0.3 and back to 0 (a step whose phase runs back, the swing
/// foot low and behind), so the controller sets the swing foot down, catches the robot from
/// double support and hands over, all inside the counted ticks.
#[test]
fn the_step_back_catch_allocates_nothing() {
    let (setup, q0) = no_stall_timeout(|speed| {
        speed.step_back_catch_m = 0.05;
        speed.stall_relaunch_s = 0.0;
    });
    let pitch = q0[2];
    // The leg slot of each output, for the stance side whose outputs at τ = 0 are the initial
    // state's joints.
    let slot_of = |stance: model::Side| -> Vec<usize> {
        setup
            .gait
            .outputs
            .iter()
            .map(|o| {
                let name = o.joint_name(stance);
                runtime::config::LEG_JOINT_NAMES
                    .iter()
                    .position(|n| *n == name)
                    .expect("an output on a leg joint")
            })
            .collect()
    };
    let joint_q = |slot: usize| {
        let j = setup
            .model
            .require_joint(runtime::config::LEG_JOINT_NAMES[slot])
            .expect("a leg joint");
        q0[setup.model.joints[j].coordinate]
    };
    let outputs_at = |tau: f64| -> Vec<f64> {
        let b = &setup.gait.bezier.alpha;
        b.iter().map(|row| model::bezier::eval(row, tau)).collect()
    };
    let stance = [model::Side::Left, model::Side::Right]
        .into_iter()
        .find(|&side| {
            slot_of(side)
                .iter()
                .zip(outputs_at(0.0))
                .all(|(&slot, y)| (joint_q(slot) - y).abs() < 1e-6)
        })
        .expect("the initial state is the outputs at τ = 0");
    let slots = slot_of(stance);
    let mut c = setup.controller(false).expect("controller");
    let mut input = TickInput::default();
    for m in input.motors.iter_mut() {
        (m.fresh, m.temperature_c) = (true, 30.0);
    }
    let mut out = TickOutput::default();
    assert!(c.begin_walk_at_step_start(0.0, &mut out.status));
    // τ(t): up to 0.3 in 0.5 s, back to 0 in the next 0.6 s, then held.
    let tau = |t: f64| {
        if t < 0.5 {
            0.6 * t
        } else {
            (0.3 - 0.5 * (t - 0.5)).max(0.0)
        }
    };
    let tau_rate = |t: f64| match t {
        t if t < 0.5 => 0.6,
        t if t < 1.1 => -0.5,
        _ => 0.0,
    };
    let mut y = [0.0; 4];
    let mut dy = [0.0; 4];
    let ((), allocations) = counted(|| {
        for k in 1..2500u32 {
            input.t_s = f64::from(k) * 1e-3;
            for (i, row) in setup.gait.bezier.alpha.iter().enumerate() {
                y[i] = model::bezier::eval(row, tau(input.t_s));
                dy[i] = model::bezier::eval_d1(row, tau(input.t_s)) * tau_rate(input.t_s);
            }
            for (i, &slot) in slots.iter().enumerate() {
                (input.motors[slot].q_rad, input.motors[slot].dq_rad_s) = (y[i], dy[i]);
            }
            input.imu = Some(still_imu(input.t_s, pitch, 0.0));
            c.tick(&input, &mut out);
        }
    });
    assert_eq!(out.status.trip, None);
    assert_eq!(out.status.state, ControlState::Walk);
    assert_eq!(out.status.catches, 1, "the catch ran");
    assert_eq!(out.status.recoveries, 0);
    assert_eq!(allocations, 0, "Controller::tick allocated");
}
