//! One design for several speeds (`adam codesign --speeds 0.20,0.25,0.30`): the gaits at each
//! speed and the thigh and shin lengths in one NLP, minimizing the mean cost of transport.
//!
//! ```text
//! x = [ gait₀ | gait₁ | … | gait_{S−1} | thigh, shin ]      (the lengths shared)
//! f = (1/S) Σ_s Φ_s(gait_s, L)    g = [ g₀(gait₀, L); …; g_{S−1}(gait_{S−1}, L) ]
//! ```
//!
//! Each block is the exactly coupled co-design problem of one speed ([`HzdProblem`] with
//! `gait.speed_mps = [v, v]`); the composite maps each block's variables into x (its design
//! variables, the last two of its layout, onto the shared pair) and sums the blocks'
//! derivatives there, so they stay exact. The design variables come last in every block and in
//! x, so each block's lower-triangle Hessian entries stay in the lower triangle.

use super::{generate, Activity};
use crate::biped::PlanarBiped;
use crate::collocation::{Codesign, HzdProblem};
use crate::config::PlannerConfig;
use crate::nlp::{self, DomainError, NlpProblem, SparsityPattern};
use crate::plan::{self, PlannedGait};
use crate::{PlannerError, Result};
use std::collections::HashMap;

/// The gaits of several speeds sharing one design.
pub struct MultiSpeedProblem {
    /// One co-design problem per speed.
    pub blocks: Vec<HzdProblem>,
    /// First index in x of each block's gait variables.
    offsets: Vec<usize>,
    /// Index in x of the shared thigh length (the shin's follows).
    design: usize,
    /// First constraint row of each block.
    rows: Vec<usize>,
    /// Each block's Hessian entries' slots in the composite's (merged) Hessian.
    hess_slots: Vec<Vec<usize>>,
    hess: SparsityPattern,
}

impl MultiSpeedProblem {
    /// The composite of `blocks` (co-design problems of one robot, with the same design spec).
    pub fn new(blocks: Vec<HzdProblem>) -> Result<Self> {
        if blocks.is_empty() || blocks.iter().any(|b| b.layout.design != 2) {
            return Err(PlannerError::Robot {
                robot: "multi-speed co-design".into(),
                reason: "needs at least one co-design problem, each with two design lengths".into(),
            });
        }
        let mut offsets = Vec::new();
        let mut rows = Vec::new();
        let (mut n, mut m) = (0, 0);
        for b in &blocks {
            offsets.push(n);
            rows.push(m);
            n += b.layout.len() - 2;
            m += b.num_constraints();
        }
        let mut me = Self {
            blocks,
            offsets,
            design: n,
            rows,
            hess_slots: Vec::new(),
            hess: SparsityPattern::default(),
        };
        let mut slot_of: HashMap<(usize, usize), usize> = HashMap::new();
        let mut hess = SparsityPattern::default();
        let mut hess_slots = Vec::new();
        for s in 0..me.blocks.len() {
            let p = me.blocks[s].hessian_structure();
            let slots = p
                .rows
                .iter()
                .zip(&p.cols)
                .map(|(&r, &c)| {
                    let key = (me.global(s, r), me.global(s, c));
                    *slot_of.entry(key).or_insert_with(|| {
                        hess.push(key.0, key.1);
                        hess.len() - 1
                    })
                })
                .collect();
            hess_slots.push(slots);
        }
        me.hess = hess;
        me.hess_slots = hess_slots;
        Ok(me)
    }

    /// Index in x of block `s`'s variable `i`.
    fn global(&self, s: usize, i: usize) -> usize {
        let gait = self.blocks[s].layout.len() - 2;
        if i < gait {
            self.offsets[s] + i
        } else {
            self.design + (i - gait)
        }
    }

    /// Block `s`'s variables out of x.
    pub fn block_x(&self, s: usize, x: &[f64]) -> Vec<f64> {
        let gait = self.blocks[s].layout.len() - 2;
        let mut v = x[self.offsets[s]..self.offsets[s] + gait].to_vec();
        v.extend_from_slice(&x[self.design..self.design + 2]);
        v
    }

    /// The shared thigh and shin lengths in x, m.
    pub fn lengths_m(&self, x: &[f64]) -> [f64; 2] {
        [x[self.design], x[self.design + 1]]
    }

    fn weight(&self) -> f64 {
        1.0 / self.blocks.len() as f64
    }
}

impl NlpProblem for MultiSpeedProblem {
    fn num_variables(&self) -> usize {
        self.design + 2
    }

