//! The regulator's law: the position loop, the integral, the step lever, the stop and the
//! belt's start (`runtime::control::speed`).

use super::*;

fn regulator(config: &SpeedConfig) -> SpeedRegulator {
    let mut r = SpeedRegulator::new(config, 0.25);
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }, false));
    r
}

#[test]
fn position_integrates_steps_against_the_belt_and_pulls_the_command_back() {
    let config = SpeedConfig {
        position_gain_per_step: 0.0,
        ..SpeedConfig::default()
    };
    let mut r = regulator(&config);
    for k in 0..=800 {
        r.advance(k as f64 * 1e-3);
    }
    // 0.8 s of belt at 0.25 m/s is 0.2 m; a 0.24 m step puts the robot 4 cm forward.
    let sigma = r.on_impact(0.24, 0.8, (0.15, 0.35));
    assert!((r.status.position_m - 0.04).abs() < 1e-9);
    // Forward of the centre: the command is below the belt speed by k_p·p ...
    let command = 0.25 - config.position_gain_per_s * 0.04;
    assert!((r.status.commanded_mps - command).abs() < 1e-9);
    // ... the library gait follows the command (no stride measured against a command yet,
    // so no error, no integral) ...
    assert!((sigma - command).abs() < 1e-12, "σ = {sigma}");
    // ... and the step was faster than the command: the next one lands longer.
    let offset = config.step_length_gain_s * (0.3 - command);
    assert!(offset > 0.0);
    assert!((r.status.step_offset_m - offset).abs() < 1e-12);
}

#[test]
fn the_position_gain_per_step_pulls_by_it_over_the_mean_step_duration() {
    let config = SpeedConfig {
        position_gain_per_step: 0.17,
        ..SpeedConfig::default()
    };
    let mut r = regulator(&config);
    // Two steps of 0.6 and 0.8 s, the robot 0.1 m behind the centre after them.
    r.belt_travel_m = 0.15;
    r.on_impact(0.15, 0.6, (0.15, 0.35));
    r.belt_travel_m = 0.3;
    r.on_impact(0.2, 0.8, (0.15, 0.35));
    assert!((r.status.position_m + 0.1).abs() < 1e-12);
    let k_p = config.position_gain_per_step / 0.7;
    assert!(
        (r.status.requested_mps - (0.25 + k_p * 0.1)).abs() < 1e-12,
        "{}",
        r.status.requested_mps
    );
    // Slower steps, a smaller gain per second: one of 1.0 s after 1.0 s.
    let mut r = regulator(&config);
    r.belt_travel_m = 0.25;
    r.on_impact(0.25, 1.0, (0.15, 0.35));
    r.belt_travel_m = 0.35;
    r.on_impact(0.25, 1.0, (0.15, 0.35));
    let k_p = config.position_gain_per_step / 1.0;
    assert!((r.status.requested_mps - (0.25 + k_p * 0.1)).abs() < 1e-12);
}

#[test]
fn a_slow_stride_raises_the_next_gait_by_the_speed_gain() {
    let config = SpeedConfig {
        speed_gain: 0.5,
        integral_gain: 0.0,
        ..SpeedConfig::default()
    };
    let mut r = regulator(&config);
    // The first step sets the command; the second, 0.05 m/s slow (the stride 0.025 m/s
    // slow), with the robot put back at the centre: σ = v_cmd + k_s·0.025.
    r.belt_travel_m = 0.2;
    r.on_impact(0.2, 0.8, (0.15, 0.35));
    r.status.position_m = 0.0;
    r.belt_travel_m = 0.16;
    let sigma = r.on_impact(0.16, 0.8, (0.15, 0.35));
    assert!((sigma - (0.25 + 0.5 * 0.025)).abs() < 1e-12, "σ = {sigma}");
}

#[test]
fn the_integral_removes_a_steady_bias() {
    let mut r = regulator(&SpeedConfig::default());
    r.on_impact(f64::NAN, 0.0, (0.15, 0.35));
    r.status.position_m = 0.0;
    // Each step walks 0.02 m/s slower than the gait it was given (a bias), the belt
    // travel matched to the step so the position stays put.
    let mut sigma = 0.25;
    for _ in 0..80 {
        let v = sigma - 0.02;
        r.belt_travel_m = v * 0.8;
        sigma = r.on_impact(v * 0.8, 0.8, (0.15, 0.35));
    }
    // The command settles where the robot walks the belt speed: σ = 0.27, the bias.
    assert!((sigma - 0.27).abs() < 1e-3, "σ = {sigma}");
    assert!((r.status.integral_mps - 0.02).abs() < 1e-3);
}

