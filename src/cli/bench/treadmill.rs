//! `adam bench treadmill`: issue #29's treadmill scenarios (`runtime::sim::scenarios`) over
//! seeds, every run in parallel on the machine's cores (rayon), one table per scenario: (a)
//! constant belts, (b) a belt step up and back, (c) pushes at five points of the step and the
//! largest push ridden through each way (a bisection), (d) start and restart. The matrix's runs
//! ([`matrix`]) and its tables ([`tables`]) are also a treadmill sweep plan's tasks and report
//! (`adam sweep`); only the bisection is the bench's alone.

use anyhow::{bail, Result};
use rayon::prelude::*;
use runtime::sim::matrix::{self, Run, RunSummary};
use runtime::sim::scenarios::{
    Restart, BELT_SPEEDS_MPS, PUSH_DURATION_S, PUSH_FORCES_N, PUSH_PHASES, SETTLE_S,
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

/// The treadmill matrix of `seeds` in table order: (a) the constant `belts` (m/s; the issue's
/// [`BELT_SPEEDS_MPS`] unless `adam bench treadmill --belts` names others) × seeds, (b) belt
/// steps × seeds, (c) push forces × points × seeds, (d) restart cases × seeds. The runs of
/// `adam bench treadmill` and the tasks of a treadmill sweep plan.
pub(crate) fn matrix_runs(seeds: &[u64], quick: bool, belts: &[f64]) -> Vec<Run> {
    let sizes = if quick { QUICK } else { FULL };
    let mut runs = Vec::new();
    for &speed_mps in belts {
        runs.extend(seeds.iter().map(|&seed| Run::ConstantBelt {
            speed_mps,
            duration_s: sizes.constant_s,
            seed,
        }));
    }
    runs.extend(seeds.iter().map(|&seed| Run::BeltSteps {
        duration_s: sizes.steps_s,
        seed,
    }));
    for &force_x_n in &PUSH_FORCES_N {
        for &phase in sizes.phases {
            runs.extend(seeds.iter().map(|&seed| Run::Push {
                force_x_n,
                phase,
                seed,
            }));
        }
    }
    for case in Restart::ALL {
        runs.extend(seeds.iter().map(|&seed| Run::Restart { case, seed }));
    }
    runs
}

/// `a of b`, e.g. `0/5`.
fn count(ok: usize, of: usize) -> String {
    format!("{ok}/{of}")
}

/// The runs of `rs` that ride through, of how many, and those that walked on only after a
/// stall relaunch (not ridden through: they stalled), e.g. `3/5` or `3/5+2`.
fn ridden(rs: &[&RunSummary]) -> String {
    let ok = rs.iter().filter(|r| r.rides_through).count();
    let relaunched = rs.iter().filter(|r| r.walks_on && !r.rides_through).count();
    if relaunched == 0 {
        count(ok, rs.len())
    } else {
        format!("{}+{relaunched}", count(ok, rs.len()))
    }
}

/// Metres or a dash.
fn metres(v: Option<f64>) -> String {
    v.map_or_else(|| "—".into(), |v| format!("{v:.3}"))
}

/// Distinct outcomes of a set of runs with how many, e.g. `ok ×3, fall: off the back of the belt ×2`.
fn outcomes(summaries: &[&RunSummary]) -> String {
    let mut seen: Vec<(&str, usize)> = Vec::new();
    for r in summaries {
        match seen.iter_mut().find(|(s, _)| *s == r.outcome) {
            Some((_, n)) => *n += 1,
            None => seen.push((&r.outcome, 1)),
        }
    }
    seen.iter()
        .map(|(o, n)| format!("{o} ×{n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The summaries of the runs `pick` selects (a run without a summary, e.g. a sweep task with
/// no result yet, is left out: the counts say of how many).
fn select<'a>(
    runs: &[Run],
    summaries: &'a [Option<RunSummary>],
    pick: impl Fn(&Run) -> bool,
) -> Vec<&'a RunSummary> {
    runs.iter()
        .zip(summaries)
        .filter(|(r, _)| pick(r))
        .filter_map(|(_, s)| s.as_ref())
        .collect()
}

/// The tables of `adam bench treadmill` (a)–(d) from the matrix's `runs` and their
/// `summaries` (`None`: no result), as `adam bench treadmill` prints them and `adam sweep
/// collect` writes them.
pub(crate) fn tables(
    seeds: &[u64],
    quick: bool,
    runs: &[Run],
    summaries: &[Option<RunSummary>],
) -> Result<String> {
    let sizes = if quick { QUICK } else { FULL };
    let mut out = String::new();
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
    // The constant belts the matrix ran, in its order.
    let mut belts: Vec<f64> = Vec::new();
    for r in runs {
        if let Run::ConstantBelt { speed_mps, .. } = r {
            if !belts.contains(speed_mps) {
                belts.push(*speed_mps);
            }
        }
    }
    for v in belts {
        let rs = select(
            runs,
            summaries,
            |r| matches!(r, Run::ConstantBelt { speed_mps, .. } if *speed_mps == v),
        );
        let falls = rs.iter().filter(|r| r.fell).count();
        let trips = rs.iter().filter(|r| r.tripped).count();
        let position = rs
            .iter()
            .filter_map(|r| r.max_abs_position_after_settle_m)
            .reduce(f64::max);
        let ratios: Vec<f64> = rs
            .iter()
            .filter_map(|r| r.speed_ratio_after_settle)
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
        // 0.15, 0.175, 0.167: as many decimals as the speed has (up to 3).
        let belt = if (v * 100.0 - (v * 100.0).round()).abs() < 1e-6 {
            format!("{v:.2}")
        } else {
            format!("{v:.3}")
        };
        writeln!(
            out,
            "{belt:>9} {:>6} {:>6} {:>18} {:>22}  {}",
            count(falls, rs.len()),
            count(trips, rs.len()),
            metres(position),
            ratio,
            outcomes(&rs)
        )?;
    }
    let [t1, t2] = [sizes.steps_s / 3.0, 2.0 * sizes.steps_s / 3.0];
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
    for (run, s) in runs.iter().zip(summaries) {
        if let (Run::BeltSteps { seed, .. }, Some(s)) = (run, s) {
            let [up, down] = s.steps_to_match.unwrap_or([None, None]);
            writeln!(
                out,
                "{seed:>5} {:>12} {:>12} {:>17.3}  {}",
                steps(up),
                steps(down),
                s.max_abs_position_m,
                s.outcome
            )?;
        }
    }
    writeln!(
        out,
        "\n(c) pushes of {PUSH_DURATION_S} s on the belt at 0.25 m/s landing at a phase of the step: runs that ride through (no trip, no stall, no fall) of {}; +n: walked on after a stall relaunch (a stall, not counted)",
        seeds.len()
    )?;
    let mut header = format!("{:>7}", "push");
    for p in sizes.phases {
        write!(header, " {:>8}", format!("{:.0} %", 100.0 * p))?;
    }
    writeln!(out, "{header}  outcomes")?;
    for &f in &PUSH_FORCES_N {
        let mut row = format!("{:>5} N", format!("{f:+.0}"));
        for &p in sizes.phases {
            let rs = select(
                runs,
                summaries,
                |r| matches!(r, Run::Push { force_x_n, phase, .. } if *force_x_n == f && *phase == p),
            );
            write!(row, " {:>8}", ridden(&rs))?;
        }
        let all = select(
            runs,
            summaries,
            |r| matches!(r, Run::Push { force_x_n, .. } if *force_x_n == f),
        );
        writeln!(out, "{row}  {}", outcomes(&all))?;
    }
    writeln!(
        out,
        "\n(d) start and restart (from Stand: Start at 0 s, the controller's ramp to Stand; 20 s; stop and walk again: Stop at 10 s, Walk at 18 s, 26 s)"
    )?;
    writeln!(out, "{:<38} {:>14}  outcomes", "case", "no trip/stall")?;
    for c in Restart::ALL {
        let rs = select(
            runs,
            summaries,
            |r| matches!(r, Run::Restart { case, .. } if *case == c),
        );
        writeln!(
            out,
            "{:<38} {:>14}  {}",
            c.name(),
            ridden(&rs),
            outcomes(&rs)
        )?;
    }
    Ok(out)
}

/// Whether a push of `force_x_n` rides through at every point of `phases` for `seed`.
fn survives(setup: &runtime::Setup, force_x_n: f64, phases: &[f64], seed: u64) -> Result<bool> {
    let results: Result<Vec<bool>> = phases
        .par_iter()
        .map(|&phase| {
            let push = Run::Push {
                force_x_n,
                phase,
                seed,
            };
            Ok(matrix::run(setup, &push)?.rides_through)
        })
        .collect();
    Ok(results?.into_iter().all(|ok| ok))
}

/// The largest push magnitude in `[0, PUSH_CEILING_N]` ridden through (no stall relaunch) at every point, by
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

/// The bisection lines of (c): the largest push ridden through each way, per seed (a search,
/// one run after another: `adam bench treadmill` only, not a sweep's matrix).
fn bisections(setup: &runtime::Setup, seeds: &[u64], sizes: Sizes) -> Result<String> {
    let found: Vec<((f64, u64), (f64, f64))> = [-1.0, 1.0]
        .into_par_iter()
        .flat_map(|sign| seeds.par_iter().map(move |&s| (sign, s)))
        .map(|(sign, s)| largest_push(setup, sign, sizes, s).map(|b| ((sign, s), b)))
        .collect::<Result<_>>()?;
    let mut out = String::new();
    for (sign, way) in [(-1.0, "backward"), (1.0, "forward")] {
        let cells: Vec<String> = found
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
    Ok(out)
}

/// The seeds of a treadmill matrix: those given (at least one), else 1–2 (`--quick`) or 1–5.
pub(crate) fn seeds_or_default(seeds: Option<Vec<u64>>, quick: bool) -> Result<Vec<u64>> {
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
    Ok(seeds)
}

/// `adam bench treadmill`: every scenario over `seeds`, printing each table as it is done,
/// then the wall time, the CPU time and the simulated time.
pub(crate) fn treadmill(
    seeds: Option<Vec<u64>>,
    quick: bool,
    belts: Option<&str>,
    config: &std::path::Path,
    gait: &std::path::Path,
) -> Result<()> {
    let sizes = if quick { QUICK } else { FULL };
    let seeds = seeds_or_default(seeds, quick)?;
    let (config, gait) = (
        crate::cli::shipped::input(config),
        crate::cli::shipped::input(gait),
    );
    let setup = runtime::Setup::load(&config, &gait)?;
    let belts = belts_or_default(belts, &setup.config.treadmill)?;
    println!(
        "adam bench treadmill: {} (its speed {:.3} m/s), {} cores{}",
        gait.display(),
        setup.gait.speed_mps,
        rayon::current_num_threads(),
        if quick { ", --quick" } else { "" }
    );
    let wall = std::time::Instant::now();
    let cpu0 = cpu_time_s();
    // Every run of the matrix at once (the tasks of a treadmill sweep plan, the same function).
    let runs = matrix_runs(&seeds, quick, &belts);
    let summaries: Vec<Option<RunSummary>> = runs
        .par_iter()
        .map(|r| Ok(Some(matrix::run(&setup, r)?)))
        .collect::<Result<_>>()?;
    print!("{}", tables(&seeds, quick, &runs, &summaries)?);
    print!("{}", bisections(&setup, &seeds, sizes)?);
    println!(
        "\nwall {:.1} s, CPU {}",
        wall.elapsed().as_secs_f64(),
        cpu0.zip(cpu_time_s())
            .map_or_else(|| "unknown".into(), |(a, b)| format!("{:.1} s", b - a))
    );
    Ok(())
}

/// The constant belts of table (a), m/s: `spec` (`lo:hi:step` or `v1,v2,…`; each within the
/// runtime config's `treadmill` range, as `adam run --belt`) or the issue's
/// [`BELT_SPEEDS_MPS`].
fn belts_or_default(
    spec: Option<&str>,
    treadmill: &runtime::config::TreadmillConfig,
) -> Result<Vec<f64>> {
    let Some(spec) = spec else {
        return Ok(BELT_SPEEDS_MPS.to_vec());
    };
    let belts =
        planner::library::parse_speeds(spec).map_err(|e| anyhow::anyhow!("--belts: {e}"))?;
    for &v in &belts {
        treadmill.check_belt_speed("--belts", v)?;
    }
    Ok(belts)
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

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// `--belts` absent: the issue's five; a range or a list: those, each a row of table (a)
    /// for every seed; a belt past the treadmill's range or a bad list: an error naming the
    /// option and the value.
    #[test]
    fn the_belts_of_table_a_are_the_issues_or_those_asked_for() {
        let treadmill = runtime::config::TreadmillConfig::default();
        assert_eq!(
            belts_or_default(None, &treadmill).unwrap(),
            BELT_SPEEDS_MPS.to_vec()
        );
        let belts = belts_or_default(Some("0.15:0.35:0.025"), &treadmill).unwrap();
        assert_eq!(belts.len(), 9);
        assert_eq!((belts[0], belts[3], belts[8]), (0.15, 0.225, 0.35));
        let runs = matrix_runs(&[1, 2], true, &[0.16, 0.167]);
        let constant: Vec<(f64, u64)> = runs
            .iter()
            .filter_map(|r| match r {
                Run::ConstantBelt {
                    speed_mps, seed, ..
                } => Some((*speed_mps, *seed)),
                _ => None,
            })
            .collect();
        assert_eq!(constant, [(0.16, 1), (0.16, 2), (0.167, 1), (0.167, 2)]);
        for (spec, what) in [
            ("0.2,0.6", "0.6"),
            ("0.3,0.2", "0.3,0.2"),
            ("0.1:0.2", "0.1:0.2"),
            ("fast", "fast"),
        ] {
            let e = belts_or_default(Some(spec), &treadmill)
                .unwrap_err()
                .to_string();
            assert!(e.contains("--belts") && e.contains(what), "{spec}: {e}");
        }
        // The range is the config's: a treadmill up to 0.3 m/s refuses 0.35.
        let slow = runtime::config::TreadmillConfig {
            belt_speed_range_mps: [0.0, 0.3],
        };
        let e = belts_or_default(Some("0.2,0.35"), &slow)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--belts") && e.contains("0.35") && e.contains("0.3]"),
            "{e}"
        );
    }
}
