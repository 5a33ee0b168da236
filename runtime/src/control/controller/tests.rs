//! The controller's state machine, outputs and trips, on a harness with ideal motors.

#![allow(clippy::unwrap_used, clippy::needless_range_loop)]

use super::*;
use crate::config::LEG_JOINT_NAMES;
use crate::control::transitions::{BRAKE_BLEND_FROM, LAUNCH_DURATION_S};
use crate::control::CommandMode;
use crate::estimator::GRAVITY_MPS2;
use crate::Setup;
use drivers::imu::ImuSample;
use model::bezier;
use model::gait::PhaseDefinition;

/// A controller whose motors track the previous tick's commands exactly (no dynamics) and
/// whose IMU reads a constant pitch.
struct Harness {
    c: Controller,
    input: TickInput,
    out: TickOutput,
    dt_s: f64,
    pitch_rad: f64,
    imu_on: bool,
}

impl Harness {
    fn new(phase: PhaseSource) -> Self {
        Self::with_config(phase, |_| {})
    }

    /// [`Harness::new`] with the shipped config changed by `tweak` first.
    fn with_config(phase: PhaseSource, tweak: impl Fn(&mut crate::config::RuntimeConfig)) -> Self {
        let mut setup = Setup::shipped().unwrap();
        tweak(&mut setup.config);
        setup.config.walk.phase = phase;
        // These tests check the gait's own outputs on a kinematic harness (the torso's pitch is
        // the IMU's, not the hips'); the orbit lever has its own tests (`control::orbit`).
        setup.config.orbit.enabled = false;
        let c = setup.controller(false).unwrap();
        let mut input = TickInput::default();
        for m in input.motors.iter_mut().take(LEG_SLOTS) {
            *m = MotorSample {
                fresh: true,
                temperature_c: 30.0,
                ..MotorSample::default()
            };
        }
        // The planned torso pitch at the start of the step.
        let pitch_rad = setup.gait.initial_state.as_ref().map_or(0.0, |s| s.q[2]);
        Self {
            c,
            input,
            out: TickOutput::default(),
            dt_s: 1e-3,
            pitch_rad,
            imu_on: true,
        }
    }

    fn step(&mut self, op: Option<OperatorCommand>) -> Status {
        self.step_with(op, |_| {})
    }

    /// A step with `tweak` applied to the inputs last (fault injection).
    fn step_with(&mut self, op: Option<OperatorCommand>, tweak: impl Fn(&mut Self)) -> Status {
        for slot in 0..LEG_SLOTS {
            let cmd = self.out.commands[slot];
            let m = &mut self.input.motors[slot];
            if cmd.mode == CommandMode::Pd {
                m.q_rad = cmd.q_des_rad;
                m.dq_rad_s = cmd.dq_des_rad_s;
            }
        }
        self.input.t_s += self.dt_s;
        self.input.imu = self.imu_on.then_some(ImuSample {
            t_s: self.input.t_s,
            gyro_pitch_rad_s: crate::backend::test_dither_rad_s(self.input.t_s),
            accel_x_mps2: -GRAVITY_MPS2 * self.pitch_rad.sin(),
            accel_z_mps2: GRAVITY_MPS2 * self.pitch_rad.cos(),
        });
        self.input.operator = op;
        tweak(self);
        self.c.tick(&self.input, &mut self.out);
        self.out.status
    }

    fn run(&mut self, seconds: f64) -> Status {
        let n = (seconds / self.dt_s).round() as usize;
        for _ in 0..n {
            self.step(None);
        }
        self.out.status
    }

    fn go_stand(&mut self) {
        self.step(None);
        assert_eq!(
            self.step(Some(OperatorCommand::Start)).state,
            ControlState::Ramp
        );
        assert_eq!(self.run(2.5).state, ControlState::Stand);
    }
}

