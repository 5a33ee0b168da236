//! The simulated ADAM (`drivers::sim::robot`): falls, standing through SimBus and the CAN codec,
//! contact and impact properties, treadmill, boom, IMU and determinism.
#![allow(clippy::unwrap_used, clippy::needless_range_loop)]

use core::time::Duration;
use drivers::a1::{Command, Reply};
use drivers::bus::MotorBus;
use drivers::imu::{Imu, ImuNoise, ImuSample};
use drivers::sim::bus::{SimBus, SimConfig};
use drivers::sim::firmware::A1Model;
use drivers::sim::plant::JointPlant;
use drivers::sim::robot::{
    Boom, Contact, FallCause, LegJoint, RobotSim, RobotSimConfig, SimEvent, PENETRATION_TOLERANCE_M,
};
use model::{PlanarModel, Side};

const PERIOD: Duration = Duration::from_millis(1);

fn adam() -> PlanarModel {
    model::design::generate_model(&model::design::DesignLengths::ADAM)
        .unwrap()
        .0
}

fn sim() -> RobotSim {
    RobotSim::new(&adam(), RobotSimConfig::default()).unwrap()
}

/// Joint-level PD on the true state (plant-level tests that do not need the bus).
fn pd(sim: &RobotSim, target: &[f64], kp: f64, kd: f64) -> Vec<f64> {
    (0..sim.joint_count())
        .map(|j| kp * (target[j] - sim.position_rad(j)) - kd * sim.velocity_rad_s(j))
        .collect()
}

/// [`pd`] plus the gravity feed-forward `ff`.
fn pd_ff(sim: &RobotSim, target: &[f64], ff: &[f64], kp: f64, kd: f64) -> Vec<f64> {
    let mut u = pd(sim, target, kp, kd);
    for (u, f) in u.iter_mut().zip(ff) {
        *u += f;
    }
    u
}

fn joints(sim: &RobotSim) -> Vec<f64> {
    (0..sim.joint_count())
        .map(|j| sim.position_rad(j))
        .collect()
}

fn bus_over(sim: RobotSim, seed: u64) -> SimBus<RobotSim> {
    let motors = sim.leg_motors(0, 1);
    let config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 2,
        motors,
        model: A1Model::default(),
        seed,
    };
    let mut bus = SimBus::new(config, sim).unwrap();
    let specs: Vec<_> = bus.config().motors.iter().map(|m| m.spec).collect();
    bus.configure(&specs).unwrap();
    bus.activate().unwrap();
    bus
}

#[test]
fn standing_pose_has_both_feet_on_the_ground_and_flexed_knees() {
    let s = sim();
    assert!(s.in_stance(Side::Left) && s.in_stance(Side::Right));
    for side in [Side::Left, Side::Right] {
        assert!(s.foot_position_m(side)[1].abs() < 1e-9);
        let knee = s.position_rad(s.joint_index(side, LegJoint::Knee));
        assert!(knee > 0.1 && knee < 2.4, "knee {knee}");
    }
    assert!(s.foot_position_m(Side::Left)[0] > s.foot_position_m(Side::Right)[0]);
    assert_eq!(s.joint_count(), 4);
}

#[test]
fn zero_torque_robot_falls_and_the_fall_is_reported() {
    let mut s = sim();
    let mut t_fall = None;
    for _ in 0..3000 {
        s.step(&[0.0; 4], 1e-3).unwrap();
        if let Some(SimEvent::Fall { t_s, what }) = s
            .events()
            .iter()
            .find(|e| matches!(e, SimEvent::Fall { .. }))
        {
            t_fall = Some((*t_s, *what));
            break;
        }
    }
    let (t, what) = t_fall.expect("a limp robot must fall within 3 s");
    // Free fall of the hip from ~0.45 m takes ≥ 0.3 s; a buckling chain is slower still.
    assert!(t > 0.1, "fell at {t} s");
    assert!(
        matches!(what, FallCause::Knee(_) | FallCause::Torso),
        "{what:?}"
    );
    assert_eq!(s.fallen(), Some(what));
    assert!(s.max_penetration_m() <= PENETRATION_TOLERANCE_M);
}

