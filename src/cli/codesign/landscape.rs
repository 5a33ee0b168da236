//! `adam codesign landscape`: the optimal cost of the fixed-design gait over a grid of the
//! design box, drawn as a heat map with the co-design optimum and the convergence study's
//! endpoints, and the constraints that hold the co-design optimum with their multipliers.

use super::{codesign_config, warm_start, CodesignArgs};
use crate::cli::paths::{writable, OUT_DIR};
use crate::cli::plots;
use anyhow::{Context, Result};
use planner::codesign::{Landscape, LandscapeStart};
use std::fmt::Write as _;
use std::path::Path;

/// `--start` of the landscape (no doc on the values: clap would list them with it).
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum StartArg {
    Initial,
    Neighbours,
}

/// What `adam codesign landscape` was asked.
pub(crate) struct LandscapeRequest<'a> {
    /// `--grid`, overriding `[codesign] landscape_grid`.
    pub(crate) grid: Option<usize>,
    /// `--out-dir`.
    pub(crate) out_dir: Option<&'a Path>,
    /// `--sweep`: a sweep.json of `adam codesign sweep` (else the sweep is run).
    pub(crate) sweep: Option<&'a Path>,
    /// `--start`.
    pub(crate) start: StartArg,
}

/// The landscape's outputs in its folder.
const OUTPUTS: [&str; 5] = [
    "landscape.png",
    "landscape.svg",
    "landscape.csv",
    "activity.md",
    "sweep.json",
];

