//! The constant-belt and belt-step scenarios of `adam bench treadmill` alone, for a runtime
//! config given on the command line (gains are config fields: no rebuild per trial), and an
//! open-loop identification of the walked speed against the library speed σ.
//!
//! ```text
//! cargo run --release -p runtime --example treadmill_probe -- accept CONFIG [SEEDS..]
//! cargo run --release -p runtime --example treadmill_probe -- ident CONFIG SPEED OFFSET SEED
//! ```
//! `accept`: the tables (a) and (b) of the bench. `ident`: speed control with every gain 0
//! (the config should say so) on an endless belt at SPEED, the operator's offset stepped by
//! OFFSET at 30 s; one line per step (t, length, duration, speed) on stdout.

use runtime::control::OperatorCommand;
use runtime::sim::matrix::{self, Run, RunSummary};
use runtime::sim::run::walk;
use runtime::sim::scenarios::{constant_belt, BELT_SPEEDS_MPS};
use runtime::Setup;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let gait = format!("{root}/{}", runtime::DEFAULT_GAIT);
    let setup = Setup::load(&args[1], &gait).expect("config and gait load");
    match args[0].as_str() {
        "ident" => {
            let v: f64 = args[2].parse().expect("speed");
            let offset: f64 = args[3].parse().expect("offset");
            let seed: u64 = args[4].parse().expect("seed");
            let mut o = constant_belt(v, 60.0, seed);
            o.belt_length_m = f64::INFINITY;
            o.script = vec![(30.0, OperatorCommand::Offset { speed_mps: offset })];
            let r = walk(&setup, &o).expect("run");
            eprintln!("{}", runtime::sim::scenarios::outcome(&r));
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
        }
        "trace" => {
            let v: f64 = args[2].parse().expect("speed");
            let seed: u64 = args[3].parse().expect("seed");
            let r = walk(&setup, &constant_belt(v, 60.0, seed)).expect("run");
            eprintln!("{}", runtime::sim::scenarios::outcome(&r));
            let mut next = 0.0;
            for s in &r.trace {
                if s.t_s >= next {
                    print!("{:.0}:{:+.3} ", s.t_s, s.position_on_belt_m);
                    next += 2.0;
                }
            }
            println!();
        }
        _ => {
            let seeds: Vec<u64> = if args.len() > 2 {
                args[2..].iter().map(|s| s.parse().expect("seed")).collect()
            } else {
                vec![1, 2, 3, 4, 5]
            };
            let mut runs = Vec::new();
            for &speed_mps in &BELT_SPEEDS_MPS {
                for &seed in &seeds {
                    runs.push(Run::ConstantBelt {
                        speed_mps,
                        duration_s: 60.0,
                        seed,
                    });
                }
            }
            for &seed in &seeds {
                runs.push(Run::BeltSteps {
                    duration_s: 60.0,
                    seed,
                });
            }
            let next = AtomicUsize::new(0);
            let out: Mutex<Vec<Option<RunSummary>>> = Mutex::new(vec![None; runs.len()]);
            std::thread::scope(|s| {
                for _ in 0..2 {
                    s.spawn(|| loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        let Some(r) = runs.get(k) else { break };
                        let summary = matrix::run(&setup, r).expect("run");
                        out.lock().expect("lock")[k] = Some(summary);
                    });
                }
            });
            let out = out.into_inner().expect("lock");
            for (r, s) in runs.iter().zip(&out) {
                let s = s.as_ref().expect("ran");
                match r {
                    Run::ConstantBelt {
                        speed_mps, seed, ..
                    } => println!(
                        "belt {speed_mps:.2} seed {seed}: {} |p|>10s {:.3} ratio {:.2} %",
                        s.outcome,
                        s.max_abs_position_after_settle_m.unwrap_or(f64::NAN),
                        100.0 * s.speed_ratio_after_settle.unwrap_or(f64::NAN)
                    ),
                    Run::BeltSteps { seed, .. } => {
                        let [u, d] = s.steps_to_match.unwrap_or([None, None]);
                        println!(
                            "step seed {seed}: {} up {u:?} down {d:?} |p| {:.3}",
                            s.outcome, s.max_abs_position_m
                        );
                    }
                    _ => {}
                }
            }
            for &v in &BELT_SPEEDS_MPS {
                let rs: Vec<&RunSummary> = runs
                    .iter()
                    .zip(&out)
                    .filter(|(r, _)| matches!(r, Run::ConstantBelt { speed_mps, .. } if *speed_mps == v))
                    .filter_map(|(_, s)| s.as_ref())
                    .collect();
                let p = rs
                    .iter()
                    .filter_map(|s| s.max_abs_position_after_settle_m)
                    .fold(0.0, f64::max);
                let ratios: Vec<f64> = rs
                    .iter()
                    .filter_map(|s| s.speed_ratio_after_settle)
                    .collect();
                let worst = ratios.iter().map(|r| (r - 1.0).abs()).fold(0.0, f64::max);
                println!(
                    "SUMMARY {v:.2}: bad {} max|p| {p:.3} mean {:.2} % worst |ratio-1| {:.2} %",
                    rs.iter().filter(|s| !s.rides_through).count(),
                    100.0 * ratios.iter().sum::<f64>() / ratios.len().max(1) as f64,
                    100.0 * worst
                );
            }
        }
    }
}