#[test]
fn pd_through_simbus_holds_the_standing_pose_within_one_degree() {
    let s = sim();
    let target = joints(&s);
    let order = s.leg_motors(0, 1); // motor i drives plant joint order[i].joint
    let ff = s.static_torques_nm().unwrap();
    let mut bus = bus_over(s, 5);
    let (kp, kd) = (300.0, 4.0);
    let commands: Vec<Command> = order
        .iter()
        .map(|m| Command::pd(m.spec.id, target[m.joint], 0.0, kp, kd, ff[m.joint]))
        .collect();
    let mut replies: Vec<Reply> = order.iter().map(|m| Reply::zeroed(m.spec.id)).collect();
    let mut worst_rad: f64 = 0.0;
    for _ in 0..2500 {
        bus.exchange(&commands, &mut replies, PERIOD).unwrap();
        let plant = bus.plant();
        for j in 0..4 {
            worst_rad = worst_rad.max((plant.position_rad(j) - target[j]).abs());
        }
        assert!(plant.in_stance(Side::Left) && plant.in_stance(Side::Right));
    }
    let plant = bus.plant();
    println!("standing: worst joint error {:.3}°", worst_rad.to_degrees());
    assert!(worst_rad < 1f64.to_radians(), "{}°", worst_rad.to_degrees());
    assert!(plant.fallen().is_none());
    assert!(plant.max_penetration_m() <= PENETRATION_TOLERANCE_M);
    assert!(!plant
        .events()
        .iter()
        .any(|e| matches!(e, SimEvent::Liftoff { .. })));
    // Both feet carry weight, and together all of it (static: Σ F_z = m g).
    let weight = plant.model().total_mass_kg() * plant.model().gravity_mps2;
    let fz = [Side::Left, Side::Right].map(|s| plant.contact_force_n(s)[1]);
    assert!(fz[0] > 0.0 && fz[1] > 0.0, "{fz:?}");
    assert!(
        ((fz[0] + fz[1]) / weight - 1.0).abs() < 0.02,
        "{fz:?} vs {weight}"
    );
    // Replies went through the codec: they agree with the truth within the reply quantum.
    for (m, r) in order.iter().zip(&replies) {
        assert!((r.q_rad - plant.position_rad(m.joint)).abs() < 2e-3);
    }
}

/// Drop the robot from `height_m` with its legs held by a PD; returns the sim afterwards.
fn drop_test(height_m: f64, pitch_rad: f64, duration_s: f64) -> RobotSim {
    let mut s = sim();
    let target = joints(&s);
    let mut q = s.q().to_vec();
    let dq = vec![0.0; q.len()];
    q[1] += height_m;
    q[2] = pitch_rad;
    s.set_state(&q, &dq).unwrap();
    assert!(!s.in_stance(Side::Left) && !s.in_stance(Side::Right));
    for _ in 0..(duration_s * 1000.0) as usize {
        let u = pd(&s, &target, 150.0, 3.0);
        s.step(&u, 1e-3).unwrap();
    }
    s
}

