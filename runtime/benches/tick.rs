//! Tick compute time (placeholder, filled below).
fn main() {}
