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

/// A grid point solved from its inner neighbour's solution `from` (its point and
/// multipliers), or from the initial gait when there is none or that solve fails: one step of
/// the `neighbours` start, the same in [`landscape`] and in [`landscape_point_from_neighbours`].
fn neighbour_step(
    config: &PlannerConfig,
    initial: &PlannedGait,
    lengths_m: [f64; 2],
    from: Option<&WarmStart>,
) -> (LandscapePoint, Option<WarmStart>) {
    let tried = from.and_then(|w| {
        let x0 = w.x.as_deref()?;
        solve_point(config, lengths_m, x0, Some(w)).ok()
    });
    match tried {
        Some((o, w)) => (
            LandscapePoint {
                lengths_m,
                outcome: Ok(o),
                from_neighbour: true,
            },
            Some(w),
        ),
        None => initial_point(config, initial, lengths_m),
    }
}

/// The `neighbours` start's order on an n × n grid: the seed (the grid point nearest the
/// initial design `model_lengths`), each point's ring (Chebyshev distance to the seed), and
/// the inner neighbour each point starts from.
struct Rings {
    n: usize,
    seed: (usize, usize),
}

impl Rings {
    fn new(n: usize, thigh_m: &[f64], shin_m: &[f64], model_lengths: [f64; 2]) -> Self {
        let nearest = |v: f64, grid: &[f64]| {
            (0..n)
                .min_by(|&a, &b| (grid[a] - v).abs().total_cmp(&(grid[b] - v).abs()))
                .unwrap_or(0)
        };
        Self {
            n,
            seed: (
                nearest(model_lengths[0], thigh_m),
                nearest(model_lengths[1], shin_m),
            ),
        }
    }

    fn ring_of(&self, (i, j): (usize, usize)) -> usize {
        i.abs_diff(self.seed.0).max(j.abs_diff(self.seed.1))
    }

    /// The neighbour one ring in that (i, j) starts from.
    fn inner(&self, (i, j): (usize, usize)) -> (usize, usize) {
        let toward = |v: usize, s: usize| match v.cmp(&s) {
            std::cmp::Ordering::Less => v + 1,
            std::cmp::Ordering::Equal => v,
            std::cmp::Ordering::Greater => v - 1,
        };
        (toward(i, self.seed.0), toward(j, self.seed.1))
    }

    /// The points of `ring`, thigh-major.
    fn members(&self, ring: usize) -> Vec<(usize, usize)> {
        let n = self.n;
        (0..n * n)
            .map(|k| (k / n, k % n))
            .filter(|&p| self.ring_of(p) == ring)
            .collect()
    }

    /// The points from the seed's ring-1 neighbour out to `p` (p last; empty for the seed).
    fn path_to(&self, p: (usize, usize)) -> Vec<(usize, usize)> {
        let mut path = Vec::new();
        let mut at = p;
        while at != self.seed {
            path.push(at);
            at = self.inner(at);
        }
        path.reverse();
        path
    }
}

/// One point of the landscape started from its neighbours (the `neighbours` start,
/// [`LandscapeStart`]) as an independent task (`adam sweep task` of a landscape plan): the
/// point at index `k` (thigh-major) of the n × n grid, as [`landscape`] finds it, bit for bit.
/// It takes the same steps: the seed from the initial gait, then each point of the chain of
/// inner neighbours from the seed out to this one, from the last one's solution (or, if that
/// fails, from the initial gait). It reads nothing another task wrote; the price is that it
/// solves again the chain's points inside it (at most n − 1). Run it on a rayon worker, as
/// [`landscape`] runs its points.
pub fn landscape_point_from_neighbours(
    config: &PlannerConfig,
    initial: &PlannedGait,
    model_lengths: [f64; 2],
    n: usize,
    k: usize,
) -> Result<LandscapePoint> {
    check_landscape_grid(n, "a landscape point", "grid")?;
    if k >= n * n {
        return Err(crate::PlannerError::Solver(format!(
            "landscape point {k}: the {n} × {n} grid has {} points",
            n * n
        )));
    }
    let c = &config.codesign;
    let (thigh_m, shin_m) = (grid_values(c.thigh_m, n), grid_values(c.shin_m, n));
    let at = |(i, j): (usize, usize)| [thigh_m[i], shin_m[j]];
    let rings = Rings::new(n, &thigh_m, &shin_m, model_lengths);
    let (mut point, mut warm) = initial_point(config, initial, at(rings.seed));
    for p in rings.path_to((k / n, k % n)) {
        (point, warm) = neighbour_step(config, initial, at(p), warm.as_ref());
    }
    Ok(point)
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
            let rings = Rings::new(n, &thigh_m, &shin_m, model_lengths);
            let seed = rings.seed;
            let mut warm: Vec<Option<WarmStart>> = vec![None; n * n];
            let (p, w) = from_initial(seed.0, seed.1);
            points[seed.0 * n + seed.1] = Some(p);
            warm[seed.0 * n + seed.1] = w;
            for ring in 1..n {
                let solved: Vec<(usize, LandscapePoint, Option<WarmStart>)> = rings
                    .members(ring)
                    .par_iter()
                    .map(|&(i, j)| {
                        let (si, sj) = rings.inner((i, j));
                        let (p, w) =
                            neighbour_step(config, initial, at(i, j), warm[si * n + sj].as_ref());
                        on_done(&p);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every point's chain starts one ring out from the seed, steps one ring out each time,
    /// each point from its inner neighbour, and ends at the point: the order the ring-by-ring
    /// loop solves them in, so a task that walks it sees what the loop saw.
    #[test]
    fn the_chain_to_a_point_is_the_rings_inner_neighbours_from_the_seed() {
        for (n, model) in [(9, [0.24, 0.25]), (4, [0.15, 0.35]), (2, [0.3, 0.2])] {
            let grid = grid_values([0.15, 0.35], n);
            let rings = Rings::new(n, &grid, &grid, model);
            assert_eq!(rings.path_to(rings.seed), Vec::new());
            let mut counted = 1;
            for ring in 1..n {
                for p in rings.members(ring) {
                    counted += 1;
                    let path = rings.path_to(p);
                    assert_eq!(path.len(), ring, "{p:?}: {path:?}");
                    assert_eq!(path.last(), Some(&p));
                    assert_eq!(rings.inner(path[0]), rings.seed);
                    for (k, w) in path.windows(2).enumerate() {
                        assert_eq!(rings.inner(w[1]), w[0], "{p:?}: {path:?}");
                        assert_eq!(rings.ring_of(w[0]), k + 1);
                    }
                }
            }
            assert_eq!(counted, n * n, "the rings cover the grid once");
        }
        // The shipped 9 × 9 grid is seeded at its centre (0.25, 0.25 m for 0.24, 0.25 m).
        let grid = grid_values([0.15, 0.35], 9);
        assert_eq!(Rings::new(9, &grid, &grid, [0.24, 0.25]).seed, (4, 4));
    }
}