#[test]
fn idle_ramp_stand_walk_stop_stand_damp_and_estop() {
    let mut h = Harness::new(PhaseSource::TimeBased);
    let s = h.step(None);
    assert_eq!(s.state, ControlState::Idle);
    assert!(h
        .out
        .commands
        .iter()
        .all(|c| c.mode == CommandMode::Damping));
    // Walk is ignored while idle.
    assert_eq!(
        h.step(Some(OperatorCommand::Walk)).state,
        ControlState::Idle
    );
    let s = h.step(Some(OperatorCommand::Start));
    assert_eq!(s.transition, Some((ControlState::Idle, ControlState::Ramp)));
    // Ramp: from straight legs (0) to the first pose; never faster than the limit.
    let first = h.c.first_pose();
    let mut peak_speed = 0.0_f64;
    let mut t_stand = None;
    for _ in 0..3000 {
        let s = h.step(None);
        for c in &h.out.commands[..LEG_SLOTS] {
            peak_speed = peak_speed.max(c.dq_des_rad_s.abs());
        }
        if s.state == ControlState::Stand && t_stand.is_none() {
            t_stand = Some(h.input.t_s);
        }
    }
    // Largest move ≈ 0.18 rad → 1.875·0.18/0.5 < 2 s minimum: the ramp takes 2 s.
    let t_stand = t_stand.unwrap();
    assert!((t_stand - (0.002 + 2.0)).abs() < 2.5e-3, "{t_stand}");
    assert!(peak_speed <= 0.5 + 1e-9, "{peak_speed}");
    for k in 0..LEG_SLOTS {
        assert!((h.input.motors[k].q_rad - first[k]).abs() < 1e-9);
    }
    // Walk: first the launch (both feet down, the torso carried forward), then a stance
    // switch every step duration (+ debounce, time-based phase from the lift-off).
    let stance0 = h.c.stance();
    assert_eq!(
        h.step(Some(OperatorCommand::Walk)).state,
        ControlState::Walk
    );
    assert!(h.c.launch.is_some());
    let s = h.run(LAUNCH_DURATION_S - 0.002);
    assert_eq!((s.state, s.stance), (ControlState::Walk, stance0));
    assert!(h.c.launch.is_some());
    h.run(0.003);
    assert!(h.c.launch.is_none() && h.c.start_blend.is_some());
    let step_s = Setup::shipped().unwrap().gait.step_duration_s;
    let mut switches = Vec::new();
    let mut prev = stance0;
    // Ticks at 1 kHz for a little over two steps.
    for _ in 0..(2.15 * step_s * 1000.0) as usize {
        let s = h.step(None);
        if s.stance != prev {
            switches.push(h.input.t_s);
            prev = s.stance;
        }
    }
    assert_eq!(switches.len(), 2, "{switches:?}");
    let period = switches[1] - switches[0];
    // Step T from the shipped gait; touchdown needs τ ≥ 1 then 3 debounced ticks.
    assert!((period - (step_s + 0.003)).abs() < 1.5e-3, "{period}");
    assert_eq!(h.out.status.steps, 2);
    // Stop: finish the step, take the braking step (its references blend into the longer
    // landing pose), then Stand holding the landing pose, two stance switches later.
    let stance_before = h.c.stance();
    assert_eq!(
        h.step(Some(OperatorCommand::Stop)).state,
        ControlState::Stop
    );
    let s = h.run(step_s + 0.05);
    assert_eq!(
        (s.state, s.stance),
        (ControlState::Stop, stance_before.other())
    );
    let mut landing = None;
    for _ in 0..(step_s * 1000.0) as usize + 100 {
        let s = h.step(None);
        if s.state == ControlState::Stop {
            // The braking step's references: y^d plus the blended offset (at the phase
            // the latency compensation leads to).
            let lead = s.phase + h.c.reference_lead_s * s.phase_rate_per_s.max(0.0);
            let lead = lead.clamp(0.0, 1.0);
            let u = ((lead - BRAKE_BLEND_FROM) / (1.0 - BRAKE_BLEND_FROM)).clamp(0.0, 1.0);
            for i in 0..OUTPUTS {
                let want = h.c.gait.eval(i, lead).0 + min_jerk(u).0 * h.c.lunge.dy_end[i];
                assert!((s.y_des_rad[i] - want).abs() < 1e-9, "{i} {s:?}");
            }
        } else if landing.is_none() {
            assert_eq!(s.state, ControlState::Stand);
            landing = Some(h.input.motors);
        }
    }
    let landing = landing.expect("Stand after the braking step");
    assert_eq!(h.c.stance(), stance_before);
    assert!(
        h.c.lunge.dy_end.iter().any(|d| d.abs() > 0.05),
        "{:?}",
        h.c.lunge
    );
    // Stand holds the landing pose.
    for k in 0..LEG_SLOTS {
        assert!((h.out.commands[k].q_des_rad - landing[k].q_rad).abs() < 1e-3);
    }
    // Orderly damping, then reset.
    assert_eq!(
        h.step(Some(OperatorCommand::Damp)).state,
        ControlState::Damping
    );
    assert_eq!(h.out.status.trip, None);
    assert_eq!(
        h.step(Some(OperatorCommand::Reset)).state,
        ControlState::Idle
    );
    // E-stop from Walk.
    h.step(Some(OperatorCommand::Start));
    h.run(2.5);
    h.step(Some(OperatorCommand::Walk));
    h.run(0.2);
    let s = h.step(Some(OperatorCommand::EStop));
    assert_eq!(s.state, ControlState::Damping);
    assert_eq!(s.trip, Some(Trip::EStop));
    assert!(s.new_trip);
    assert!(h
        .out
        .commands
        .iter()
        .all(|c| c.mode == CommandMode::Damping));
    // Latched: Start does nothing until Reset.
    assert_eq!(
        h.step(Some(OperatorCommand::Start)).state,
        ControlState::Damping
    );
    let s = h.step(Some(OperatorCommand::Reset));
    assert_eq!((s.state, s.trip), (ControlState::Idle, None));
}

