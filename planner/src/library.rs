//! The gait library (`adam plan library`): one gait per walking speed for a fixed design, each
//! planned with `gait.speed_mps` = [v, v], verified on its own, and written as one
//! [`model::library::GaitLibrary`].
//!
//! ```text
//! speeds (lo:hi:step or a list) ─▶ middle speed: the paper's two-step plan (cold)
//!                                     │ its optimum, with d moved to v·T, starts the neighbour's
//!                                     ▼ cost-of-transport solve (power slacks re-centred)
//!                     walk outwards: down the slower speeds, up the faster ones
//!                     (a warm solve that fails is planned cold instead)
//!                                     ▼
//!             verify each (Newton on the Poincaré map, eigenvalues, the step it walks)
//!                                     ▼
//!     GaitLibrary (entries by speed), or an error naming a hole wider than MAX_GAP_MPS
//! ```
//!
//! A speed whose gait fails to plan or verify is reported with the reason and left out; the
//! library fails only when what is left has a hole wider than [`MAX_GAP_MPS`] (between two
//! gaits, or between an end of the range asked for and the nearest gait).
//!
//! [`plan_speed`] is one speed of the same computation as an independent task (a gait-library
//! sweep's task on a cluster, `adam sweep plan --study library`): the anchor's plan and the
//! walk out to its speed, with the same steps as [`plan_library`] (the `Chains` of both are
//! one function's), so the library the sweep collects is the in-process one.
//!
//! [`Schedule`] says how the two walks share the machine: one after the other, each solve's
//! block evaluations spread over the rayon pool ([`Schedule::Sequential`]), or the two walks at
//! once, each solve on one thread ([`Schedule::TwoChains`]).

use crate::biped::PlanarBiped;
use crate::collocation::HzdProblem;
use crate::config::PlannerConfig;
use crate::plan::{self, gait_from_solution, plan_gait, Guards};
use crate::verify::{feedforward_from_orbit, verify_gait, VerifyOptions, VerifyReport};
use crate::{PlannerError, Result};
use model::gait::{GaitFile, RobotReference};
use model::library::{GaitLibrary, LibraryCheck, LibraryEntry, LIBRARY_SCHEMA_VERSION};
use model::PlanarModel;
use rayon::prelude::*;
use std::time::Instant;

/// The widest hole a library may have, m/s (issue #29).
pub const MAX_GAP_MPS: f64 = 0.05;

/// The most speeds one library may ask for.
pub const MAX_SPEEDS: usize = 200;

/// How the walks outwards from the middle speed share the machine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Schedule {
    /// One walk after the other; each solve spreads its block evaluations over the pool.
    Sequential,
    /// The slower and the faster walk at once (`rayon::join`), each solve on one thread.
    #[default]
    TwoChains,
}

/// Options of [`plan_library`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LibraryOptions {
    /// How the walks share the machine.
    pub schedule: Schedule,
    /// The verification's options.
    pub verify: VerifyOptions,
    /// Largest relative difference between the verified orbit's step (duration and length)
    /// and the plan's for a gait to enter the library.
    pub max_step_error: f64,
}

impl Default for LibraryOptions {
    fn default() -> Self {
        Self {
            schedule: Schedule::default(),
            verify: VerifyOptions::default(),
            max_step_error: crate::verify::STEP_DURATION_TOLERANCE,
        }
    }
}

