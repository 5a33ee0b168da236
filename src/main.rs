//! `adam`: the command-line entry point of adam-hzd. It only parses arguments and calls
//! library functions in `model`, `planner`, `drivers` and `runtime`.
//!
//! This file parses and dispatches; each group of commands lives in its own module under
//! [`cli`]: `run` (run, demo, soak), `plan` (plan, gait check), `codesign`, `bench`, `logs`
//! (logs, replay, plot), `op`, `live` (the live view in Foxglove), `model` (model,
//! generate-urdf), `emulate` (emulated hardware) and `sweep` (a study as the tasks of a
//! cluster's job array). What a command prints at length comes from `Display` types in the
//! group's `report` module; `cli::plots` draws the figures and `cli::paths` derives file paths.
//!
//! **From any folder.** The shipped robots, gaits and configs are found from any working
//! directory (`cli::shipped`): a relative `configs/…` input missing from the working directory
//! is looked up in `$ADAM_CONFIG_DIR`, else in the repository the binary was built from, else
//! in a copy embedded in the binary. Paths inside a file resolve relative to that file.
//!
//! **Never over what ships.** Generated gaits, URDFs and sweeps go to `out/` (or the output
//! named), and a file that exists is written over only with `--force` (`cli::paths`).

use anyhow::Result;
use clap::{Parser, Subcommand};
use cli::bench::BenchWhat;
use cli::codesign::CodesignStudy;
use cli::logs::{LogsCommand, PlotWhat};
use cli::plan::GaitCommand;
use cli::{bench, calibrate, can, codesign, emulate, live, logs, model, op, plan, run, sweep};

mod cli;

