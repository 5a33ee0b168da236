//! The planner configuration (`configs/planner/*.toml`): checked data with a schema version.
//!
//! Every setting a user may change lives here, the co-design's too: `[codesign]` holds the
//! design box (thigh and shin length bounds, paper Table I), the initial design, the inertia
//! coupling and Alg. 1's stopping rule; `[codesign.sweep]` the convergence study's grid and the
//! cost-of-transport margin that marks a worse local minimum ([`CodesignConfig`],
//! [`SweepConfig`]). [`PlannerConfig::validate`] names the file, the field and the value.

use crate::{PlannerError, Result};
use model::Side;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The config schema version this build reads.
pub const PLANNER_CONFIG_VERSION: u32 = 1;

/// Collocation settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollocationConfig {
    /// Hermite–Simpson intervals N (2N + 1 collocation points).
    pub intervals: usize,
    /// Bézier degree b of the desired outputs.
    pub bezier_degree: usize,
    /// ε of the output dynamics ÿ + 2εẏ + ε²y = 0 imposed at every point, 1/s.
    pub output_gain_per_s: f64,
    /// Grading g ∈ [0, 0.95] of the mesh: 0 uniform; g > 0 makes the first and last intervals
    /// 1 − g times the uniform length and the middle ones up to 1 + g times
    /// ([`crate::collocation::mesh_nodes`]), where the transcription error is largest
    /// (planner/CODESIGN.md, "Plan accuracy"). Default [`DEFAULT_MESH_GRADING`].
    #[serde(default = "default_mesh_grading")]
    pub mesh_grading: f64,
}

/// The default `[collocation] mesh_grading` (planner/CODESIGN.md, "Plan accuracy").
pub const DEFAULT_MESH_GRADING: f64 = 0.8;

/// The default `[collocation] intervals` (planner/CODESIGN.md, "Plan accuracy").
pub const DEFAULT_INTERVALS: usize = 20;

/// The largest `[collocation] mesh_grading` accepted (1 would make the end intervals empty).
pub const MAX_MESH_GRADING: f64 = 0.95;

fn default_mesh_grading() -> f64 {
    DEFAULT_MESH_GRADING
}

/// The gait's essential and physical constraints.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitConfig {
    /// The stance leg of the planned step (the other steps are its mirror image).
    pub stance_leg: Side,
    /// Step length range, m (paper Table I: 0.15–0.35).
    pub step_length_m: [f64; 2],
    /// Step duration range, s (paper Table I: 0.6–0.9).
    pub step_duration_s: [f64; 2],
    /// Mean forward speed d/T of the step, m/s: `[lo, hi]`, a band, or `lo = hi` for one
    /// speed; absent, the speed is free. An essential constraint on the step length d and
    /// duration T, written linearly (d − lo·T ≥ 0, hi·T − d ≥ 0; d − v·T = 0 for one speed) so
    /// its derivatives are exact constants.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_mps: Option<[f64; 2]>,
    /// The zero dynamics' Poincaré eigenvalue, at most: λ_z = (σ⁺/σ⁻)², σ the angular momentum
    /// about the stance foot just after and just before the impact (σ⁺ is the momentum about
    /// the swing foot before it, which the impact conserves). λ_z is how much of a speed error
    /// a step keeps; absent, free (ours, not Table I: the paper's gaits have no such bound).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_zero_dynamics_eigenvalue: Option<f64>,
    /// The apex margin m, at least: the angular momentum about the stance foot σ stays above
    /// √(1 − (1 − m)²)·σ⁺ at every collocation point, σ⁺ the post-impact one, so that a step
    /// that starts with (1 − m)·σ⁺ still passes over the stance foot
    /// (`planner::verify::apex_margin`; the verified orbit's margin lands on it). Absent, free
    /// (ours, not Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_apex_margin: Option<f64>,
    /// Swing-foot height at mid-step, at least, m.
    pub swing_clearance_m: f64,
    /// Downward swing-foot velocity at impact, at least, m/s.
    pub impact_velocity_mps: f64,
    /// Upward velocity of the old stance foot just after impact, at least, m/s.
    pub liftoff_velocity_mps: f64,
    /// Coulomb friction coefficient μ at the stance foot (forces and the impact impulse).
    pub friction_coefficient: f64,
    /// Normal contact force at the stance foot, at least, N.
    pub min_normal_force_n: f64,
    /// Torso pitch range, rad.
    pub pitch_limits_rad: [f64; 2],
}