#[test]
fn a_fast_step_lands_the_next_step_longer_within_the_limit() {
    let config = SpeedConfig::default();
    let mut r = regulator(&config);
    // Without a step measured: the gait's own step.
    r.on_impact(f64::NAN, 0.0, (0.15, 0.35));
    assert_eq!(r.status.step_offset_m, 0.0);
    // A step at 0.28 m/s on a 0.25 m/s belt, the robot at the centre: 0.03 m/s fast.
    r.status.position_m = 0.0;
    r.belt_travel_m = 0.224;
    r.on_impact(0.224, 0.8, (0.15, 0.35));
    assert_eq!(r.status.commanded_mps, 0.25);
    let expected = config.step_length_gain_s * 0.03;
    assert!(expected > 0.0 && expected < config.max_step_offset_m);
    assert!(
        (r.status.step_offset_m - expected).abs() < 1e-9,
        "{:?}",
        r.status
    );
    // A very fast one: at most the limit.
    r.status.position_m = 0.0;
    r.on_impact(0.4, 0.5, (0.15, 0.35));
    assert_eq!(r.status.step_offset_m, config.max_step_offset_m);
    // A restart forgets it.
    r.restart();
    assert_eq!(r.status.step_offset_m, 0.0);
}

/// A regulator at the centre of a 0.25 m/s belt after a first step and then a 0.16 m step
/// in 0.8 s (0.2 m/s, slow), the belt's travel matched so the position stays put.
fn after_a_slow_step(config: &SpeedConfig) -> SpeedRegulator {
    let mut r = regulator(config);
    r.on_impact(f64::NAN, 0.0, (0.15, 0.35));
    r.status.position_m = 0.0;
    r.belt_travel_m = 0.16;
    r.on_impact(0.16, 0.8, (0.15, 0.35));
    r
}

#[test]
fn after_a_slow_step_the_lever_takes_its_slow_side_gain() {
    // None: no shorter step after a slow one.
    let config = SpeedConfig {
        slow_step_length_gain_s: 0.0,
        ..SpeedConfig::default()
    };
    let r = after_a_slow_step(&config);
    assert_eq!(r.status.commanded_mps, 0.25);
    assert_eq!(r.status.step_offset_m, 0.0);
    // With a slow-side gain: shorter by it, at most the limit.
    let config = SpeedConfig {
        slow_step_length_gain_s: 0.5,
        ..SpeedConfig::default()
    };
    let mut r = after_a_slow_step(&config);
    let expected = 0.5 * (0.2 - 0.25);
    assert!(expected < 0.0);
    assert!((r.status.step_offset_m - expected).abs() < 1e-12);
    r.status.position_m = 0.0;
    r.on_impact(0.01, 2.0, (0.15, 0.35));
    assert_eq!(r.status.step_offset_m, -config.max_step_offset_m);
}

/// A calibration in which every gait walks 20 % faster than its library speed.
struct Fast;
impl SpeedMap for Fast {
    fn sigma_for(&self, walked_mps: f64) -> f64 {
        walked_mps / 1.2
    }
    fn walked_at(&self, sigma_mps: f64) -> f64 {
        1.2 * sigma_mps
    }
}

#[test]
fn with_a_calibration_the_regulator_asks_for_the_gait_that_walks_the_command() {
    let config = SpeedConfig {
        integral_gain: 0.0,
        ..SpeedConfig::default()
    };
    let mut r = regulator(&config);
    r.status.library_mps = 0.21;
    // At the centre, a step at the belt's speed: the command is the belt's 0.25 m/s and σ
    // the gait that walks it, 0.25 / 1.2.
    r.belt_travel_m = 0.2;
    let sigma = r.on_impact_mapped(0.2, 0.8, (0.15, 0.35), &Fast);
    assert_eq!(r.status.commanded_mps, 0.25);
    assert!((sigma - 0.25 / 1.2).abs() < 1e-12, "σ = {sigma}");
    // A belt faster than the fastest gait walks (0.42 m/s): the command stops there.
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.5 }, false));
    r.on_impact_mapped(0.2, 0.8, (0.15, 0.35), &Fast);
    assert!(r.status.clamped);
    assert!((r.status.commanded_mps - 0.42).abs() < 1e-12);
}

