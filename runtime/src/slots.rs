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
    /// Leg slots: model angle = direction · motor angle / gear ratio + offset (±1).
    pub direction: [f64; LEG_SLOTS],
    /// Leg slots: the model angle at motor zero, rad.
    pub offset_rad: [f64; LEG_SLOTS],
    /// Leg slots: motor output turns per joint turn (1: the A1 drives the joint directly).
    pub gear_ratio: [f64; LEG_SLOTS],
    /// Held slots: position, rad (motor side).
    pub held_center_rad: [f64; SLOTS],
    /// Held slots: tolerance, rad.
    pub held_tolerance_rad: [f64; SLOTS],
    /// Held slots: kp, N·m/rad.
    pub held_kp: [f64; SLOTS],
    /// Held slots: kd, N·m·s/rad.
    pub held_kd: [f64; SLOTS],
}

/// The one place motor quantities become joint quantities and back (the runtime config's
/// `[calibration]`, `runtime::config::calibration`): plain arithmetic, no allocation. With the
/// identity calibration (direction 1, offset 0, gear ratio 1) every map is exact: the value
/// passes through bit for bit.
impl SlotLayout {
    /// Leg slot `slot`'s model joint angle at motor angle `motor_rad`, rad.
    pub fn model_rad(&self, slot: usize, motor_rad: f64) -> f64 {
        self.direction[slot] * motor_rad / self.gear_ratio[slot] + self.offset_rad[slot]
    }

    /// Leg slot `slot`'s motor angle at model joint angle `model_rad`, rad.
    pub fn motor_rad(&self, slot: usize, model_rad: f64) -> f64 {
        (model_rad - self.offset_rad[slot]) * self.gear_ratio[slot] * self.direction[slot]
    }

    /// Leg slot `slot`'s joint rate at motor rate `motor_rad_s`, rad/s.
    pub fn model_rate_rad_s(&self, slot: usize, motor_rad_s: f64) -> f64 {
        self.direction[slot] * motor_rad_s / self.gear_ratio[slot]
    }

    /// Leg slot `slot`'s motor rate at joint rate `model_rad_s`, rad/s.
    pub fn motor_rate_rad_s(&self, slot: usize, model_rad_s: f64) -> f64 {
        model_rad_s * self.gear_ratio[slot] * self.direction[slot]
    }

    /// Leg slot `slot`'s motor torque for joint torque `model_nm`, N·m (the transmission
    /// multiplies the motor's torque by its ratio: power is the same on both sides).
    pub fn motor_torque_nm(&self, slot: usize, model_nm: f64) -> f64 {
        self.direction[slot] * model_nm / self.gear_ratio[slot]
    }

    /// Leg slot `slot`'s joint torque at motor torque `motor_nm`, N·m.
    pub fn model_torque_nm(&self, slot: usize, motor_nm: f64) -> f64 {
        self.direction[slot] * motor_nm * self.gear_ratio[slot]
    }

    /// The factor from a joint-side gain (kp, kd) to the motor-side one of leg slot `slot`:
    /// 1 / gear ratio² (held slots: 1).
    pub fn gain_factor(&self, slot: usize) -> f64 {
        if slot < LEG_SLOTS {
            let n = self.gear_ratio[slot];
            1.0 / (n * n)
        } else {
            1.0
        }
    }

    /// Whether any held motor is driven (the `with_held` this layout was made with, for a
    /// config that has held joints).
    pub fn with_held(&self) -> bool {
        self.present[LEG_SLOTS..].iter().any(|&p| p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout(direction: f64, offset_rad: f64, gear_ratio: f64) -> SlotLayout {
        SlotLayout {
            present: [true; SLOTS],
            direction: [direction; LEG_SLOTS],
            offset_rad: [offset_rad; LEG_SLOTS],
            gear_ratio: [gear_ratio; LEG_SLOTS],
            held_center_rad: [0.0; SLOTS],
            held_tolerance_rad: [0.0; SLOTS],
            held_kp: [0.0; SLOTS],
            held_kd: [0.0; SLOTS],
        }
    }

    /// A PD law on the joint side and the same law on the motor side (gains scaled by the
    /// layout, targets mapped) give the same joint torque, and power is the same on both sides.
    #[test]
    fn the_calibration_maps_a_pd_law_and_power_consistently() {
        for l in [
            layout(-1.0, 0.3, 2.0),
            layout(1.0, -0.7, 0.5),
            layout(-1.0, 0.0, 1.0),
        ] {
            let (kp, kd) = (150.0, 3.0);
            let (q, dq, q_des, dq_des, ff) = (0.4, -1.3, 0.9, 0.2, 5.0);
            let joint_tau = kp * (q_des - q) + kd * (dq_des - dq) + ff;
            let (m, dm) = (l.motor_rad(0, q), l.motor_rate_rad_s(0, dq));
            let g = l.gain_factor(0);
            let motor_tau = kp * g * (l.motor_rad(0, q_des) - m)
                + kd * g * (l.motor_rate_rad_s(0, dq_des) - dm)
                + l.motor_torque_nm(0, ff);
            let back = l.model_torque_nm(0, motor_tau);
            assert!(
                (back - joint_tau).abs() < 1e-9,
                "{l:?}: {back} vs {joint_tau}"
            );
            assert!((motor_tau * dm - joint_tau * dq).abs() < 1e-9, "power");
            assert!((l.model_rad(0, m) - q).abs() < 1e-12);
            assert!((l.model_rate_rad_s(0, dm) - dq).abs() < 1e-12);
        }
    }
}