/// Parses a speed list: `lo:hi:step` (lo, lo + step, … up to hi) or `v1,v2,…`, m/s. Errors
/// name the spec and what is wrong with it (lo > hi, step ≤ 0, a non-finite or non-positive
/// speed, a list out of order or with a duplicate, more than [`MAX_SPEEDS`]).
pub fn parse_speeds(spec: &str) -> Result<Vec<f64>> {
    let bad = |reason: String| PlannerError::InvalidSpeeds {
        spec: spec.to_string(),
        reason,
    };
    let number = |part: &str, what: &str| -> Result<f64> {
        let v: f64 = part
            .trim()
            .parse()
            .map_err(|_| bad(format!("{what} '{}' is not a number", part.trim())))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(bad(format!("{what} {v} is not finite")))
        }
    };
    let speeds = if spec.contains(':') {
        let parts: Vec<&str> = spec.split(':').collect();
        let [lo, hi, step] = parts[..] else {
            return Err(bad(format!(
                "a range is lo:hi:step (three numbers), this has {} parts",
                parts.len()
            )));
        };
        let (lo, hi, step) = (number(lo, "lo")?, number(hi, "hi")?, number(step, "step")?);
        if lo > hi {
            return Err(bad(format!("lo {lo} is above hi {hi}")));
        }
        if step <= 0.0 {
            return Err(bad(format!("step {step} must be positive")));
        }
        let n = ((hi - lo) / step + 1e-9).floor();
        if n + 1.0 > MAX_SPEEDS as f64 {
            return Err(bad(format!(
                "{} speeds; at most {MAX_SPEEDS}",
                n as u64 + 1
            )));
        }
        // Rounded to 1e-9 m/s so that 0.15 + 3 × 0.025 reads 0.225.
        (0..=n as usize)
            .map(|i| ((lo + i as f64 * step) * 1e9).round() / 1e9)
            .collect()
    } else {
        let v: Vec<f64> = spec
            .split(',')
            .map(|p| number(p, "speed"))
            .collect::<Result<_>>()?;
        if v.len() > MAX_SPEEDS {
            return Err(bad(format!("{} speeds; at most {MAX_SPEEDS}", v.len())));
        }
        for w in v.windows(2) {
            if w[1] <= w[0] {
                return Err(bad(format!(
                    "{} after {}: list the speeds once each, slowest first",
                    w[1], w[0]
                )));
            }
        }
        v
    };
    if let Some(v) = speeds.iter().find(|v| **v <= 0.0) {
        return Err(bad(format!("speed {v} m/s must be positive")));
    }
    Ok(speeds)
}

/// How one speed of the library went (also a gait-library sweep task's result, which
/// `adam sweep task` writes as JSON).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeedOutcome {
    /// The speed asked for, m/s.
    pub speed_mps: f64,
    /// The entry, or why the speed is left out.
    pub result: std::result::Result<LibraryEntry, String>,
    /// Whether the gait was planned from its neighbour's (false: the two-step plan).
    pub warm: bool,
    /// Solver iterations, all solves of this speed.
    pub iterations: usize,
    /// Wall time of this speed's solves, s.
    pub solve_time_s: f64,
    /// Wall time of its verification and feed-forward table, s.
    pub verify_time_s: f64,
}

/// What [`plan_library`] did: one outcome per speed asked for, by speed, and the wall time.
#[derive(Clone, Debug)]
pub struct LibraryPlan {
    /// The library's robot.
    pub robot: RobotReference,
    /// One per speed, slowest first.
    pub outcomes: Vec<SpeedOutcome>,
    /// Wall time of the whole library, s.
    pub wall_time_s: f64,
}

