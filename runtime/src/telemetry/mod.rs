//! What a run tells the outside: the per-tick [`sample::StateSample`] published over iceoryx2,
//! the MCAP log ([`log`]: writer thread; [`log_read`]: reading it back) and the deterministic
//! [`replay`] of a log through the controller.

pub mod log;
mod log_guard;
pub mod log_read;
pub mod replay;
pub mod sample;