impl GaitConfig {
    /// The speeds a step within `step_length_m` and `step_duration_s` can have, m/s:
    /// [shortest / longest, longest / shortest].
    pub fn reachable_speed_mps(&self) -> [f64; 2] {
        [
            self.step_length_m[0] / self.step_duration_s[1],
            self.step_length_m[1] / self.step_duration_s[0],
        ]
    }

    /// Checks `speed_mps` (if given): finite, 0 < lo ≤ hi, and reachable by some step within
    /// the length and duration bounds (an error names both fields). The length and duration
    /// ranges must already be valid.
    pub fn check_speed(&self, origin: &str) -> Result<()> {
        let Some([lo, hi]) = self.speed_mps else {
            return Ok(());
        };
        let bad = |value: String, reason: String| PlannerError::InvalidField {
            origin: origin.to_string(),
            field: "gait.speed_mps".into(),
            value,
            reason,
        };
        let shown = format!("[{lo}, {hi}]");
        if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi) {
            return Err(bad(
                shown,
                "must be [lower, upper] m/s with 0 < lower ≤ upper (lower = upper for one speed)"
                    .into(),
            ));
        }
        let [slowest, fastest] = self.reachable_speed_mps();
        if hi < slowest || lo > fastest {
            let [d_lo, d_hi] = self.step_length_m;
            let [t_lo, t_hi] = self.step_duration_s;
            return Err(bad(
                shown,
                format!(
                    "no step can reach it: gait.step_length_m = [{d_lo}, {d_hi}] and gait.step_duration_s = [{t_lo}, {t_hi}] allow {slowest:.4}–{fastest:.4} m/s"
                ),
            ));
        }
        Ok(())
    }
}

/// The cost the gait minimizes (`[cost]`): its kind, the per-joint weights every kind applies,
/// and, for `kind = "weighted"`, the weights of the sum. The formulas and units are in
/// [`crate::collocation`] ("Costs") and `planner/CODESIGN.md`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CostConfig {
    /// Which cost: `mechanical` (the default), `electrical`, `torque_squared` or `weighted`.
    #[serde(default)]
    pub kind: CostKind,
    /// Weight w_i per actuated joint, in the model's coordinate order (every kind).
    pub weights: Vec<f64>,
    /// The weighted sum's weights (`[cost.weighted]`); only with `kind = "weighted"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weighted: Option<CostMix>,
}

/// The kinds of cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CostKind {
    /// Mechanical cost of transport Σ w_i ∫ |u_i q̇_i| dt / (m g d), dimensionless.
    #[default]
    Mechanical,
    /// Electrical cost of transport of the A1 actuators: Σ w_i ∫ [(u_i / (N k_t))² R +
    /// max(u_i q̇_i, 0)] dt / (m g d), dimensionless (copper loss plus positive mechanical
    /// power, no regeneration); N, k_t, R from the robot's transmissions.
    Electrical,
    /// Torque squared per distance Σ w_i ∫ u_i² dt / d, N²·m·s.
    TorqueSquared,
    /// The weighted sum of the three, weights in `[cost.weighted]`.
    Weighted,
}

impl CostKind {
    /// The name as the config writes it.
    pub fn name(self) -> &'static str {
        match self {
            CostKind::Mechanical => "mechanical",
            CostKind::Electrical => "electrical",
            CostKind::TorqueSquared => "torque_squared",
            CostKind::Weighted => "weighted",
        }
    }
}

/// Weights of the weighted sum λ_m Φ_mech + λ_e Φ_elec + λ_τ Φ_τ² (each ≥ 0, not all zero).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CostMix {
    /// λ_m, on the mechanical cost of transport (dimensionless).
    #[serde(default)]
    pub mechanical: f64,
    /// λ_e, on the electrical cost of transport (dimensionless).
    #[serde(default)]
    pub electrical: f64,
    /// λ_τ, on the torque squared per distance, 1/(N²·m·s).
    #[serde(default)]
    pub torque_squared: f64,
}