impl LibraryPlan {
    /// The library of the gaits that planned and verified, or an error naming the widest hole
    /// wider than [`MAX_GAP_MPS`] (and the speeds that failed in it, with their reasons).
    pub fn library(&self) -> Result<GaitLibrary> {
        let entries: Vec<LibraryEntry> = self
            .outcomes
            .iter()
            .filter_map(|o| o.result.as_ref().ok().cloned())
            .collect();
        let (Some(first), Some(last)) = (self.outcomes.first(), self.outcomes.last()) else {
            return Err(PlannerError::EmptyLibrary {
                failed: String::new(),
            });
        };
        // The ends of the range asked for count as neighbours: a missing end is a hole too.
        let mut marks: Vec<f64> = vec![first.speed_mps];
        marks.extend(entries.iter().map(|e| e.speed_mps));
        marks.push(last.speed_mps);
        let widest = marks
            .windows(2)
            .map(|w| (w[0], w[1]))
            .max_by(|a, b| (a.1 - a.0).total_cmp(&(b.1 - b.0)));
        let hole = widest.filter(|(a, b)| b - a > MAX_GAP_MPS + 1e-9);
        if entries.is_empty() || hole.is_some() {
            let (from, to) = hole.unwrap_or((first.speed_mps, last.speed_mps));
            let failed: Vec<String> = self
                .outcomes
                .iter()
                .filter(|o| {
                    entries.is_empty() || (o.speed_mps >= from - 1e-12 && o.speed_mps <= to + 1e-12)
                })
                .filter_map(|o| {
                    o.result
                        .as_ref()
                        .err()
                        .map(|e| format!("{} m/s: {e}", o.speed_mps))
                })
                .collect();
            let failed = failed.join("; ");
            if entries.is_empty() {
                return Err(PlannerError::EmptyLibrary { failed });
            }
            return Err(PlannerError::LibraryHole {
                max_gap_mps: MAX_GAP_MPS,
                from_mps: from,
                to_mps: to,
                failed,
            });
        }
        Ok(GaitLibrary {
            schema_version: LIBRARY_SCHEMA_VERSION,
            robot: self.robot.clone(),
            entries,
        })
    }
}

/// A planned gait before its check: the costed problem's optimum and how it was found.
struct Solved {
    x: Vec<f64>,
    gait: GaitFile,
    warm: bool,
    iterations: usize,
    solve_time_s: f64,
}

