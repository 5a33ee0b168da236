//! The three speed-control options that issue #29's work measured and left off in the shipped
//! configs (`runtime::control::speed`, "The step lean", "The step's length" and "The start on
//! the plan"): with all three on, the belts from 0.20 m/s up hold the issue's ±0.10 m, which
//! the shipped treadmill config misses at 0.20–0.35 m/s (0.170 / 0.262 / 0.123 / 0.111 m,
//! seeds 1–5, `tests/treadmill.rs`). They stay off there because the belt step down then
//! matches in more than 8 steps in a seed of five (18 steps, seed 2) and the 0.15 m/s belt
//! trips in one (seed 5) (README, "Treadmill speeds"). The config with them is
//! `configs/runtime/adam_treadmill_options.toml` (`extends` the treadmill config).

use runtime::sim::run::walk;
use runtime::sim::scenarios::{
    constant_belt, max_abs_position_after_m, outcome, rides_through, SETTLE_S,
};
use runtime::telemetry::speed_read::SpeedRow;
use runtime::Setup;

/// How far the leg odometry's position estimate drifted from the simulator's truth between
/// `from_s` and the run's end, m: the mean of (estimate − truth) over the last 4 impacts less
/// its mean over the first 4 after `from_s` (the two frames differ by a constant: the estimate
/// counts feet, the truth the hip).
fn odometry_drift_m(rows: &[SpeedRow], from_s: f64) -> f64 {
    let error: Vec<f64> = rows
        .iter()
        .filter(|r| r.position_m.is_finite() && r.true_position_m.is_finite())
        .filter(|r| r.t_s >= from_s)
        .map(|r| r.position_m - r.true_position_m)
        .collect();
    assert!(
        error.len() >= 8,
        "{} impacts logged after {from_s} s",
        error.len()
    );
    let mean = |e: &[f64]| e.iter().sum::<f64>() / e.len() as f64;
    mean(&error[error.len() - 4..]) - mean(&error[..4])
}

/// `configs/runtime/adam_treadmill_options.toml`: the treadmill config with the step lean, each
/// step's length measured again at the tick after the impact, and the start on the plan.
fn with_the_options() -> Setup {
    let root = env!("CARGO_MANIFEST_DIR");
    let setup = Setup::load(
        format!("{root}/configs/runtime/adam_treadmill_options.toml"),
        format!("{root}/{}", runtime::DEFAULT_GAIT),
    )
    .expect("the options config, its base, the gait library and the shipped gait load");
    let s = &setup.config.speed;
    assert!(
        s.step_lean_gain_rad_per_mps > 0.0 && s.step_length_after_impact && s.start_on_plan,
        "the three options are on: {s:?}"
    );
    setup
}

/// The belt at `v` m/s (0.20, 0.25, 0.30 and 0.35 below, a test each) for 60 s, seeds 1–5,
/// with the three options: no fall, no trip, within ±0.10 m of the centre after 10 s (the figure; measured
/// 2026-12-06: at most 0.086, 0.087, 0.071 and 0.067 m; without the start on the plan 0.193,
/// 0.097, 0.085 and 0.046 m, so 0.20 m/s tells that option's work from its absence), and the
/// leg odometry's estimate drifts from the truth by at most 1.5 cm over the last 50 s.
/// Measured 2026-12-06 at 0.25 and 0.35 m/s, seeds 1 and 4: 0.002 – 0.007 m with the length
/// measured after the impact, 0.043 – 0.062 m without it (each step counted 0.5–0.7 mm
/// short), so the bound tells that option's work from its absence. (Seeds 6–10 do not hold
/// 0.10 m at 0.20 and 0.25 m/s: 0.125 and 0.102 m.)
fn with_the_options_the_belt_holds_10_cm(v: f64) {
    let setup = with_the_options();
    for seed in 1..=5 {
        let options = constant_belt(v, 60.0, seed);
        let r = walk(&setup, &options).expect("the simulated run starts");
        assert!(rides_through(&r), "{v} m/s seed {seed}: {}", outcome(&r));
        let p = max_abs_position_after_m(&r, SETTLE_S).expect("walked past 10 s");
        assert!(p <= 0.10, "{v} m/s seed {seed}: |position| {p} m");
        // The run's `/speed` rows, from its summary (as a log holds them: runtime/tests/speed_sim.rs).
        let drift = odometry_drift_m(&r.summary.speed_rows, SETTLE_S);
        assert!(
            drift.abs() <= 0.015,
            "{v} m/s seed {seed}: the odometry drifted {drift} m from the truth"
        );
    }
}

/// [`with_the_options_the_belt_holds_10_cm`] at 0.20 m/s (a test a belt: they run side by side).
#[test]
fn with_the_options_the_0_20_m_s_belt_holds_10_cm() {
    with_the_options_the_belt_holds_10_cm(0.20);
}

/// [`with_the_options_the_belt_holds_10_cm`] at 0.25 m/s.
#[test]
fn with_the_options_the_0_25_m_s_belt_holds_10_cm() {
    with_the_options_the_belt_holds_10_cm(0.25);
}

/// [`with_the_options_the_belt_holds_10_cm`] at 0.30 m/s.
#[test]
fn with_the_options_the_0_30_m_s_belt_holds_10_cm() {
    with_the_options_the_belt_holds_10_cm(0.30);
}

/// [`with_the_options_the_belt_holds_10_cm`] at 0.35 m/s.
#[test]
fn with_the_options_the_0_35_m_s_belt_holds_10_cm() {
    with_the_options_the_belt_holds_10_cm(0.35);
}
