//! Tick compute time of `Controller::tick` in Walk (both phase sources), printed as a table of
//! median / p99 / max over 20 000 ticks after 1 000 warm-up ticks. Run with
//! `cargo bench -p runtime --bench tick`. Wall-clock figures are machine-dependent and are
//! reported, never asserted.

use runtime::config::PhaseSource;
use runtime::control::{CommandMode, OperatorCommand, TickInput, TickOutput};
use runtime::estimator::GRAVITY_MPS2;
use runtime::{ImuSample, Setup};
use std::time::Instant;

fn measure(phase: PhaseSource) -> (f64, f64, f64, f64) {
    let mut setup = Setup::shipped().expect("shipped setup");
    setup.config.walk.phase = phase;
    // No robot: with the state-based phase the step never ends; keep the stall check quiet.
    setup.config.safety.stall_timeout_s = 1e9;
    let mut c = setup.controller(false).expect("controller");
    let mut input = TickInput::default();
    for m in input.motors.iter_mut().take(4) {
        m.fresh = true;
        m.temperature_c = 30.0;
    }
    let mut out = TickOutput::default();
    let mut times = Vec::with_capacity(20_000);
    for k in 0..24_000u32 {
        for slot in 0..4 {
            let cmd = out.commands[slot];
            if cmd.mode == CommandMode::Pd {
                input.motors[slot].q_rad = cmd.q_des_rad;
                input.motors[slot].dq_rad_s = cmd.dq_des_rad_s;
            }
        }
        input.t_s = f64::from(k) * 1e-3;
        input.imu = Some(ImuSample {
            t_s: input.t_s,
            gyro_pitch_rad_s: runtime::backend::test_dither_rad_s(input.t_s),
            accel_x_mps2: -GRAVITY_MPS2 * 0.0237_f64.sin(),
            accel_z_mps2: GRAVITY_MPS2 * 0.0237_f64.cos(),
        });
        input.operator = match k {
            1 => Some(OperatorCommand::Start),
            2500 => Some(OperatorCommand::Walk),
            _ => None,
        };
        let t0 = Instant::now();
        c.tick(&input, &mut out);
        let dt = t0.elapsed().as_nanos() as f64;
        if k >= 4000 {
            times.push(dt);
        }
    }
    times.sort_by(f64::total_cmp);
    let q = |p: f64| times[((times.len() as f64 - 1.0) * p).round() as usize];
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    (q(0.5), q(0.99), times[times.len() - 1], mean)
}

fn main() {
    println!("Controller::tick in Walk, 20 000 ticks (ns)");
    println!(
        "{:<14} {:>8} {:>8} {:>8} {:>8}",
        "phase", "median", "p99", "max", "mean"
    );
    for (name, phase) in [
        ("state_based", PhaseSource::StateBased),
        ("time_based", PhaseSource::TimeBased),
    ] {
        let (median, p99, max, mean) = measure(phase);
        println!("{name:<14} {median:>8.0} {p99:>8.0} {max:>8.0} {mean:>8.0}");
    }
}
