//! The simulated treadmill's belt (`drivers::sim::robot`, "Treadmill"): a ramp acts on a
//! standing robot through its stance feet with the force that accelerates it, the feet ride
//! the belt, and a robot carried past an end of the belt has fallen off it.
#![allow(clippy::unwrap_used)]

use drivers::sim::plant::JointPlant;
use drivers::sim::robot::{BeltEnd, FallCause, RobotSim, RobotSimConfig};
use model::{PlanarModel, Side};

fn adam() -> PlanarModel {
    model::design::generate_model(&model::design::DesignLengths::ADAM)
        .unwrap()
        .0
}

/// One millisecond of joint PD (with the standing feed-forward) toward `target`.
fn hold(s: &mut RobotSim, target: &[f64], ff: &[f64]) {
    let u: Vec<f64> = (0..s.joint_count())
        .map(|j| 300.0 * (target[j] - s.position_rad(j)) - 4.0 * s.velocity_rad_s(j) + ff[j])
        .collect();
    s.step(&u, 1e-3).unwrap();
}

/// World x velocity of the centre of mass, m/s (the belt-frame velocity by a finite
/// difference, minus the belt's speed).
fn com_velocity_x_mps(s: &RobotSim) -> f64 {
    let eps = 1e-7;
    let q1: Vec<f64> = s.q().iter().zip(s.dq()).map(|(q, v)| q + eps * v).collect();
    let c0 = s.model().center_of_mass(s.q()).unwrap();
    let c1 = s.model().center_of_mass(&q1).unwrap();
    (c1[0] - c0[0]) / eps - s.belt_speed_mps()
}

#[test]
fn a_belt_ramp_drags_a_standing_robot_through_its_feet_by_its_momentum() {
    let mut s = RobotSim::new(&adam(), RobotSimConfig::default()).unwrap();
    let target: Vec<f64> = (0..s.joint_count()).map(|j| s.position_rad(j)).collect();
    let ff = s.static_torques_nm().unwrap();
    assert_eq!(s.position_on_belt_m(), 0.0);
    let mass_kg = s.model().total_mass_kg();
    s.set_belt_target_speed(0.3).unwrap();
    let foot0 = s.foot_position_m(Side::Left)[0];
    // Contact impulse over most of the ramp (0.3 m/s at 0.5 m/s²: 0.6 s).
    let mut impulse_ns = 0.0;
    let mut momentum0 = 0.0;
    let mut travel_m = 0.0;
    for k in 0..1500 {
        let v0 = s.belt_speed_mps();
        hold(&mut s, &target, &ff);
        travel_m += 0.5 * (v0 + s.belt_speed_mps()) * 1e-3;
        if k == 99 {
            momentum0 = mass_kg * com_velocity_x_mps(&s);
        }
        if (100..500).contains(&k) {
            let fx = s.contact_force_n(Side::Left)[0] + s.contact_force_n(Side::Right)[0];
            impulse_ns += fx * 1e-3;
        }
        if k == 499 {
            // In the world the belt is the only horizontal force on the robot: its impulse
            // is the change of momentum (to the 1 ms sampling of the force), and the robot
            // is dragged backwards.
            let dp = mass_kg * com_velocity_x_mps(&s) - momentum0;
            println!("ramp 0.5 m/s², 0.1–0.5 s: contact impulse {impulse_ns:.4} N·s, Δp {dp:.4} N·s, −M·a·t {:.4}", -mass_kg * 0.5 * 0.4);
            assert!(
                (impulse_ns - dp).abs() < 0.03 * dp.abs(),
                "{impulse_ns} vs {dp}"
            );
            assert!(dp < -0.5 * mass_kg * 0.5 * 0.4, "{dp}");
        }
        // The ramp: 0.5 m/s² until 0.3 m/s.
        let expected = (0.5 * s.time_s()).min(0.3);
        assert!((s.belt_speed_mps() - expected).abs() < 1e-9, "{k}");
        // The stance foot rides the belt: world x = start − belt travel.
        let x = s.foot_position_m(Side::Left)[0];
        assert!(
            (x - (foot0 - travel_m)).abs() < 1e-9,
            "{k}: {x} vs {foot0} − {travel_m}"
        );
    }
    // After the ramp, standing still on the belt: the hip rides along at the belt's speed.
    assert_eq!(s.belt_target_speed_mps(), 0.3);
    let v = s.base_velocity_mps()[0];
    assert!((v + 0.3).abs() < 0.05, "hip {v} m/s");
    assert!(s.position_on_belt_m() < -0.2, "{}", s.position_on_belt_m());
    assert!(s.set_belt_target_speed(f64::NAN).is_err());
}

#[test]
fn a_robot_carried_past_the_back_end_has_fallen_off_the_belt() {
    let config = RobotSimConfig {
        belt_speed_mps: 0.5,
        ..RobotSimConfig::default()
    };
    let mut s = RobotSim::new(&adam(), config).unwrap();
    assert_eq!(s.belt_length_m(), 1.6);
    let target: Vec<f64> = (0..s.joint_count()).map(|j| s.position_rad(j)).collect();
    let ff = s.static_torques_nm().unwrap();
    // The rear foot stands 0.08 m behind the hip: it reaches the back end (0.8 m behind the
    // centre) when the hip is 0.72 m back, after 0.72 / 0.5 = 1.44 s.
    for _ in 0..2000 {
        hold(&mut s, &target, &ff);
        if s.fallen().is_some() {
            break;
        }
    }
    let fall = s.fall_record().expect("fell off the belt");
    assert_eq!(fall.what, FallCause::OffBelt(BeltEnd::Back));
    assert_eq!(fall.what.to_string(), "off the back of the belt");
    assert!((fall.t_s - 1.44).abs() < 0.02, "{fall:?}");
    assert!((fall.position_on_belt_m + 0.72).abs() < 0.01, "{fall:?}");

    // An endless belt carries it on.
    let config = RobotSimConfig {
        belt_length_m: f64::INFINITY,
        ..config
    };
    let mut s = RobotSim::new(&adam(), config).unwrap();
    for _ in 0..2000 {
        hold(&mut s, &target, &ff);
    }
    assert_eq!(s.fallen(), None);
    assert!(s.position_on_belt_m() < -0.9);
    // A belt of no length is refused by name.
    let bad = RobotSimConfig {
        belt_length_m: 0.0,
        ..RobotSimConfig::default()
    };
    let e = RobotSim::new(&adam(), bad).unwrap_err().to_string();
    assert!(e.contains("belt_length_m") && e.contains('0'), "{e}");
}