#[test]
fn walking_outputs_follow_the_bezier_with_the_legs_relabeled() {
    let mut h = Harness::new(PhaseSource::TimeBased);
    h.go_stand();
    h.step(Some(OperatorCommand::Walk));
    // The launch, then the first step (which blends from the launch's pose): from the
    // second step on, the outputs are the gait's.
    let setup = Setup::shipped().unwrap();
    h.run(LAUNCH_DURATION_S + setup.gait.step_duration_s + 0.01);
    assert_eq!(h.c.stance(), Side::Left);
    assert!(h.c.start_blend.is_none());
    let t0 = h.c.step_start_t_s;
    let s = h.run(t0 + 0.3 - h.input.t_s);
    let tau = s.phase;
    assert!(
        (tau - 0.3 / setup.gait.step_duration_s).abs() < 3e-3,
        "{tau}"
    );
    // The references are taken τ̇·lead ahead (latency compensation).
    let ahead = tau + setup.config.walk.reference_lead_s / setup.gait.step_duration_s;
    for i in 0..OUTPUTS {
        let a = &setup.gait.bezier.alpha[i];
        assert!((s.y_des_rad[i] - bezier::eval(a, ahead)).abs() < 1e-12);
        let dy = bezier::eval_d1(a, ahead) / setup.gait.step_duration_s;
        assert!((s.dy_des_rad_s[i] - dy).abs() < 1e-9);
    }
    // The left leg stands: stance hip is slot 0.
    assert_eq!(s.stance, Side::Left);
    assert_eq!(h.out.commands[0].q_des_rad, s.y_des_rad[0]);
    assert_eq!(h.out.commands[3].q_des_rad, s.y_des_rad[3]);
    // After the switch the right leg stands: stance hip is slot 2.
    let s = h.run(setup.gait.step_duration_s - 0.3 + 0.1);
    assert_eq!(s.stance, Side::Right);
    assert_eq!(h.out.commands[2].q_des_rad, s.y_des_rad[0]);
    assert_eq!(h.out.commands[0].q_des_rad, s.y_des_rad[2]);
}

#[test]
fn state_based_phase_matches_the_model_stance_leg_angle() {
    let mut h = Harness::new(PhaseSource::StateBased);
    h.go_stand();
    let s = h.step(Some(OperatorCommand::Walk));
    // At the first pose the stance-leg angle is θ⁺ up to the torso pitch of the IMU, so
    // τ ≈ 0 (|Δθ| small against θ⁻ − θ⁺ = 0.307 rad).
    assert!(s.phase.abs() < 0.1, "{}", s.phase);
    let setup = Setup::shipped().unwrap();
    let model = &setup.model;
    let mut q = setup.gait.initial_state.clone().unwrap().q;
    let legs = model.legs().unwrap();
    for (k, name) in LEG_JOINT_NAMES.iter().enumerate() {
        q[model.joints[model.require_joint(name).unwrap()].coordinate] = s.leg_q_rad[k];
    }
    q[2] = s.pitch_rad;
    let theta = model.stance_leg_angle(&q, &legs, Side::Right).unwrap();
    let PhaseDefinition::StateBased {
        theta_plus_rad,
        theta_minus_rad,
    } = setup.gait.phase
    else {
        panic!()
    };
    let expected = (theta - theta_plus_rad) / (theta_minus_rad - theta_plus_rad);
    assert!(
        (s.phase - expected).abs() < 1e-12,
        "{} vs {expected}",
        s.phase
    );
}

