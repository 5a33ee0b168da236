//! The NLP's shared vocabulary, spoken by the caller and by every backend: the problem trait,
//! the options, the solver trait with its iteration callback, the outcome with its statistics,
//! and the errors. It depends on nothing else in [`crate::nlp`].

mod error;
mod options;
mod outcome;
mod problem;
mod solver;

pub use error::{NlpError, Result};
pub use options::{Backend, SolveOptions, WarmStart};
pub use outcome::{
    sum_if_both, EvaluationCounts, PhaseTimes, Solution, SolveStatistics, SolveStatus,
};
pub use problem::{DomainError, NlpProblem, SparsityPattern};
pub use solver::{IterationControl, IterationReport, NlpSolver};
