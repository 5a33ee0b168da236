//! `adam sweep slurm`: the `sbatch` scripts of a plan. `array.sbatch` runs every task as one
//! element of a job array (`--array=0-(n-1)%limit`, the plan's time and memory per task, one
//! CPU, a log per task); `collect.sbatch` runs `adam sweep collect` once the array is over
//! (`--dependency=afterany:<array job id>`, given at submission); `submit.sh` submits both.
//! Nothing is submitted unless asked (`--submit`) and `sbatch` is on the path.

use super::plan::SweepPlan;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The three scripts of a plan, as text.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SlurmScripts {
    /// The job array: one task per element.
    pub(crate) array: String,
    /// The collect job.
    pub(crate) collect: String,
    /// Submits the array, then the collect job depending on it.
    pub(crate) submit: String,
}

/// A path quoted for bash (single quotes; a single quote inside closed, escaped and reopened).
fn quoted(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', r"'\''"))
}

/// `HH:MM:00` (`D-HH:MM:00` past a day) of `minutes`, for `--time`.
pub(crate) fn slurm_time(minutes: u32) -> String {
    let (days, rem) = (minutes / 1440, minutes % 1440);
    let hm = format!("{:02}:{:02}:00", rem / 60, rem % 60);
    if days > 0 {
        format!("{days}-{hm}")
    } else {
        hm
    }
}

/// The scripts for `plan` (read from `plan_path`), running the `adam` at `adam`.
pub(crate) fn scripts(plan: &SweepPlan, plan_path: &Path, adam: &Path) -> Result<SlurmScripts> {
    let n = plan.tasks.len();
    let r = &plan.resources;
    let logs = plan.out_dir.join("logs");
    let name = format!("adam-{}", plan.study.name());
    let mut array = String::new();
    writeln!(array, "#!/bin/bash")?;
    writeln!(
        array,
        "# adam sweep: the {} study, {n} tasks, one per element of this job array.",
        plan.study.name()
    )?;
    writeln!(
        array,
        "# Written by {} for the plan {}. Submit with {}/submit.sh (array, then collect).",
        plan.tool,
        plan_path.display(),
        plan.out_dir.join("slurm").display()
    )?;
    writeln!(array, "#SBATCH --job-name={name}")?;
    writeln!(array, "#SBATCH --array=0-{}%{}", n - 1, r.array_limit)?;
    writeln!(array, "#SBATCH --time={}", slurm_time(r.time_per_task_min))?;
    writeln!(array, "#SBATCH --mem={}M", r.mem_per_task_mb)?;
    writeln!(array, "#SBATCH --ntasks=1")?;
    writeln!(array, "#SBATCH --cpus-per-task=1")?;
    writeln!(
        array,
        "#SBATCH --output={}",
        logs.join("task-%a.out").display()
    )?;
    writeln!(array, "#\n# The tasks (index: what it runs):")?;
    for t in &plan.tasks {
        let what = serde_json::to_string(t).context("a task as JSON")?;
        writeln!(array, "#   task {}: {what}", t.index)?;
    }
    writeln!(array, "set -euo pipefail")?;
    writeln!(
        array,
        "exec {} sweep task --plan {} --index \"$SLURM_ARRAY_TASK_ID\"",
        quoted(adam),
        quoted(plan_path)
    )?;

    let mut collect = String::new();
    writeln!(collect, "#!/bin/bash")?;
    writeln!(
        collect,
        "# adam sweep: collect the {} study's {n} results into its report, after the array.",
        plan.study.name()
    )?;
    writeln!(collect, "#SBATCH --job-name={name}-collect")?;
    writeln!(
        collect,
        "#SBATCH --time={}",
        slurm_time(r.time_per_task_min)
    )?;
    writeln!(collect, "#SBATCH --mem={}M", r.mem_per_task_mb)?;
    writeln!(collect, "#SBATCH --ntasks=1")?;
    writeln!(collect, "#SBATCH --cpus-per-task=1")?;
    writeln!(
        collect,
        "#SBATCH --output={}",
        logs.join("collect.out").display()
    )?;
    writeln!(collect, "set -euo pipefail")?;
    writeln!(
        collect,
        "exec {} sweep collect --plan {}",
        quoted(adam),
        quoted(plan_path)
    )?;

    let dir = plan.out_dir.join("slurm");
    let mut submit = String::new();
    writeln!(submit, "#!/bin/bash")?;
    writeln!(
        submit,
        "# Submits the {} study's job array, then its collect job once the array is over.",
        plan.study.name()
    )?;
    writeln!(submit, "set -euo pipefail")?;
    writeln!(submit, "mkdir -p {}", quoted(&logs))?;
    writeln!(
        submit,
        "array_id=$(sbatch --parsable {})",
        quoted(&dir.join("array.sbatch"))
    )?;
    writeln!(submit, "array_id=${{array_id%%;*}}")?;
    writeln!(
        submit,
        "collect_id=$(sbatch --parsable --dependency=afterany:\"$array_id\" {})",
        quoted(&dir.join("collect.sbatch"))
    )?;
    writeln!(submit, "collect_id=${{collect_id%%;*}}")?;
    writeln!(
        submit,
        "echo \"array job $array_id, collect job $collect_id\""
    )?;
    Ok(SlurmScripts {
        array,
        collect,
        submit,
    })
}