fn tripped(h: &mut Harness, max_ticks: usize, tweak: impl Fn(&mut Harness)) -> (Trip, usize) {
    for n in 1..=max_ticks {
        let s = h.step_with(None, &tweak);
        if s.state == ControlState::Damping {
            assert!(s.new_trip);
            assert!(h
                .out
                .commands
                .iter()
                .all(|c| c.mode == CommandMode::Damping));
            return (s.trip.unwrap(), n);
        }
    }
    panic!("no trip in {max_ticks} ticks");
}

#[test]
fn every_safety_trip_goes_to_damping_with_its_reason() {
    let standing = || {
        let mut h = Harness::new(PhaseSource::TimeBased);
        h.go_stand();
        h
    };
    let mut h = standing();
    let (t, n) = tripped(&mut h, 5, |h| h.input.motors[1].q_rad = 3.0);
    assert_eq!(n, 1);
    assert!(
        matches!(t, Trip::JointLimit { slot: 1, q_rad, upper_rad, .. } if q_rad == 3.0 && upper_rad == 2.2),
        "{t:?}"
    );

    let mut h = standing();
    let (t, n) = tripped(&mut h, 100, |h| h.input.motors[3].tau_nm = -33.4);
    assert_eq!(n, 50, "persistent: exactly torque_saturation_ticks");
    assert!(
        matches!(
            t,
            Trip::TorqueSaturation {
                slot: 3,
                ticks: 50,
                ..
            }
        ),
        "{t:?}"
    );

    let mut h = standing();
    h.pitch_rad = 0.9;
    let (t, _) = tripped(&mut h, 5000, |_| {});
    assert!(
        matches!(t, Trip::Fall { pitch_rad, limit_rad } if pitch_rad > 0.6 && limit_rad == 0.6),
        "{t:?}"
    );

    let mut h = standing();
    let (t, _) = tripped(&mut h, 5, |h| h.input.motors[0].temperature_c = 91.0);
    assert!(
        matches!(t, Trip::OverTemperature { slot: 0, temperature_c, .. } if temperature_c == 91.0),
        "{t:?}"
    );

    let mut h = standing();
    let (t, _) = tripped(&mut h, 5, |h| h.input.motors[2].errors = 0b10);
    assert_eq!(t, Trip::MotorFault { slot: 2, flags: 2 });

    let mut h = standing();
    let (t, n) = tripped(&mut h, 50, |h| h.input.motors[2].fresh = false);
    assert_eq!(
        (t, n),
        (
            Trip::MissingReplies {
                slot: 2,
                consecutive: 5
            },
            5
        )
    );

    let mut h = standing();
    h.imu_on = false;
    let (t, n) = tripped(&mut h, 100, |_| {});
    assert!(matches!(t, Trip::ImuStale { .. }), "{t:?}");
    assert!((20..=22).contains(&n), "stale after 0.02 s: {n}");

    // One implausible sample (an impact spike) does not trip; a run of them does.
    let mut h = standing();
    let spike = |h: &mut Harness| {
        if let Some(imu) = h.input.imu.as_mut() {
            imu.gyro_pitch_rad_s = 100.0;
        }
    };
    for _ in 0..4 {
        assert_eq!(h.step_with(None, spike).trip, None);
    }
    assert_eq!(h.step(None).trip, None, "a good sample resets the count");
    let (t, n) = tripped(&mut h, 10, spike);
    assert_eq!(n, 5, "the fifth implausible sample in a row trips: {t:?}");
    assert!(
        matches!(t, Trip::ImuImplausible { gyro_rad_s, accel_norm_mps2 } if gyro_rad_s == 100.0 && (accel_norm_mps2 - GRAVITY_MPS2).abs() < 1e-9),
        "{t:?}"
    );

    let mut h = standing();
    let (t, n) = tripped(&mut h, 5, |h| h.input.overrun_streak = 20);
    assert_eq!(
        (t, n),
        (
            Trip::OverrunStreak {
                streak: 20,
                limit: 20
            },
            1
        )
    );
}

