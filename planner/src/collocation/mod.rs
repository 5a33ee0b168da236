//! The HZD gait optimization as a sparse NLP: Hermite–Simpson direct collocation of the
//! single-domain hybrid system (paper Sec. II–III), with exact derivatives from dual numbers.
//!
//! # Transcription
//! N intervals, 2N + 1 points k (even k: nodes, odd k: midpoints), step duration T a variable and
//! interval i of length h_i = T·w_i, its fraction w_i fixed by `[collocation] mesh_grading`
//! (uniform w_i = 1/N at grading 0; the default grades them shorter at the step's ends, where
//! the transcription error is largest: [`mesh_nodes`], planner/CODESIGN.md "Plan accuracy"). At every point: reduced state q_r, q̇_r, q̈_r (pinned stance, see [`crate::biped`]),
//! torques u and, in the cost-of-transport problem, the positive/negative parts p, n of each
//! actuator's power (the feasibility problem has no cost and no power slacks). Global variables: the
//! Bézier coefficients α (m × (b+1)), θ⁺ and θ⁻ of the phase variable, T, and the step length d.
//!
//! Constraints (all from [`crate::config::PlannerConfig`]):
//! - **pinned-stance dynamics** at every point: D q̈ + H = B u + J_stᵀ λ with λ the stance force,
//!   computed from the x and z rows; λ_z ≥ λ_min and |λ_x| ≤ μ λ_z (friction cone);
//! - **Hermite–Simpson** (separated form): midpoint interpolation and Simpson defects for q and q̇;
//! - **virtual constraints** the way FROST enforces them: y = ẏ = 0 at the first point and the
//!   output dynamics ÿ + 2εẏ + ε²y = 0 at every point (PLANNER-NOTES: position-level y = 0 at
//!   every point over-constrains the interpolant and does not converge);
//! - **phase** (lifted: τ, τ̇, τ̈ are variables at every point): θ(q) − θ⁺ = τ (θ⁻ − θ⁺) and its
//!   first and second time derivatives, with τ = 0 at the first point and τ = 1 at the last;
//! - **swing foot**: z_nsf ≥ c·4s(1−s) at every interior point (s = k/2N, c the mid-step
//!   clearance: the foot stays clear of the ground, not merely above it; `[constraints]
//!   clearance_profile = "midstep"` asks c at mid-step only and z ≥ 0 elsewhere), = 0 at the end
//!   (the guard) with ż_nsf ≤ −v_impact, x_nsf = d at the end;
//! - **impact and periodicity** (the HZD condition, with y = ẏ = 0 at the start):
//!   x_0 = relabel(Δ(x_2N)); the impact impulse inside the friction cone; the old stance foot
//!   leaves the ground (upward velocity after impact; `[constraints] liftoff = false` drops it);
//! - **speed** (only if `gait.speed_mps` = [lo, hi] is given): d − lo·T ≥ 0 and hi·T − d ≥ 0,
//!   or d − v·T = 0 for one speed: linear, so exact with constant derivatives and scaled like
//!   the step length;
//! - bounds: joint limits, A1 torque and speed limits, torso pitch, Table I (d, T).
//!
//! Which of these the paper states and which are ours: [`ConstraintGroup::source`]
//! (planner/CODESIGN.md, "Constraints", has the audit of ours).
//!
//! Cost (`[cost]`, [`crate::config::CostConfig`]; formulas, units and derivatives in `cost`'s
//! docs and `planner/CODESIGN.md`): by default the weighted mechanical cost of transport
//! Φ = 1/(M g d) Σ_i w_i ∫ |u_i q̇_i| dt with |u q̇| = p + n, p − n = u q̇, p, n ≥ 0 (slack
//! variables), integrated with Simpson's rule; or the A1's electrical cost of transport (copper
//! loss plus the positive power p), the torque squared per distance, or a weighted sum.
//! The cost stage creates p and n from the feasible point's u q̇, just off the bound the cost
//! pushes them to ([`Layout::with_slacks`], [`HzdProblem::centre_power_slacks`]). (A smooth
//! √(P² + δ²) − δ instead of the slacks was measured and not kept: planner/NLP.md, "Eleventh
//! round".)
//!
//! # Derivatives
//! Each constraint group is a *block*: a generic function of a few variables. Jacobians come from
//! forward-mode `Dual64` sweeps (one per block variable), Lagrangian Hessians from `HyperDual64`
//! evaluations of Σ μ_r c_r (one per structurally non-zero variable pair). Structural zeros are
//! found once per block kind at set-up by evaluating at a random point. In the solve loop the
//! sweeps run four at a time ([`crate::nlp::lanes`]: `Dual<Lanes<4>>`, `HyperDual<Lanes<4>>`,
//! bit for bit the scalar results) and the blocks are spread over the rayon pool when the
//! caller is not already on it; contributions to shared Hessian entries are added in block
//! order, so the values never depend on the schedule. Each model block runs the kinematics once
//! per evaluation, with the floating base at rest at the origin
//! ([`PlanarBiped::states_at_rest_base`](crate::biped::PlanarBiped::states_at_rest_base)): inverse dynamics, the stance-foot Jacobian, the
//! stance-leg angle and the swing foot relative to the stance foot depend only on relative
//! positions, so the pinned-stance base enters only through the base acceleration that keeps
//! the stance foot still. The objective's
//! derivatives are hand-derived and checked against finite differences in the tests.
//! Acceleration and torque variables are scaled by 1/10 (PLANNER-NOTES: 219 → 78 iterations).
//!
//! # Where things are
//! - `problem`: [`HzdProblem`] and [`Codesign`]; building the problem, its start point and
//!   diagnostics (violation by constraint kind, block statistics);
//! - `layout`: [`Layout`], where each variable lives in x, and the variable scales;
//! - `blocks`: the constraint block kinds and what a block records (rows, variables, seeds);
//! - `constraints`: which blocks the transcription has, with their bounds, and the variable
//!   bounds;
//! - `residuals`: what each block computes (dynamics, phase, outputs, defects, swing foot,
//!   impact); `design`: the co-design's design joints and link mass properties in a block;
//! - `cost`: the costs (mechanical, electrical, torque squared, weighted) with their exact
//!   gradient and Hessian, the feasibility stage's torque regularizer and the power slacks'
//!   start;
//! - `sparsity`: the structural zeros found at set-up; `derivatives`: the dual-number sweeps
//!   over the blocks and the Hessian's assembly;
//! - `nlp_problem`: [`HzdProblem`] as an [`NlpProblem`](crate::nlp::NlpProblem).

mod blocks;
mod constraints;
mod cost;
mod derivatives;
mod design;
mod layout;
mod nlp_problem;
mod problem;
mod residuals;
mod sparsity;

pub use constraints::{ConstraintGroup, ConstraintGroups};
pub use cost::FEASIBILITY_TORQUE_WEIGHT;
pub use layout::{mesh_nodes, Layout, ACC_SCALE, TORQUE_SCALE};
pub use problem::{Codesign, HzdProblem};
