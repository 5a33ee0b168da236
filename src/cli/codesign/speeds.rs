//! `adam codesign --speeds 0.20,0.25,0.30`: one robot co-designed for the gaits of several
//! speeds together, against the single-speed co-design at each speed.

use super::{codesign_config, CodesignArgs};
use crate::cli::paths::{relative_path, writable, OUT_DIR};
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The gait file of one speed: `<stem>_<speed>.json` beside `base`.
fn gait_path(base: &Path, speed_mps: f64) -> PathBuf {
    let stem = base
        .file_stem()
        .map_or("adam_codesign".into(), |s| s.to_string_lossy().into_owned());
    base.with_file_name(format!("{stem}_{speed_mps:.2}.json"))
}

/// A single-speed co-design: thigh and shin (m), step length (m), duration (s), cost of transport.
type Alone = ([f64; 2], f64, f64, f64);

/// `adam codesign --speeds`.
pub(crate) fn codesign_speeds(args: &CodesignArgs, speeds: &[f64]) -> Result<()> {
    if speeds.len() < 2 {
        bail!(
            "--speeds: give at least two speeds, comma-separated (one speed: set [gait] speed_mps)"
        );
    }
    if let Some(v) = speeds.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        bail!("--speeds: {v} is not a positive speed in m/s");
    }
    let cfg = codesign_config(&args.config, args.inertia)?;
    let out = Path::new(OUT_DIR);
    let base = args
        .out_gait
        .clone()
        .unwrap_or_else(|| out.join("gaits/adam_codesign_speeds.json"));
    let out_urdf = args
        .out_urdf
        .clone()
        .unwrap_or_else(|| out.join("robots/adam_codesign_speeds.urdf"));
    let gait_paths: Vec<PathBuf> = speeds.iter().map(|&v| gait_path(&base, v)).collect();
    for p in gait_paths.iter().chain([&out_urdf]) {
        writable(p, args.force)?;
    }
    let urdf_ref = relative_path(&out_urdf, &base);
    println!("co-designing one robot for {speeds:?} m/s (one NLP, shared lengths) ...");
    let t0 = std::time::Instant::now();
    let r = planner::codesign::codesign_speeds(&cfg, speeds, &urdf_ref)?;
    let multi_s = t0.elapsed().as_secs_f64();
    std::fs::write(&out_urdf, &r.urdf)
        .with_context(|| format!("writing {}", out_urdf.display()))?;
    for (p, g) in gait_paths.iter().zip(&r.gaits) {
        g.gait.save(p)?;
    }
    // The single-speed co-design at each speed, for comparison.
    println!("co-designing for each speed alone, for comparison ...");
    let singles: Vec<Result<Alone, String>> = speeds
        .iter()
        .map(|&v| {
            let mut one = cfg.clone();
            one.gait.speed_mps = Some([v, v]);
            let run = || -> Result<Alone> {
                let r = planner::codesign::codesign(&one, "robot.urdf", &mut |_| {})?;
                let g = &r.planned.gait;
                Ok((
                    [r.design.thigh_length_m, r.design.shin_length_m],
                    g.step_length_m,
                    g.step_duration_s,
                    g.cost_of_transport,
                ))
            };
            run().map_err(|e| e.to_string())
        })
        .collect();
    let mut md = String::new();
    writeln!(
        md,
        "One design for {} speeds: thigh {:.4} m, shin {:.4} m ({} iterations, {}, mean cost of transport {:.5}; {multi_s:.1} s)\n",
        speeds.len(),
        r.lengths_m[0],
        r.lengths_m[1],
        r.iterations,
        r.status,
        r.mean_cost
    )?;
    writeln!(
        md,
        "| speed m/s | shared design: step m / s, cost of transport | alone: thigh / shin m | alone: step m / s, cost of transport |"
    )?;
    writeln!(md, "|---|---|---|---|")?;
    for ((v, g), s) in speeds.iter().zip(&r.gaits).zip(&singles) {
        let g = &g.gait;
        let alone = match s {
            Ok((l, d, t, c)) => format!("{:.4} / {:.4} | {d:.4} / {t:.4}, {c:.5}", l[0], l[1]),
            Err(e) => format!("failed: {e} |"),
        };
        writeln!(
            md,
            "| {v:.2} | {:.4} / {:.4}, {:.5} | {alone} |",
            g.step_length_m, g.step_duration_s, g.cost_of_transport
        )?;
    }
    for (v, a) in speeds.iter().zip(&r.activity) {
        let value = |g| {
            a.group(g)
                .and_then(|x| x.value)
                .map_or(String::new(), |(v, side)| match side {
                    Some((_, b)) => format!("{v:.4} (at bound {b})"),
                    None => format!("{v:.4} (interior)"),
                })
        };
        writeln!(
            md,
            "\nAt {v:.2} m/s the shared thigh is {}, the shin {}.",
            value(planner::collocation::ConstraintGroup::ThighLength),
            value(planner::collocation::ConstraintGroup::ShinLength)
        )?;
    }
    print!("\n{md}");
    println!(
        "wrote {} and {}",
        out_urdf.display(),
        gait_paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}
