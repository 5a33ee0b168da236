//! The step lean, the disturbance settle's command and the step's length measured again after
//! the impact (`runtime::control::speed`, "The step lean", "The step's length").

use super::*;

/// The treadmill config's lean: 0.2 rad/(m/s) after a fast step, 0.1 after a slow one, in full
/// from σ = 0.22 m/s, none below 0.16, at most 6 mrad; no other feedback in the way.
fn lean_config() -> SpeedConfig {
    SpeedConfig {
        position_gain_per_s: 0.0,
        speed_gain: 0.0,
        integral_gain: 0.0,
        step_length_gain_s: 0.0,
        slow_step_length_gain_s: 0.0,
        step_lean_gain_rad_per_mps: 0.2,
        slow_step_lean_gain_rad_per_mps: 0.1,
        step_lean_from_mps: 0.16,
        step_lean_full_mps: 0.22,
        max_step_lean_rad: 0.006,
        integral_delay_steps: 2,
        ..SpeedConfig::default()
    }
}

/// A regulator walking σ = 0.25 on a 0.25 m/s belt, past the first steps' rest.
fn walking(config: &SpeedConfig) -> SpeedRegulator {
    walking_at(config, 0.25)
}

/// A regulator walking σ = `belt_mps` on a belt at that speed, past the first steps' rest.
fn walking_at(config: &SpeedConfig, belt_mps: f64) -> SpeedRegulator {
    let mut r = SpeedRegulator::new(config, belt_mps);
    assert!(r.operator(
        OperatorCommand::Belt {
            speed_mps: belt_mps
        },
        false
    ));
    for _ in 0..config.integral_delay_steps {
        step(&mut r, 1.1 * belt_mps);
        assert_eq!(r.status.step_lean_rad, 0.0, "rests in the first steps");
    }
    step(&mut r, belt_mps);
    r
}

/// One 0.7 s step at `v` m/s, the robot put back at the centre.
fn step(r: &mut SpeedRegulator, v: f64) -> f64 {
    r.status.position_m = 0.0;
    r.belt_travel_m = v * 0.7;
    r.on_impact(v * 0.7, 0.7, (0.125, 0.40))
}

#[test]
fn a_fast_step_leans_the_next_back_a_slow_one_forward_within_the_limit() {
    let config = lean_config();
    let mut r = walking(&config);
    step(&mut r, 0.26);
    let fast = 0.26 - r.status.commanded_mps;
    assert!(fast > 0.0);
    assert!(
        (r.status.step_lean_rad + 0.2 * fast).abs() < 1e-12,
        "{}",
        r.status.step_lean_rad
    );
    step(&mut r, 0.24);
    let slow = 0.24 - r.status.commanded_mps;
    assert!((r.status.step_lean_rad + 0.1 * slow).abs() < 1e-12);
    assert!(r.status.step_lean_rad > 0.0);
    // 0.1 m/s too fast asks 20 mrad: held at 6.
    step(&mut r, 0.35);
    assert_eq!(r.status.step_lean_rad, -config.max_step_lean_rad);
}

#[test]
fn the_lean_fades_with_the_gait_below_its_full_speed() {
    let config = lean_config();
    // σ = 0.19 m/s: halfway between 0.16 and 0.22, half the gain after a slow step.
    let mut r = walking_at(&config, 0.19);
    step(&mut r, 0.185);
    let sigma = r.status.library_mps;
    let share = ((sigma - 0.16) / 0.06).clamp(0.0, 1.0);
    assert!(share > 0.0 && share < 1.0, "σ = {sigma}");
    let slow = 0.185 - r.status.commanded_mps;
    assert!(slow < 0.0);
    assert!((r.status.step_lean_rad + share * 0.1 * slow).abs() < 1e-12);
    assert!((share - 0.5).abs() < 0.05, "share {share}");
    // On the slowest gaits a slow step leans nothing ...
    let mut r = walking_at(&config, 0.13);
    step(&mut r, 0.125);
    assert!(r.status.library_mps < 0.16);
    assert_eq!(r.status.step_lean_rad, 0.0);
    // ... nor a step a little fast; but a step as fast as a faster gait walks leans back
    // as that gait would: 0.18 m/s is σ = 0.18 here (no calibration), a third of the gain.
    step(&mut r, 0.14);
    assert_eq!(r.status.step_lean_rad, 0.0);
    step(&mut r, 0.18);
    let fast = 0.18 - r.status.commanded_mps;
    let expected = -(1.0 / 3.0) * 0.2 * fast;
    assert!(expected > -config.max_step_lean_rad);
    assert!(
        (r.status.step_lean_rad - expected).abs() < 1e-12,
        "{}",
        r.status.step_lean_rad
    );
}

