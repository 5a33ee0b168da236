//! `adam bench treadmill`: issue #29's treadmill scenarios (`runtime::sim::scenarios`) over
//! seeds, every run in parallel on the machine's cores (rayon), one table per scenario: (a)
//! constant belts, (b) a belt step up and back, (c) pushes at five points of the step and the
//! largest push ridden through each way (a bisection), (d) start and restart.

use anyhow::{bail, Result};
use rayon::prelude::*;
use runtime::sim::run::{walk, SimWalkOptions, SimWalkReport};
use runtime::sim::scenarios::{
    belt_steps, constant_belt, max_abs_position_after_m, max_abs_position_m, outcome,
    push_at_phase, rides_through, speed_ratio_after, start_restart, steps_to_match, Restart,
    BELT_SPEEDS_MPS, PUSH_DURATION_S, PUSH_FORCES_N, PUSH_PHASES, SETTLE_S,
};
use std::fmt::Write as _;

/// The sizes of one bench: full (the acceptance) or `--quick`.
#[derive(Clone, Copy, Debug)]
struct Sizes {
    /// Constant-belt run, s.
    constant_s: f64,
    /// Belt-step run, s.
    steps_s: f64,
    /// Push points.
    phases: &'static [f64],
    /// Bisection iterations on the push magnitude.
    bisections: u32,
}

const FULL: Sizes = Sizes {
    constant_s: 60.0,
    steps_s: 60.0,
    phases: &PUSH_PHASES,
    bisections: 6,
};

const QUICK: Sizes = Sizes {
    constant_s: 20.0,
    steps_s: 30.0,
    phases: &[0.1, 0.5, 0.9],
    bisections: 3,
};

/// Largest push magnitude the bisection tries, N.
const PUSH_CEILING_N: f64 = 160.0;

/// One walk, its failure to start as an error.
fn run(setup: &runtime::Setup, options: &SimWalkOptions) -> Result<SimWalkReport> {
    Ok(walk(setup, options)?)
}

/// Runs every job in parallel, in order.
fn run_all(setup: &runtime::Setup, jobs: &[SimWalkOptions]) -> Result<Vec<SimWalkReport>> {
    jobs.par_iter().map(|o| run(setup, o)).collect()
}

/// `a of b`, e.g. `0/5`.
fn count(ok: usize, of: usize) -> String {
    format!("{ok}/{of}")
}

/// Metres or a dash.
fn metres(v: Option<f64>) -> String {
    v.map_or_else(|| "—".into(), |v| format!("{v:.3}"))
}