#[test]
fn idle_is_not_armed() {
    let mut h = Harness::new(PhaseSource::TimeBased);
    h.input.motors[0].temperature_c = 120.0;
    assert_eq!(h.run(0.1).state, ControlState::Idle);
    // Armed on Start: trips at once.
    let s = h.step(Some(OperatorCommand::Start));
    assert_eq!(s.state, ControlState::Damping);
    assert!(matches!(s.trip, Some(Trip::OverTemperature { .. })));
}

#[test]
fn a_braking_step_out_of_the_legs_reach_is_refused_by_name() {
    let setup = Setup::shipped().unwrap();
    let mut config = setup.config.clone();
    // Legs of 0.7 m cannot straddle 1.6 m.
    config.walk.stop_step_length_m = 1.6;
    let err = Controller::new(&config, &setup.gait, setup.model.clone(), false)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("walk.stop_step_length_m") && err.contains("1.6"),
        "{err}"
    );
    // The shipped length is reachable and lengthens the swing: the braking pose's θ lies
    // beyond the gait's θ⁻.
    let c = Controller::new(&setup.config, &setup.gait, setup.model.clone(), false).unwrap();
    assert!(
        c.lunge.theta_rad > c.gait.theta_minus_rad + 0.05,
        "{:?}",
        c.lunge
    );
}

#[test]
fn min_jerk_is_smooth_and_peaks_at_1_875() {
    assert_eq!(min_jerk(0.0), (0.0, 0.0));
    assert_eq!(min_jerk(1.0).0, 1.0);
    assert!((min_jerk(0.5).1 - MIN_JERK_PEAK_RATE).abs() < 1e-12);
    let h = 1e-6;
    let fd = (min_jerk(0.3 + h).0 - min_jerk(0.3 - h).0) / (2.0 * h);
    assert!((fd - min_jerk(0.3).1).abs() < 1e-8);
}

/// A walk on the harness after the launch from Stand: ideal motors, the torso pitching at
/// `pitch_rate_rad_s` (gyro) from then on. Returns the trip and how long after the launch, or
/// the phase and the steps walked after `seconds`.
fn walk_pitching(
    pitch_rate_rad_s: f64,
    seconds: f64,
) -> std::result::Result<(Trip, f64), (f64, u32)> {
    let mut h = Harness::new(PhaseSource::StateBased);
    h.go_stand();
    h.step(Some(OperatorCommand::Walk));
    h.run(LAUNCH_DURATION_S + 0.01);
    let t0 = h.input.t_s;
    let steps0 = h.out.status.steps;
    for _ in 0..(seconds / h.dt_s).round() as usize {
        let s = h.step_with(None, |h| {
            if let Some(imu) = h.input.imu.as_mut() {
                imu.gyro_pitch_rad_s += pitch_rate_rad_s;
            }
        });
        if s.state == ControlState::Damping {
            return Ok((s.trip.unwrap(), h.input.t_s - t0));
        }
    }
    Err((h.out.status.phase, h.out.status.steps - steps0))
}

#[test]
fn the_step_timeout_trips_a_held_walk_but_not_a_slow_step() {
    let setup = Setup::shipped().unwrap();
    let limit_s = setup.config.safety.stall_timeout_s;
    // Held (the harness's torso does not move): the phase stops; the step timeout trips once
    // it has not progressed for the limit.
    let (trip, after_s) = walk_pitching(0.0, 10.0).unwrap();
    let Trip::StepTimeout {
        elapsed_s,
        limit_s: l,
    } = trip
    else {
        panic!("{trip}")
    };
    assert_eq!(l, limit_s);
    assert!(
        elapsed_s > limit_s && elapsed_s < limit_s + 0.002,
        "{elapsed_s}"
    );
    assert!(after_s < limit_s + 0.1, "{after_s}");
    // Pitching backward, the phase runs back: a stall too.
    assert!(walk_pitching(-0.02, 3.0 * limit_s).is_ok());
    // Slow: the torso pitching forward at 0.01 rad/s moves the phase on slowly: no trip in
    // twice the limit, longer than the old timeout (three times the gait's step duration),
    // the step still under way and its phase well on (from 0.22 at the launch's end).
    let seconds = 2.0 * limit_s;
    assert!(seconds > 3.0 * setup.gait.step_duration_s);
    let (phase, steps) = walk_pitching(0.01, seconds).unwrap_err();
    assert_eq!(steps, 0);
    assert!(phase > 0.5 && phase < 1.0, "{phase}");
}

