//! The HZD collocation problem ([`HzdProblem`], [`Codesign`]): building it, its start point,
//! and what it reports about a point (violations, block statistics).

use super::blocks::Block;
use super::layout::Layout;
use crate::biped::PlanarBiped;
use crate::config::PlannerConfig;
use crate::nlp::{NlpProblem, SparsityPattern};
use model::kinematics::Constant;
use model::robot::BodyInertia;

/// The HZD collocation problem.
pub struct HzdProblem {
    /// The robot.
    pub biped: PlanarBiped,
    /// The config.
    pub config: PlannerConfig,
    /// Variable layout.
    pub layout: Layout,
    /// Whether the cost of transport is minimized (false: the feasibility stage).
    pub with_cost: bool,
    pub(super) blocks: Vec<Block>,
    pub(super) lower_g: Vec<f64>,
    pub(super) upper_g: Vec<f64>,
    pub(super) jac_rows: Vec<usize>,
    pub(super) jac_cols: Vec<usize>,
    pub(super) hess_pattern: SparsityPattern,
    /// Objective Hessian slots: (T,T unused) T–slack, T–d, slack–d, d–d.
    pub(super) obj_slots: ObjectiveSlots,
    /// The configured cost's terms ([`super::cost`]).
    pub(super) objective: ObjectiveTerms,
    /// Copper-loss coefficient R / (N k_t)² of each actuator, W/(N·m)² (empty when the robot
    /// lacks the constants and the cost does not need them).
    pub(super) copper_loss_w_per_nm2: Vec<f64>,
    pub(super) initial: Vec<f64>,
    pub(super) total_mass_kg: f64,
    pub(super) design: Option<DesignModel>,
    /// The model's mass properties, body by body, as [`Constant`]s.
    pub(super) constant_inertias: Vec<BodyInertia<Constant>>,
    /// The barrier parameter the start point is centred for ([`Self::centre_power_slacks`]).
    pub(super) initial_barrier: Option<f64>,
}

/// The cost Φ = (T/d) · (Σ a_i x_i + Σ b_j x_j²) as lists of (variable, coefficient).
#[derive(Clone, Debug, Default)]
pub(super) struct ObjectiveTerms {
    /// (slack variable, a_i): the power slacks' coefficients (zeros left out).
    pub(super) linear: Vec<(usize, f64)>,
    /// (torque variable, b_j): the scaled torques' coefficients (zeros left out).
    pub(super) quadratic: Vec<(usize, f64)>,
}

#[derive(Clone, Debug, Default)]
pub(super) struct ObjectiveSlots {
    /// (T, x_i) and (x_i, d) of each linear term.
    pub(super) t_lin: Vec<usize>,
    pub(super) lin_d: Vec<usize>,
    /// (x_j, x_j), (T, x_j) and (x_j, d) of each quadratic term.
    pub(super) quad: Vec<usize>,
    pub(super) t_quad: Vec<usize>,
    pub(super) quad_d: Vec<usize>,
    pub(super) t_d: usize,
    pub(super) d_d: usize,
    /// Diagonal slots of the scaled torques (feasibility-stage regularizer).
    pub(super) torque: Vec<usize>,
}

/// Co-design (paper Sec. III): the thigh and shin lengths become NLP variables. They enter
/// through the design virtual joints q_D = L − L_nominal, the same in both legs (so q_LT = q_RT
/// and q_LS = q_RS hold by construction) and constant over the step (q̇_D = 0: they are
/// parameters of every point); the relabeling keeps them.
#[derive(Clone, Debug, PartialEq)]
pub struct Codesign {
    /// Total thigh and shin length at design-joint zero (the model's own links), m.
    pub nominal_m: [f64; 2],
    /// Bounds on the total thigh and shin length, m (paper Table I: 0.15–0.35).
    pub bounds_m: [[f64; 2]; 2],
    /// Link mass properties follow the lengths through the cubic fits inside the NLP (exact
    /// coupling, differentiated with everything else); false: frozen at the model's (the
    /// inner solve of the paper's Alg. 1).
    pub exact_inertia: bool,
    /// The mass model the fits of exact coupling sample (the config's
    /// [`crate::config::CodesignConfig::mass_model`]: the leg tubes' density scale).
    pub mass: model::design::MassModel,
}

