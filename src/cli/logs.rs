//! `adam logs`, `adam replay` and `adam plot`: what a run log holds, a cut-off or damaged log
//! recovered, a log replayed through this build's controller, and figures drawn from logs.
//! Every command reads a damaged log past its damage and warns (on stderr) what it lost.

use crate::cli::paths::{writable, OUT_DIR};
use crate::cli::plots;
use crate::cli::shipped;
use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// Arguments of `adam replay`.
#[derive(clap::Args)]
pub(crate) struct ReplayArgs {
    /// The log(s) to replay.
    #[arg(required_unless_present = "mint")]
    logs: Vec<PathBuf>,
    /// Record the replay fixtures into this folder (after an intended controller change).
    #[arg(long, conflicts_with = "logs")]
    mint: Option<PathBuf>,
}

/// The subcommands of `adam logs`.
#[derive(clap::Subcommand)]
pub(crate) enum LogsCommand {
    /// Channels, message counts, duration, drops, safety trips, gait and design of a log.
    Info {
        /// The log.
        log: PathBuf,
    },
    /// Rewrite a log cut off by a crash or damaged with summary and indexes: every message of
    /// every chunk whose CRC holds, and an account of what was lost.
    Recover {
        /// The cut-off or damaged log.
        log: PathBuf,
        /// Output (default: `<log stem>.recovered.mcap` beside the input).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write over an existing output.
        #[arg(long)]
        force: bool,
    },
    /// Every CAN frame of a log (the `/can` channel) in can-utils' candump log format,
    /// `(seconds) canN ID#DATA`, for `cantools decode drivers/a1_can.dbc` and `canplayer`.
    Candump {
        /// The log.
        log: PathBuf,
        /// Output file (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write over an existing output.
        #[arg(long)]
        force: bool,
    },
}

/// The figures of `adam plot`.
#[derive(clap::Subcommand)]
pub(crate) enum PlotWhat {
    /// Phase portraits (q vs q̇) of the hips and knees, like the paper's Fig. 4, as PNG and SVG.
    Portrait {
        /// The run.
        log: PathBuf,
        /// A second run to overlay (e.g. another gait, seed or the hardware).
        #[arg(long)]
        compare: Option<PathBuf>,
        /// Output prefix (default: `out/<log stem>-portrait`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write over existing figures.
        #[arg(long)]
        force: bool,
    },
    /// Gait tiles, like the paper's Fig. 5: stick figures at evenly spaced phases of one step
    /// of a logged walk, as PNG and SVG.
    Tiles {
        /// The run (a walk of at least two steps).
        log: PathBuf,
        /// Number of figures (phases 0, 1/(n−1), …, 1).
        #[arg(long, default_value_t = 8)]
        count: usize,
        /// Output prefix (default: `out/<log stem>-tiles`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write over existing figures.
        #[arg(long)]
        force: bool,
    },
    /// Treadmill speed control: belt speed, commanded and measured walking speed, the library
    /// speed in use, and the estimated (and, simulated, true) position on the belt against time,
    /// as PNG and SVG.
    Speed {
        /// The run (with speed control: a gait library and a belt speed).
        log: PathBuf,
        /// Output prefix (default: `out/<log stem>-speed`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write over existing figures.
        #[arg(long)]
        force: bool,
    },
}

/// `adam replay`: each log replayed through this build's controller, or the fixtures minted.
pub(crate) fn replay(args: &ReplayArgs) -> Result<()> {
    let (logs, mint) = (&args.logs, args.mint.as_deref());
    if let Some(dir) = mint {
        let setup = runtime::Setup::load(
            shipped::input(Path::new(shipped::RUNTIME_CONFIG)),
            shipped::input(Path::new(runtime::DEFAULT_GAIT)),
        )?;
        let paths = runtime::telemetry::replay::mint_fixtures(&setup, dir)?;
        for (path, (_, what)) in paths.iter().zip(runtime::telemetry::replay::FIXTURES) {
            let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            println!("wrote {} ({bytes} bytes): {what}", path.display());
        }
        return Ok(());
    }
    let mut diverged = 0;
    for log in logs {
        let report = runtime::telemetry::replay::replay(log)?;
        print!("{report}");
        if let Some(t) = &report.truncated {
            eprintln!(
                "warning: {}: {t}; replay checked ticks 0–{}",
                log.display(),
                report.ticks.saturating_sub(1)
            );
        }
        diverged += usize::from(report.divergence.is_some());
    }
    if diverged > 0 {
        bail!("{diverged} of {} log(s) diverged", logs.len());
    }
    Ok(())
}

/// `adam logs info`: channels, counts, drops, trips, gait and design of a log.
pub(crate) fn info(log: &std::path::Path) -> Result<()> {
    let info = runtime::telemetry::log_read::read_info(log)?;
    print!("{info}");
    if let Some(t) = &info.truncated {
        eprintln!("warning: {}: {t}", log.display());
    }
    Ok(())
}