#[test]
fn impacts_never_add_energy_and_feet_do_not_penetrate() {
    for (height, pitch) in [(0.03, 0.0), (0.05, 0.1), (0.02, -0.15)] {
        let s = drop_test(height, pitch, 0.6);
        let touchdowns: Vec<_> = s
            .events()
            .iter()
            .filter_map(|e| match e {
                SimEvent::Touchdown(t) => Some(*t),
                _ => None,
            })
            .collect();
        assert!(!touchdowns.is_empty(), "{height} m: no touchdown");
        for t in &touchdowns {
            assert!(
                t.kinetic_energy_after_j <= t.kinetic_energy_before_j * (1.0 + 1e-12),
                "{t:?}"
            );
        }
        // Known limitation (no slip model): at near-simultaneous or grazing touchdowns the
        // no-slip pin of both feet can ask for a small normal pull. Its size depends on the
        // grazing geometry and on rounding, not on the integration path: the 0.05 m drop at
        // pitch 0.1 pulled 7 % of the first impulse with the Cholesky solves of an earlier
        // version; drops from 0.049, 0.0499, 0.05, 0.0501, 0.051 and 0.052 m pull 13.9, 13.2,
        // 19.6, 7.0, 5.9 and 5.5 % with every step exact (`dynamics_refresh_substeps: 1`), and
        // 5.4, 13.8, 13.5, 13.0, 6.8 and 6.5 % on the default multi-rate path. Bound it: ≤ 20 %
        // of the first impact's normal impulse, which pushes.
        let first_push = touchdowns[0].impulse_ns[1];
        assert!(first_push > 0.0);
        let worst_pull = touchdowns
            .iter()
            .map(|t| -t.impulse_ns[1])
            .fold(0.0, f64::max);
        println!(
            "drop {height} m: {} touchdowns, first normal impulse {first_push:.3} N·s, worst pull {worst_pull:.3} N·s",
            touchdowns.len()
        );
        assert!(worst_pull <= 0.2 * first_push, "{worst_pull} N·s");
        // The first impact of a fall from h: KE before ≈ m g h (the legs are held, the
        // foot hits after falling h; the PD does little work in 0.1 s): within 10 %.
        let first = touchdowns[0];
        let mgh = s.model().total_mass_kg() * 9.81 * height;
        if pitch == 0.0 {
            // (A pitched torso puts one foot lower: it falls less than h.)
            assert!(
                (first.kinetic_energy_before_j / mgh - 1.0).abs() < 0.1,
                "{first:?} vs {mgh}"
            );
        }
        println!(
            "drop {height} m, pitch {pitch}: first impact KE {:.3} → {:.3} J, max penetration {:.2e} m",
            first.kinetic_energy_before_j,
            first.kinetic_energy_after_j,
            s.max_penetration_m()
        );
        assert!(s.max_penetration_m() <= PENETRATION_TOLERANCE_M);
        assert!(s.fallen().is_none(), "{height}: {:?}", s.fallen());
    }
}

#[test]
fn a_foot_lifted_by_its_leg_leaves_the_ground() {
    let mut s = sim();
    let mut target = joints(&s);
    for _ in 0..200 {
        let u = pd(&s, &target, 300.0, 4.0);
        s.step(&u, 1e-3).unwrap();
    }
    assert!(s.in_stance(Side::Right));
    // Flex the right knee and swing the hip forward: the right foot must come up.
    target[s.joint_index(Side::Right, LegJoint::Knee)] += 0.6;
    target[s.joint_index(Side::Right, LegJoint::Hip)] -= 0.3;
    let mut peak_m: f64 = 0.0;
    for _ in 0..150 {
        let u = pd(&s, &target, 300.0, 4.0);
        s.step(&u, 1e-3).unwrap();
        peak_m = peak_m.max(s.foot_position_m(Side::Right)[1]);
    }
    assert!(s.events().iter().any(|e| matches!(
        e,
        SimEvent::Liftoff {
            side: Side::Right,
            ..
        }
    )));
    assert!(peak_m > 0.02, "right foot rose only {peak_m} m");
    assert!(s.in_stance(Side::Left));
    assert!(s.max_penetration_m() <= PENETRATION_TOLERANCE_M);
}