/// What the co-design needs of the model: the thigh and shin bodies of both legs and the fits.
#[derive(Clone, Debug)]
pub(super) struct DesignModel {
    pub(super) spec: Codesign,
    /// Body index of the left and right thigh, and of the left and right shin.
    pub(super) thigh_bodies: [usize; 2],
    pub(super) shin_bodies: [usize; 2],
    pub(super) fits: model::design::InertiaFits,
    pub(super) base: Vec<model::robot::BodyInertia<f64>>,
}

impl HzdProblem {
    /// Builds the problem; `initial` is the starting point (see [`crate::guess`]).
    pub fn new(
        biped: PlanarBiped,
        config: PlannerConfig,
        initial: Vec<f64>,
        with_cost: bool,
    ) -> crate::Result<Self> {
        Self::with_codesign(biped, config, initial, with_cost, None)
    }

    /// Builds the problem, with the thigh and shin lengths as variables if `codesign` is given
    /// (the model must have design joints in both legs).
    pub fn with_codesign(
        biped: PlanarBiped,
        config: PlannerConfig,
        initial: Vec<f64>,
        with_cost: bool,
        codesign: Option<Codesign>,
    ) -> crate::Result<Self> {
        // The power slacks only serve the cost: the feasibility problem has none.
        let slacks = with_cost;
        let design = match codesign {
            None => None,
            Some(spec) => {
                let robot_error = |reason: String| crate::PlannerError::Robot {
                    robot: biped.model.name.clone(),
                    reason,
                };
                let mut thigh_bodies = [0; 2];
                let mut shin_bodies = [0; 2];
                for (k, side) in [model::Side::Left, model::Side::Right]
                    .into_iter()
                    .enumerate()
                {
                    let leg = biped.legs.side(side);
                    if leg.thigh_design.is_none() || leg.shin_design.is_none() {
                        return Err(robot_error(format!(
                            "co-design needs thigh and shin design joints in the {} leg",
                            side.prefix()
                        )));
                    }
                    thigh_bodies[k] = biped.model.joints[leg.hip].body;
                    shin_bodies[k] = biped.model.joints[leg.knee].body;
                }
                let fits = model::design::InertiaFits::adam_with(&spec.mass);
                Some(DesignModel {
                    spec,
                    thigh_bodies,
                    shin_bodies,
                    fits,
                    base: biped.model.bodies.iter().map(|b| b.inertia).collect(),
                })
            }
        };
        let layout = Layout {
            nq: biped.nq(),
            nu: biped.nu(),
            m: biped.outputs.len(),
            degree: config.collocation.bezier_degree,
            intervals: config.collocation.intervals,
            stride: 3 * biped.nq() + if slacks { 3 } else { 1 } * biped.nu() + 3,
            design: if design.is_some() { 2 } else { 0 },
            slacks,
            mesh: super::layout::mesh_nodes(
                config.collocation.intervals,
                config.collocation.mesh_grading,
            ),
        };
        if config.cost.weights.len() != layout.nu {
            return Err(crate::PlannerError::InvalidField {
                origin: "planner config".into(),
                field: "cost.weights".into(),
                value: format!("{} weights", config.cost.weights.len()),
                reason: format!("the robot has {} actuated joints", layout.nu),
            });
        }
        let copper_loss_w_per_nm2 = copper_loss_coefficients(&biped, &config)?;
        let total_mass_kg = biped.model.total_mass_kg();
        let constant_inertias = biped.model.constant_inertias();
        let mut p = Self {
            biped,
            config,
            layout,
            with_cost,
            blocks: Vec::new(),
            lower_g: Vec::new(),
            upper_g: Vec::new(),
            jac_rows: Vec::new(),
            jac_cols: Vec::new(),
            hess_pattern: SparsityPattern::default(),
            obj_slots: ObjectiveSlots::default(),
            objective: ObjectiveTerms::default(),
            copper_loss_w_per_nm2,
            initial,
            total_mass_kg,
            constant_inertias,
            initial_barrier: None,
            design,
        };
        p.build_blocks();
        p.objective = p.objective_terms();
        p.build_patterns();
        Ok(p)
    }

