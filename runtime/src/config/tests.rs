//! Tests of the runtime config (`super`): the shipped file, and each check naming its field.

#![allow(clippy::unwrap_used)]

use super::*;

fn shipped() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/runtime/adam.toml"
    ))
    .unwrap()
}

#[test]
fn shipped_config_loads_with_14_motors_on_valid_buses() {
    let c = RuntimeConfig::from_toml(&shipped(), "adam.toml").unwrap();
    assert_eq!(c.leg_motors.len() + c.held.len(), 14);
    assert_eq!(c.loop_.rate_hz, 1000.0);
}

#[test]
fn an_ignored_setting_is_named_with_its_value_and_what_replaced_it() {
    let c = RuntimeConfig::from_toml(&shipped(), "adam.toml").unwrap();
    assert!(
        c.ignored_settings().is_empty(),
        "{:?}",
        c.ignored_settings()
    );
    let old = shipped().replace("[safety]\n", "[safety]\nmax_step_duration_factor = 3.0\n");
    let c = RuntimeConfig::from_toml(&old, "old.toml").unwrap();
    assert_eq!(c.safety.max_step_duration_factor, Some(3.0));
    let ignored = c.ignored_settings();
    assert_eq!(ignored.len(), 1, "{ignored:?}");
    assert!(
        ignored[0].starts_with("safety.max_step_duration_factor = 3 is ignored")
            && ignored[0].contains("stall_timeout_s = 1.5 s"),
        "{}",
        ignored[0]
    );
}

#[test]
fn belt_speeds_are_checked_against_the_treadmill_range_naming_who_asked() {
    let c = RuntimeConfig::from_toml(&shipped(), "adam.toml").unwrap();
    assert_eq!(c.treadmill.belt_speed_range_mps, [0.0, 0.5]);
    c.treadmill.check_belt_speed("--belt", 0.2).unwrap();
    for bad in [-0.2, 5.0, f64::NAN] {
        let e = c
            .treadmill
            .check_belt_speed("--belt", bad)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--belt") && e.contains(&format!("{bad} m/s")) && e.contains("[0, 0.5] m/s"),
            "{e}"
        );
    }
    // Without a [treadmill] section: the default range; a reversed range is refused.
    let without = shipped()
        .replace("[treadmill]", "")
        .replace("belt_speed_range_mps = [0.0, 0.5]", "");
    let c = RuntimeConfig::from_toml(&without, "x.toml").unwrap();
    assert_eq!(
        c.treadmill.belt_speed_range_mps,
        DEFAULT_BELT_SPEED_RANGE_MPS
    );
    let reversed = shipped().replace(
        "belt_speed_range_mps = [0.0, 0.5]",
        "belt_speed_range_mps = [0.5, 0.1]",
    );
    let e = RuntimeConfig::from_toml(&reversed, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("x.toml")
            && e.contains("treadmill.belt_speed_range_mps")
            && e.contains("[0.5, 0.1]"),
        "{e}"
    );
}

#[test]
fn a_wrong_schema_version_is_named_in_words() {
    let text = shipped().replace("schema_version = 1", "schema_version = 2");
    let e = RuntimeConfig::from_toml(&text, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`schema_version` = 2") && !e.contains("Some("),
        "{e}"
    );
    let text = shipped().replace("schema_version = 1", "");
    let e = RuntimeConfig::from_toml(&text, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`schema_version` = (missing)"), "{e}");
}

#[test]
fn errors_name_field_and_value() {
    let text = shipped().replace("rate_hz = 1000.0", "rate_hz = 1500.0");
    let e = RuntimeConfig::from_toml(&text, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("x.toml") && e.contains("loop.rate_hz") && e.contains("1500"),
        "{e}"
    );
    // A rate so small that its period overflows a Duration: an error, not a panic.
    let text = shipped().replace("rate_hz = 1000.0", "rate_hz = 1e-320");
    let e = RuntimeConfig::from_toml(&text, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("loop.rate_hz") && e.contains("representable"),
        "{e}"
    );
    let text = shipped().replace("schema_version = 1", "schema_version = 9");
    let e = RuntimeConfig::from_toml(&text, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("schema_version"), "{e}");
    let text = shipped().replace("max_pitch_rad = 0.6", "max_pitch_rad = nan");
    let e = RuntimeConfig::from_toml(&text, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("safety.max_pitch_rad") && e.contains("NaN"),
        "{e}"
    );
    // The estimator keeps the last 4 estimates: a lag of 3 samples at most.
    let lag = |n: u32| {
        let field = format!("touchdown_pitch_sigma_rad = 0.01\nencoder_lag_samples = {n}");
        RuntimeConfig::from_toml(
            &shipped().replace("touchdown_pitch_sigma_rad = 0.01", &field),
            "x.toml",
        )
    };
    assert_eq!(lag(3).unwrap().estimator.encoder_lag_samples, 3);
    let e = lag(4).unwrap_err().to_string();
    assert!(
        e.contains("estimator.encoder_lag_samples") && e.contains('4'),
        "{e}"
    );
    // The touchdown gate: a distance, never negative.
    let text = shipped().replace(
        "touchdown_pitch_sigma_rad = 0.01",
        "touchdown_pitch_sigma_rad = 0.01\ntouchdown_gate_rad = -0.01",
    );
    let e = RuntimeConfig::from_toml(&text, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("estimator.touchdown_gate_rad") && e.contains("-0.01"),
        "{e}"
    );
    let text = shipped().replace("[telemetry]", "[telemetry]\nbogus = 1");
    let e = RuntimeConfig::from_toml(&text, "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("bogus"), "{e}");
}

#[test]
fn four_motors_on_one_bus_are_refused_at_1_khz() {
    let mut c = RuntimeConfig::from_toml(&shipped(), "adam.toml").unwrap();
    c.held.clear();
    for m in c.leg_motors.iter_mut() {
        m.bus = 0;
    }
    let e = c.validate("t").unwrap_err().to_string();
    assert!(e.contains("bus 0 carries 4 motors"), "{e}");
}
