//! The convergence study's runs as a JSON file (`adam codesign sweep` writes `sweep.json`;
//! `adam codesign landscape --sweep` reads the endpoints back to draw them on the heat map).

use super::SweepRun;
use crate::{PlannerError, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The sweep file's schema version.
pub const SWEEP_FILE_VERSION: u32 = 1;

/// One run of the study in the file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepEndpoint {
    /// Initial thigh and shin length, m.
    pub initial_m: [f64; 2],
    /// Converged thigh and shin length, m (`null`: the run failed).
    pub lengths_m: Option<[f64; 2]>,
    /// Cost of transport at the converged design (`null`: the run failed).
    pub cost_of_transport: Option<f64>,
    /// Why the run failed (`null`: it converged).
    pub error: Option<String>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    schema_version: u32,
    runs: Vec<SweepEndpoint>,
}

/// Writes the study's runs to `path` as JSON.
pub fn save_sweep(path: &Path, runs: &[SweepRun]) -> Result<()> {
    let file = SweepFile {
        schema_version: SWEEP_FILE_VERSION,
        runs: runs
            .iter()
            .map(|r| SweepEndpoint {
                initial_m: r.initial_m,
                lengths_m: r.outcome.as_ref().ok().map(|o| o.lengths_m),
                cost_of_transport: r.outcome.as_ref().ok().map(|o| o.cost_of_transport),
                error: r.outcome.as_ref().err().cloned(),
            })
            .collect(),
    };
    let text = serde_json::to_string_pretty(&file).map_err(|e| PlannerError::Parse {
        origin: path.display().to_string(),
        message: e.to_string(),
    })?;
    std::fs::write(path, text).map_err(|error| PlannerError::Io {
        path: path.display().to_string(),
        error,
    })
}

/// Reads a sweep file's runs, checking every length is a finite number.
pub fn load_sweep_endpoints(path: &Path) -> Result<Vec<SweepEndpoint>> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|error| PlannerError::Io {
        path: origin.clone(),
        error,
    })?;
    let file: SweepFile = serde_json::from_str(&text).map_err(|e| PlannerError::Parse {
        origin: origin.clone(),
        message: e.to_string(),
    })?;
    if file.schema_version != SWEEP_FILE_VERSION {
        return Err(PlannerError::InvalidField {
            origin,
            field: "schema_version".into(),
            value: file.schema_version.to_string(),
            reason: format!("this build reads sweep files of version {SWEEP_FILE_VERSION}"),
        });
    }
    for (k, r) in file.runs.iter().enumerate() {
        let lengths = r.initial_m.iter().chain(r.lengths_m.iter().flatten());
        if let Some(v) = lengths.copied().find(|v| !v.is_finite() || *v <= 0.0) {
            return Err(PlannerError::InvalidField {
                origin,
                field: format!("runs[{k}]"),
                value: v.to_string(),
                reason: "lengths must be positive numbers of metres".into(),
            });
        }
    }
    Ok(file.runs)
}
