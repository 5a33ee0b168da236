//! # planner: offline HZD gait optimization and co-design for ADAM
//!
//! Stands on [`model`]. Available now: [`nlp`], the nonlinear-programming layer
//! (our `NlpProblem`/`NlpSolver` traits, the pure-Rust interior-point backend,
//! AD helpers and a derivative checker). The collocation problem
//! (`planner::collocation`) arrives with the "Planner I" issue, the co-design of
//! thigh and shin lengths with "Planner II".

pub mod nlp;