#[test]
fn stance_feet_stay_on_their_anchors() {
    let mut s = sim();
    let target = joints(&s);
    let anchors = [Side::Left, Side::Right].map(|side| s.contact(side));
    for _ in 0..1000 {
        let u = pd(&s, &target, 300.0, 4.0);
        s.step(&u, 1e-3).unwrap();
    }
    for (i, side) in [Side::Left, Side::Right].into_iter().enumerate() {
        assert_eq!(s.contact(side), anchors[i]);
        let Contact::Stance { anchor_xz_m } = anchors[i] else {
            panic!("not in stance")
        };
        let p = s.foot_position_m(side);
        assert!(
            (p[0] - anchor_xz_m[0]).abs() < 1e-9 && p[1].abs() < 1e-9,
            "{p:?}"
        );
    }
}

#[test]
fn treadmill_carries_the_stance_feet_backwards_at_belt_speed() {
    let config = RobotSimConfig {
        belt_speed_mps: 0.5,
        ..RobotSimConfig::default()
    };
    let mut s = RobotSim::new(&adam(), config).unwrap();
    let target = joints(&s);
    let x0 = s.foot_position_m(Side::Left)[0];
    let b0 = s.base_position_m()[0];
    for _ in 0..1000 {
        let u = pd(&s, &target, 300.0, 4.0);
        s.step(&u, 1e-3).unwrap();
    }
    let t = s.time_s();
    assert!((t - 1.0).abs() < 1e-9);
    assert!((s.foot_position_m(Side::Left)[0] - (x0 - 0.5 * t)).abs() < 1e-9);
    // Standing still on the belt: the base rides along (within the PD's sway).
    assert!((s.base_position_m()[0] - (b0 - 0.5)).abs() < 5e-3);
    assert!((s.base_velocity_mps()[0] + 0.5).abs() < 1e-2);
}

#[test]
fn boom_adds_its_mass_to_the_torso() {
    let boom = Boom {
        mass_kg: 2.0,
        com_xz_m: [0.0, 0.1],
        inertia_yy_kgm2: 0.3,
    };
    let plain = sim();
    let config = RobotSimConfig {
        boom: Some(boom),
        ..RobotSimConfig::default()
    };
    let with = RobotSim::new(&adam(), config).unwrap();
    let dm = with.model().total_mass_kg() - plain.model().total_mass_kg();
    assert!((dm - 2.0).abs() < 1e-12);
    assert!(
        with.model().bodies[0].inertia.inertia_yy_kgm2
            > plain.model().bodies[0].inertia.inertia_yy_kgm2 + 0.3
    );
    let bad = RobotSimConfig {
        boom: Some(Boom {
            mass_kg: -1.0,
            ..boom
        }),
        ..RobotSimConfig::default()
    };
    let e = RobotSim::new(&adam(), bad).unwrap_err();
    assert!(e.to_string().contains("boom.mass_kg"), "{e}");
}

#[test]
fn flight_conserves_energy() {
    // Zero torque, no contact, no gravity (a tumbling robot): semi-implicit Euler at 10 kHz is
    // symplectic, so the energy error stays an O(h) oscillation: within 0.1 % over 1 s.
    let mut m = adam();
    m.gravity_mps2 = 0.0;
    let mut s = RobotSim::new(&m, RobotSimConfig::default()).unwrap();
    let mut q = s.q().to_vec();
    q[1] += 1.0;
    let mut dq = vec![0.0; q.len()];
    dq[2] = 2.0;
    dq[s.model().joints[s.model().legs().unwrap().left.knee].coordinate] = 3.0;
    dq[s.model().joints[s.model().legs().unwrap().right.hip].coordinate] = -2.0;
    s.set_state(&q, &dq).unwrap();
    let e0 = s.kinetic_energy_j();
    let mut worst: f64 = 0.0;
    for _ in 0..1000 {
        s.step(&[0.0; 4], 1e-3).unwrap();
        worst = worst.max((s.kinetic_energy_j() - e0).abs());
    }
    assert!(!s.in_stance(Side::Left) && !s.in_stance(Side::Right));
    println!("flight: worst |ΔE| {worst:.2e} J of {e0:.3} J");
    assert!(worst < 1e-3 * e0, "{worst} J");
}

