//! Open-loop identification of the speed each library gait walks against its library speed σ
//! (the source of `speed.walked_mps` in `configs/runtime/adam_treadmill.toml`).
//!
//! ```text
//! cargo run --release -p runtime --example treadmill_probe -- CONFIG SPEED OFFSET SEED
//! ```
//! Speed control with every gain 0 (CONFIG should say so, `speed.position_gain_per_s` too, which
//! acts when `position_gain_per_step` is 0, so that σ is the belt speed) on an
//! endless belt at SPEED m/s, the operator's offset stepped by OFFSET m/s at 30 s, 60 s with
//! noise seed SEED; one line per step on stdout: t (s), length (m), duration (s), speed (m/s),
//! position on the belt (m). The closed-loop scenarios (constant belts, the belt step, pushes,
//! restarts) are `adam bench treadmill --config CONFIG`.

use runtime::control::OperatorCommand;
use runtime::sim::run::walk;
use runtime::sim::scenarios::{constant_belt, outcome};
use runtime::Setup;
use std::process::ExitCode;

const USAGE: &str = "usage: treadmill_probe CONFIG SPEED_MPS OFFSET_MPS SEED";

fn main() -> ExitCode {
    match probe(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("treadmill_probe: {e}\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

fn probe(args: Vec<String>) -> Result<(), String> {
    let [config, speed, offset, seed] = args.as_slice() else {
        return Err(format!("4 arguments expected, {} given", args.len()));
    };
    let number = |name: &str, v: &str| {
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{name} = {v:?} is not a finite number"))
    };
    let speed_mps = number("SPEED_MPS", speed)?;
    let offset_mps = number("OFFSET_MPS", offset)?;
    let seed: u64 = seed
        .parse()
        .map_err(|_| format!("SEED = {seed:?} is not a non-negative integer"))?;
    let gait = format!(
        "{}/../{}",
        env!("CARGO_MANIFEST_DIR"),
        runtime::DEFAULT_GAIT
    );
    let setup = Setup::load(config, &gait).map_err(|e| e.to_string())?;
    let mut o = constant_belt(speed_mps, 60.0, seed);
    o.belt_length_m = f64::INFINITY;
    o.script = vec![(
        30.0,
        OperatorCommand::Offset {
            speed_mps: offset_mps,
        },
    )];
    let r = walk(&setup, &o).map_err(|e| e.to_string())?;
    eprintln!("{}", outcome(&r));
    for s in &r.step_records {
        println!(
            "{:.4} {:.5} {:.5} {:.5} {:.4}",
            s.t_s,
            s.length_m,
            s.duration_s,
            s.speed_mps(),
            s.position_on_belt_m
        );
    }
    Ok(())
}