/// `adam codesign landscape`.
pub(crate) fn landscape(args: &CodesignArgs, request: &LandscapeRequest<'_>) -> Result<()> {
    super::refuse_gait_outputs(args, "landscape")?;
    let mut cfg = codesign_config(&args.config, args.inertia)?;
    if let Some(grid) = request.grid {
        planner::config::check_landscape_grid(grid, "adam codesign landscape", "--grid")?;
        cfg.codesign.landscape_grid = grid;
    }
    let n = cfg.codesign.landscape_grid;
    let default_dir = Path::new(OUT_DIR).join("codesign-landscape");
    let out_dir = request.out_dir.unwrap_or(&default_dir);
    // A given sweep file is read before any solve: a bad one fails at once.
    let given_sweep = match request.sweep {
        Some(path) => Some(planner::codesign::load_sweep_endpoints(path)?),
        None => None,
    };
    for name in OUTPUTS {
        if name == "sweep.json" && given_sweep.is_some() {
            continue;
        }
        writable(&out_dir.join(name), args.force)?;
    }
    std::fs::create_dir_all(out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let t0 = std::time::Instant::now();
    let model_lengths = cfg.codesign.initial_m;
    let initial = warm_start(&cfg)?;
    let warm_s = t0.elapsed().as_secs_f64();
    let bar = progress(n * n, "fixed-design solves")?;
    let start = match request.start {
        StartArg::Initial => LandscapeStart::Initial,
        StartArg::Neighbours => LandscapeStart::Neighbours,
    };
    let land =
        planner::codesign::landscape(&cfg, &initial, model_lengths, n, start, &|_| bar.inc(1))?;
    bar.finish();
    println!("co-design from the initial design, for the optimum and its multipliers ...");
    let t1 = std::time::Instant::now();
    let co = planner::codesign::codesign_study_run(&cfg, &initial, model_lengths, model_lengths)?;
    let codesign_s = t1.elapsed().as_secs_f64();
    let t2 = std::time::Instant::now();
    let ends: Vec<(f64, f64)> = match given_sweep {
        Some(runs) => runs
            .iter()
            .filter_map(|r| r.lengths_m.map(|l| (l[0], l[1])))
            .collect(),
        None => {
            let starts = planner::codesign::sweep_grid(&cfg, cfg.codesign.sweep.grid);
            let bar = progress(starts.len(), "co-design runs (the convergence study)")?;
            let runs =
                planner::codesign::sweep(&cfg, &initial, model_lengths, &starts, &|_| bar.inc(1));
            bar.finish();
            planner::codesign::save_sweep(&out_dir.join("sweep.json"), &runs)?;
            runs.iter()
                .filter_map(|r| r.outcome.as_ref().ok())
                .map(|o| (o.lengths_m[0], o.lengths_m[1]))
                .collect()
        }
    };
    let sweep_s = t2.elapsed().as_secs_f64();
    let optimum = [co.design.thigh_length_m, co.design.shin_length_m];
    let mut md = String::new();
    writeln!(
        md,
        "# Cost landscape ({n} × {n} fixed designs, {} start)\n",
        match request.start {
            StartArg::Initial => "initial-gait",
            StartArg::Neighbours => "neighbour",
        }
    )?;
    md.push_str(&write_grid_report(
        &cfg,
        &land,
        out_dir,
        Some((optimum[0], optimum[1])),
        &ends,
    )?);
    let fixed_s = land.wall_time_s;
    let g = &co.planned.gait;
    writeln!(
        md,
        "## Co-design optimum ({} coupling): thigh {:.4} m, shin {:.4} m\n\nstep {:.4} m in {:.4} s ({:.4} m/s), cost of transport {:.5}; {} convergence-study endpoints drawn.\n",
        super::report::coupling_name(cfg.codesign.inertia),
        optimum[0],
        optimum[1],
        g.step_length_m,
        g.step_duration_s,
        g.speed_mps,
        g.cost_of_transport,
        ends.len()
    )?;
    match &co.activity {
        Some(a) => writeln!(
            md,
            "Active constraints at the optimum, with the cost they hold it at (the co-design \
             objective {:.5}; relief = cost saved per unit a group's active bounds move \
             outward, from the interior point's multipliers):\n\n{a}",
            a.cost
        )?,
        None => writeln!(
            md,
            "The last co-design solve did not end usable: no multipliers."
        )?,
    }
    writeln!(
        md,
        "\nTimes: warm start {warm_s:.2} s, {} fixed-design solves {fixed_s:.2} s wall, co-design {codesign_s:.2} s, sweep {sweep_s:.2} s; {} threads.",
        n * n,
        std::thread::available_parallelism().map_or(1, |n| n.get())
    )?;
    let md_path = out_dir.join("activity.md");
    std::fs::write(&md_path, &md).with_context(|| format!("writing {}", md_path.display()))?;
    print!("\n{md}");
    println!(
        "wrote {0}/landscape.png, {0}/landscape.svg, {0}/landscape.csv and {0}/activity.md{1}",
        out_dir.display(),
        if request.sweep.is_some() {
            String::new()
        } else {
            format!(" and {}/sweep.json", out_dir.display())
        }
    );
    Ok(())
}

/// The grid's part of the landscape's report, the same from `adam codesign landscape` and from
/// `adam sweep collect` of a landscape plan: `landscape.csv`, the heat map
/// (`landscape.png/.svg`, with the co-design optimum and the sweep's endpoints if given) and,
/// returned, the cost table with the best point in Markdown. Nothing in it depends on time.
pub(crate) fn write_grid_report(
    cfg: &planner::config::PlannerConfig,
    land: &Landscape,
    out_dir: &Path,
    optimum_m: Option<(f64, f64)>,
    sweep_ends_m: &[(f64, f64)],
) -> Result<String> {
    std::fs::create_dir_all(out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let costs: Vec<Option<f64>> = land
        .points
        .iter()
        .map(|p| p.outcome.as_ref().ok().map(|o| o.objective))
        .collect();
    plots::landscape(
        &out_dir.join("landscape"),
        &plots::HeatMap {
            thigh_m: &land.thigh_m,
            shin_m: &land.shin_m,
            cost: &costs,
            cost_label: cost_label(cfg),
            optimum_m,
            sweep_ends_m,
        },
    )?;
    let csv_path = out_dir.join("landscape.csv");
    std::fs::write(&csv_path, landscape_csv(land))
        .with_context(|| format!("writing {}", csv_path.display()))?;
    let mut md = String::new();
    writeln!(md, "{}", cost_table(land))?;
    let failed = land.points.iter().filter(|p| p.outcome.is_err()).count();
    if let Some(best) = land.best() {
        if let Ok(o) = &best.outcome {
            writeln!(
                md,
                "Best grid point: thigh {:.4} m, shin {:.4} m, objective {:.5}, mechanical cost of transport {:.5} (step {:.4} m in {:.4} s).",
                best.lengths_m[0], best.lengths_m[1], o.objective, o.cost_of_transport, o.step_length_m, o.step_duration_s
            )?;
        }
    }
    writeln!(
        md,
        "Failed grid solves: {failed}. Iterations over the grid: {}.\n",
        land.iterations()
    )?;
    Ok(md)
}

fn progress(n: usize, what: &str) -> Result<indicatif::ProgressBar> {
    let bar = indicatif::ProgressBar::new(n as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{bar:40}} {{pos}}/{{len}} {what}, {{elapsed}} elapsed, ETA {{eta}}"
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?,
    );
    Ok(bar)
}

/// Every grid point: lengths, gait figures, iterations, or the error.
fn landscape_csv(land: &Landscape) -> String {
    let mut s = String::from(
        "thigh_m,shin_m,cost_of_transport,step_length_m,step_duration_s,speed_mps,iterations,from_neighbour,error\n",
    );
    for p in &land.points {
        let [a, b] = p.lengths_m;
        let _ = match &p.outcome {
            Ok(o) => writeln!(
                s,
                "{a:.6},{b:.6},{:.8},{:.6},{:.6},{:.6},{},{},",
                o.cost_of_transport,
                o.step_length_m,
                o.step_duration_s,
                o.speed_mps,
                o.iterations,
                p.from_neighbour
            ),
            Err(e) => writeln!(
                s,
                "{a:.6},{b:.6},,,,,,{},\"{}\"",
                p.from_neighbour,
                e.replace('"', "'")
            ),
        };
    }
    s
}

/// The cost grid as a Markdown table: shin down the rows (longest first), thigh across.
fn cost_table(land: &Landscape) -> String {
    let mut s = String::from("| shin \\ thigh (m) |");
    for t in &land.thigh_m {
        let _ = write!(s, " {t:.3} |");
    }
    s.push_str("\n|---|");
    s.push_str(&"---|".repeat(land.n));
    s.push('\n');
    for j in (0..land.n).rev() {
        let _ = write!(s, "| {:.3} |", land.shin_m[j]);
        for i in 0..land.n {
            let _ = match &land.points[i * land.n + j].outcome {
                Ok(o) => write!(s, " {:.5} |", o.cost_of_transport),
                Err(_) => write!(s, " failed |"),
            };
        }
        s.push('\n');
    }
    s
}

/// The heat map's colour: the objective `[cost]` minimizes.
fn cost_label(cfg: &planner::config::PlannerConfig) -> &'static str {
    match cfg.cost.kind {
        planner::config::CostKind::Mechanical => "mechanical cost of transport",
        planner::config::CostKind::Electrical => "electrical cost of transport (A1)",
        planner::config::CostKind::TorqueSquared => "torque squared per distance (N²·m·s)",
        planner::config::CostKind::Weighted => "weighted cost",
    }
}