#[test]
fn imu_reads_gravity_at_rest_and_needs_attaching() {
    let mut s = sim();
    let target = joints(&s);
    let ff = s.static_torques_nm().unwrap();
    let mut sample = ImuSample::default();
    assert!(s.read(&mut sample).is_err());
    s.attach_imu(ImuNoise::NONE, 1);
    for _ in 0..500 {
        let u = pd_ff(&s, &target, &ff, 300.0, 4.0);
        s.step(&u, 1e-3).unwrap();
    }
    s.read(&mut sample).unwrap();
    assert!((sample.accel_z_mps2 - 9.81).abs() < 0.05, "{sample:?}");
    assert!(sample.accel_x_mps2.abs() < 0.05, "{sample:?}");
    assert!(sample.gyro_pitch_rad_s.abs() < 0.01, "{sample:?}");
    // Pitched torso: gravity appears on the torso x axis as g·sin(pitch), sign by rotation.
    let mut q = s.q().to_vec();
    q[1] += 0.5;
    q[2] = 0.3;
    let dq = vec![0.0; q.len()];
    s.set_state(&q, &dq).unwrap();
    s.step(&[0.0; 4], 1e-3).unwrap();
    s.read(&mut sample).unwrap();
    // Free fall: the specific force is zero (no contact) up to the leg reaction torques = 0.
    assert!(
        sample.accel_x_mps2.abs() < 0.5 && sample.accel_z_mps2.abs() < 0.5,
        "{sample:?}"
    );
}

#[test]
fn same_seed_gives_bit_identical_runs() {
    let run = |imu_seed: u64| {
        let mut s = sim();
        s.attach_imu(ImuNoise::default(), imu_seed);
        let target = joints(&s);
        let order = s.leg_motors(0, 1);
        let mut bus = bus_over(s, 9);
        let mut replies: Vec<Reply> = order.iter().map(|m| Reply::zeroed(m.spec.id)).collect();
        let mut trace = Vec::new();
        let mut sample = ImuSample::default();
        for k in 0..400 {
            // A swaying target so that contacts and forces change.
            let sway = 0.1 * (k as f64 * 0.02).sin();
            let commands: Vec<Command> = order
                .iter()
                .map(|m| Command::pd(m.spec.id, target[m.joint] + sway, 0.0, 200.0, 3.0, 0.0))
                .collect();
            bus.exchange(&commands, &mut replies, PERIOD).unwrap();
            bus.plant_mut().read(&mut sample).unwrap();
            trace.extend(bus.plant().q().iter().map(|v| v.to_bits()));
            trace.push(sample.gyro_pitch_rad_s.to_bits());
            trace.push(sample.accel_x_mps2.to_bits());
        }
        trace
    };
    let a = run(1);
    assert_eq!(a, run(1));
    assert_ne!(a, run(2));
}

/// World velocity of the centre of mass, m/s (the belt-frame velocity by a finite difference).
fn com_velocity_mps(s: &RobotSim) -> [f64; 2] {
    let eps = 1e-7;
    let q1: Vec<f64> = s.q().iter().zip(s.dq()).map(|(q, v)| q + eps * v).collect();
    let c0 = s.model().center_of_mass(s.q()).unwrap();
    let c1 = s.model().center_of_mass(&q1).unwrap();
    [
        (c1[0] - c0[0]) / eps - s.belt_speed_mps(),
        (c1[1] - c0[1]) / eps,
    ]
}