impl CostConfig {
    /// The cost as a weighted sum: each kind is the sum with one weight 1.
    pub fn mix(&self) -> CostMix {
        let one = |m: f64, e: f64, t: f64| CostMix {
            mechanical: m,
            electrical: e,
            torque_squared: t,
        };
        match self.kind {
            CostKind::Mechanical => one(1.0, 0.0, 0.0),
            CostKind::Electrical => one(0.0, 1.0, 0.0),
            CostKind::TorqueSquared => one(0.0, 0.0, 1.0),
            CostKind::Weighted => self.weighted.unwrap_or_default(),
        }
    }
}

/// Solver settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverConfig {
    /// Convergence tolerance.
    pub tolerance: f64,
    /// Iteration limit per solve.
    pub max_iterations: usize,
    /// The NLP backend: `"native"` (default: our own interior point,
    /// [`crate::nlp::NativeSolver`]; a stage whose restoration fails is solved again with
    /// ripopt) or `"ripopt"`.
    #[serde(default)]
    pub backend: SolverBackend,
    /// Initial barrier parameter μ₀ of the cost-of-transport solve (IPOPT's `mu_init`). That
    /// solve starts from the feasibility solve's point, with power slacks made from its u q̇ on
    /// the central path of μ₀ ([`crate::collocation::HzdProblem::centre_power_slacks`]); a
    /// smaller μ₀ keeps it closer to that start.
    #[serde(default = "default_cost_stage_mu_init")]
    pub cost_stage_mu_init: f64,
}

fn default_cost_stage_mu_init() -> f64 {
    DEFAULT_COST_STAGE_MU_INIT
}

/// The default `[solver] cost_stage_mu_init` (planner/NLP.md, "Eleventh round").
pub const DEFAULT_COST_STAGE_MU_INIT: f64 = 1e-5;

/// Which NLP backend the planner uses (`[solver] backend`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverBackend {
    /// ripopt, the IPOPT port (`planner::nlp::Backend::Ripopt`).
    Ripopt,
    /// Our own interior point (`planner::nlp::Backend::Native`), the default.
    #[default]
    Native,
}

/// A planner config file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannerConfig {
    /// Must equal [`PLANNER_CONFIG_VERSION`].
    pub schema_version: u32,
    /// Collocation.
    pub collocation: CollocationConfig,
    /// Constraints.
    pub gait: GaitConfig,
    /// Cost.
    pub cost: CostConfig,
    /// Solver.
    pub solver: SolverConfig,
    /// Co-design of the thigh and shin lengths (`adam codesign`).
    #[serde(default)]
    pub codesign: CodesignConfig,
    /// Switches for the constraints that are ours, not the paper's (`adam codesign audit`).
    #[serde(default)]
    pub constraints: ConstraintSwitches,
}

/// Switches for the constraints the planner adds to the paper's (`[constraints]`; the audit
/// of planner/CODESIGN.md, "Constraints", solves with and without each). The defaults are the
/// shipped behaviour. The numeric margins of `[gait]` turn the other added constraints down to
/// their physical form: `swing_clearance_m = 0` leaves z ≥ 0 for the swing foot,
/// `impact_velocity_mps = 0` a touchdown that does not rise, `min_normal_force_n = 0` a
/// unilateral contact.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSwitches {
    /// Where the swing foot must clear `gait.swing_clearance_m`: over the whole swing under
    /// the envelope 4s(1−s)·c (`envelope`, the default), or at mid-step only with z ≥ 0
    /// elsewhere (`midstep`, the paper's "minimum foot clearance").
    pub clearance_profile: ClearanceProfile,
    /// The old stance foot must leave the ground after impact (upward velocity at least
    /// `gait.liftoff_velocity_mps`); false drops the row's bound.
    pub liftoff: bool,
}

impl Default for ConstraintSwitches {
    fn default() -> Self {
        Self {
            clearance_profile: ClearanceProfile::Envelope,
            liftoff: true,
        }
    }
}

