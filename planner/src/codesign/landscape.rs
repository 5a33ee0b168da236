//! The cost landscape of the design box: the gait optimized at every design of an n × n grid of
//! thigh and shin lengths (`adam codesign landscape`), in parallel.
//!
//! Each grid point is the cost-of-transport solve at a fixed design on the robot
//! GenerateModel makes there. Two ways to start them ([`LandscapeStart`]):
//! - `initial`: every point from the gait planned at the config's initial design, all points at
//!   once on the rayon pool;
//! - `neighbours`: the point nearest the initial design first, then ring by ring (Chebyshev
//!   distance in the grid) outward, each point from the point and multipliers of its neighbour
//!   one ring in (a point whose warm start fails is solved again from the initial gait).
//!
//! Inside the rayon pool each solve evaluates its derivatives on one thread (the blocks go
//! to the pool only when the caller is not on it), so the grid keeps every core on whole solves.

use super::{generate, SweepOutcome};
use crate::biped::PlanarBiped;
use crate::collocation::HzdProblem;
use crate::config::{check_landscape_grid, PlannerConfig};
use crate::nlp::WarmStart;
use crate::plan::{self, PlannedGait};
use crate::Result;
use std::time::Instant;

/// Stack of each landscape worker, bytes (a main thread's 8 MiB).
const WORKER_STACK_BYTES: usize = 8 << 20;

/// Where the grid's solves start from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LandscapeStart {
    /// Every point from the gait at the initial design.
    Initial,
    /// Ring by ring from the initial design, each point from its inner neighbour's solution.
    Neighbours,
}

/// One grid point.
#[derive(Clone, Debug, PartialEq)]
pub struct LandscapePoint {
    /// Thigh and shin length, m.
    pub lengths_m: [f64; 2],
    /// The gait optimized there, or why it failed.
    pub outcome: std::result::Result<SweepOutcome, String>,
    /// Whether the solve started from a neighbour's solution (else from the initial gait).
    pub from_neighbour: bool,
}

/// The optimal cost over the design box.
#[derive(Clone, Debug, PartialEq)]
pub struct Landscape {
    /// Grid size n.
    pub n: usize,
    /// The thigh lengths of the grid's columns, m.
    pub thigh_m: Vec<f64>,
    /// The shin lengths of the grid's rows, m.
    pub shin_m: Vec<f64>,
    /// n × n points, thigh-major: point (i, j) at `i * n + j` has thigh `thigh_m[i]` and shin
    /// `shin_m[j]`.
    pub points: Vec<LandscapePoint>,
    /// Wall time of the grid, s.
    pub wall_time_s: f64,
}

impl Landscape {
    /// The point of lowest cost of transport, if any solve succeeded.
    pub fn best(&self) -> Option<&LandscapePoint> {
        self.points
            .iter()
            .filter(|p| p.outcome.is_ok())
            .min_by(|a, b| cost(a).total_cmp(&cost(b)))
    }

    /// Solver iterations over all points.
    pub fn iterations(&self) -> usize {
        self.points
            .iter()
            .filter_map(|p| p.outcome.as_ref().ok())
            .map(|o| o.iterations)
            .sum()
    }
}

fn cost(p: &LandscapePoint) -> f64 {
    p.outcome.as_ref().map_or(f64::INFINITY, |o| o.objective)
}

/// A solved grid point: its outcome, and its point and multipliers for a neighbour's start.
type Solved = (SweepOutcome, WarmStart);

/// The gait optimized at the fixed design `lengths_m`, from `x0` (a gait of the same layout at
/// another design) and, if given, that gait's multipliers.
fn solve_point(
    config: &PlannerConfig,
    lengths_m: [f64; 2],
    x0: &[f64],
    warm: Option<&WarmStart>,
) -> Result<Solved> {
    let (model, urdf) = generate(lengths_m, &config.codesign)?;
    let biped = PlanarBiped::new(model, config.gait.stance_leg, &[])?;
    let problem = HzdProblem::new(biped, config.clone(), x0.to_vec(), true)?;
    let attempt = plan::solve_stage_attempt(
        &problem,
        "fixed design",
        config,
        warm.cloned(),
        plan::Guards::default(),
        &mut |_| {},
    )?;
    let warm_next = attempt.solution.warm_start();
    let (x, report) = attempt.into_result()?;
    let g = plan::gait_from_solution(
        &problem,
        &x,
        "robot.urdf",
        &urdf,
        std::slice::from_ref(&report),
    )?;
    Ok((
        SweepOutcome {
            lengths_m,
            step_length_m: g.step_length_m,
            step_duration_s: g.step_duration_s,
            speed_mps: g.speed_mps,
            cost_of_transport: g.cost_of_transport,
            objective: report.objective,
            iterations: report.iterations,
            solve_time_s: report.solve_time_s,
        },
        warm_next,
    ))
}

/// A grid point solved from the gait at the initial design, and its warm start for a neighbour.
fn initial_point(
    config: &PlannerConfig,
    initial: &PlannedGait,
    lengths_m: [f64; 2],
) -> (LandscapePoint, Option<WarmStart>) {
    let r = solve_point(config, lengths_m, &initial.x, None);
    let p = LandscapePoint {
        lengths_m,
        outcome: r.as_ref().map(|s| s.0.clone()).map_err(|e| e.to_string()),
        from_neighbour: false,
    };
    (p, r.ok().map(|s| s.1))
}