/// An IMU slower than the loop hands the same sample (its own time stamp) to two ticks: the
/// estimator integrates it once, exactly as if the second tick had no sample at all.
#[test]
fn a_repeated_imu_sample_is_integrated_once() {
    let mut repeated = Harness::new(PhaseSource::TimeBased);
    let mut missing = Harness::new(PhaseSource::TimeBased);
    // Tilted 0.05 rad from the gait's pitch: the accelerometer corrections carry weight.
    repeated.pitch_rad += 0.05;
    missing.pitch_rad += 0.05;
    let mut last: Option<ImuSample> = None;
    for tick in 0..400 {
        let odd = tick % 2 == 1;
        repeated.step_with(None, |h| {
            if odd {
                h.input.imu = last;
            }
        });
        last = repeated.input.imu;
        missing.step_with(None, |h| {
            if odd {
                h.input.imu = None;
            }
        });
    }
    let (a, b) = (&repeated.c.estimator, &missing.c.estimator);
    assert_eq!(a.pitch_rad().to_bits(), b.pitch_rad().to_bits());
    assert_eq!(a.gyro_bias_rad_s().to_bits(), b.gyro_bias_rad_s().to_bits());
    assert_eq!(a.pitch_sigma_rad().to_bits(), b.pitch_sigma_rad().to_bits());
}

/// The stall relaunch (`control::recovery`) on the harness, whose torso never moves: a walk from
/// the planned post-impact state (both feet down, as after an impact) that makes no progress
/// relaunches once from double support after `speed.stall_relaunch_s`, hands over to the step
/// within the relaunch, and, still held, trips the step timeout: the timeout stays the last
/// resort. The first step after Walk from Stand never relaunches (no impact since its launch).
#[test]
fn a_held_walk_relaunches_once_then_trips_the_step_timeout() {
    use crate::control::recovery::RELAUNCH_DURATION_S;
    let relaunch_s = 0.3;
    let mut h = Harness::with_config(PhaseSource::StateBased, |c| {
        c.speed.stall_relaunch_s = relaunch_s;
    });
    let limit_s = h.c.progress.limit_s();
    // Held rigidly: the legs stay in the gait's planned post-impact pose (both feet down),
    // whatever the commands.
    let q0 = Setup::shipped().unwrap().gait.initial_state.unwrap().q;
    let held: [f64; LEG_SLOTS] = std::array::from_fn(|k| q0[h.c.leg_coord[k]]);
    let hold = |h: &mut Harness| {
        for (m, q) in h.input.motors.iter_mut().zip(held) {
            (m.q_rad, m.dq_rad_s) = (q, 0.0);
        }
    };
    h.step_with(None, hold);
    let mut status = h.out.status;
    assert!(h.c.begin_walk_at_step_start(h.input.t_s, &mut status));
    let t0 = h.input.t_s;
    let (mut relaunched_at, mut handed_over_at, mut trip_at) = (None, None, None);
    for _ in 0..6000 {
        let s = h.step_with(None, hold);
        let t = h.input.t_s - t0;
        if s.recoveries == 1 && relaunched_at.is_none() {
            relaunched_at = Some(t);
            assert!(h.c.launch.is_some(), "the relaunch starts a launch");
        }
        if relaunched_at.is_some() && handed_over_at.is_none() && h.c.launch.is_none() {
            handed_over_at = Some(t);
        }
        if s.state == ControlState::Damping {
            trip_at = Some((t, s.trip.unwrap()));
            break;
        }
    }
    let relaunched_at = relaunched_at.expect("a relaunch");
    assert!(
        relaunched_at > relaunch_s && relaunched_at < relaunch_s + 0.05,
        "{relaunched_at}"
    );
    let handed_over_at = handed_over_at.expect("a hand-over");
    assert!(
        handed_over_at - relaunched_at <= RELAUNCH_DURATION_S + 0.002,
        "{relaunched_at} {handed_over_at}"
    );
    let (t, trip) = trip_at.expect("the step timeout trips");
    assert_eq!(trip.name(), "step_timeout", "{trip}");
    assert!(t > handed_over_at + limit_s, "{t} {handed_over_at}");
    assert_eq!(h.out.status.recoveries, 1);
    assert_eq!(h.out.status.steps, 0);

    // After Walk from Stand: held, no relaunch, the step timeout as without the relaunch.
    let mut h = Harness::with_config(PhaseSource::StateBased, |c| {
        c.speed.stall_relaunch_s = relaunch_s;
    });
    h.go_stand();
    h.step(Some(OperatorCommand::Walk));
    let s = h.run(LAUNCH_DURATION_S + limit_s + 0.2);
    assert_eq!(s.state, ControlState::Damping);
    assert_eq!(s.trip.map(|t| t.name()), Some("step_timeout"));
    assert_eq!(s.recoveries, 0);
}

