//! The lifecycle steps every frame-level [`MotorBus`](crate::bus::MotorBus) shares: configure,
//! activate with rollback, deactivate, and the disable a bus sends when it is dropped active.
//!
//! [`FrameBus`](crate::frame_bus::FrameBus) (SocketCAN, UDP) and the simulated
//! [`SimBus`](crate::sim::bus::SimBus) differ only in how one round of special frames reaches the
//! motors (a wall-clock round trip against simulated bus time); that is [`SpecialRounds`].

use crate::a1::Special;
use crate::bus::{BusError, Lifecycle, MotorSpec, MotorTable, Operation};
use crate::frame_log::FrameLog;

/// The parts of a bus its lifecycle touches.
pub(crate) struct LifecycleParts<'a> {
    /// Where the bus is in its lifecycle.
    pub state: &'a mut Lifecycle,
    /// The configured motors.
    pub table: &'a mut MotorTable,
    /// The frames of the last round.
    pub frames: &'a mut FrameLog,
}

/// A bus that can send one special frame (enable, disable) to every configured motor.
pub(crate) trait SpecialRounds {
    /// Its lifecycle state, motor table and frame log.
    fn parts(&mut self) -> LifecycleParts<'_>;
    /// Number of buses the motors may sit on.
    fn buses(&self) -> usize;
    /// One special frame to every configured motor; an enable a motor refuses is
    /// [`BusError::EnableRefused`].
    fn special_to_all(&mut self, special: Special) -> Result<(), BusError>;
}

/// [`MotorBus::configure`](crate::bus::MotorBus::configure): the motor table, checked.
pub(crate) fn configure(
    bus: &mut impl SpecialRounds,
    motors: &[MotorSpec],
) -> Result<(), BusError> {
    let buses = bus.buses();
    let parts = bus.parts();
    parts.state.allows(Operation::Configure)?;
    *parts.table = MotorTable::new(motors, buses)?;
    *parts.state = Lifecycle::Configured;
    Ok(())
}

/// [`MotorBus::activate`](crate::bus::MotorBus::activate): enable every motor, or, when one
/// refuses or does not answer, disable them all again (nothing is left half enabled) and keep
/// both rounds in the frame log.
pub(crate) fn activate(bus: &mut impl SpecialRounds) -> Result<(), BusError> {
    bus.parts().state.allows(Operation::Activate)?;
    if let Err(e) = bus.special_to_all(Special::Enable) {
        let enable_frames = *bus.parts().frames;
        let _ = bus.special_to_all(Special::Disable);
        let frames = bus.parts().frames;
        let disable_frames = core::mem::replace(frames, enable_frames);
        frames.append(&disable_frames);
        return Err(e);
    }
    *bus.parts().state = Lifecycle::Active;
    Ok(())
}

/// [`MotorBus::deactivate`](crate::bus::MotorBus::deactivate): back to configured, every motor
/// disabled.
pub(crate) fn deactivate(bus: &mut impl SpecialRounds) -> Result<(), BusError> {
    let parts = bus.parts();
    parts.state.allows(Operation::Deactivate)?;
    *parts.state = Lifecycle::Configured;
    bus.special_to_all(Special::Disable)
}

/// What `Drop` does: a bus dropped while active disables its motors (best effort).
pub(crate) fn disable_if_active(bus: &mut impl SpecialRounds) {
    if *bus.parts().state == Lifecycle::Active {
        let _ = bus.special_to_all(Special::Disable);
    }
}
