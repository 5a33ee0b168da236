//! Old home of `SimBus`, kept as paths only: its parts moved to [`crate::sim`] (issue #26), the bus to
//! [`crate::sim::bus`], the A1 firmware to [`crate::sim::firmware`], the plants to
//! [`crate::sim::plant`], the wire faults to [`crate::sim::wire`].

// Compatibility paths for the runtime and the CLI until they move to the new rooms (issue #26).
pub use crate::sim::bus::{SimBus, SimConfig, SimError, MAX_BUSES};
pub use crate::sim::firmware::{A1Model, SimMotor, DISABLE_DAMPING_NM_S_PER_RAD};
pub use crate::sim::plant::{InertiaDampingPlant, JointPlant, RigidJoint};
pub use crate::sim::wire::{
    corrupt, Corruption, Direction, TapEntry, WireFaults, WireStats, WireTap,
};
