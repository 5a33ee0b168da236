//! # planner: offline HZD gait optimization for ADAM
//!
//! Stands on [`model`]. The pieces:
//!
//! ```text
//! configs/planner/*.toml ─▶ PlannerConfig ─┐
//! URDF ─▶ PlanarModel ─▶ PlanarBiped ──────┼─▶ HzdProblem (collocation, exact derivatives)
//!                                          │        │  two solves (feasibility, then cost)
//!                           initial guess ─┘        ▼
//!                      nlp::solve (native interior point, the default; or ripopt)
//!                                                   ▼
//!                     PlannedGait: GaitFile (model::gait) + a StageReport per solve
//!                                                   ▼
//!                      verify: closed-loop orbit, Poincaré eigenvalues, consistency
//! ```
//!
//! - [`nlp`]: the NLP trait, the native interior point and the ripopt backend, their statuses
//!   and statistics (iterations, restoration, time by phase), tested on the Hock–Schittkowski
//!   collection. Inside: `nlp/interface` (the problem trait, options, solver trait, outcome
//!   and errors every backend shares), `nlp/native` (the interior point: iteration, Newton
//!   step, line search, restoration, KKT system), `nlp/ripopt_backend.rs`, and `nlp/solve.rs`
//!   (the choice of backend, above both).
//! - [`biped`]: the robot in pinned-stance coordinates, found in the URDF by the naming
//!   convention of [`model::robot`].
//! - [`collocation`]: the HZD gait optimization as a sparse NLP (its docs list every constraint).
//!   Inside: `problem` (building it), `layout`, `blocks`, `constraints` (blocks and bounds),
//!   `residuals` and `design` (what a block computes), `cost`, `sparsity`, `derivatives`
//!   (the dual-number sweeps) and `nlp_problem` (the [`nlp::NlpProblem`] implementation).
//! - [`guess`]: the hand-built first step the feasibility solve starts from.
//! - [`plan`]: the paper's two-step solve and the gait file it writes.
//! - [`verify`]: the independent check of a gait (`adam gait check`).
//! - [`library`]: a gait per speed for one design, each warm-started from its neighbour and
//!   verified (`adam plan library`), written as a [`model::library::GaitLibrary`].
//! - [`codesign`]: thigh and shin lengths as variables (`adam codesign`), the convergence
//!   study, the cost landscape over the design box with the constraints that hold the optimum
//!   (`codesign/landscape.rs`, `codesign/activity.rs`), the audit of the constraints that are
//!   ours (`codesign/audit.rs`) and one design for several speeds (`codesign/speeds.rs`);
//!   planner/CODESIGN.md has the results.
//!
//! ```no_run
//! use planner::{config::PlannerConfig, plan::plan_gait};
//! let model = model::PlanarModel::from_urdf_file("configs/robots/adam_planar.urdf")?;
//! let config = PlannerConfig::load("configs/planner/adam.toml")?;
//! let planned = plan_gait(&model, "adam_planar.urdf", "<urdf text>", &config, &mut |_| {})?;
//! println!("step length {:.3} m", planned.gait.step_length_m);
//! # Ok::<(), planner::PlannerError>(())
//! ```

pub mod biped;
pub mod codesign;
pub mod collocation;
pub mod config;
mod error;
pub mod guess;
pub mod library;
pub mod nlp;
pub mod plan;
pub mod verify;

pub use error::{PlannerError, Result};