#[test]
fn a_walk_started_on_its_plan_keeps_its_gait_until_the_steps_show_the_creep() {
    let config = SpeedConfig {
        start_on_plan: true,
        ..SpeedConfig::default()
    };
    // Begun in the 0.25 m/s gait's own state on a 0.25 m/s belt: the integral starts at what
    // the calibration says that gait walks over its plan, 1.2 · 0.25 − 0.25 = 0.05 m/s ...
    let mut r = regulator(&config);
    r.restart_on(0.25, &Fast);
    assert!((r.status.integral_mps - 0.05).abs() < 1e-12);
    // ... so a first step at the plan's speed, at the centre, keeps the gait it started on
    // (without the option: the gait that walks 0.25 m/s after the creep, 0.25 / 1.2).
    r.belt_travel_m = 0.2;
    let sigma = r.on_impact_mapped(0.2, 0.8, (0.15, 0.35), &Fast);
    assert!((sigma - 0.25).abs() < 1e-12, "σ = {sigma}");
    // The steps then walk faster than the command (the creep shows): the integral takes it
    // up by k_i times the stride's error each step, and σ comes down with it.
    let mut integral = r.status.integral_mps;
    let mut previous_m = 0.2;
    for _ in 0..5 {
        r.status.position_m = 0.0;
        r.belt_travel_m = 0.2;
        let (before, command) = (r.status.library_mps, r.status.commanded_mps);
        r.on_impact_mapped(0.22, 0.8, (0.15, 0.35), &Fast);
        // The error of the stride (this step and the one before) against its command.
        let error = command - (previous_m + 0.22) / 1.6;
        previous_m = 0.22;
        assert!(error < 0.0);
        assert!((r.status.integral_mps - (integral + config.integral_gain * error)).abs() < 1e-12);
        assert!(r.status.library_mps < before);
        integral = r.status.integral_mps;
    }
    // Off, or with no calibration, the walk starts with no integral.
    for (start_on_plan, restart_on) in [(false, true), (true, false)] {
        let config = SpeedConfig {
            start_on_plan,
            ..SpeedConfig::default()
        };
        let mut r = regulator(&config);
        if restart_on {
            r.restart_on(0.25, &Fast);
        } else {
            r.restart_on(0.25, &Uncalibrated);
        }
        assert_eq!(r.status.integral_mps, 0.0);
    }
    // The integral's limit holds: 0.4 m/s walks 0.48, 0.08 over, limited to 0.05.
    let config = SpeedConfig {
        start_on_plan: true,
        integral_limit_mps: 0.05,
        ..SpeedConfig::default()
    };
    let mut r = regulator(&config);
    r.restart_on(0.4, &Fast);
    assert_eq!(r.status.integral_mps, 0.05);
}

/// The treadmill config's start and restart settings.
fn start_config() -> SpeedConfig {
    SpeedConfig {
        first_step_unlimited: true,
        position_from_start: true,
        integral_delay_steps: 2,
        belt_start_settle_steps: 2,
        reference_glide_mps: 0.02,
        stop_ahead_m: 0.35,
        stop_approach_mps: 0.12,
        stop_library_mps: 0.21,
        ..SpeedConfig::default()
    }
}

#[test]
fn a_walk_from_stand_keeps_the_belt_travel_and_its_first_impact_jumps_to_the_command() {
    let mut r = SpeedRegulator::new(&start_config(), 0.15);
    r.at_start();
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }, false));
    // Standing 1 s on the belt: 0.25 m back, kept at Walk.
    for k in 0..=1000 {
        r.advance(f64::from(k) * 1e-3);
    }
    r.restart_from_stand();
    r.belt_travel_m += 0.25;
    // The launch and first step: 0.15 m while the belt ran 0.25 m.
    let sigma = r.on_impact(0.15, 1.0, (0.15, 0.40));
    assert!((r.status.position_m + 0.35).abs() < 1e-9, "{:?}", r.status);
    // Behind the centre: the command is above the belt's, and σ goes there at once.
    assert!(r.status.commanded_mps > 0.3);
    assert!(
        (sigma - r.status.commanded_mps).abs() < 1e-12,
        "σ = {sigma}"
    );
    // Then limited again; the integral rests for the first impacts.
    let before = r.status.library_mps;
    r.belt_travel_m = 0.1;
    let sigma = r.on_impact(0.1, 1.0, (0.15, 0.40));
    assert!((sigma - before).abs() <= 0.02 + 1e-12);
    assert_eq!(r.status.integral_mps, 0.0);
    // A walk from the gait's own state forgets the position and is limited from the start.
    r.restart();
    assert_eq!(r.status.position_m, 0.0);
    let last = r.status.library_mps;
    let sigma = r.on_impact(0.15, 1.0, (0.15, 0.40));
    assert!(
        (sigma - (last - 0.02)).abs() < 1e-12,
        "σ = {sigma} after {last}"
    );
}