    /// Replaces the start point (`x`, [`Layout::len`] long).
    pub fn set_initial(&mut self, x: Vec<f64>) {
        debug_assert_eq!(x.len(), self.layout.len());
        self.initial = x;
        self.initial_barrier = None;
    }

    /// The initial barrier parameter the start point is centred for, if any
    /// ([`Self::centre_power_slacks`]).
    pub fn initial_barrier(&self) -> Option<f64> {
        self.initial_barrier
    }

    /// Largest violation of any constraint or bound at x.
    pub fn max_violation(&self, x: &[f64]) -> f64 {
        let mut g = vec![0.0; self.num_constraints()];
        if self.constraints(x, &mut g).is_err() {
            return f64::INFINITY;
        }
        let (lo, hi) = self.bounds();
        let cons = g
            .iter()
            .enumerate()
            .map(|(i, &v)| (self.lower_g[i] - v).max(v - self.upper_g[i]).max(0.0));
        let vars = x
            .iter()
            .enumerate()
            .map(|(i, &v)| (lo[i] - v).max(v - hi[i]).max(0.0));
        cons.chain(vars).fold(0.0, f64::max)
    }

    /// Per block kind: (blocks, Jacobian entries per block, Hessian pairs per block), for profiling.
    pub fn block_statistics(&self) -> Vec<(String, usize, usize, usize)> {
        let mut out: Vec<(String, usize, usize, usize)> = Vec::new();
        for b in &self.blocks {
            let name = format!("{:?}", b.kind);
            if let Some(e) = out.iter_mut().find(|e| e.0 == name) {
                e.1 += 1;
            } else {
                out.push((name, 1, b.jac.len(), b.hess_slots.len()));
            }
        }
        out
    }

    /// Largest violation per block kind at x, for diagnosing a start point or a failed solve.
    pub fn violation_by_kind(&self, x: &[f64]) -> Vec<(String, f64)> {
        let mut g = vec![0.0; self.num_constraints()];
        let _ = self.constraints(x, &mut g);
        let mut out: Vec<(String, f64)> = Vec::new();
        for b in &self.blocks {
            let v = (b.row0..b.row0 + b.n_out)
                .map(|i| {
                    (self.lower_g[i] - g[i])
                        .max(g[i] - self.upper_g[i])
                        .max(0.0)
                })
                .fold(0.0, f64::max);
            let name = b.kind.describe();
            match out.iter_mut().find(|e| e.0 == name) {
                Some(e) => e.1 = e.1.max(v),
                None => out.push((name, v)),
            }
        }
        out
    }

    /// Constraint bounds (lower, upper).
    pub fn constraint_bounds_vec(&self) -> (&[f64], &[f64]) {
        (&self.lower_g, &self.upper_g)
    }
}

/// Each actuator's copper-loss coefficient R / (N k_t)² from the robot's drives; an error naming
/// the joint and the missing constant when the cost needs them (an electrical term), else empty
/// when any is missing.
fn copper_loss_coefficients(
    biped: &PlanarBiped,
    config: &PlannerConfig,
) -> crate::Result<Vec<f64>> {
    let model = &biped.model;
    let mut out = Vec::new();
    for j in model.actuated_joints() {
        let joint = &model.joints[j];
        match joint.drive.copper_loss_w_per_nm2() {
            Ok(c) => out.push(c),
            Err(missing) if config.cost.mix().electrical > 0.0 => {
                return Err(crate::PlannerError::Robot {
                    robot: model.name.clone(),
                    reason: format!(
                        "the electrical cost (cost.kind = \"{}\") needs the actuator constants of joint '{}', but its <transmission> has no <{missing}> (see model::urdf for the format)",
                        config.cost.kind.name(),
                        joint.name
                    ),
                });
            }
            Err(_) => return Ok(Vec::new()),
        }
    }
    Ok(out)
}
