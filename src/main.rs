//! `adam`: the command-line entry point of adam-hzd. It only parses arguments and calls
//! library functions in `model`, `planner`, `drivers` and `runtime`.

use anyhow::Result;
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "adam", version, about = "HZD co-design and walking for the ADAM humanoid")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The main job on the simulated robot (today: the parts that exist).
    Demo,
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Demo => {
            println!("adam demo: nothing is built yet");
            Ok(())
        }
    }
}
