//! Helpers shared by the root tests that start `adam` processes.

use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdout, Command, Stdio};

/// The `adam` binary of this build, run from the repository root.
pub fn adam() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_adam"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

/// `adam emulate motors` on a free local UDP port (it exits after 60 s idle): the child, the
/// rest of its stdout, and the address it serves (from its first line, `… from <addr> …`).
pub fn spawn_emulator() -> (Child, BufReader<ChildStdout>, String) {
    let mut emulator = adam()
        .args([
            "emulate",
            "motors",
            "--listen",
            "127.0.0.1:0",
            "--idle-exit",
            "60",
        ])
        .stdout(Stdio::piped())
        .spawn()
        .expect("spawn `adam emulate motors`");
    let mut out = BufReader::new(emulator.stdout.take().expect("the emulator's stdout"));
    let mut first = String::new();
    out.read_line(&mut first)
        .expect("the emulator's first line");
    let addr = first
        .split(" from ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap_or_else(|| panic!("no address in `{first}`"))
        .to_string();
    (emulator, out, addr)
}