/// Where the swing-foot clearance applies (`[constraints] clearance_profile`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ClearanceProfile {
    /// z ≥ 4s(1−s)·c at every interior point (s = k/2N).
    #[default]
    Envelope,
    /// z ≥ c at the mid-step point only, z ≥ 0 at the other interior points.
    Midstep,
}

/// The co-design's settings (paper Sec. III–IV).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CodesignConfig {
    /// Initial thigh and shin length, m.
    pub initial_m: [f64; 2],
    /// Bounds on the thigh length, m (paper Table I).
    pub thigh_m: [f64; 2],
    /// Bounds on the shin length, m (paper Table I).
    pub shin_m: [f64; 2],
    /// Link inertias as differentiated polynomials of the lengths inside the NLP (`exact`), or
    /// frozen per solve and regenerated between solves (`alg1`, the paper's Alg. 1).
    pub inertia: InertiaCoupling,
    /// Alg. 1 stops when no length moved more than this between outer iterations, m (δ).
    pub tolerance_m: f64,
    /// Alg. 1 outer iterations at most.
    pub max_outer_iterations: usize,
    /// The convergence study (`adam codesign sweep`).
    #[serde(default)]
    pub sweep: SweepConfig,
    /// Grid size n of the cost landscape (`adam codesign landscape`: n × n fixed-design solves
    /// over the design box; `--grid` overrides it), at least 2.
    #[serde(default = "default_landscape_grid")]
    pub landscape_grid: usize,
    /// GenerateModel writes the A1 drives into each design's robot
    /// ([`model::design::MassModel::a1_drives`]: the rotors' armature, and the constants the
    /// electrical cost needs). Default false: the rigid-body robot the shipped gaits use.
    #[serde(default)]
    pub a1_drives: bool,
    /// Scale on the leg tubes' mass per metre (0.645 kg/m at 1; brackets, the knee's A1 and
    /// the foot do not scale), in [`LINK_DENSITY_SCALE_RANGE`]: GenerateModel's robots and the
    /// exact coupling's inertia fits both follow it ([`model::design::MassModel`]), so the
    /// landscape and the co-design can be run with lighter or heavier links. Default 1.
    #[serde(default = "default_link_density_scale")]
    pub link_density_scale: f64,
}

fn default_landscape_grid() -> usize {
    9
}

fn default_link_density_scale() -> f64 {
    1.0
}

/// The link density scales `[codesign] link_density_scale` accepts: a tenth to five times the
/// shipped tube (0.065–3.2 kg/m).
pub const LINK_DENSITY_SCALE_RANGE: [f64; 2] = [0.1, 5.0];

impl CodesignConfig {
    /// The mass model GenerateModel and the inertia fits use for this config's designs.
    pub fn mass_model(&self) -> model::design::MassModel {
        model::design::MassModel {
            link_density_scale: self.link_density_scale,
            a1_drives: self.a1_drives,
        }
    }
}

/// The convergence study's settings (`[codesign.sweep]`, `adam codesign sweep`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepConfig {
    /// Grid size n: co-designs start from an n × n grid of initial thigh and shin lengths over
    /// the design box `thigh_m` × `shin_m` (`--grid` overrides it).
    pub grid: usize,
    /// A converged run whose cost of transport is more than this fraction above the best run's
    /// is counted as a worse local minimum (and left out of the table's mean ± std).
    pub local_minimum_margin: f64,
}

/// The smallest landscape grid (n × n solves): one point is not a landscape.
pub const MIN_LANDSCAPE_GRID: usize = 2;

/// The largest landscape grid accepted.
pub const MAX_LANDSCAPE_GRID: usize = 30;

/// Checks a landscape grid size (`--grid`, `[codesign] landscape_grid`), naming `origin` and
/// `field`.
pub fn check_landscape_grid(n: usize, origin: &str, field: &str) -> Result<()> {
    if (MIN_LANDSCAPE_GRID..=MAX_LANDSCAPE_GRID).contains(&n) {
        return Ok(());
    }
    Err(PlannerError::InvalidField {
        origin: origin.into(),
        field: field.into(),
        value: n.to_string(),
        reason: format!(
            "a landscape needs {MIN_LANDSCAPE_GRID}..={MAX_LANDSCAPE_GRID} points per side \
             (n × n fixed-design solves)"
        ),
    })
}

