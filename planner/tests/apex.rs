//! The apex margin of a verified gait means what it says: a step that starts with its
//! post-impact momentum cut by a little less than the margin passes over the stance foot, one
//! cut by a little more does not (the closed loop of the verification, the paper's controller).

use planner::verify::{apex_margin, load_gait_and_robot, verify_gait, ClosedLoop, VerifyOptions};
use std::path::Path;

/// The shipped co-designed gait (0.15 m in 0.90 s) and the 0.24 / 0.25 m ADAM's (adam_walk).
const GAITS: [&str; 2] = [
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/gaits/adam_codesign.json"
    ),
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/gaits/adam_walk.json"
    ),
];

/// Scales the rates of the reduced state `x` (its second half) by `k`: on the outputs'
/// manifold (y = 0, ẏ = 0 stay so) the zero dynamics start with k times the momentum.
fn with_rates_scaled(x: &[f64], k: f64) -> Vec<f64> {
    let nq = x.len() / 2;
    x.iter()
        .enumerate()
        .map(|(i, &v)| if i < nq { v } else { k * v })
        .collect()
}

#[test]
fn a_step_passes_the_stance_foot_exactly_while_the_lost_momentum_is_within_the_margin() {
    for path in GAITS {
        let (gait, robot) = load_gait_and_robot(Path::new(path)).expect("loads");
        let options = VerifyOptions::default();
        let report = verify_gait(&robot, &gait, options).expect("verifies");
        let cl = ClosedLoop::new(&robot, &gait, options).expect("closed loop");
        let x = cl.planned_state(&gait, "test").expect("initial state");
        let planned = cl.step(&x).expect("the planned step");
        let margin = apex_margin(planned.start_momentum_kgm2_s, planned.min_momentum_kgm2_s);
        println!("{path}: apex margin {:.2} %", 100.0 * margin);
        // From the planned post-impact state or from the fixed point (4e-5 rad apart): the
        // same margin to 0.2 percentage points.
        assert!(
            (margin - report.apex_margin).abs() < 2e-3,
            "{path}: {margin} from the plan, {} at the fixed point",
            report.apex_margin
        );
        assert!(margin > 0.01 && margin < 0.5, "{path}: margin {margin}");
        // The momentum is linear in the rates: k scales the step's start momentum by k.
        let k_pass = 1.0 - margin + 0.005;
        let slowed = cl.step(&with_rates_scaled(&x, k_pass)).expect("passes");
        assert!(
            (slowed.start_momentum_kgm2_s / planned.start_momentum_kgm2_s - k_pass).abs() < 1e-9,
            "{path}"
        );
        // Half a percent above the critical start the robot crawls over the top and lands its step.
        assert!(
            slowed.length_m > 0.9 * gait.step_length_m && slowed.duration_s > planned.duration_s,
            "{path}: {slowed:?}"
        );
        assert!(slowed.min_momentum_kgm2_s > 0.0, "{path}: {slowed:?}");
        // Half a percent below it the robot stops short of the stance foot and falls back: no step
        // forward (the swing foot comes down behind, or the simulation reports the fall).
        let k_stop = 1.0 - margin - 0.005;
        match cl.step(&with_rates_scaled(&x, k_stop)) {
            Ok(step) => {
                println!(
                    "{path}: with {k_stop} of the momentum: a step of {:.3} m",
                    step.length_m
                );
                assert!(
                    step.length_m < 0.0 && step.min_momentum_kgm2_s < 0.0,
                    "{path}: with {k_stop} of the momentum the robot still stepped: {step:?}"
                )
            }
            Err(e) => println!("{path}: with {k_stop} of the momentum: {e}"),
        }
    }
}

/// The margin of a step from its momenta: all of it (1) when the momentum does not drop over
/// the top, none (0) when the orbit stops there, and NaN when it cannot be read (no momentum, or the
/// robot already moving back).
#[test]
fn the_margin_follows_the_zero_dynamics_energy() {
    assert_eq!(apex_margin(4.0, 4.0), 1.0);
    assert_eq!(apex_margin(4.0, 0.0), 0.0);
    // σ_min/σ⁺ = 0.6: the top needs √(1 − 0.36) = 0.8 of σ⁺, so 20 % may go.
    assert!((apex_margin(5.0, 3.0) - 0.2).abs() < 1e-12);
    assert!((apex_margin(-5.0, -3.0) - 0.2).abs() < 1e-12);
    assert!(apex_margin(0.0, 0.0).is_nan());
    assert!(apex_margin(4.0, -1.0).is_nan());
}

/// `ClosedLoop::walk` measures the steps it settles at and names the step a robot that stops
/// short of the stance foot falls back in: from the planned state the co-designed gait walks
/// its plan; with 5 % more momentum lost than its apex margin allows, its first step fails; it
/// refuses to measure none of its steps, or more than it walks.
#[test]
fn a_walk_measures_its_last_steps_and_names_the_step_that_falls_back() {
    let (gait, robot) = load_gait_and_robot(Path::new(GAITS[0])).expect("loads");
    let cl = ClosedLoop::new(&robot, &gait, VerifyOptions::default()).expect("closed loop");
    let x = cl.planned_state(&gait, "test").expect("initial state");
    for (steps, measured) in [(6, 0), (6, 7)] {
        let e = cl
            .walk(&x, steps, measured)
            .expect_err("nothing or more than walked to measure")
            .to_string();
        assert!(
            e.contains(&format!("{measured} steps measured of {steps}")),
            "{e}"
        );
    }
    let walked = cl.walk(&x, 6, 3).expect("walks");
    let plan = gait.step_length_m / gait.step_duration_s;
    assert!((walked.speed_mps() / plan - 1.0).abs() < 0.01, "{walked:?}");
    assert!(
        (walked.length_m - gait.step_length_m).abs() < 1e-3,
        "{walked:?}"
    );
    let planned = cl.step(&x).expect("step");
    let margin = apex_margin(planned.start_momentum_kgm2_s, planned.min_momentum_kgm2_s);
    let e = cl
        .walk(&with_rates_scaled(&x, 1.0 - margin - 0.05), 6, 3)
        .expect_err("falls back")
        .to_string();
    assert!(e.contains("step 1 of 6") && e.contains("fell back"), "{e}");
}
