//! The multi-rate simulator (`D`, `H`, their factor and the contact operator held for
//! `dynamics_refresh_substeps` steps, the default) against the exact path (everything evaluated
//! every step), both behind `SimBus` with the same seed: PD-held standing, and marching in place
//! with liftoffs and touchdowns. See `drivers::sim::robot`, "Multi-rate dynamics".
#![allow(clippy::unwrap_used)]

mod common;

use drivers::a1::Command;
use drivers::sim::plant::JointPlant;
use drivers::sim::robot::{RobotSimConfig, SimEvent, PENETRATION_TOLERANCE_M};

/// The state at one control tick: joints \[rad\], torso (x, z) \[m\] and pitch \[rad\].
struct Sample {
    joints_rad: Vec<f64>,
    torso_xz_m: [f64; 2],
    pitch_rad: f64,
}

/// 1.5 s at 1 kHz control (10 kHz firmware and plant), PD (300 N·m/rad, 4 N·m·s/rad) with
/// gravity feed-forward on the standing pose; marching flexes one knee by 0.35 rad for 0.15 s of
/// every 0.25 s from 0.25 s on, alternating. Every tick's sample and the touchdown count.
fn run(dynamics_refresh_substeps: u32, march: bool) -> (Vec<Sample>, usize) {
    let config = RobotSimConfig {
        dynamics_refresh_substeps,
        ..RobotSimConfig::default()
    };
    let mut rig = common::standing_rig(config, 3);
    let mut commands: Vec<Command> = Vec::with_capacity(4);
    let mut samples = Vec::with_capacity(1500);
    for k in 0..1500 {
        rig.stand_or_march(k, march, &mut commands);
        let p = rig.bus.plant();
        samples.push(Sample {
            joints_rad: (0..p.joint_count()).map(|j| p.position_rad(j)).collect(),
            torso_xz_m: p.base_position_m(),
            pitch_rad: p.torso_pitch_rad(),
        });
    }
    let bus = rig.bus;
    let p = bus.plant();
    assert!(p.fallen().is_none(), "{:?}", p.fallen());
    assert!(p.max_penetration_m() <= PENETRATION_TOLERANCE_M);
    let touchdowns = p
        .events()
        .iter()
        .filter(|e| matches!(e, SimEvent::Touchdown(_)))
        .count();
    (samples, touchdowns)
}

/// Largest joint \[rad\], torso position \[m\] and pitch \[rad\] difference over two runs.
fn worst_difference(a: &[Sample], b: &[Sample]) -> (f64, f64, f64) {
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        for (p, q) in x.joints_rad.iter().zip(&y.joints_rad) {
            worst.0 = worst.0.max((p - q).abs());
        }
        for (p, q) in x.torso_xz_m.iter().zip(&y.torso_xz_m) {
            worst.1 = worst.1.max((p - q).abs());
        }
        worst.2 = worst.2.max((x.pitch_rad - y.pitch_rad).abs());
    }
    worst
}

#[test]
fn multi_rate_dynamics_track_the_exact_path() {
    let held = RobotSimConfig::default().dynamics_refresh_substeps;
    assert!(held > 1, "the default holds the dynamics");
    // Standing is smooth, so the hold's own error shows: measured 4.5e-5° (joints), 9.6e-8 m
    // (torso), 2.8e-5° (pitch); bounded at 4 to 10 times that. Marching has touchdowns and
    // liftoffs, whose times shift by parts of a step under any perturbation: measured 0.034°,
    // 0.26 mm and 0.038°, the size of the exact path's own change when its step is halved
    // (0.028°, 0.18 mm, 0.032°); bounded by the 0.1° and 1 mm issue #5 asks for (and 0.15° of
    // pitch), 3.0, 3.8 and 3.9 times the measured. (With the Box–Muller encoder noise before the
    // Ziggurat: 0.054°, 0.29 mm and 0.054°; the halved step's 0.027°, 0.18 mm, 0.03°.)
    for (march, joint_deg, torso_m, pitch_deg) in
        [(false, 2e-4, 1e-6, 2e-4), (true, 0.1, 1e-3, 0.15)]
    {
        let (exact, touchdowns_exact) = run(1, march);
        let (fast, touchdowns_fast) = run(held, march);
        let (joint_rad, torso_diff_m, pitch_rad) = worst_difference(&exact, &fast);
        println!(
            "march {march}: worst differences: joints {:.2e}°, torso {torso_diff_m:.2e} m, \
             pitch {:.2e}°; touchdowns {touchdowns_exact} exact, {touchdowns_fast} held",
            joint_rad.to_degrees(),
            pitch_rad.to_degrees()
        );
        assert_eq!(touchdowns_exact, touchdowns_fast);
        if march {
            assert!(touchdowns_exact >= 4, "{touchdowns_exact} touchdowns");
        }
        assert!(joint_rad.to_degrees() < joint_deg, "march {march}");
        assert!(torso_diff_m < torso_m, "march {march}");
        assert!(pitch_rad.to_degrees() < pitch_deg, "march {march}");
    }
}
