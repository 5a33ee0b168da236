//! # planner: offline HZD gait optimization for ADAM
//!
//! Stands on [`model`]. The pieces:
//!
//! ```text
//! configs/planner/*.toml ─▶ PlannerConfig ─┐
//! URDF ─▶ PlanarModel ─▶ PlanarBiped ──────┼─▶ HzdProblem (collocation, exact derivatives)
//!                                          │        │  two solves (feasibility, then cost)
//!                           initial guess ─┘        ▼
//!                                     nlp::solve (ripopt, IPOPT-class interior point)
//!                                                   ▼
//!                                         GaitFile (model::gait) + PlanReport
//! ```
//!
//! - [`nlp`]: the NLP trait and solver backend, tested on the Hock–Schittkowski collection.
//! - [`collocation`]: the HZD gait optimization as a sparse NLP (its docs list every constraint).
//! - [`plan`]: the paper's two-step solve and the gait file it writes.
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
pub mod nlp;
pub mod plan;
pub mod verify;

pub use error::{PlannerError, Result};
