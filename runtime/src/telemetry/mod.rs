//! What a run tells the outside: the per-tick [`sample::StateSample`] published over iceoryx2,
//! the MCAP log ([`log`]: writer thread; [`log_read`]: reading it back; [`salvage`]: the one
//! way every reader reads, past damage; [`loss`]: what damage took; [`recover`]: a damaged log
//! rewritten whole) and the deterministic [`replay`] of a log through the controller.

pub mod log;
pub mod log_read;
pub mod loss;
pub mod recover;
pub mod replay;
pub mod salvage;
pub mod sample;