/// One point of the landscape started from `initial` (the `initial` start, [`LandscapeStart`]):
/// the gait optimized at the fixed design `lengths_m`. The task of a landscape plan (`adam
/// sweep task`) and of `adam codesign landscape --start initial`, on both paths from a rayon
/// worker (its derivatives on one thread).
pub fn landscape_point(
    config: &PlannerConfig,
    initial: &PlannedGait,
    lengths_m: [f64; 2],
) -> LandscapePoint {
    initial_point(config, initial, lengths_m).0
}

/// The grid values of a range: n points from its lower to its upper end (n ≥ 2).
pub fn grid_values([a, b]: [f64; 2], n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
        .collect()
}

/// The optimal cost of transport over an `n × n` grid of the config's design box, every solve
/// warm-started as `start` says from `initial` (the gait planned at `model_lengths`).
/// `on_done` is called from the worker threads as points finish (for a progress bar).
pub fn landscape(
    config: &PlannerConfig,
    initial: &PlannedGait,
    model_lengths: [f64; 2],
    n: usize,
    start: LandscapeStart,
    on_done: &(dyn Fn(&LandscapePoint) + Sync),
) -> Result<Landscape> {
    use rayon::prelude::*;
    check_landscape_grid(n, "adam codesign landscape", "grid")?;
    let t0 = Instant::now();
    let c = &config.codesign;
    let (thigh_m, shin_m) = (grid_values(c.thigh_m, n), grid_values(c.shin_m, n));
    let at = |i: usize, j: usize| [thigh_m[i], shin_m[j]];
    let from_initial = |i: usize, j: usize| {
        let (p, w) = initial_point(config, initial, at(i, j));
        on_done(&p);
        (p, w)
    };
    let mut points: Vec<Option<LandscapePoint>> = vec![None; n * n];
    // Whole solves on the workers: a pool of its own with the stack of a main thread (a
    // solve's fallback to ripopt overflowed a default 2 MiB worker stack in a test run
    // beside another solve).
    let pool = rayon::ThreadPoolBuilder::new()
        .stack_size(WORKER_STACK_BYTES)
        .build()
        .map_err(|e| crate::PlannerError::Solver(format!("the landscape's thread pool: {e}")))?;
    pool.install(|| match start {
        LandscapeStart::Initial => {
            let solved: Vec<LandscapePoint> = (0..n * n)
                .into_par_iter()
                .map(|k| from_initial(k / n, k % n).0)
                .collect();
            points = solved.into_iter().map(Some).collect();
        }
        LandscapeStart::Neighbours => {
            let nearest = |v: f64, grid: &[f64]| {
                (0..n)
                    .min_by(|&a, &b| (grid[a] - v).abs().total_cmp(&(grid[b] - v).abs()))
                    .unwrap_or(0)
            };
            let seed = (
                nearest(model_lengths[0], &thigh_m),
                nearest(model_lengths[1], &shin_m),
            );
            let mut warm: Vec<Option<WarmStart>> = vec![None; n * n];
            let (p, w) = from_initial(seed.0, seed.1);
            points[seed.0 * n + seed.1] = Some(p);
            warm[seed.0 * n + seed.1] = w;
            let ring_of = |i: usize, j: usize| i.abs_diff(seed.0).max(j.abs_diff(seed.1));
            let toward = |v: usize, s: usize| match v.cmp(&s) {
                std::cmp::Ordering::Less => v + 1,
                std::cmp::Ordering::Equal => v,
                std::cmp::Ordering::Greater => v - 1,
            };
            for ring in 1..n {
                let members: Vec<(usize, usize)> = (0..n * n)
                    .map(|k| (k / n, k % n))
                    .filter(|&(i, j)| ring_of(i, j) == ring)
                    .collect();
                let solved: Vec<(usize, LandscapePoint, Option<WarmStart>)> = members
                    .par_iter()
                    .map(|&(i, j)| {
                        let src = toward(i, seed.0) * n + toward(j, seed.1);
                        let neighbour = warm[src].as_ref();
                        let tried = neighbour.and_then(|w| {
                            let x0 = w.x.as_deref()?;
                            solve_point(config, at(i, j), x0, Some(w)).ok()
                        });
                        let (p, w) = match tried {
                            Some((o, w)) => {
                                let p = LandscapePoint {
                                    lengths_m: at(i, j),
                                    outcome: Ok(o),
                                    from_neighbour: true,
                                };
                                on_done(&p);
                                (p, Some(w))
                            }
                            None => from_initial(i, j),
                        };
                        (i * n + j, p, w)
                    })
                    .collect();
                for (k, p, w) in solved {
                    points[k] = Some(p);
                    warm[k] = w;
                }
            }
        }
    });
    let points = points
        .into_iter()
        .enumerate()
        .map(|(k, p)| {
            p.unwrap_or_else(|| LandscapePoint {
                lengths_m: at(k / n, k % n),
                outcome: Err("not solved".into()),
                from_neighbour: false,
            })
        })
        .collect();
    Ok(Landscape {
        n,
        thigh_m,
        shin_m,
        points,
        wall_time_s: t0.elapsed().as_secs_f64(),
    })
}