/// `adam logs recover`: rewrites a cut-off log with summary and indexes.
pub(crate) fn recover(log: PathBuf, out: Option<PathBuf>, force: bool) -> Result<()> {
    let out = out.unwrap_or_else(|| log.with_extension("recovered.mcap"));
    writable(&out, force)?;
    let stats = runtime::telemetry::log_read::recover(&log, &out)?;
    print!("{stats}");
    Ok(())
}

/// `adam plot portrait`: phase portraits of one run, or two overlaid.
pub(crate) fn portrait(
    log: PathBuf,
    compare: Option<PathBuf>,
    out: Option<PathBuf>,
    force: bool,
) -> Result<()> {
    let a = runtime::telemetry::log_read::joint_series(&log)?;
    let b = compare
        .as_ref()
        .map(|p| runtime::telemetry::log_read::joint_series(p))
        .transpose()?;
    for (path, series) in std::iter::once((&log, &a)).chain(compare.iter().zip(&b)) {
        if let Some(d) = &series.damage {
            eprintln!(
                "warning: {}: {d}; drawing the {} samples read",
                path.display(),
                series.t_s.len()
            );
        }
    }
    let mut runs = vec![plots::PortraitRun {
        label: log.display().to_string(),
        series: &a,
    }];
    if let (Some(p), Some(b)) = (&compare, &b) {
        runs.push(plots::PortraitRun {
            label: p.display().to_string(),
            series: b,
        });
    }
    let prefix = figure_prefix(&log, out, "-portrait", force)?;
    plots::portraits(&prefix, &runs)?;
    println!(
        "wrote {} and {}",
        prefix.with_extension("png").display(),
        prefix.with_extension("svg").display()
    );
    Ok(())
}

/// `adam plot tiles`: stick figures of one step of a logged walk.
pub(crate) fn tiles(log: PathBuf, count: usize, out: Option<PathBuf>, force: bool) -> Result<()> {
    let tiles = runtime::tiles::gait_tiles(&log, count)?;
    if let Some(d) = &tiles.damage {
        eprintln!(
            "warning: {}: {d}; drawing a step of what was read",
            log.display()
        );
    }
    let prefix = figure_prefix(&log, out, "-tiles", force)?;
    let name = log
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    plots::tiles(&prefix, &tiles, &name)?;
    println!(
        "step {} ({:.3} m in {:.3} s), {} figures: wrote {} and {}",
        tiles.step,
        tiles.step_length_m,
        tiles.step_duration_s,
        tiles.figures.len(),
        prefix.with_extension("png").display(),
        prefix.with_extension("svg").display()
    );
    Ok(())
}

/// `adam plot speed`: belt and walking speed and the position on the belt against time, from
/// the `/speed` channel of a run with treadmill speed control.
pub(crate) fn speed(log: PathBuf, out: Option<PathBuf>, force: bool) -> Result<()> {
    let rows = runtime::telemetry::speed_read::read_speed(&log)?;
    let prefix = figure_prefix(&log, out, "-speed", force)?;
    let name = log
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    plots::speed(&prefix, &rows, &name)?;
    let clamped = rows.iter().filter(|r| r.clamped).count();
    println!(
        "{} steps from {:.2} s to {:.2} s ({clamped} with the command clamped to the library): wrote {} and {}",
        rows.len(),
        rows[0].t_s,
        rows[rows.len() - 1].t_s,
        prefix.with_extension("png").display(),
        prefix.with_extension("svg").display()
    );
    Ok(())
}

/// The output prefix of a figure: `out` or `out/<log stem><suffix>`, checked so that neither its
/// PNG nor its SVG is written over without `--force`.
fn figure_prefix(log: &Path, out: Option<PathBuf>, suffix: &str, force: bool) -> Result<PathBuf> {
    let prefix = out.unwrap_or_else(|| {
        let stem = log.file_stem().unwrap_or_default().to_string_lossy();
        Path::new(OUT_DIR).join(format!("{stem}{suffix}"))
    });
    for extension in ["png", "svg"] {
        writable(&prefix.with_extension(extension), force)?;
    }
    Ok(prefix)
}

/// `adam logs candump`: the log's `/can` frames as a candump log, to `out` or standard output.
pub(crate) fn candump(log: &Path, out: Option<PathBuf>, force: bool) -> Result<()> {
    use std::io::Write as _;
    let rows = runtime::telemetry::frames_read::read_frames(log)?;
    let mut text = String::with_capacity(rows.len() * 40);
    for row in &rows {
        text.push_str(&runtime::telemetry::frames_read::candump_line(row));
        text.push('\n');
    }
    match out {
        Some(path) => {
            writable(&path, force)?;
            std::fs::write(&path, text)
                .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))?;
            eprintln!("wrote {} ({} frames)", path.display(), rows.len());
        }
        None => std::io::stdout().lock().write_all(text.as_bytes())?,
    }
    Ok(())
}
