//! The error type of the `planner` crate.

/// Result alias of the `planner` crate.
pub type Result<T, E = PlannerError> = std::result::Result<T, E>;

/// What can go wrong while configuring, solving or verifying a gait.
#[derive(Debug, thiserror::Error)]
pub enum PlannerError {
    /// The robot model or a model computation failed.
    #[error(transparent)]
    Model(#[from] model::ModelError),
    /// A config file could not be read.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        error: std::io::Error,
    },
    /// A config file is not valid TOML for the planner's schema.
    #[error("{origin}: {message}")]
    Parse {
        /// The file.
        origin: String,
        /// The parser's message (with line and column).
        message: String,
    },
    /// A config value is out of range.
    #[error("{origin}: field '{field}' = {value}: {reason}")]
    InvalidField {
        /// The file.
        origin: String,
        /// Dotted field path.
        field: String,
        /// The value.
        value: String,
        /// Why it is rejected.
        reason: String,
    },
    /// The robot does not fit the planner (naming, actuators).
    #[error("robot '{robot}': {reason}")]
    Robot {
        /// The robot name.
        robot: String,
        /// What is missing.
        reason: String,
    },
    /// The NLP solver failed or ended without a usable solution.
    #[error("{stage}: the solver ended with status {status} after {iterations} iterations (constraint violation {violation:.2e}{})", violated_text(violated))]
    NotSolved {
        /// Which solve.
        stage: String,
        /// The solver's status.
        status: String,
        /// Iterations used.
        iterations: usize,
        /// Largest constraint violation at the end.
        violation: f64,
        /// The most violated constraint groups at the end, worst first, with their violation.
        violated: Vec<(String, f64)>,
    },
    /// A speed list (`adam plan library --speeds`) is not one.
    #[error("speeds '{spec}': {reason}")]
    InvalidSpeeds {
        /// The list as given (`lo:hi:step` or `v1,v2,…`).
        spec: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The gaits that planned and verified leave a hole in the library wider than allowed
    /// (`planner::library::MAX_GAP_MPS`).
    #[error("the gait library would have a hole from {from_mps} to {to_mps} m/s ({:.3} m/s wide, at most {max_gap_mps} allowed){}", to_mps - from_mps, failed_text(failed))]
    LibraryHole {
        /// The widest hole allowed, m/s.
        max_gap_mps: f64,
        /// The speed below the hole (a gait, or the slowest speed asked for), m/s.
        from_mps: f64,
        /// The speed above it, m/s.
        to_mps: f64,
        /// The speeds in it that failed, with their reasons.
        failed: String,
    },
    /// No speed of a library gave a gait that planned and verified.
    #[error("no speed gave a gait for the library{}", failed_text(failed))]
    EmptyLibrary {
        /// The speeds that failed, with their reasons.
        failed: String,
    },
    /// The solver itself reported an error.
    #[error("solver error: {0}")]
    Solver(String),
}

fn violated_text(violated: &[(String, f64)]) -> String {
    if violated.is_empty() {
        return String::new();
    }
    let list: Vec<String> = violated
        .iter()
        .map(|(what, v)| format!("{what} {v:.2e}"))
        .collect();
    format!("; most violated: {}", list.join(", "))
}

fn failed_text(failed: &str) -> String {
    if failed.is_empty() {
        String::new()
    } else {
        format!("; left out: {failed}")
    }
}
