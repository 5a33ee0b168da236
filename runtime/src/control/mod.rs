//! Control: the sans-IO tick of [`Controller`] — state machine, phase and stance switching,
//! desired outputs y^d(τ), PD commands — and what it reads and writes ([`tick`]).
//!
//! | module | what |
//! |---|---|
//! | [`tick`] | [`TickInput`], [`TickOutput`], [`Status`], [`JointCommand`], [`OperatorCommand`], [`ControlState`] |
//! | [`controller`] | the [`Controller`]: state machine and tick; its Walk evaluation and joint commands |
//! | `gait_table` | the gait in fixed arrays: Bézier outputs, stance relabeling, feed-forward |
//! | `orbit` | the within-step orbit lever: the planned momentum about the stance foot σ*(τ), the torso lean that pulls σ back onto it |
//! | `speed` | treadmill speed control: the gait library by speed, interpolated at impact; the step-to-step regulator and the belt-position loop |
//! | `transitions` | ramp, launch, start blend, braking step; minimum-jerk blends |
//! | `orbit_table` | the planned orbit's stance-leg angular momentum σ*(θ) (zero dynamics), for the launch's hand-over |
//! | `recovery` | the stall relaunch: a Walk step stalled on both feet launches again from double support; the step-back catch |
//! | `pendulum` | the step-back catch's inverted pendulum in double support |
//! | `double_support` | kinematics with both feet down: torso pose, inverse kinematics |

pub mod controller;
mod double_support;
mod gait_table;
mod orbit;
mod orbit_table;
mod pendulum;
mod recovery;
mod speed;
pub mod tick;
mod transitions;

pub use controller::Controller;
pub use tick::{
    CommandMode, ControlState, JointCommand, OperatorCommand, SpeedStatus, Status, TickInput,
    TickOutput,
};