/// Plans one gait per speed of `speeds_mps` (increasing) for `model` as it is, verifies each,
/// and reports every speed; [`LibraryPlan::library`] makes the file.
pub fn plan_library(
    model: &PlanarModel,
    urdf_ref: &str,
    urdf_text: &str,
    config: &PlannerConfig,
    speeds_mps: &[f64],
    options: LibraryOptions,
) -> Result<LibraryPlan> {
    let start = Instant::now();
    let chains = Chains::new(config, speeds_mps)?;
    let robot = robot_reference(model, urdf_ref, urdf_text);
    let mut solved: Vec<Option<std::result::Result<Solved, String>>> =
        chains.refused.iter().map(|r| r.clone().map(Err)).collect();
    let Some(anchor) = chains.anchor else {
        return Ok(LibraryPlan {
            robot,
            outcomes: solved
                .into_iter()
                .zip(speeds_mps)
                .map(|(s, &v)| check_speed(model, v, s, options))
                .collect(),
            wall_time_s: start.elapsed().as_secs_f64(),
        });
    };
    let job = Job {
        model,
        urdf_ref,
        urdf_text,
        config,
        speeds_mps,
    };
    let first = job.solve_cold(anchor);
    let seed = first.as_ref().ok().map(|s| s.x.clone());
    solved[anchor] = Some(first.map_err(|e| e.to_string()));
    let pool = worker_pool()?;
    let (slower, faster) = pool.install(|| match options.schedule {
        Schedule::Sequential => (job.walk(&chains.down, &seed), job.walk(&chains.up, &seed)),
        Schedule::TwoChains => rayon::join(
            || job.walk(&chains.down, &seed),
            || job.walk(&chains.up, &seed),
        ),
    });
    for (i, r) in slower.into_iter().chain(faster) {
        solved[i] = Some(r);
    }
    // Verify every gait (and tabulate its feed-forward), spread over the pool.
    let outcomes: Vec<SpeedOutcome> = pool.install(|| {
        solved
            .into_par_iter()
            .zip(speeds_mps.par_iter())
            .map(|(s, &v)| check_speed(model, v, s, options))
            .collect()
    });
    Ok(LibraryPlan {
        robot,
        outcomes,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

/// One speed of the library, `speeds_mps[index]`, as an independent task (a gait-library
/// sweep's task, `adam sweep task`): its outcome is the one [`plan_library`] gives that speed,
/// bit for bit, because it runs the same steps in the same order: the anchor's cold plan, then
/// the walk from the anchor out to this speed (the part of [`plan_library`]'s walk that leads
/// here), each solve from the previous one's optimum, then the check. It reads nothing another
/// task wrote; the price is that it solves again the |index − anchor| speeds between the anchor
/// and its own (the wall time of the longest task is that of [`plan_library`]'s longer walk).
pub fn plan_speed(
    model: &PlanarModel,
    urdf_ref: &str,
    urdf_text: &str,
    config: &PlannerConfig,
    speeds_mps: &[f64],
    index: usize,
    options: LibraryOptions,
) -> Result<SpeedOutcome> {
    let chains = Chains::new(config, speeds_mps)?;
    let Some(&speed_mps) = speeds_mps.get(index) else {
        return Err(PlannerError::InvalidSpeeds {
            spec: format!("{speeds_mps:?}"),
            reason: format!("speed index {index}: the list has {}", speeds_mps.len()),
        });
    };
    let job = Job {
        model,
        urdf_ref,
        urdf_text,
        config,
        speeds_mps,
    };
    let solved = match (&chains.refused[index], chains.anchor) {
        (Some(reason), _) => Err(reason.clone()),
        (None, None) => Err("not planned".to_string()),
        (None, Some(anchor)) => {
            let first = job.solve_cold(anchor);
            if index == anchor {
                first.map_err(|e| e.to_string())
            } else {
                let seed = first.as_ref().ok().map(|s| s.x.clone());
                let walk = chains.walk_to(index);
                let pool = worker_pool()?;
                let mut done = pool.install(|| job.walk(walk, &seed));
                match done.pop() {
                    Some((i, r)) if i == index => r,
                    _ => Err("not planned".to_string()),
                }
            }
        }
    };
    let pool = worker_pool()?;
    Ok(pool.install(|| check_speed(model, speed_mps, Some(solved), options)))
}

/// The order of a library's solves: the speeds the config refuses (left out before any solve),
/// the anchor (the middle one of the others, planned cold) and the two walks outwards from it,
/// each speed warm-started from the one before it in its walk.
struct Chains {
    /// Per speed, why the config refuses it (no step within its bounds reaches it).
    refused: Vec<Option<String>>,
    /// The middle speed of those planned.
    anchor: Option<usize>,
    /// The slower speeds, from the anchor down.
    down: Vec<usize>,
    /// The faster speeds, from the anchor up.
    up: Vec<usize>,
}

impl Chains {
    /// The chains of `speeds_mps` under `config` (checked: a valid config, increasing speeds).
    fn new(config: &PlannerConfig, speeds_mps: &[f64]) -> Result<Self> {
        config.validate("planner config")?;
        for w in speeds_mps.windows(2) {
            if w[1] <= w[0] {
                return Err(PlannerError::InvalidSpeeds {
                    spec: format!("{speeds_mps:?}"),
                    reason: format!("{} after {}: speeds must increase", w[1], w[0]),
                });
            }
        }
        let refused: Vec<Option<String>> = speeds_mps
            .iter()
            .map(|&v| {
                at_speed(config, v)
                    .validate("planner config")
                    .err()
                    .map(|e| e.to_string())
            })
            .collect();
        let open: Vec<usize> = (0..speeds_mps.len())
            .filter(|&i| refused[i].is_none())
            .collect();
        let anchor = open.get(open.len() / 2).copied();
        let (down, up) = match anchor {
            Some(a) => (
                open.iter().copied().filter(|&i| i < a).rev().collect(),
                open.iter().copied().filter(|&i| i > a).collect(),
            ),
            None => (Vec::new(), Vec::new()),
        };
        Ok(Self {
            refused,
            anchor,
            down,
            up,
        })
    }

    /// The walk from the anchor to speed `index`, `index` last (empty for the anchor and for
    /// a refused speed).
    fn walk_to(&self, index: usize) -> &[usize] {
        for walk in [&self.down, &self.up] {
            if let Some(k) = walk.iter().position(|&i| i == index) {
                return &walk[..=k];
            }
        }
        &[]
    }
}

/// What every solve of a library shares.
struct Job<'a> {
    model: &'a PlanarModel,
    urdf_ref: &'a str,
    urdf_text: &'a str,
    config: &'a PlannerConfig,
    speeds_mps: &'a [f64],
}

impl Job<'_> {
    /// The paper's two-step plan of speed `index`.
    fn solve_cold(&self, index: usize) -> Result<Solved> {
        solve_cold(
            self.model,
            self.urdf_ref,
            self.urdf_text,
            self.config,
            self.speeds_mps[index],
        )
    }

    /// The speeds of `order`, one after the other, each from the last optimum (the first from
    /// `seed`, the anchor's).
    fn walk(
        &self,
        order: &[usize],
        seed: &Option<Vec<f64>>,
    ) -> Vec<(usize, std::result::Result<Solved, String>)> {
        let mut from = seed.clone();
        order
            .iter()
            .map(|&i| {
                let r = solve_speed(
                    self.model,
                    self.urdf_ref,
                    self.urdf_text,
                    self.config,
                    self.speeds_mps[i],
                    &from,
                );
                if let Ok(s) = &r {
                    from = Some(s.x.clone());
                }
                (i, r.map_err(|e| e.to_string()))
            })
            .collect()
    }
}

/// Whole solves run on the workers: a pool of its own with the stack of a main thread (a
/// solve overflowed a 2 MiB test-thread stack), as the co-design landscape does.
fn worker_pool() -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .stack_size(WORKER_STACK_BYTES)
        .build()
        .map_err(|e| PlannerError::Solver(format!("the library's thread pool: {e}")))
}