/// The largest sweep grid accepted (n × n co-designs).
pub const MAX_SWEEP_GRID: usize = 20;

impl Default for SweepConfig {
    fn default() -> Self {
        Self {
            grid: 5,
            local_minimum_margin: 0.01,
        }
    }
}

/// How link inertias follow the design in the co-design.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InertiaCoupling {
    /// Inside the NLP, exact derivatives: one self-consistent solve.
    Exact,
    /// The paper's Alg. 1: frozen per solve, regenerated with GenerateModel(q_D) between solves.
    Alg1,
}

impl Default for CodesignConfig {
    fn default() -> Self {
        Self {
            initial_m: [0.24, 0.25],
            thigh_m: [0.15, 0.35],
            shin_m: [0.15, 0.35],
            inertia: InertiaCoupling::Exact,
            tolerance_m: 1e-3,
            max_outer_iterations: 10,
            sweep: SweepConfig::default(),
            landscape_grid: default_landscape_grid(),
            a1_drives: false,
            link_density_scale: default_link_density_scale(),
        }
    }
}

impl Default for PlannerConfig {
    fn default() -> Self {
        Self {
            schema_version: PLANNER_CONFIG_VERSION,
            collocation: CollocationConfig {
                intervals: DEFAULT_INTERVALS,
                bezier_degree: 5,
                output_gain_per_s: 10.0,
                mesh_grading: DEFAULT_MESH_GRADING,
            },
            gait: GaitConfig {
                stance_leg: Side::Right,
                step_length_m: [0.15, 0.35],
                step_duration_s: [0.6, 0.9],
                speed_mps: None,
                max_zero_dynamics_eigenvalue: None,
                min_apex_margin: None,
                swing_clearance_m: 0.03,
                impact_velocity_mps: 0.01,
                liftoff_velocity_mps: 0.0,
                friction_coefficient: 0.6,
                min_normal_force_n: 0.0,
                pitch_limits_rad: [-0.5, 0.5],
            },
            cost: CostConfig {
                kind: CostKind::Mechanical,
                weights: vec![1.0; 4],
                weighted: None,
            },
            solver: SolverConfig {
                tolerance: 1e-6,
                max_iterations: 500,
                backend: SolverBackend::Native,
                cost_stage_mu_init: DEFAULT_COST_STAGE_MU_INIT,
            },
            codesign: CodesignConfig::default(),
            constraints: ConstraintSwitches::default(),
        }
    }
}