/// Writes the scripts under `<out_dir>/slurm/` and returns their paths (array, collect,
/// submit).
pub(crate) fn write_scripts(plan: &SweepPlan, s: &SlurmScripts) -> Result<[PathBuf; 3]> {
    let dir = plan.out_dir.join("slurm");
    for d in [&dir, &plan.out_dir.join("logs")] {
        std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
    }
    let paths = [
        dir.join("array.sbatch"),
        dir.join("collect.sbatch"),
        dir.join("submit.sh"),
    ];
    for (path, text) in paths.iter().zip([&s.array, &s.collect, &s.submit]) {
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
        executable(path)?;
    }
    Ok(paths)
}

#[cfg(unix)]
fn executable(path: &Path) -> Result<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))
        .with_context(|| format!("making {} executable", path.display()))
}

#[cfg(not(unix))]
fn executable(_: &Path) -> Result<()> {
    Ok(())
}

/// `sbatch` on the path, if any.
pub(crate) fn sbatch_on_path() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("sbatch"))
        .find(|p| p.is_file())
}

/// The job id `sbatch --parsable` printed (`id` or `id;cluster`).
pub(crate) fn parse_job_id(stdout: &str) -> Result<u64> {
    let first = stdout.trim().split(';').next().unwrap_or_default();
    first
        .parse()
        .with_context(|| format!("sbatch printed {:?}, not a job id", stdout.trim()))
}

/// Submits the array and the collect job depending on it; returns their job ids.
pub(crate) fn submit(sbatch: &Path, array: &Path, collect: &Path) -> Result<(u64, u64)> {
    let run = |args: &[String]| -> Result<u64> {
        let out = std::process::Command::new(sbatch)
            .args(args)
            .output()
            .with_context(|| format!("running {}", sbatch.display()))?;
        if !out.status.success() {
            bail!(
                "{} {} failed ({}): {}",
                sbatch.display(),
                args.join(" "),
                out.status,
                String::from_utf8_lossy(&out.stderr).trim()
            );
        }
        parse_job_id(&String::from_utf8_lossy(&out.stdout))
    };
    let array_id = run(&["--parsable".into(), array.display().to_string()])?;
    let collect_id = run(&[
        "--parsable".into(),
        format!("--dependency=afterany:{array_id}"),
        collect.display().to_string(),
    ])?;
    Ok((array_id, collect_id))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn slurm_times_and_job_ids() {
        assert_eq!(slurm_time(30), "00:30:00");
        assert_eq!(slurm_time(61), "01:01:00");
        assert_eq!(slurm_time(1440 + 90), "1-01:30:00");
        assert_eq!(parse_job_id("1234\n").unwrap(), 1234);
        assert_eq!(parse_job_id("77;cluster\n").unwrap(), 77);
        assert!(parse_job_id("Submitted batch job 5")
            .unwrap_err()
            .to_string()
            .contains("Submitted batch job 5"));
        assert_eq!(quoted(Path::new("/a b/it's")), r"'/a b/it'\''s'");
    }
}