/// Stack of the library's workers, bytes (a main thread's).
const WORKER_STACK_BYTES: usize = 8 << 20;

/// The robot a library names: the model's name, its URDF as `urdf_ref` (relative to the
/// library file) and the SHA-256 of `urdf_text`.
pub fn robot_reference(model: &PlanarModel, urdf_ref: &str, urdf_text: &str) -> RobotReference {
    RobotReference {
        name: model.name.clone(),
        urdf: urdf_ref.to_string(),
        sha256: model::gait::sha256_hex(urdf_text),
    }
}

/// The config with `gait.speed_mps` = [v, v].
fn at_speed(config: &PlannerConfig, speed_mps: f64) -> PlannerConfig {
    let mut c = config.clone();
    c.gait.speed_mps = Some([speed_mps, speed_mps]);
    c
}

/// The paper's two-step plan at one speed.
fn solve_cold(
    model: &PlanarModel,
    urdf_ref: &str,
    urdf_text: &str,
    config: &PlannerConfig,
    speed_mps: f64,
) -> Result<Solved> {
    let c = at_speed(config, speed_mps);
    let t0 = Instant::now();
    let planned = plan_gait(model, urdf_ref, urdf_text, &c, &mut |_| {})?;
    Ok(Solved {
        iterations: planned.stages.iter().map(|s| s.iterations).sum(),
        solve_time_s: t0.elapsed().as_secs_f64(),
        x: planned.x,
        gait: planned.gait,
        warm: false,
    })
}