/// Distinct outcomes of a set of runs with how many, e.g. `ok ×3, fall: off the back of the belt ×2`.
fn outcomes(reports: &[&SimWalkReport]) -> String {
    let mut seen: Vec<(String, usize)> = Vec::new();
    for r in reports {
        let o = outcome(r);
        match seen.iter_mut().find(|(s, _)| *s == o) {
            Some((_, n)) => *n += 1,
            None => seen.push((o, 1)),
        }
    }
    seen.iter()
        .map(|(o, n)| format!("{o} ×{n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// (a) Constant belts.
fn constant(setup: &runtime::Setup, seeds: &[u64], sizes: Sizes, out: &mut String) -> Result<()> {
    let jobs: Vec<SimWalkOptions> = BELT_SPEEDS_MPS
        .iter()
        .flat_map(|&v| {
            seeds
                .iter()
                .map(move |&s| constant_belt(v, sizes.constant_s, s))
        })
        .collect();
    let reports = run_all(setup, &jobs)?;
    writeln!(
        out,
        "\n(a) belt at a constant speed, {:.0} s, seeds {seeds:?}; figures after the first {SETTLE_S:.0} s, up to any fall",
        sizes.constant_s
    )?;
    writeln!(
        out,
        "{:>9} {:>6} {:>6} {:>18} {:>22}  outcomes",
        "belt m/s", "falls", "trips", "max |position| m", "walking/belt % (mean)"
    )?;
    for (k, &v) in BELT_SPEEDS_MPS.iter().enumerate() {
        let rs: Vec<&SimWalkReport> = reports[k * seeds.len()..(k + 1) * seeds.len()]
            .iter()
            .collect();
        let falls = rs.iter().filter(|r| r.fall.is_some()).count();
        let trips = rs.iter().filter(|r| r.summary.trip.is_some()).count();
        let position = rs
            .iter()
            .filter_map(|r| max_abs_position_after_m(r, SETTLE_S))
            .reduce(f64::max);
        let ratios: Vec<f64> = rs
            .iter()
            .filter_map(|r| speed_ratio_after(&r.step_records, SETTLE_S))
            .collect();
        let ratio = if ratios.is_empty() {
            "—".to_string()
        } else {
            format!(
                "{:.1} ({} runs)",
                100.0 * ratios.iter().sum::<f64>() / ratios.len() as f64,
                ratios.len()
            )
        };
        writeln!(
            out,
            "{v:>9.2} {:>6} {:>6} {:>18} {:>22}  {}",
            count(falls, rs.len()),
            count(trips, rs.len()),
            metres(position),
            ratio,
            outcomes(&rs)
        )?;
    }
    Ok(())
}

/// (b) A belt step up and back.
fn belt_step(setup: &runtime::Setup, seeds: &[u64], sizes: Sizes, out: &mut String) -> Result<()> {
    let jobs: Vec<(SimWalkOptions, [f64; 2])> = seeds
        .iter()
        .map(|&s| belt_steps(sizes.steps_s, s))
        .collect();
    let options: Vec<SimWalkOptions> = jobs.iter().map(|(o, _)| o.clone()).collect();
    let reports = run_all(setup, &options)?;
    let [t1, t2] = jobs[0].1;
    writeln!(
        out,
        "\n(b) belt 0.20 → 0.30 m/s at {t1:.0} s and back at {t2:.0} s (ramps of 0.5 m/s²), {:.0} s: steps until the walk stays within 0.05 m/s of the belt",
        sizes.steps_s
    )?;
    writeln!(
        out,
        "{:>5} {:>12} {:>12} {:>17}  outcome",
        "seed", "steps ↑", "steps ↓", "max |position| m"
    )?;
    let steps = |n: Option<usize>| n.map_or_else(|| "never".into(), |n| n.to_string());
    for (seed, r) in seeds.iter().zip(&reports) {
        writeln!(
            out,
            "{seed:>5} {:>12} {:>12} {:>17.3}  {}",
            steps(steps_to_match(&r.step_records, t1, t2)),
            steps(steps_to_match(&r.step_records, t2, sizes.steps_s)),
            max_abs_position_m(r),
            outcome(r)
        )?;
    }
    Ok(())
}

/// Whether a push of `force_x_n` rides through at every point of `phases` for `seed`.
fn survives(setup: &runtime::Setup, force_x_n: f64, phases: &[f64], seed: u64) -> Result<bool> {
    let results: Result<Vec<bool>> = phases
        .par_iter()
        .map(|&p| {
            Ok(rides_through(&run(
                setup,
                &push_at_phase(force_x_n, p, seed),
            )?))
        })
        .collect();
    Ok(results?.into_iter().all(|ok| ok))
}

/// The largest push magnitude in `[0, PUSH_CEILING_N]` ridden through at every point, by
/// bisection: (survived, failed) N (`failed` = ∞ if the ceiling survives).
fn largest_push(setup: &runtime::Setup, sign: f64, sizes: Sizes, seed: u64) -> Result<(f64, f64)> {
    if survives(setup, sign * PUSH_CEILING_N, sizes.phases, seed)? {
        return Ok((PUSH_CEILING_N, f64::INFINITY));
    }
    let (mut lo, mut hi) = (0.0, PUSH_CEILING_N);
    for _ in 0..sizes.bisections {
        let mid = 0.5 * (lo + hi);
        if survives(setup, sign * mid, sizes.phases, seed)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok((lo, hi))
}

/// (c) Pushes at points of the step.
fn pushes(setup: &runtime::Setup, seeds: &[u64], sizes: Sizes, out: &mut String) -> Result<()> {
    let jobs: Vec<SimWalkOptions> = PUSH_FORCES_N
        .iter()
        .flat_map(|&f| {
            sizes
                .phases
                .iter()
                .flat_map(move |&p| seeds.iter().map(move |&s| push_at_phase(f, p, s)))
        })
        .collect();
    let reports = run_all(setup, &jobs)?;
    writeln!(
        out,
        "\n(c) pushes of {PUSH_DURATION_S} s on the belt at 0.25 m/s landing at a phase of the step: runs that ride through (no trip, no stall, no fall) of {}",
        seeds.len()
    )?;
    let mut header = format!("{:>7}", "push");
    for p in sizes.phases {
        write!(header, " {:>6}", format!("{:.0} %", 100.0 * p))?;
    }
    writeln!(out, "{header}  outcomes")?;
    let per_force = sizes.phases.len() * seeds.len();
    for (k, f) in PUSH_FORCES_N.iter().enumerate() {
        let mut row = format!("{:>5} N", format!("{f:+.0}"));
        let rs = &reports[k * per_force..(k + 1) * per_force];
        for chunk in rs.chunks(seeds.len()) {
            let ok = chunk.iter().filter(|r| rides_through(r)).count();
            write!(row, " {:>6}", count(ok, seeds.len()))?;
        }
        let all: Vec<&SimWalkReport> = rs.iter().collect();
        writeln!(out, "{row}  {}", outcomes(&all))?;
    }
    let bisections: Vec<((f64, u64), (f64, f64))> = [-1.0, 1.0]
        .into_par_iter()
        .flat_map(|sign| seeds.par_iter().map(move |&s| (sign, s)))
        .map(|(sign, s)| largest_push(setup, sign, sizes, s).map(|b| ((sign, s), b)))
        .collect::<Result<_>>()?;
    for (sign, way) in [(-1.0, "backward"), (1.0, "forward")] {
        let cells: Vec<String> = bisections
            .iter()
            .filter(|((s, _), _)| *s == sign)
            .map(|((_, seed), (lo, hi))| {
                if hi.is_infinite() {
                    format!("seed {seed}: ≥ {lo:.0} N")
                } else {
                    format!("seed {seed}: {lo:.0} N (fails at {hi:.0})")
                }
            })
            .collect();
        writeln!(
            out,
            "largest {way} push ridden through at every point (bisection): {}",
            cells.join("; ")
        )?;
    }
    Ok(())
}

/// (d) Start and restart.
fn restarts(setup: &runtime::Setup, seeds: &[u64], out: &mut String) -> Result<()> {
    let jobs: Vec<SimWalkOptions> = Restart::ALL
        .iter()
        .flat_map(|&c| seeds.iter().map(move |&s| start_restart(c, s)))
        .collect();
    let reports = run_all(setup, &jobs)?;
    writeln!(
        out,
        "\n(d) start and restart (from Stand: Start at 0 s, the controller's ramp to Stand; 20 s)"
    )?;
    writeln!(out, "{:<38} {:>14}  outcomes", "case", "no trip/fall")?;
    for (k, case) in Restart::ALL.iter().enumerate() {
        let rs: Vec<&SimWalkReport> = reports[k * seeds.len()..(k + 1) * seeds.len()]
            .iter()
            .collect();
        let ok = rs.iter().filter(|r| rides_through(r)).count();
        writeln!(
            out,
            "{:<38} {:>14}  {}",
            case.name(),
            count(ok, rs.len()),
            outcomes(&rs)
        )?;
    }
    Ok(())
}

/// `adam bench treadmill`: every scenario over `seeds`, printing each table as it is done,
/// then the wall time, the CPU time and the simulated time.
pub(crate) fn treadmill(
    seeds: Option<Vec<u64>>,
    quick: bool,
    config: &std::path::Path,
    gait: &std::path::Path,
) -> Result<()> {
    let sizes = if quick { QUICK } else { FULL };
    let seeds = seeds.unwrap_or_else(|| {
        if quick {
            vec![1, 2]
        } else {
            vec![1, 2, 3, 4, 5]
        }
    });
    if seeds.is_empty() {
        bail!("--seeds must name at least one seed");
    }
    let (config, gait) = (
        crate::cli::shipped::input(config),
        crate::cli::shipped::input(gait),
    );
    let setup = runtime::Setup::load(&config, &gait)?;
    println!(
        "adam bench treadmill: {} (its speed {:.3} m/s), {} cores{}",
        gait.display(),
        setup.gait.speed_mps,
        rayon::current_num_threads(),
        if quick { ", --quick" } else { "" }
    );
    let wall = std::time::Instant::now();
    let cpu0 = cpu_time_s();
    type Scenario = fn(&runtime::Setup, &[u64], Sizes, &mut String) -> Result<()>;
    let scenarios: [Scenario; 4] = [constant, belt_step, pushes, |s, seeds, _, out| {
        restarts(s, seeds, out)
    }];
    for scenario in scenarios {
        let mut out = String::new();
        scenario(&setup, &seeds, sizes, &mut out)?;
        print!("{out}");
    }
    println!(
        "\nwall {:.1} s, CPU {}",
        wall.elapsed().as_secs_f64(),
        cpu0.zip(cpu_time_s())
            .map_or_else(|| "unknown".into(), |(a, b)| format!("{:.1} s", b - a))
    );
    Ok(())
}

/// CPU time of this process so far (user + system), s, from `/proc/self/stat` (Linux).
fn cpu_time_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command's closing parenthesis: utime and stime are the 12th and 13th.
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    // USER_HZ is 100 on Linux.
    Some(ticks / 100.0)
}