#[derive(Parser)]
#[command(
    name = "adam",
    version,
    about = "HZD co-design and walking for the ADAM humanoid",
    after_help = AFTER_HELP
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// What `adam --help` says after the commands: where files are found and written.
const AFTER_HELP: &str = "\
Files:
  Inputs named configs/... (every default, e.g. configs/runtime/adam.toml) are found from any
  folder: from the working directory if there, else in $ADAM_CONFIG_DIR (a folder laid out like
  configs/), else in the repository adam was built from, else in a copy built into adam.
  Paths inside a file (a gait's URDF) are relative to that file.
  plan, codesign and codesign sweep write under out/ unless told otherwise; no command writes
  over an existing file without --force.";

#[derive(Subcommand)]
enum Command {
    /// Walk the shipped gait for 30 s on the simulated treadmill through the CAN codec path,
    /// log to `logs/<timestamp>.mcap`, print a summary.
    Demo(run::DemoArgs),
    /// Walk a gait with the real-time runtime on the simulated robot or on the robot over CAN.
    Run(Box<run::RunArgs>),
    /// Walk the simulated robot for a long time under random faults; after each trip reset and
    /// walk on. Prints ticks, overruns, trips by reason, log drops, worst tick, distance.
    Soak(run::SoakArgs),
    /// Figures from run logs: `adam plot portrait <run.mcap> [--compare <other.mcap>]`,
    /// `adam plot tiles <run.mcap>`, `adam plot speed <run.mcap>`.
    Plot {
        #[command(subcommand)]
        what: logs::PlotWhat,
    },
    /// Benchmarks that print a table (medians over repeated runs).
    Bench {
        #[command(subcommand)]
        what: bench::BenchWhat,
    },
    /// Send an operator command to a running `adam run` over iceoryx2.
    Op(op::OpArgs),
    /// Serve a running `adam run` live to Foxglove (WebSocket, default ws://127.0.0.1:8765):
    /// the log's channels, the robot in 3D and the belt; read-only unless --live-commands.
    Live(live::LiveArgs),
    /// Print a robot model: bodies, joints, total mass, leg lengths and D(q) at the nominal pose.
    Model(model::ModelArgs),
    /// Co-design the thigh and shin lengths with the gait (paper Sec. III): write the
    /// co-designed URDF and its gait file, verified like `adam gait check`.
    Codesign(codesign::CodesignArgs),
    /// Plan a periodic HZD walking gait (the paper's two-step solve) and write the gait file.
    Plan(plan::PlanArgs),
    /// Gait files: `adam gait check <gait.json>` verifies a gait independently of the optimizer.
    Gait {
        #[command(subcommand)]
        command: plan::GaitCommand,
    },
    /// MCAP logs: `adam logs info <run.mcap>`, `adam logs recover <in.mcap> [--out <out.mcap>]`,
    /// `adam logs candump <run.mcap> [--out <run.log>]`.
    Logs {
        #[command(subcommand)]
        command: logs::LogsCommand,
    },
    /// Emulate hardware for a runtime in another process: `adam emulate motors --listen
    /// 127.0.0.1:PORT` serves the simulated robot's A1 motors over CAN-over-UDP; `adam emulate
    /// imu --pty` a VN-100 on a pseudo-terminal.
    Emulate {
        #[command(subcommand)]
        what: emulate::EmulateWhat,
    },
    /// Replay a log through this build's controller and compare every command with the logged
    /// one: bit-identical, or the first divergence (exit code 1). `--mint <dir>` instead records
    /// the replay fixtures (`tests/fixtures`) anew.
    Replay(logs::ReplayArgs),
    /// Write the URDF of ADAM for a design (GenerateModel: inertias from the cubic fits).
    GenerateUrdf(model::GenerateUrdfArgs),
    /// Measure each leg motor's direction and zero offset (robot hung on the boom, legs clamped
    /// in the config's jig poses A then B) and write them into a new runtime config.
    Calibrate(calibrate::CalibrateArgs),
    /// The motor buses: `adam can scan --backend sim|can` asks every configured motor.
    Can {
        #[command(subcommand)]
        command: can::CanCommand,
    },
    /// A study as independent tasks for a cluster (SLURM job arrays): `adam sweep plan
    /// --study codesign|landscape|library|treadmill`, `adam sweep slurm --plan P
    /// [--submit]`, `adam sweep task --plan P [--index I]`, `adam sweep collect --plan P`.
    Sweep {
        #[command(subcommand)]
        command: sweep::SweepCommand,
    },
}

fn main() -> std::process::ExitCode {
    match dispatch(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Runs the command.
fn dispatch(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Demo(args) => run::demo(&args),
        Command::Run(args) => run::run(*args),
        Command::Soak(args) => run::soak(args),
        Command::Plan(args) => plan::plan(&args),
        Command::Gait {
            command:
                GaitCommand::Check {
                    gait,
                    epsilon,
                    runtime,
                    latency_s,
                },
        } => plan::gait_check(&gait, epsilon, runtime.as_deref(), latency_s),
        Command::Logs {
            command: LogsCommand::Info { log },
        } => logs::info(&log),
        Command::Logs {
            command: LogsCommand::Recover { log, out, force },
        } => logs::recover(log, out, force),
        Command::Logs {
            command: LogsCommand::Candump { log, out, force },
        } => logs::candump(&log, out, force),
        Command::Emulate { what } => emulate::emulate(what),
        Command::Replay(args) => logs::replay(&args),
        Command::Calibrate(args) => calibrate::calibrate(args),
        Command::Can {
            command: can::CanCommand::Scan(args),
        } => can::scan(args),
        Command::Model(args) => model::show_model(&args),
        Command::Bench {
            what:
                BenchWhat::Plan {
                    runs,
                    robot,
                    config,
                    backend,
                },
        } => bench::plan(runs, &robot, &config, backend),
        Command::Bench {
            what: BenchWhat::Check { runs, gait },
        } => bench::check(runs, &gait),
        Command::Bench {
            what: BenchWhat::Library(args),
        } => bench::library(&args),
        Command::Bench {
            what: BenchWhat::Live(args),
        } => bench::live(&args),
        Command::Bench {
            what:
                BenchWhat::Treadmill {
                    seeds,
                    quick,
                    belts,
                    config,
                    gait,
                },
        } => bench::treadmill(seeds, quick, belts.as_deref(), &config, &gait),
        Command::Plot {
            what:
                PlotWhat::Portrait {
                    log,
                    compare,
                    out,
                    force,
                },
        } => logs::portrait(log, compare, out, force),
        Command::Plot {
            what:
                PlotWhat::Tiles {
                    log,
                    count,
                    out,
                    force,
                },
        } => logs::tiles(log, count, out, force),
        Command::Plot {
            what: PlotWhat::Speed { log, out, force },
        } => logs::speed(log, out, force),
        Command::Op(args) => op::send(&args),
        Command::Live(args) => live::live(&args),
        Command::Codesign(args) => match &args.study {
            None => codesign::codesign(&args),
            Some(CodesignStudy::Sweep { grid, out_dir }) => {
                codesign::convergence_sweep(&args, *grid, out_dir.as_deref())
            }
            Some(CodesignStudy::Landscape {
                grid,
                out_dir,
                sweep,
                start,
            }) => codesign::landscape(
                &args,
                &codesign::LandscapeRequest {
                    grid: *grid,
                    out_dir: out_dir.as_deref(),
                    sweep: sweep.as_deref(),
                    start: *start,
                },
            ),
            Some(CodesignStudy::Audit { urdf, out_dir }) => {
                codesign::audit(&args, urdf.as_deref(), out_dir.as_deref())
            }
        },
        Command::GenerateUrdf(args) => model::write_urdf(args),
        Command::Sweep { command } => sweep::sweep(command),
    }
}