#[test]
fn a_push_in_flight_changes_the_momentum_by_its_impulse() {
    // No gravity, no contact: the only external force is the push at the hip axis, so the
    // centre of mass gains Δv = F·d / M whatever the body rotates.
    let mut m = adam();
    m.gravity_mps2 = 0.0;
    let mut s = RobotSim::new(&m, RobotSimConfig::default()).unwrap();
    let mut q = s.q().to_vec();
    q[1] += 1.0;
    s.set_state(&q, &vec![0.0; q.len()]).unwrap();
    let mass = s.model().total_mass_kg();
    let (force, duration) = ([30.0, -12.0], 0.2);
    s.push(force, duration).unwrap();
    for _ in 0..300 {
        s.step(&[0.0; 4], 1e-3).unwrap();
    }
    let v = com_velocity_mps(&s);
    for k in 0..2 {
        let dv = force[k] * duration / mass;
        // The push acts on whole 0.1 ms sim steps (one step more or less in 0.2 s is 5e-4),
        // and semi-implicit Euler conserves momentum only to O(h) on rotating bodies: 2e-3.
        assert!(
            (v[k] - dv).abs() < 2e-3 * dv.abs(),
            "axis {k}: {} vs {dv}",
            v[k]
        );
    }
    assert!(s.push([f64::NAN, 0.0], 0.1).is_err());
}

#[test]
fn a_belt_step_carries_the_stance_feet_at_the_new_speed() {
    let mut s = sim();
    let target = joints(&s);
    for _ in 0..200 {
        let u = pd(&s, &target, 300.0, 4.0);
        s.step(&u, 1e-3).unwrap();
    }
    let com_v = |s: &RobotSim| com_velocity_mps(s)[0];
    let v_before = com_v(&s);
    s.set_belt_speed(0.3).unwrap();
    // The impulse through the pinned feet drags the robot back, by less than the step (the
    // legs give way: the torso keeps part of its world velocity).
    let v_after = com_v(&s);
    println!("belt step 0 → 0.3 m/s: CoM world velocity {v_before:+.4} → {v_after:+.4} m/s");
    assert!(
        v_after < v_before && v_after > v_before - 0.3,
        "{v_before} → {v_after}"
    );
    assert!(s.in_stance(Side::Left) && s.in_stance(Side::Right));
    let x0 = s.foot_position_m(Side::Left)[0];
    let t0 = s.time_s();
    for _ in 0..500 {
        let u = pd(&s, &target, 300.0, 4.0);
        s.step(&u, 1e-3).unwrap();
    }
    let dt = s.time_s() - t0;
    assert!(s.in_stance(Side::Left));
    assert!((s.foot_position_m(Side::Left)[0] - (x0 - 0.3 * dt)).abs() < 1e-9);
    assert!(s.set_belt_speed(f64::INFINITY).is_err());
}

#[test]
fn imu_faults_drop_spike_and_freeze_the_simulated_imu() {
    use drivers::imu::{ImuError, ImuFault};
    let mut s = sim();
    s.attach_imu(ImuNoise::default(), 3);
    let mut out = ImuSample::default();
    s.step(&[0.0; 4], 1e-3).unwrap();
    s.read(&mut out).unwrap();
    let held = out;
    s.set_imu_fault(ImuFault::Frozen);
    for _ in 0..3 {
        s.step(&[0.0; 4], 1e-3).unwrap();
        s.read(&mut out).unwrap();
        assert_eq!(out.gyro_pitch_rad_s, held.gyro_pitch_rad_s);
        assert_eq!(out.accel_z_mps2, held.accel_z_mps2);
    }
    s.set_imu_fault(ImuFault::Dropout);
    assert_eq!(s.read(&mut out), Err(ImuError::Timeout));
    s.set_imu_fault(ImuFault::Spike { gyro_rad_s: 100.0 });
    s.read(&mut out).unwrap();
    assert!(out.gyro_pitch_rad_s > 99.0);
    s.set_imu_fault(ImuFault::None);
    s.step(&[0.0; 4], 1e-3).unwrap();
    s.read(&mut out).unwrap();
    assert!(out.gyro_pitch_rad_s.abs() < 1.0 && out.gyro_pitch_rad_s != held.gyro_pitch_rad_s);
}
