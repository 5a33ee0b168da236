//! `adam codesign audit`: the gait with and without each constraint that is ours, not the
//! paper's (planner/CODESIGN.md, "Constraints").

use super::{codesign_config, CodesignArgs};
use crate::cli::paths::{writable, OUT_DIR};
use crate::cli::shipped;
use anyhow::{Context, Result};
use model::design::DesignLengths;
use planner::codesign::{AuditRow, AuditSolve};
use std::fmt::Write as _;
use std::path::Path;

/// `adam codesign audit`: writes `<out-dir>/audit.md` and prints it.
pub(crate) fn audit(
    args: &CodesignArgs,
    urdf: Option<&Path>,
    out_dir: Option<&Path>,
) -> Result<()> {
    super::refuse_gait_outputs(args, "audit")?;
    let cfg = codesign_config(&args.config, args.inertia)?;
    let default_dir = Path::new(OUT_DIR).join("codesign-audit");
    let out_dir = out_dir.unwrap_or(&default_dir);
    let md_path = out_dir.join("audit.md");
    writable(&md_path, args.force)?;
    let (model, text, robot) = match urdf {
        Some(path) => {
            let path = shipped::input(path);
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("reading {}", path.display()))?;
            let model = model::PlanarModel::from_urdf_str(&text, &path.display().to_string())?;
            (model, text, path.display().to_string())
        }
        None => {
            let [thigh, shin] = cfg.codesign.initial_m;
            let (model, text) = model::design::generate_model_with(
                &DesignLengths {
                    thigh_length_m: thigh,
                    shin_length_m: shin,
                },
                &cfg.codesign.mass_model(),
            )?;
            (
                model,
                text,
                format!("ADAM generated at thigh {thigh} m, shin {shin} m"),
            )
        }
    };
    println!("auditing the constraints on {robot} ...");
    let t0 = std::time::Instant::now();
    let audit = planner::codesign::audit(&model, &text, &cfg)?;
    let wall_s = t0.elapsed().as_secs_f64();
    let mut md = String::new();
    writeln!(
        md,
        "# Constraint audit: {robot}, config {}\n",
        args.config.display()
    )?;
    writeln!(
        md,
        "Each variant relaxes the shipped constraints; \"from ours\" is the cost-of-transport solve \
         from the baseline optimum, \"from scratch\" the whole two-step plan from the hand-built \
         guess. Δ is relative to the baseline's cost of transport from the same start.\n"
    )?;
    writeln!(
        md,
        "| variant | change | from ours: cost of transport (Δ) | step m / s | lowest swing foot m | from scratch: cost of transport (Δ) | step m / s |"
    )?;
    writeln!(md, "|---|---|---|---|---|---|---|")?;
    let base = audit.rows.first();
    let base_of = |f: fn(&AuditRow) -> &Result<AuditSolve, String>| {
        base.and_then(|r| f(r).as_ref().ok())
            .map(|s| s.cost_of_transport)
    };
    let (b_warm, b_scratch) = (base_of(|r| &r.from_baseline), base_of(|r| &r.from_scratch));
    for r in &audit.rows {
        let cell = |s: &Result<AuditSolve, String>, base: Option<f64>| match s {
            Ok(s) => {
                let delta = base
                    .map(|b| format!(" ({:+.1} %)", 100.0 * (s.cost_of_transport / b - 1.0)))
                    .unwrap_or_default();
                (
                    format!("{:.5}{delta}", s.cost_of_transport),
                    format!("{:.4} / {:.4}", s.step_length_m, s.step_duration_s),
                    format!("{:.4}", s.min_swing_height_m),
                )
            }
            Err(e) => (format!("failed: {e}"), String::new(), String::new()),
        };
        let (wc, ws, wh) = cell(&r.from_baseline, b_warm);
        let (sc, ss, _) = cell(&r.from_scratch, b_scratch);
        writeln!(
            md,
            "| {} | {} | {wc} | {ws} | {wh} | {sc} | {ss} |",
            r.variant.name, r.variant.change
        )?;
    }
    match &audit.baseline_activity {
        Some(a) => writeln!(
            md,
            "\nAt the baseline optimum (cost-of-transport solve, objective {:.5}), which constraints \
             are active and what relaxing them is worth (relief: cost saved per unit a group's \
             active bounds move outward):\n\n{a}",
            a.cost
        )?,
        None => writeln!(md, "\nThe baseline solve did not end usable: no activity.")?,
    }
    writeln!(
        md,
        "\n{} variants, each solved twice, in {wall_s:.1} s wall.",
        audit.rows.len()
    )?;
    std::fs::write(&md_path, &md).with_context(|| format!("writing {}", md_path.display()))?;
    print!("\n{md}");
    println!("wrote {}", md_path.display());
    Ok(())
}