/// Stand on a belt whose speed is known measures the legs' pitch every tick against the latest
/// estimate whatever `estimator.encoder_lag_samples` (the choice measured in `Controller::tick`:
/// with the lag there, a walk from Stand onto the 0.25 m/s belt launched 0.8 s later). Two
/// harnesses, lag 0 and lag 1, their IMU 0.02 rad off the legs' pitch so that every
/// measurement moves the estimate: their estimators stay identical bit for bit, while at the
/// same states a lagged measurement would have moved the estimate elsewhere.
#[test]
fn stand_on_a_known_belt_measures_the_legs_pitch_unlagged_whatever_the_encoder_lag() {
    let mut hs = [0, 1].map(|lag| {
        Harness::with_config(PhaseSource::TimeBased, |c| {
            c.estimator.encoder_lag_samples = lag;
        })
    });
    for h in &mut hs {
        h.pitch_rad += 0.02;
        h.go_stand();
        h.step(Some(OperatorCommand::Belt { speed_mps: 0.25 }));
    }
    let sigma_rad = hs[1].c.touchdown_pitch_sigma_rad;
    let mut lag_would_matter = 0;
    for _ in 0..500 {
        for h in &mut hs {
            assert_eq!(h.step(None).state, ControlState::Stand);
        }
        let (a, b) = (&hs[0].c.estimator, &hs[1].c.estimator);
        assert_eq!(a.pitch_rad().to_bits(), b.pitch_rad().to_bits());
        assert_eq!(a.gyro_bias_rad_s().to_bits(), b.gyro_bias_rad_s().to_bits());
        // The same measurement, lagged and not, from this state.
        let probe_rad = b.pitch_rad() - 0.01;
        let (mut lagged, mut latest) = (*b, *b);
        lagged.measure_pitch_lagged(probe_rad, sigma_rad, 1);
        latest.measure_pitch_lagged(probe_rad, sigma_rad, 0);
        if lagged.pitch_rad() != latest.pitch_rad() {
            lag_would_matter += 1;
        }
    }
    // The estimate moves every tick (gyro and measurements), so the lag would change each one.
    assert_eq!(lag_would_matter, 500);
    // The measurements did act: the estimate left the IMU's pitch for the legs' (measured:
    // 0.52 mrad from the legs' pitch, which is 20 mrad from the IMU's; the bound is a tenth of
    // that gap, where an estimate that only half-moved would fail).
    let imu_rad = hs[1].pitch_rad;
    let leg_q: [f64; LEG_SLOTS] = std::array::from_fn(|k| hs[1].input.motors[k].q_rad);
    let legs_rad = hs[1].c.touchdown_pitch_rad(&leg_q);
    let off_rad = (hs[1].c.estimator.pitch_rad() - legs_rad).abs();
    assert!(
        off_rad < 0.1 * (imu_rad - legs_rad).abs(),
        "{off_rad} rad from the legs' pitch"
    );
}
