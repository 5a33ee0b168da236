//! # planner::nlp — nonlinear programming behind our own trait
//!
//! (full documentation written below)

mod problem;
mod ripopt_backend;
mod solver;
mod validate;

pub mod ad;
pub mod check;

pub use problem::{DomainError, NlpProblem, SparsityPattern};
pub use ripopt_backend::RipoptSolver;
pub use solver::{
    solve, solve_with_callback, Backend, EvaluationCounts, IterationControl, IterationReport,
    NlpError, NlpSolver, Result, Solution, SolveOptions, SolveStatistics, SolveStatus, WarmStart,
};