#[test]
fn the_lean_rests_while_sigma_slews_to_a_new_belt_and_in_a_stop() {
    let config = lean_config();
    let mut r = walking(&config);
    // The belt steps down by 0.1 m/s: σ comes down 0.02 m/s a step, no lean on the way.
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.15 }, true));
    let before = r.status.library_mps;
    step(&mut r, 0.25);
    assert!((before - r.status.library_mps - config.max_change_per_step_mps).abs() < 1e-12);
    assert_eq!(r.status.step_lean_rad, 0.0);
    // A Stop's approach on a moving belt: no lean either (without one the step under way
    // ends and the braking step follows, which never leans).
    let config = SpeedConfig {
        stop_ahead_m: 0.35,
        ..config
    };
    let mut r = walking(&config);
    r.begin_stop();
    assert!(r.stopping());
    step(&mut r, 0.27);
    assert_eq!(r.status.step_lean_rad, 0.0);
}

#[test]
fn a_disturbance_settle_never_raises_the_command_and_does_not_renew_itself() {
    let config = SpeedConfig {
        disturbance_settle_mps: 0.13,
        disturbance_settle_steps: 4,
        ..lean_config()
    };
    let mut r = walking(&config);
    // A pushed step at 0.45 m/s: the command follows the robot, less 0.02 m/s ...
    step(&mut r, 0.45);
    assert!((r.status.requested_mps - 0.43).abs() < 1e-12);
    // ... then never up again, however fast the next steps are ...
    let mut last = r.status.requested_mps;
    for _ in 0..3 {
        step(&mut r, 0.6);
        assert!(
            r.status.requested_mps <= last,
            "{} > {last}",
            r.status.requested_mps
        );
        last = r.status.requested_mps;
    }
    // ... and the settle ends after its steps: a robot still that fast is no longer a push,
    // the position loop's command again.
    step(&mut r, 0.6);
    assert!(
        (r.status.requested_mps - 0.25).abs() < 1e-12,
        "{}",
        r.status.requested_mps
    );
    // A new push after a step near the belt starts a new settle.
    step(&mut r, 0.25);
    step(&mut r, 0.45);
    assert!((r.status.requested_mps - 0.43).abs() < 1e-12);
}

#[test]
fn a_step_measured_again_after_the_impact_moves_the_position_and_the_stride() {
    let config = lean_config();
    let mut r = walking(&config);
    // Two steps of 0.175 m in 0.7 s at the belt's travel: the position stays at 0.
    step(&mut r, 0.25);
    let before = r.status;
    r.correct_step_length(0.0006);
    assert!((r.status.position_m - before.position_m - 0.0006).abs() < 1e-15);
    assert!((r.status.step_length_m - 0.1756).abs() < 1e-12);
    assert!((r.status.step_speed_mps - 0.1756 / 0.7).abs() < 1e-12);
    assert_eq!(
        r.previous_step.map(|(l, _)| l),
        Some(r.status.step_length_m)
    );
    // The next step's gait, chosen at the impact, stays.
    assert_eq!(r.status.library_mps, before.library_mps);
    // More than a centimetre, or not finite: not a measurement, ignored.
    let kept = r.status;
    r.correct_step_length(0.011);
    r.correct_step_length(f64::NAN);
    assert_eq!(r.status, kept);
}