/// One speed from its neighbour's optimum `from` (if any; else, or if that solve fails, cold).
fn solve_speed(
    model: &PlanarModel,
    urdf_ref: &str,
    urdf_text: &str,
    config: &PlannerConfig,
    speed_mps: f64,
    from: &Option<Vec<f64>>,
) -> Result<Solved> {
    if let Some(x) = from {
        let t0 = Instant::now();
        match solve_warm(model, urdf_ref, urdf_text, config, speed_mps, x) {
            Ok(mut s) => {
                s.solve_time_s = t0.elapsed().as_secs_f64();
                return Ok(s);
            }
            Err(spent) => {
                // The failed warm solve's work is this speed's too.
                let mut s = solve_cold(model, urdf_ref, urdf_text, config, speed_mps)?;
                s.iterations += spent;
                s.solve_time_s = t0.elapsed().as_secs_f64();
                return Ok(s);
            }
        }
    }
    solve_cold(model, urdf_ref, urdf_text, config, speed_mps)
}

/// The cost-of-transport solve at `speed_mps` from a neighbouring speed's optimum `x`: the
/// same point with the step length moved to v·T (the duration kept, or moved where the length
/// meets its bounds) and the power slacks re-centred for `[solver] cost_stage_mu_init`. A
/// failed solve gives the iterations it spent.
fn solve_warm(
    model: &PlanarModel,
    urdf_ref: &str,
    urdf_text: &str,
    config: &PlannerConfig,
    speed_mps: f64,
    x: &[f64],
) -> std::result::Result<Solved, usize> {
    let fail = |_: PlannerError| 0_usize;
    let c = at_speed(config, speed_mps);
    let biped = PlanarBiped::new(model.clone(), c.gait.stance_leg, &[]).map_err(fail)?;
    let mut problem = HzdProblem::new(biped, c.clone(), Vec::new(), true).map_err(fail)?;
    let l = problem.layout.clone();
    let mut x0 = x.to_vec();
    let (step, duration) = plan::start_at_speed(&c, x0[l.length()], x0[l.duration()]);
    x0[l.length()] = step;
    x0[l.duration()] = duration;
    problem.set_initial(x0);
    problem.centre_power_slacks(c.solver.cost_stage_mu_init);
    let attempt = plan::solve_stage_attempt(
        &problem,
        "cost of transport",
        &c,
        None,
        Guards::default(),
        &mut |_| {},
    )
    .map_err(fail)?;
    let spent = attempt.report.iterations;
    let (xs, report) = attempt.into_result().map_err(|_| spent)?;
    let gait = gait_from_solution(
        &problem,
        &xs,
        urdf_ref,
        urdf_text,
        std::slice::from_ref(&report),
    )
    .map_err(|_| spent)?;
    Ok(Solved {
        x: xs,
        gait,
        warm: true,
        iterations: report.iterations,
        solve_time_s: report.solve_time_s,
    })
}

/// Verifies one planned gait, adds its feed-forward table, and makes its entry (or the reason
/// it is left out).
fn check_speed(
    model: &PlanarModel,
    speed_mps: f64,
    solved: Option<std::result::Result<Solved, String>>,
    options: LibraryOptions,
) -> SpeedOutcome {
    let mut outcome = SpeedOutcome {
        speed_mps,
        result: Err("not planned".into()),
        warm: false,
        iterations: 0,
        solve_time_s: 0.0,
        verify_time_s: 0.0,
    };
    let s = match solved {
        Some(Ok(s)) => s,
        Some(Err(e)) => {
            outcome.result = Err(format!("planning failed: {e}"));
            return outcome;
        }
        None => return outcome,
    };
    outcome.warm = s.warm;
    outcome.iterations = s.iterations;
    outcome.solve_time_s = s.solve_time_s;
    let t0 = Instant::now();
    let mut gait = s.gait;
    let checked = verify_gait(model, &gait, options.verify).and_then(|report| {
        gait.feedforward = Some(feedforward_from_orbit(model, &gait, options.verify)?);
        Ok(report)
    });
    outcome.verify_time_s = t0.elapsed().as_secs_f64();
    outcome.result = match checked {
        Err(e) => Err(format!("verification failed: {e}")),
        Ok(report) => entry(speed_mps, gait, &report, options),
    };
    outcome
}