#[test]
fn after_a_pushed_step_the_command_follows_the_robot_down_then_the_reference_glides_back() {
    let config = SpeedConfig {
        disturbance_settle_mps: 0.13,
        disturbance_settle_steps: 2,
        speed_gain: 0.0,
        ..start_config()
    };
    let mut r = regulator(&config);
    r.belt_travel_m = 0.2;
    r.on_impact(0.2, 0.8, (0.15, 0.40));
    // A step 0.12 m/s faster than the belt: within the threshold, the lever acts.
    r.belt_travel_m = 0.1;
    r.on_impact(0.185, 0.5, (0.15, 0.40));
    assert!(r.status.step_offset_m > 0.0 && r.status.requested_mps < 0.25);
    r.status.position_m = 0.0;
    r.status.integral_mps = 0.01;
    // A pushed step at 0.65 m/s: the command is its speed less 0.02 m/s, σ goes there at
    // once (the range's top), no lever, the integral at rest.
    let sigma = r.on_impact(0.26, 0.4, (0.15, 0.40));
    assert!((r.status.requested_mps - 0.63).abs() < 1e-12);
    assert_eq!(sigma, 0.40);
    assert_eq!(r.status.step_offset_m, 0.0);
    assert_eq!(r.status.integral_mps, 0.01);
    // The next, 0.30 m/s (within the threshold), the last of the 2 settling impacts: the
    // command follows it down, σ by the step limit; then the reference glides back.
    r.on_impact(0.15, 0.5, (0.15, 0.40));
    assert!((r.status.requested_mps - 0.28).abs() < 1e-12);
    assert!((r.status.library_mps - 0.38).abs() < 1e-12);
    r.belt_travel_m = 0.125;
    r.on_impact(0.125, 0.5, (0.15, 0.40));
    assert!(r.status.requested_mps < 0.25 && r.status.requested_mps > 0.24);
    // A slow step (a backward push, 0.1 m/s: 0.15 m/s below the belt's) starts no settle:
    // the position loop asks for more than the belt's speed; off (0) nothing settles.
    r.belt_travel_m = 0.125;
    r.on_impact(0.05, 0.5, (0.15, 0.40));
    assert_eq!((r.settle_left, r.disturbed), (0, false));
    assert!(r.status.requested_mps > 0.25, "{}", r.status.requested_mps);
    let mut r = regulator(&start_config());
    r.belt_travel_m = 0.2;
    r.on_impact(0.2, 0.8, (0.15, 0.40));
    r.belt_travel_m = 0.1;
    r.on_impact(0.26, 0.4, (0.15, 0.40));
    assert!(r.status.requested_mps < 0.25 && r.status.step_offset_m > 0.0);
}

#[test]
fn the_belt_started_under_the_walking_robot_is_ridden_out_then_the_reference_glides_back() {
    let mut r = SpeedRegulator::new(&start_config(), 0.15);
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.0 }, true));
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }, true));
    // A shoved step 0.2 m ahead: the command stays the belt's, no longer step.
    r.on_impact(0.2, 0.5, (0.15, 0.40));
    assert_eq!(r.status.requested_mps, 0.25);
    assert_eq!(r.status.step_offset_m, 0.0);
    r.on_impact(0.125, 0.5, (0.15, 0.40));
    assert_eq!(r.status.requested_mps, 0.25);
    // Then the reference glides back (0.02 m/s over a 0.5 s step): a small pull back.
    r.belt_travel_m = 0.125;
    r.on_impact(0.125, 0.5, (0.15, 0.40));
    assert!(r.status.requested_mps < 0.25 && r.status.requested_mps > 0.24);
    // A belt that changes speed while moving does not start it again.
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.30 }, true));
    assert_eq!(r.settle_left, 0);
}