    fn num_constraints(&self) -> usize {
        self.rows.last().copied().unwrap_or(0)
            + self.blocks.last().map_or(0, |b| b.num_constraints())
    }

    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        for (s, b) in self.blocks.iter().enumerate() {
            let n = b.num_variables();
            let (mut lo, mut hi) = (vec![0.0; n], vec![0.0; n]);
            b.variable_bounds(&mut lo, &mut hi);
            for i in 0..n {
                let g = self.global(s, i);
                lower[g] = lo[i];
                upper[g] = hi[i];
            }
        }
    }

    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        for (s, b) in self.blocks.iter().enumerate() {
            let (r, m) = (self.rows[s], b.num_constraints());
            b.constraint_bounds(&mut lower[r..r + m], &mut upper[r..r + m]);
        }
    }

    fn initial_point(&self, x0: &mut [f64]) {
        for (s, b) in self.blocks.iter().enumerate() {
            let mut v = vec![0.0; b.num_variables()];
            b.initial_point(&mut v);
            for (i, value) in v.into_iter().enumerate() {
                x0[self.global(s, i)] = value;
            }
        }
    }

    fn objective(&self, x: &[f64]) -> Result<f64, DomainError> {
        let mut f = 0.0;
        for (s, b) in self.blocks.iter().enumerate() {
            f += b.objective(&self.block_x(s, x))?;
        }
        Ok(f * self.weight())
    }

    fn gradient(&self, x: &[f64], gradient: &mut [f64]) -> Result<(), DomainError> {
        gradient.fill(0.0);
        for (s, b) in self.blocks.iter().enumerate() {
            let mut g = vec![0.0; b.num_variables()];
            b.gradient(&self.block_x(s, x), &mut g)?;
            for (i, v) in g.into_iter().enumerate() {
                gradient[self.global(s, i)] += v * self.weight();
            }
        }
        Ok(())
    }

    fn constraints(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        for (s, b) in self.blocks.iter().enumerate() {
            let (r, m) = (self.rows[s], b.num_constraints());
            b.constraints(&self.block_x(s, x), &mut values[r..r + m])?;
        }
        Ok(())
    }

    fn jacobian_structure(&self) -> SparsityPattern {
        let mut p = SparsityPattern::default();
        for (s, b) in self.blocks.iter().enumerate() {
            let j = b.jacobian_structure();
            for (&r, &c) in j.rows.iter().zip(&j.cols) {
                p.push(self.rows[s] + r, self.global(s, c));
            }
        }
        p
    }

    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) -> Result<(), DomainError> {
        let mut at = 0;
        for (s, b) in self.blocks.iter().enumerate() {
            let k = b.jacobian_structure().len();
            b.jacobian_values(&self.block_x(s, x), &mut values[at..at + k])?;
            at += k;
        }
        Ok(())
    }

    fn hessian_structure(&self) -> SparsityPattern {
        self.hess.clone()
    }

    fn hessian_values(
        &self,
        x: &[f64],
        objective_factor: f64,
        multipliers: &[f64],
        values: &mut [f64],
    ) -> Result<(), DomainError> {
        values.fill(0.0);
        for (s, b) in self.blocks.iter().enumerate() {
            let (r, m) = (self.rows[s], b.num_constraints());
            let mut h = vec![0.0; self.hess_slots[s].len()];
            b.hessian_values(
                &self.block_x(s, x),
                objective_factor * self.weight(),
                &multipliers[r..r + m],
                &mut h,
            )?;
            for (v, &slot) in h.into_iter().zip(&self.hess_slots[s]) {
                values[slot] += v;
            }
        }
        Ok(())
    }
}

/// The design found for several speeds, and each speed's gait on it.
pub struct MultiSpeedResult {
    /// The shared thigh and shin lengths, m.
    pub lengths_m: [f64; 2],
    /// The speeds, m/s.
    pub speeds_mps: Vec<f64>,
    /// Each speed's gait planned on the co-designed robot (design fixed, polished).
    pub gaits: Vec<PlannedGait>,
    /// The co-designed robot's URDF.
    pub urdf: String,
    /// The composite solve's iterations, status and mean cost of transport.
    pub iterations: usize,
    /// The solver's status.
    pub status: String,
    /// The composite objective at its optimum (mean cost of transport, mass of the start).
    pub mean_cost: f64,
    /// Which constraints hold the shared design, per speed.
    pub activity: Vec<Activity>,
}

