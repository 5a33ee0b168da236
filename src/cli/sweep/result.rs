//! One task's result file (`<out_dir>/results/task-NNNNN.json`): written whole through a
//! temporary name and a rename, so a task killed mid-run leaves no result (and a re-run
//! replaces only its own file); read back with every problem named.

use super::plan::{tool_version, Study, SweepPlan, Task};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The result file's schema version.
pub(crate) const RESULT_SCHEMA_VERSION: u32 = 1;

/// What one task produced, by study.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub(crate) enum Payload {
    /// A co-design run (or why it failed).
    Codesign(Result<planner::codesign::SweepOutcome, String>),
    /// A landscape point (or why its solve failed).
    Landscape(Result<planner::codesign::SweepOutcome, String>),
    /// A treadmill run's figures (or why it could not run).
    Treadmill(Result<runtime::sim::matrix::RunSummary, String>),
}

impl Payload {
    /// The error of a run that failed.
    pub(crate) fn error(&self) -> Option<&str> {
        match self {
            Payload::Codesign(Err(e)) | Payload::Landscape(Err(e)) | Payload::Treadmill(Err(e)) => {
                Some(e)
            }
            _ => None,
        }
    }

    /// The study this payload belongs to.
    fn study(&self) -> Study {
        match self {
            Payload::Codesign(_) => Study::Codesign,
            Payload::Landscape(_) => Study::Landscape,
            Payload::Treadmill(_) => Study::Treadmill,
        }
    }
}

/// A result file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TaskResult {
    /// [`RESULT_SCHEMA_VERSION`].
    pub(crate) schema_version: u32,
    /// The tool that ran the task.
    pub(crate) tool: String,
    /// The task's index in its plan.
    pub(crate) index: usize,
    /// The task as the plan gave it (a result of another plan's task is not this task's).
    pub(crate) task: Task,
    /// What it produced.
    pub(crate) payload: Payload,
    /// Wall time of the task (set-up included), s.
    pub(crate) wall_time_s: f64,
    /// The machine it ran on.
    pub(crate) host: String,
}

/// This machine's name (`/etc/hostname`, `$HOSTNAME`), or `unknown`.
pub(crate) fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// Writes `result` as task `result.index`'s file of `plan`: into a temporary file beside it,
/// then renamed over it (atomic on one file system).
pub(crate) fn write_result(plan: &SweepPlan, result: &TaskResult) -> Result<PathBuf> {
    let path = plan.result_path(result.index);
    let dir = plan.results_dir();
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let tmp = dir.join(format!(
        ".task-{:05}.json.{}.tmp",
        result.index,
        std::process::id()
    ));
    let text = serde_json::to_string_pretty(result).context("the result as JSON")?;
    std::fs::write(&tmp, text + "\n").with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, &path)
        .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))?;
    Ok(path)
}

/// Reads task `index`'s result of `plan`: `Ok(None)` if there is none yet; an error naming the
/// file and what is wrong with it if it cannot be used (corrupt, another tool, another task or
/// study).
pub(crate) fn read_result(plan: &SweepPlan, index: usize) -> Result<Option<TaskResult>> {
    let path = plan.result_path(index);
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    let r: TaskResult = serde_json::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{}: not a task result: {e}", path.display()))?;
    check(&r, plan, index, &path)?;
    Ok(Some(r))
}

fn check(r: &TaskResult, plan: &SweepPlan, index: usize, path: &Path) -> Result<()> {
    let file = path.display();
    if r.schema_version != RESULT_SCHEMA_VERSION {
        bail!(
            "{file}: field 'schema_version' = {}: this build reads results of version {RESULT_SCHEMA_VERSION}",
            r.schema_version
        );
    }
    if r.tool != tool_version() {
        bail!(
            "{file}: field 'tool' = \"{}\": written by another version of adam (this is \"{}\")",
            r.tool,
            tool_version()
        );
    }
    if r.index != index {
        bail!(
            "{file}: field 'index' = {}: the file of task {index} holds another task's result",
            r.index
        );
    }
    if plan.tasks.get(index) != Some(&r.task) {
        bail!(
            "{file}: field 'task': the result is of another plan's task {index} ({}); this plan's task {index} is different",
            serde_json::to_string(&r.task).unwrap_or_default()
        );
    }
    if r.payload.study() != plan.study {
        bail!(
            "{file}: field 'payload' holds a {} result; the plan's study is {}",
            r.payload.study().name(),
            plan.study.name()
        );
    }
    Ok(())
}