#[test]
fn a_belt_change_while_walking_sets_the_next_gait_at_once_with_the_feed_forward() {
    let config = SpeedConfig {
        belt_change_unlimited_mps: 0.05,
        ..SpeedConfig::default()
    };
    let mut r = regulator(&config);
    r.status.integral_mps = 0.03;
    // A small change (0.02 m/s) and a change while not walking: limited as before.
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.27 }, true));
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.20 }, false));
    assert!(!r.unlimited_next);
    assert_eq!(r.status.integral_mps, 0.03);
    // The operator steps the belt 0.20 -> 0.30 m/s under the walking robot: the next impact
    // goes to the new belt's gait (at the centre) and the integral starts again.
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.30 }, true));
    assert_eq!(r.status.integral_mps, 0.0);
    r.status.library_mps = 0.20;
    r.belt_travel_m = 0.24;
    let sigma = r.on_impact(0.24, 0.8, (0.15, 0.40));
    assert!((sigma - 0.30).abs() < 1e-12, "σ = {sigma}");
    // Then limited again.
    r.belt_travel_m = 0.24;
    let before = r.status.library_mps;
    let sigma = r.on_impact(0.16, 0.8, (0.15, 0.40));
    assert!((sigma - before).abs() <= 0.02 + 1e-12, "σ = {sigma}");
    // A slow-down is limited (a jump down to a slow gait stalled).
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.20 }, true));
    assert!(!r.unlimited_next);
    // Off (0, the default): the same step is limited.
    let mut r = regulator(&SpeedConfig::default());
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.30 }, true));
    assert!(!r.unlimited_next);
}

#[test]
fn a_stop_on_a_moving_belt_walks_ahead_then_slows_then_brakes() {
    let mut r = regulator(&start_config());
    r.status.library_mps = 0.21;
    r.begin_stop();
    assert!(r.stopping() && !r.brake_now());
    // Approach: the belt's speed plus the approach speed, whatever the position loop says.
    r.belt_travel_m = 0.2;
    r.on_impact(0.2, 0.8, (0.15, 0.40));
    assert!((r.status.requested_mps - 0.37).abs() < 1e-12);
    assert!(!r.brake_now());
    // There (within 5 cm of 0.35 m ahead), on a fast gait: one slowing step at 0.21 ...
    r.status.library_mps = 0.33;
    r.status.position_m = 0.3;
    r.belt_travel_m = 0.2;
    let sigma = r.on_impact(0.2, 0.8, (0.15, 0.40));
    assert!((sigma - 0.21).abs() < 1e-12, "σ = {sigma}");
    assert!(!r.brake_now());
    // ... then the braking step.
    r.belt_travel_m = 0.2;
    r.on_impact(0.2, 0.8, (0.15, 0.40));
    assert!(r.brake_now());
    // Without the settings a Stop brakes at once.
    let mut r = regulator(&SpeedConfig::default());
    r.begin_stop();
    assert!(!r.stopping());
}

#[test]
fn commands_outside_the_library_are_clamped_and_flagged() {
    let config = SpeedConfig {
        position_gain_per_step: 0.0,
        ..SpeedConfig::default()
    };
    let mut r = regulator(&config);
    assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.5 }, false));
    let sigma = r.on_impact(0.2, 0.8, (0.15, 0.35));
    assert!(r.status.clamped);
    let k_p = config.position_gain_per_s;
    assert_eq!(r.status.requested_mps, 0.5 - k_p * r.status.position_m);
    assert_eq!(r.status.commanded_mps, 0.35);
    // ... and the library speed moves towards it by at most the step limit.
    assert!((sigma - 0.27).abs() < 1e-12, "σ = {sigma}");
    assert!(!r.operator(OperatorCommand::Walk, false));
    assert!(r.operator(OperatorCommand::Nudge { delta_mps: 0.025 }, false));
    assert!(r.operator(OperatorCommand::Nudge { delta_mps: 0.025 }, false));
    assert!((r.status.offset_mps - 0.05).abs() < 1e-15);
}