/// The library entry of a verified gait, or why it is left out.
fn entry(
    speed_mps: f64,
    gait: GaitFile,
    report: &VerifyReport,
    options: LibraryOptions,
) -> std::result::Result<LibraryEntry, String> {
    let check = LibraryCheck {
        eigenvalues: report
            .eigenvalues
            .iter()
            .map(|&(re, im)| [re, im])
            .collect(),
        spectral_radius: report.spectral_radius,
        fixed_point_residual: report.fixed_point_residual,
        verified_step_length_m: report.step_length_m,
        verified_step_duration_s: report.step_duration_s,
        apex_margin: report.apex_margin.is_finite().then_some(report.apex_margin),
    };
    let mut failures = report.failures(options.verify.fixed_point_tolerance);
    for (what, error) in [
        ("duration", check.duration_error(&gait)),
        ("length", check.length_error(&gait)),
    ] {
        // NaN fails too.
        if error.is_nan() || error > options.max_step_error {
            failures.push(format!(
                "the verified step {what} is {:.2} % off the plan (limit {:.2} %)",
                100.0 * error,
                100.0 * options.max_step_error
            ));
        }
    }
    if failures.is_empty() {
        Ok(LibraryEntry {
            speed_mps,
            gait,
            check,
        })
    } else {
        Err(format!("check failed: {}", failures.join("; ")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_ranges_and_lists_parse_and_bad_ones_are_named() {
        let v = parse_speeds("0.15:0.35:0.025").expect("range");
        assert_eq!(v.len(), 9);
        assert_eq!((v[0], v[3], v[8]), (0.15, 0.225, 0.35));
        assert_eq!(parse_speeds("0.2,0.25").expect("list"), vec![0.2, 0.25]);
        assert_eq!(parse_speeds("0.2:0.2:0.1").expect("one"), vec![0.2]);
        for (spec, words) in [
            (
                "0.35:0.15:0.025",
                &["'0.35:0.15:0.025'", "lo 0.35 is above hi 0.15"][..],
            ),
            ("0.15:0.35:0", &["step 0 must be positive"][..]),
            ("0.15:0.35:-1", &["step -1 must be positive"][..]),
            ("nan:0.35:0.025", &["lo NaN is not finite"][..]),
            ("0.1:0.2", &["lo:hi:step", "2 parts"][..]),
            ("0.25,0.2", &["0.2 after 0.25"][..]),
            ("0.2,0.2", &["0.2 after 0.2"][..]),
            ("0,0.2", &["speed 0 m/s must be positive"][..]),
            ("0.1:100:0.001", &["at most 200"][..]),
            ("fast", &["speed 'fast' is not a number"][..]),
        ] {
            let e = parse_speeds(spec).expect_err(spec).to_string();
            for w in words {
                assert!(e.contains(w), "{spec}: {w}: {e}");
            }
        }
    }

    /// The walks go out from the middle open speed, one speed at a time; the walk to a speed
    /// is the prefix of its walk that ends there; a refused speed has none.
    #[test]
    fn the_walk_to_a_speed_is_the_prefix_of_its_chain_from_the_anchor() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../configs/planner/adam_library.toml"
        );
        let config = PlannerConfig::load(path).expect("shipped config");
        let speeds = parse_speeds("0.15:0.35:0.025").expect("speeds");
        let chains = Chains::new(&config, &speeds).expect("chains");
        assert!(chains.refused.iter().all(Option::is_none));
        assert_eq!(chains.anchor, Some(4));
        assert_eq!(chains.down, vec![3, 2, 1, 0]);
        assert_eq!(chains.up, vec![5, 6, 7, 8]);
        assert_eq!(chains.walk_to(4), &[] as &[usize]);
        assert_eq!(chains.walk_to(1), &[3, 2, 1]);
        assert_eq!(chains.walk_to(8), &[5, 6, 7, 8]);
        // A speed no step within the bounds reaches is refused and has no walk; the anchor is
        // the middle of the others.
        let chains = Chains::new(&config, &[0.01, 0.2, 0.25, 0.3]).expect("chains");
        assert!(chains.refused[0].is_some());
        assert_eq!(chains.anchor, Some(2));
        assert_eq!(chains.walk_to(0), &[] as &[usize]);
        assert_eq!(chains.walk_to(1), &[1]);
        let e = Chains::new(&config, &[0.3, 0.2])
            .err()
            .expect("decreasing speeds");
        assert!(e.to_string().contains("0.2 after 0.3"), "{e}");
    }

    fn outcome(speed_mps: f64, ok: bool) -> SpeedOutcome {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../configs/gaits/adam_codesign.json"
        );
        let mut gait = GaitFile::load(path).expect("shipped gait");
        gait.step_length_m = speed_mps * gait.step_duration_s;
        gait.speed_mps = speed_mps;
        let check = LibraryCheck {
            eigenvalues: vec![[0.5, 0.0]],
            spectral_radius: 0.5,
            fixed_point_residual: 1e-9,
            verified_step_length_m: gait.step_length_m,
            verified_step_duration_s: gait.step_duration_s,
            apex_margin: Some(0.1),
        };
        SpeedOutcome {
            speed_mps,
            result: if ok {
                Ok(LibraryEntry {
                    speed_mps,
                    gait,
                    check,
                })
            } else {
                Err("planning failed: infeasible".into())
            },
            warm: true,
            iterations: 10,
            solve_time_s: 0.1,
            verify_time_s: 0.1,
        }
    }

    fn plan_of(pattern: &[(f64, bool)]) -> LibraryPlan {
        let outcomes: Vec<SpeedOutcome> = pattern.iter().map(|&(v, ok)| outcome(v, ok)).collect();
        LibraryPlan {
            robot: outcomes
                .iter()
                .find_map(|o| o.result.as_ref().ok().map(|e| e.gait.robot.clone()))
                .unwrap_or_else(|| outcome(0.2, true).result.expect("ok").gait.robot),
            outcomes,
            wall_time_s: 1.0,
        }
    }

    /// Two failed speeds in a row at a 0.025 m/s step leave a 0.075 m/s hole: refused, naming
    /// it and the speeds in it; one failed speed (0.05 m/s) is allowed and left out, and so is a
    /// failed end, unless the missing end itself is wider than 0.05 m/s.
    #[test]
    fn a_hole_wider_than_five_centimetres_per_second_is_refused_and_named() {
        let one = plan_of(&[(0.15, true), (0.175, false), (0.2, true), (0.225, true)]);
        let lib = one.library().expect("one gap of 0.05 m/s");
        let speeds: Vec<f64> = lib.entries.iter().map(|e| e.speed_mps).collect();
        assert_eq!(speeds, vec![0.15, 0.2, 0.225]);
        let two = plan_of(&[(0.15, true), (0.175, false), (0.2, false), (0.225, true)]);
        let e = two.library().expect_err("a 0.075 m/s hole").to_string();
        assert!(
            e.contains("from 0.15 to 0.225 m/s")
                && e.contains("0.075 m/s wide")
                && e.contains("0.175 m/s: planning failed")
                && e.contains("0.2 m/s: planning failed"),
            "{e}"
        );
        let end = plan_of(&[(0.15, false), (0.175, true), (0.2, true)]);
        assert_eq!(end.library().expect("a 0.025 m/s end").entries.len(), 2);
        let ends = plan_of(&[(0.1, false), (0.125, false), (0.15, false), (0.175, true)]);
        let e = ends.library().expect_err("a 0.075 m/s end").to_string();
        assert!(e.contains("from 0.1 to 0.175 m/s"), "{e}");
        let none = plan_of(&[(0.2, false)]);
        let e = none.library().expect_err("nothing").to_string();
        assert!(
            e.contains("no speed gave a gait") && e.contains("0.2 m/s: planning failed"),
            "{e}"
        );
    }
}
