//! The convergence study's report from its runs, whichever way they ran: `adam codesign sweep`
//! (every run in this process) and `adam sweep collect` (each run a task of a plan, perhaps on
//! a cluster) both call [`write_sweep_report`], so the two cannot drift. The report is what the
//! runs found and nothing of how long they took: `sweep.csv`, `sweep.json`, `table.md` and
//! `convergence.png/.svg` are the same bit for bit from either path. Times go to `times.csv`.

use super::report::{SweepCsv, SweepTable};
use super::PAPER_OPTIMUM_M;
use crate::cli::plots;
use anyhow::{Context, Result};
use planner::codesign::{local_minima, mean_std, SweepOutcome, SweepRun};
use planner::config::PlannerConfig;
use std::fmt::Write as _;
use std::path::Path;

/// The files of the study's report in its folder (the figure's two files included).
pub(crate) const SWEEP_OUTPUTS: [&str; 6] = [
    "sweep.csv",
    "sweep.json",
    "table.md",
    "times.csv",
    "convergence.png",
    "convergence.svg",
];

/// Writes the report of the convergence study of `cfg` (its `[codesign]` box, coupling,
/// `[codesign.sweep]` grid and margin) from `runs` (in the grid's order) into `out_dir`, and
/// returns `table.md`'s text. `task_wall_s` is each run's wall time as its task measured it
/// (for `times.csv`).
pub(crate) fn write_sweep_report(
    cfg: &PlannerConfig,
    runs: &[SweepRun],
    task_wall_s: &[f64],
    out_dir: &Path,
) -> Result<String> {
    std::fs::create_dir_all(out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let margin = cfg.codesign.sweep.local_minimum_margin;
    let minima = local_minima(runs, margin);
    let write = |name: &str, text: &str| {
        let path = out_dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
    };
    write(
        "sweep.csv",
        &SweepCsv {
            runs,
            local_minima: &minima,
        }
        .to_string(),
    )?;
    planner::codesign::save_sweep(&out_dir.join("sweep.json"), runs)?;
    let mut times = String::from("initial_thigh_m,initial_shin_m,solve_time_s,wall_time_s\n");
    for (r, wall) in runs.iter().zip(task_wall_s) {
        let solve = r.outcome.as_ref().map_or(f64::NAN, |o| o.solve_time_s);
        writeln!(
            times,
            "{},{},{solve:.3},{wall:.3}",
            r.initial_m[0], r.initial_m[1]
        )?;
    }
    write("times.csv", &times)?;
    // Table II: mean ± std over the runs that are not local minima.
    let good: Vec<&SweepOutcome> = runs
        .iter()
        .zip(&minima)
        .filter(|(_, &lm)| !lm)
        .filter_map(|(r, _)| r.outcome.as_ref().ok())
        .collect();
    let col =
        |f: fn(&SweepOutcome) -> f64| mean_std(&good.iter().map(|o| f(o)).collect::<Vec<_>>());
    let rows = [
        ("thigh length (m)", col(|o| o.lengths_m[0]), "0.2425"),
        ("shin length (m)", col(|o| o.lengths_m[1]), "0.2515"),
        ("step length (m)", col(|o| o.step_length_m), "—"),
        ("step duration (s)", col(|o| o.step_duration_s), "—"),
        ("speed (m/s)", col(|o| o.speed_mps), "—"),
        ("cost of transport", col(|o| o.cost_of_transport), "—"),
        ("solver iterations", col(|o| o.iterations as f64), "—"),
    ];
    let grid = cfg.codesign.sweep.grid;
    let md = SweepTable {
        runs: runs.len(),
        planned_runs: grid * grid,
        grid,
        thigh_m: cfg.codesign.thigh_m,
        shin_m: cfg.codesign.shin_m,
        inertia: cfg.codesign.inertia,
        warm_start_m: cfg.codesign.initial_m,
        converged: good.len(),
        local_minima: minima.iter().filter(|&&m| m).count(),
        local_minimum_margin: margin,
        failed: runs.iter().filter(|r| r.outcome.is_err()).count(),
        rows: &rows,
    }
    .to_string();
    write("table.md", &md)?;
    let arrows: Vec<plots::ConvergenceArrow> = runs
        .iter()
        .zip(&minima)
        .filter_map(|(r, &lm)| {
            r.outcome.as_ref().ok().map(|o| plots::ConvergenceArrow {
                from_m: (r.initial_m[0], r.initial_m[1]),
                to_m: (o.lengths_m[0], o.lengths_m[1]),
                local_minimum: lm,
            })
        })
        .collect();
    plots::convergence(
        &out_dir.join("convergence"),
        &arrows,
        [cfg.codesign.thigh_m, cfg.codesign.shin_m],
        (PAPER_OPTIMUM_M[0], PAPER_OPTIMUM_M[1]),
    )?;
    Ok(md)
}