impl PlannerConfig {
    /// Reads and validates a config file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| PlannerError::Io {
            path: origin.clone(),
            error,
        })?;
        Self::from_toml(&text, &origin)
    }

    /// Parses and validates TOML; `origin` names the source in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self> {
        let cfg: Self = toml::from_str(text).map_err(|e| PlannerError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        cfg.validate(origin)?;
        Ok(cfg)
    }

    /// Rejects out-of-range values, naming the field.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let bad = |field: &str, value: String, reason: &str| PlannerError::InvalidField {
            origin: origin.to_string(),
            field: field.to_string(),
            value,
            reason: reason.to_string(),
        };
        if self.schema_version != PLANNER_CONFIG_VERSION {
            return Err(bad(
                "schema_version",
                self.schema_version.to_string(),
                &format!("this build reads planner config version {PLANNER_CONFIG_VERSION}"),
            ));
        }
        let c = &self.collocation;
        if !(4..=200).contains(&c.intervals) {
            return Err(bad(
                "collocation.intervals",
                c.intervals.to_string(),
                "must be in 4..=200",
            ));
        }
        if !(2..=model::bezier::MAX_BEZIER_DEGREE).contains(&c.bezier_degree) {
            return Err(bad(
                "collocation.bezier_degree",
                c.bezier_degree.to_string(),
                &format!("must be in 2..={}", model::bezier::MAX_BEZIER_DEGREE),
            ));
        }
        let positive = |field: &str, v: f64| -> Result<()> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(bad(field, v.to_string(), "must be a positive number"))
            }
        };
        let nonneg = |field: &str, v: f64| -> Result<()> {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(bad(field, v.to_string(), "must be a finite number ≥ 0"))
            }
        };
        let range = |field: &str, r: [f64; 2]| -> Result<()> {
            if r[0].is_finite() && r[1].is_finite() && r[0] <= r[1] {
                Ok(())
            } else {
                Err(bad(
                    field,
                    format!("[{}, {}]", r[0], r[1]),
                    "must be [lower, upper] with lower ≤ upper",
                ))
            }
        };
        positive("collocation.output_gain_per_s", c.output_gain_per_s)?;
        if !(c.mesh_grading.is_finite() && (0.0..=MAX_MESH_GRADING).contains(&c.mesh_grading)) {
            return Err(bad(
                "collocation.mesh_grading",
                c.mesh_grading.to_string(),
                &format!("must be in [0, {MAX_MESH_GRADING}] (0: uniform intervals)"),
            ));
        }
        let g = &self.gait;
        range("gait.step_length_m", g.step_length_m)?;
        positive("gait.step_length_m[0]", g.step_length_m[0])?;
        range("gait.step_duration_s", g.step_duration_s)?;
        positive("gait.step_duration_s[0]", g.step_duration_s[0])?;
        range("gait.pitch_limits_rad", g.pitch_limits_rad)?;
        g.check_speed(origin)?;
        if let Some(l) = g.max_zero_dynamics_eigenvalue {
            if !(l.is_finite() && l > 0.0 && l < 1.0) {
                return Err(bad(
                    "gait.max_zero_dynamics_eigenvalue",
                    l.to_string(),
                    "must be in (0, 1): a stable gait's eigenvalue is below 1",
                ));
            }
        }
        if let Some(m) = g.min_apex_margin {
            if !(m.is_finite() && m > 0.0 && m < 1.0) {
                return Err(bad(
                    "gait.min_apex_margin",
                    m.to_string(),
                    "must be in (0, 1): a fraction of the post-impact momentum",
                ));
            }
        }
        nonneg("gait.swing_clearance_m", g.swing_clearance_m)?;
        nonneg("gait.impact_velocity_mps", g.impact_velocity_mps)?;
        nonneg("gait.liftoff_velocity_mps", g.liftoff_velocity_mps)?;
        positive("gait.friction_coefficient", g.friction_coefficient)?;
        nonneg("gait.min_normal_force_n", g.min_normal_force_n)?;
        for (i, w) in self.cost.weights.iter().enumerate() {
            nonneg(&format!("cost.weights[{i}]"), *w)?;
        }
        match (self.cost.kind, &self.cost.weighted) {
            (CostKind::Weighted, None) => {
                return Err(bad(
                    "cost.kind",
                    "\"weighted\"".into(),
                    "a weighted sum needs its weights: add [cost.weighted] with mechanical, electrical and torque_squared",
                ))
            }
            (CostKind::Weighted, Some(mix)) => {
                nonneg("cost.weighted.mechanical", mix.mechanical)?;
                nonneg("cost.weighted.electrical", mix.electrical)?;
                nonneg("cost.weighted.torque_squared", mix.torque_squared)?;
                if mix.mechanical + mix.electrical + mix.torque_squared == 0.0 {
                    return Err(bad(
                        "cost.weighted",
                        "all zero".into(),
                        "at least one weight of the sum must be positive",
                    ));
                }
            }
            (kind, Some(_)) => {
                return Err(bad(
                    "cost.weighted",
                    format!("given with kind = \"{}\"", kind.name()),
                    "the weights of the sum are read only with kind = \"weighted\"; remove them or change the kind",
                ))
            }
            (_, None) => {}
        }
        positive("solver.tolerance", self.solver.tolerance)?;
        positive("solver.cost_stage_mu_init", self.solver.cost_stage_mu_init)?;
        let c = &self.codesign;
        let (lo, hi) = (model::design::DESIGN_MIN_M, model::design::DESIGN_MAX_M);
        for (name, [a, b]) in [
            ("codesign.thigh_m", c.thigh_m),
            ("codesign.shin_m", c.shin_m),
        ] {
            if !(a.is_finite() && b.is_finite() && lo <= a && a < b && b <= hi) {
                return Err(bad(
                    name,
                    format!("[{a}, {b}]"),
                    &format!(
                        "must be an increasing range inside [{lo}, {hi}] m (the inertia fits)"
                    ),
                ));
            }
        }
        for (i, (name, [a, b])) in [("thigh", c.thigh_m), ("shin", c.shin_m)]
            .iter()
            .enumerate()
        {
            let v = c.initial_m[i];
            if !(v.is_finite() && *a <= v && v <= *b) {
                return Err(bad(
                    &format!("codesign.initial_m[{i}]"),
                    v.to_string(),
                    &format!("the initial {name} length must lie in its bounds [{a}, {b}] m"),
                ));
            }
        }
        positive("codesign.tolerance_m", c.tolerance_m)?;
        let [lo, hi] = LINK_DENSITY_SCALE_RANGE;
        if !(lo..=hi).contains(&c.link_density_scale) {
            return Err(bad(
                "codesign.link_density_scale",
                c.link_density_scale.to_string(),
                &format!(
                    "must be in [{lo}, {hi}] (a scale on the leg tubes' 0.645 kg/m; 1 is the \
                     shipped tube)"
                ),
            ));
        }
        if !(1..=MAX_SWEEP_GRID).contains(&c.sweep.grid) {
            return Err(bad(
                "codesign.sweep.grid",
                c.sweep.grid.to_string(),
                &format!("must be in 1..={MAX_SWEEP_GRID} (n × n co-designs)"),
            ));
        }
        check_landscape_grid(c.landscape_grid, origin, "codesign.landscape_grid")?;
        nonneg(
            "codesign.sweep.local_minimum_margin",
            c.sweep.local_minimum_margin,
        )?;
        if c.max_outer_iterations == 0 {
            return Err(bad(
                "codesign.max_outer_iterations",
                "0".into(),
                "must be at least 1",
            ));
        }
        if self.solver.max_iterations == 0 {
            return Err(bad(
                "solver.max_iterations",
                "0".into(),
                "must be at least 1",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_round_trips_through_toml() {
        let cfg = PlannerConfig::default();
        let text = toml::to_string(&cfg).expect("serializes");
        assert_eq!(
            PlannerConfig::from_toml(&text, "x.toml").expect("parses"),
            cfg
        );
    }

    #[test]
    fn bad_values_name_the_field() {
        let text = toml::to_string(&PlannerConfig::default())
            .expect("serializes")
            .replace("friction_coefficient = 0.6", "friction_coefficient = -1.0");
        let e = PlannerConfig::from_toml(&text, "x.toml")
            .expect_err("rejected")
            .to_string();
        assert!(
            e.contains("x.toml") && e.contains("gait.friction_coefficient") && e.contains("-1"),
            "{e}"
        );
        let text =
            toml::to_string(&PlannerConfig::default()).expect("serializes") + "\nsurprise = 1\n";
        let e = PlannerConfig::from_toml(&text, "x.toml")
            .expect_err("rejected")
            .to_string();
        assert!(e.contains("surprise"), "{e}");
    }

    #[test]
    fn the_shipped_adam_config_holds_the_codesign_defaults_and_bad_ones_are_named() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/planner/adam.toml");
        let text = std::fs::read_to_string(path).expect("shipped config");
        let cfg = PlannerConfig::from_toml(&text, path).expect("parses");
        // The shipped file states today's defaults, so `adam codesign` behaves as before.
        assert_eq!(cfg.codesign, CodesignConfig::default());
        for (from, to, field, value) in [
            (
                "thigh_m = [0.15, 0.35]",
                "thigh_m = [0.35, 0.15]",
                "codesign.thigh_m",
                "[0.35, 0.15]",
            ),
            (
                "shin_m = [0.15, 0.35]",
                "shin_m = [0.15, 0.9]",
                "codesign.shin_m",
                "[0.15, 0.9]",
            ),
            (
                "link_density_scale = 1.0",
                "link_density_scale = 0.05",
                "codesign.link_density_scale",
                "0.05",
            ),
            (
                "link_density_scale = 1.0",
                "link_density_scale = nan",
                "codesign.link_density_scale",
                "NaN",
            ),
            ("grid = 5", "grid = 0", "codesign.sweep.grid", "0"),
            ("grid = 5", "grid = 21", "codesign.sweep.grid", "21"),
            (
                "local_minimum_margin = 0.01",
                "local_minimum_margin = -0.1",
                "codesign.sweep.local_minimum_margin",
                "-0.1",
            ),
        ] {
            assert!(text.contains(from), "{from}");
            let e = PlannerConfig::from_toml(&text.replace(from, to), "x.toml")
                .expect_err("rejected")
                .to_string();
            assert!(
                e.contains("x.toml") && e.contains(field) && e.contains(value),
                "{to}: {e}"
            );
        }
        let e = PlannerConfig::from_toml(&text.replace("grid = 5", "grid = 5\nsize = 3"), "x.toml")
            .expect_err("unknown field")
            .to_string();
        assert!(e.contains("size"), "{e}");
    }

    /// The mesh grading defaults to [`DEFAULT_MESH_GRADING`] when a config leaves it out, and
    /// a grading outside [0, 0.95] (or NaN) is an error naming the field and value.
    #[test]
    fn the_mesh_grading_defaults_and_bad_ones_are_named() {
        let text = toml::to_string(&PlannerConfig::default()).expect("serializes");
        let line = format!("mesh_grading = {DEFAULT_MESH_GRADING}");
        assert!(text.contains(&line), "{text}");
        let cfg = PlannerConfig::from_toml(&text.replace(&line, ""), "x.toml").expect("parses");
        assert_eq!(cfg.collocation.mesh_grading, DEFAULT_MESH_GRADING);
        for bad in ["1.5", "-0.1", "nan"] {
            let text = text.replace(&line, &format!("mesh_grading = {bad}"));
            let e = PlannerConfig::from_toml(&text, "x.toml")
                .expect_err("rejected")
                .to_string();
            assert!(
                e.contains("x.toml")
                    && e.contains("collocation.mesh_grading")
                    && e.to_lowercase().contains(bad),
                "{e}"
            );
        }
    }

    #[test]
    fn the_cost_stage_mu_init_defaults_to_1e_5_and_must_be_positive() {
        let text = toml::to_string(&PlannerConfig::default()).expect("serializes");
        let line = "cost_stage_mu_init = 0.00001";
        assert!(text.contains(line), "{text}");
        let without: String = text
            .lines()
            .filter(|l| !l.starts_with("cost_stage_mu_init"))
            .map(|l| format!("{l}\n"))
            .collect();
        let cfg = PlannerConfig::from_toml(&without, "x.toml").expect("parses");
        assert_eq!(cfg.solver.cost_stage_mu_init, 1e-5);
        for bad in ["0.0", "-1e-4", "nan"] {
            let text = text.replace(line, &format!("cost_stage_mu_init = {bad}"));
            let e = PlannerConfig::from_toml(&text, "x.toml")
                .expect_err("rejected")
                .to_string();
            assert!(
                e.contains("x.toml") && e.contains("solver.cost_stage_mu_init"),
                "{e}"
            );
        }
    }

    #[test]
    fn the_backend_is_native_unless_the_config_names_another() {
        let text = toml::to_string(&PlannerConfig::default()).expect("serializes");
        let without: String = text
            .lines()
            .filter(|l| !l.starts_with("backend"))
            .map(|l| format!("{l}\n"))
            .collect();
        let cfg = PlannerConfig::from_toml(&without, "x.toml").expect("parses");
        assert_eq!(cfg.solver.backend, SolverBackend::Native);
        let ripopt = text.replace("backend = \"native\"", "backend = \"ripopt\"");
        let cfg = PlannerConfig::from_toml(&ripopt, "x.toml").expect("parses");
        assert_eq!(cfg.solver.backend, SolverBackend::Ripopt);
        let bad = text.replace("backend = \"native\"", "backend = \"ipopt\"");
        let e = PlannerConfig::from_toml(&bad, "x.toml")
            .expect_err("rejected")
            .to_string();
        assert!(
            e.contains("x.toml") && e.contains("ipopt") && e.contains("native"),
            "{e}"
        );
    }
}
