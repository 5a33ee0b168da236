//! The motor slots everyone shares: how many there are, what a motor reply looks like to the
//! controller ([`MotorSample`]) and which slots have motors ([`SlotLayout`]). A leaf: it imports
//! nothing of the crate.
//!
//! Motor slots: 0..4 are the leg joints (left hip, left knee, right hip, right knee); 4..14 the
//! held joints of the config, in order.

/// Leg motor slots (hip and knee of each leg).
pub const LEG_SLOTS: usize = 4;
/// Most held joints.
pub const MAX_HELD: usize = 10;
/// All motor slots.
pub const SLOTS: usize = LEG_SLOTS + MAX_HELD;
/// Controlled outputs (stance hip, stance knee, swing hip, swing knee).
pub const OUTPUTS: usize = 4;

/// One motor's reply as the controller sees it (motor-side units).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotorSample {
    /// A reply arrived this tick (otherwise the values are the last known ones).
    pub fresh: bool,
    /// Position, rad.
    pub q_rad: f64,
    /// Velocity, rad/s.
    pub dq_rad_s: f64,
    /// Torque, N·m.
    pub tau_nm: f64,
    /// Winding temperature, °C.
    pub temperature_c: f64,
    /// Fault bits ([`drivers::a1::ErrorFlags`]).
    pub errors: u8,
}

/// Which slots have motors, and the fixed data of each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlotLayout {
    /// A motor is driven in this slot.
    pub present: [bool; SLOTS],
    /// Leg slots: model angle = direction · motor angle + offset.
    pub direction: [f64; LEG_SLOTS],
    /// Leg slots: offset, rad.
    pub offset_rad: [f64; LEG_SLOTS],
    /// Held slots: position, rad (motor side).
    pub held_center_rad: [f64; SLOTS],
    /// Held slots: tolerance, rad.
    pub held_tolerance_rad: [f64; SLOTS],
    /// Held slots: kp, N·m/rad.
    pub held_kp: [f64; SLOTS],
    /// Held slots: kd, N·m·s/rad.
    pub held_kd: [f64; SLOTS],
}

impl SlotLayout {
    /// Leg slot `slot`'s model joint angle at motor angle `motor_rad`, rad.
    pub fn model_rad(&self, slot: usize, motor_rad: f64) -> f64 {
        self.direction[slot] * motor_rad + self.offset_rad[slot]
    }

    /// Leg slot `slot`'s motor angle at model joint angle `model_rad`, rad.
    pub fn motor_rad(&self, slot: usize, model_rad: f64) -> f64 {
        (model_rad - self.offset_rad[slot]) * self.direction[slot]
    }

    /// Whether any held motor is driven (the `with_held` this layout was made with, for a
    /// config that has held joints).
    pub fn with_held(&self) -> bool {
        self.present[LEG_SLOTS..].iter().any(|&p| p)
    }
}
