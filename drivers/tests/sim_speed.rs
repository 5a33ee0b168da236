//! Speed of the simulated robot behind `SimBus` (prints, never asserts wall time):
//! simulated seconds per wall second, standing and marching in place, 10 kHz firmware and
//! plant, 1 kHz control, four runs of 1.5 s each. Run:
//! `cargo test -p drivers --release --test sim_speed -- --nocapture`.
//! Also printed, on Linux: simulated seconds per second the thread was on a CPU, which a
//! machine shared with other work lowers much less than the wall-clock figure.
#![allow(clippy::unwrap_used)]

mod common;

use drivers::a1::Command;
use drivers::sim::robot::RobotSimConfig;
use std::time::Instant;

/// Simulated and wall-clock seconds and seconds on a CPU (if known) of one 1.5 s run.
fn run(march: bool) -> (f64, f64, Option<f64>) {
    let mut rig = common::standing_rig(RobotSimConfig::default(), 3);
    let mut commands: Vec<Command> = Vec::with_capacity(4);
    let start = Instant::now();
    let cpu_start_ns = thread_cpu_ns();
    for k in 0..1500 {
        rig.stand_or_march(k, march, &mut commands);
    }
    let bus = rig.bus;
    let wall_s = start.elapsed().as_secs_f64();
    let cpu_s = cpu_start_ns
        .zip(thread_cpu_ns())
        .map(|(a, b)| b.saturating_sub(a) as f64 * 1e-9);
    let plant = bus.plant();
    assert!(plant.fallen().is_none(), "{:?}", plant.fallen());
    assert!(plant.max_penetration_m() <= drivers::sim::robot::PENETRATION_TOLERANCE_M);
    (bus.time_s(), wall_s, cpu_s)
}

/// Time this thread has run on a CPU \[ns\] (Linux schedstat), if available.
fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

#[test]
fn real_time_factor() {
    for (label, march) in [("standing", false), ("marching in place", true)] {
        let (mut simulated_s, mut wall_s, mut cpu_s) = (0.0, 0.0, Some(0.0));
        for _ in 0..4 {
            let (s, w, c) = run(march);
            simulated_s += s;
            wall_s += w;
            cpu_s = cpu_s.zip(c).map(|(a, b)| a + b);
        }
        let per_cpu = cpu_s.map_or(String::new(), |c| {
            format!(", {:.0}× per CPU second", simulated_s / c)
        });
        println!(
            "{label}: {simulated_s:.1} s simulated in {wall_s:.3} s wall = {:.0}× real time{per_cpu}",
            simulated_s / wall_s
        );
    }
}
