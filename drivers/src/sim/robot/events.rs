//! What happens in the simulation: touchdowns, liftoffs, friction warnings, falls
//! ([`SimEvent`]), and where a fall happened ([`FallRecord`]).

use super::BeltEnd;
use model::Side;

/// What touched the ground (or tipped over) in a fall.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FallCause {
    /// The torso (its hip axis or its top) reached the ground.
    Torso,
    /// A knee joint reached the ground.
    Knee(Side),
    /// The torso pitched beyond the limit.
    Pitch,
    /// A stance foot was carried (or stepped) past an end of the belt.
    OffBelt(BeltEnd),
}

/// What fell, for a user, e.g. `left knee on the ground`.
impl core::fmt::Display for FallCause {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            FallCause::Torso => f.write_str("torso on the ground"),
            FallCause::Knee(Side::Left) => f.write_str("left knee on the ground"),
            FallCause::Knee(Side::Right) => f.write_str("right knee on the ground"),
            FallCause::Pitch => f.write_str("torso pitched past its limit"),
            FallCause::OffBelt(BeltEnd::Back) => f.write_str("off the back of the belt"),
            FallCause::OffBelt(BeltEnd::Front) => f.write_str("off the front of the belt"),
        }
    }
}

/// A foot touchdown: the plastic impact and the step it ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touchdown {
    /// Time of contact \[s\].
    pub t_s: f64,
    /// Foot that touched down.
    pub side: Side,
    /// Its world x position \[m\].
    pub foot_x_m: f64,
    /// Step length: this foot's x minus the other foot's x at touchdown \[m\].
    pub step_length_m: f64,
    /// Impulse on the robot at this foot, world (x, z) \[N·s\].
    pub impulse_ns: [f64; 2],
    /// Kinetic energy just before the impact \[J\].
    pub kinetic_energy_before_j: f64,
    /// Kinetic energy just after the impact \[J\].
    pub kinetic_energy_after_j: f64,
    /// Belt speed at touchdown \[m/s\].
    pub belt_speed_mps: f64,
    /// The hip's position on the belt at touchdown, forward of its centre \[m\].
    pub position_on_belt_m: f64,
}

/// Where and when the robot fell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FallRecord {
    /// Time \[s\].
    pub t_s: f64,
    /// What touched the ground, tipped, or left the belt.
    pub what: FallCause,
    /// The hip's world x then \[m\].
    pub base_x_m: f64,
    /// The hip's position on the belt then, forward of its centre \[m\].
    pub position_on_belt_m: f64,
}

/// Something that happened in the simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SimEvent {
    /// A foot touched down.
    Touchdown(Touchdown),
    /// A stance foot left the ground (its normal force or impulse would have pulled).
    Liftoff {
        /// Time \[s\].
        t_s: f64,
        /// Which foot.
        side: Side,
    },
    /// The tangential force of a stance foot exceeds μ × its normal force (foot kept pinned).
    FrictionExceeded {
        /// Time \[s\].
        t_s: f64,
        /// Which foot.
        side: Side,
        /// |F_x| / F_z.
        ratio: f64,
    },
    /// The robot fell (reported once).
    Fall {
        /// Time \[s\].
        t_s: f64,
        /// What touched the ground or tipped.
        what: FallCause,
    },
    /// A step failed; the simulation is frozen (see [`RobotSim::step`](super::RobotSim::step)).
    Fault {
        /// Time \[s\].
        t_s: f64,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fall_reads_as_words() {
        assert_eq!(FallCause::Torso.to_string(), "torso on the ground");
        assert_eq!(
            FallCause::Knee(Side::Right).to_string(),
            "right knee on the ground"
        );
        assert_eq!(FallCause::Pitch.to_string(), "torso pitched past its limit");
        assert_eq!(
            FallCause::OffBelt(BeltEnd::Back).to_string(),
            "off the back of the belt"
        );
    }
}