/// Co-designs one robot for every speed in `speeds_mps` (m/s) from the config's initial design:
/// plans each speed's gait there (the warm starts), solves the composite NLP, then plans each
/// speed's gait on the regenerated robot. `urdf_ref` is how the gait files name the URDF.
pub fn codesign_speeds(
    config: &PlannerConfig,
    speeds_mps: &[f64],
    urdf_ref: &str,
) -> Result<MultiSpeedResult> {
    let c = &config.codesign;
    let lengths = c.initial_m;
    let (model, urdf) = generate(lengths, &config.codesign)?;
    let at_speed = |v: f64| {
        let mut cfg = config.clone();
        cfg.gait.speed_mps = Some([v, v]);
        cfg.validate("planner config with --speeds")?;
        Ok::<_, PlannerError>(cfg)
    };
    let mut blocks = Vec::new();
    for &v in speeds_mps {
        let cfg = at_speed(v)?;
        let warm = plan::plan_gait(&model, urdf_ref, &urdf, &cfg, &mut |_| {})?;
        let biped = PlanarBiped::new(model.clone(), cfg.gait.stance_leg, &[])?;
        let mut x0 = warm.x.clone();
        x0.extend(lengths);
        let spec = Codesign {
            nominal_m: lengths,
            bounds_m: [c.thigh_m, c.shin_m],
            exact_inertia: true,
            mass: c.mass_model(),
        };
        blocks.push(HzdProblem::with_codesign(biped, cfg, x0, true, Some(spec))?);
    }
    let problem = MultiSpeedProblem::new(blocks)?;
    let options = nlp::SolveOptions {
        tolerance: config.solver.tolerance,
        constraint_violation_tolerance: 1e-6,
        max_iterations: config.solver.max_iterations,
        backend: match config.solver.backend {
            crate::config::SolverBackend::Ripopt => nlp::Backend::Ripopt,
            crate::config::SolverBackend::Native => nlp::Backend::Native,
        },
        ..nlp::SolveOptions::default()
    };
    let sol = nlp::solve(&problem, &options).map_err(|e| PlannerError::Solver(e.to_string()))?;
    if !sol.status.is_success() {
        return Err(PlannerError::NotSolved {
            stage: format!("multi-speed co-design at {speeds_mps:?} m/s"),
            status: format!("{:?}", sol.status).to_lowercase(),
            iterations: sol.statistics.iterations,
            violation: sol.statistics.primal_infeasibility,
            violated: Vec::new(),
        });
    }
    let found = problem.lengths_m(&sol.x);
    // Each block's activity, from its slice of the multipliers.
    let activity = (0..problem.blocks.len())
        .map(|s| {
            let b = &problem.blocks[s];
            let (r, m) = (problem.rows[s], b.num_constraints());
            let n = b.num_variables();
            let idx: Vec<usize> = (0..n).map(|i| problem.global(s, i)).collect();
            let pick = |v: &[f64]| idx.iter().map(|&g| v[g]).collect::<Vec<f64>>();
            let mut one = sol.clone();
            one.x = problem.block_x(s, &sol.x);
            one.constraint_values = sol.constraint_values[r..r + m].to_vec();
            one.constraint_multipliers = sol.constraint_multipliers[r..r + m].to_vec();
            one.lower_bound_multipliers = pick(&sol.lower_bound_multipliers);
            one.upper_bound_multipliers = pick(&sol.upper_bound_multipliers);
            super::activity(b, &one)
        })
        .collect();
    // Each speed's gait on the co-designed robot, design fixed, from its block's solution.
    let (model, urdf) = generate(found, &config.codesign)?;
    let mut gaits = Vec::new();
    for (s, &v) in speeds_mps.iter().enumerate() {
        let cfg = at_speed(v)?;
        let biped = PlanarBiped::new(model.clone(), cfg.gait.stance_leg, &[])?;
        let mut x = problem.block_x(s, &sol.x);
        x.truncate(x.len() - 2);
        let fixed = HzdProblem::new(biped, cfg.clone(), x, true)?;
        let (xf, report) = plan::solve_stage(&fixed, "polish", &cfg, &mut |_| {})?;
        let mut gait =
            plan::gait_from_solution(&fixed, &xf, urdf_ref, &urdf, std::slice::from_ref(&report))?;
        gait.feedforward = Some(crate::verify::feedforward_from_orbit(
            &model,
            &gait,
            crate::verify::VerifyOptions::default(),
        )?);
        let size = (fixed.layout.len(), fixed.num_constraints());
        gaits.push(PlannedGait {
            gait,
            stages: vec![report],
            x: xf,
            feasible_x: Vec::new(),
            size,
            feasibility_size: None,
            setup_time_s: 0.0,
        });
    }
    Ok(MultiSpeedResult {
        lengths_m: found,
        speeds_mps: speeds_mps.to_vec(),
        gaits,
        urdf,
        iterations: sol.statistics.iterations,
        status: format!("{:?}", sol.status).to_lowercase(),
        mean_cost: sol.statistics.objective,
        activity,
    })
}
