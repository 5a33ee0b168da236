//! What a run tells the outside: the per-tick [`sample::StateSample`] published over iceoryx2,
//! the MCAP log ([`log`]: writer thread; [`log_read`]: reading it back; [`salvage`]: the one
//! way every reader reads, past damage; [`loss`]: what damage took; [`recover`]: a damaged log
//! rewritten whole), the deterministic [`replay`] of a log through the controller, and the
//! treadmill speed control's `/speed` channel ([`speed_log`], read by [`speed_read`]), and the
//! raw CAN frames of the `/can` channel ([`frames`], read by [`frames_read`]: `adam logs candump`);
//! the channels' schemas and a sample's messages, shared with the live view ([`channels`]); the
//! robot in 3D for Foxglove: `/tf`, `/scene`, `/robot_description` ([`scene`]).

pub mod channels;
pub mod frames;
pub mod frames_read;
pub mod log;
pub mod log_read;
pub mod loss;
pub mod recover;
pub mod replay;
pub mod salvage;
pub mod sample;
pub mod scene;
pub mod speed_log;
pub mod speed_read;
