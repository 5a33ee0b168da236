//! The moves between the controller's states: the ramp to the first pose, the launch of a walk
//! from Stand, the first step's blend into the gait, and the braking step of a Stop (its
//! touchdown pose by inverse kinematics); minimum-jerk blends.

use super::double_support::{Geometry, TorsoPose};
use super::gait_table::{side_index, GaitTable};
use super::orbit_table::OrbitTable;
use crate::slots::{LEG_SLOTS, OUTPUTS, SLOTS};

/// The torso pose of the gait's first pose relative to its stance foot (the planned pitch;
/// level if the gait has no initial state), and where the other foot is.
pub(super) fn first_pose_torso(
    geometry: &Geometry,
    gait: &GaitTable,
) -> Option<(TorsoPose, [f64; 2])> {
    let stance = gait.first_stance;
    let mut leg_q = [0.0; LEG_SLOTS];
    for i in 0..OUTPUTS {
        leg_q[gait.out_slot[side_index(stance)][i]] = gait.eval(i, 0.0).0;
    }
    let pitch = gait.initial_pitch.map_or(0.0, |p| p.0);
    let m = geometry.measure(stance, pitch, 0.0, &leg_q, &[0.0; LEG_SLOTS])?;
    Some((m.pose, m.other_foot_xz_m))
}

/// The braking step's touchdown pose for a step of `length_m`: both feet down, the torso at the
/// gait's first-pose pitch and at the same fraction of the way between the feet, lowered so the
/// torso stays as far from the feet as there. `None` if the legs cannot reach it.
pub(super) fn braking_touchdown(
    geometry: &Geometry,
    gait: &GaitTable,
    length_m: f64,
) -> Option<Lunge> {
    let (stand, other) = first_pose_torso(geometry, gait)?;
    if !(length_m.is_finite() && length_m > 0.0) || other[0].abs() < 1e-3 {
        return None;
    }
    let front = gait.first_stance;
    let rear = front.other();
    let fraction = stand[0] / other[0];
    let half = 0.5 * other[0];
    let z2 = stand[1] * stand[1] + half * half - 0.25 * length_m * length_m;
    if z2 <= 0.0 {
        return None;
    }
    let pose = [-fraction * length_m, z2.sqrt(), stand[2]];
    let mut warm = [0.0; LEG_SLOTS];
    for i in 0..OUTPUTS {
        warm[gait.out_slot[side_index(front)][i]] = gait.eval(i, 0.0).0;
    }
    let (leg_q, _) = geometry.solve(front, pose, [0.0; 3], [-length_m, 0.0], &warm)?;
    let mut dy_end = [0.0; OUTPUTS];
    for (i, d) in dy_end.iter_mut().enumerate() {
        *d = leg_q[gait.out_slot[side_index(rear)][i]] - gait.eval(i, 1.0).0;
    }
    let theta_rad = geometry.stance_leg_angle(rear, pose, &leg_q)?;
    Some(Lunge { dy_end, theta_rad })
}

/// Minimum-jerk blend `s(u) = 10u³ − 15u⁴ + 6u⁵` and its derivative ds/du (peak 1.875).
pub(super) fn min_jerk(u: f64) -> (f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let u2 = u * u;
    (
        u2 * u * (10.0 - 15.0 * u + 6.0 * u2),
        30.0 * u2 * (1.0 - 2.0 * u + u2),
    )
}

/// A minimum-jerk blend weight over phase: 0 at `from`, 1 at `from + span`, at phase `s`; and
/// its time derivative at phase rate `rate` (0 outside the ramp, or outside the step).
pub(super) fn blend_weight(s: f64, from: f64, span: f64, inside: bool, rate: f64) -> (f64, f64) {
    let u = (s - from) / span;
    let (b, db_du) = min_jerk(u);
    let db = if inside && u > 0.0 && u < 1.0 {
        db_du / span * rate
    } else {
        0.0
    };
    (b, db)
}

/// How well the planned initial pitch is known when walking starts from the planned state, rad.
pub(super) const PLANNED_PITCH_SIGMA_RAD: f64 = 0.002;

/// The braking step follows the gait up to this phase, then blends into its touchdown pose.
pub(super) const BRAKE_BLEND_FROM: f64 = 0.3;

/// A launch carries the torso to this far behind the stance foot, m: the robot then needs
/// little speed to pass over it (README: the range that walked while tuning).
pub(super) const LAUNCH_BEHIND_M: f64 = 0.04;
/// ... arriving at this forward speed after a Stop, m/s (after Ramp: the orbit's, `orbit_table`).
pub(super) const LAUNCH_SPEED_MPS: f64 = 0.2;
/// ... (or less far forward, if the rear foot would make the torso drop more than this, m) ...
pub(super) const LAUNCH_MAX_DROP_M: f64 = 0.03;
/// ... (and then faster: this margin over the speed that carries an inverted pendulum over the
/// stance foot) ...
pub(super) const LAUNCH_PASS_MARGIN: f64 = 1.3;
/// ... in this long, s.
pub(super) const LAUNCH_DURATION_S: f64 = 1.0;
/// ... with the torso no higher than keeps the rear leg within this fraction of its reach.
pub(super) const LAUNCH_REACH_FRACTION: f64 = 0.995;
/// A launch onto the orbit (from the gait's own stance) hands over as soon as the measured
/// angular momentum about the stance foot reaches the planned orbit's σ*(θ), but not before this
/// far into it, s (the torso overshoots its quintic's end speed by 10-30 %: measured).
pub(super) const LAUNCH_ORBIT_EARLIEST_S: f64 = 0.9;
/// Gains of the launch's torso pose feedback: proportional, and integral (1/s).
pub(super) const LAUNCH_POSE_KP: f64 = 0.9;
pub(super) const LAUNCH_POSE_KI_PER_S: f64 = 3.0;
/// After a launch, the first step's outputs blend into the gait's over this much phase...
pub(super) const START_BLEND_SPAN: f64 = 0.3;
/// ... and the swing knee's over this much.
pub(super) const START_KNEE_BLEND_SPAN: f64 = 0.2;
/// A launch's end pose further than this from the gait's (largest output offset, rad) blends
/// over proportionally more phase: after a Stop the launch starts from the braking step's wide
/// stance and ends with the stance knee ~0.6 rad more bent than the gait's (the torso lowered to
/// keep the rear foot in reach); blended out over 0.3 of phase, raising the torso asked the
/// stance knee for −33.5 N·m against its 33 N·m limit (measured, `runtime/tests/restart_sim.rs`).
pub(super) const START_BLEND_OFFSET_RAD: f64 = 0.2;
/// ... but the blend ends by this phase, before the touchdown.
pub(super) const START_BLEND_END_PHASE: f64 = 0.9;

/// Stand starts this long after the braking step's touchdown, s: the motor replies then
/// report the post-impact pose.
pub(super) const STAND_DELAY_S: f64 = 0.005;

/// Peak of ds/du of [`min_jerk`].
pub(super) const MIN_JERK_PEAK_RATE: f64 = 1.875;

/// How a launch runs: the quintic's duration, the earliest hand-over onto the orbit, and
/// whether it starts from the measured torso rate (a relaunch after a stall) or from rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct LaunchTiming {
    pub(super) duration_s: f64,
    pub(super) earliest_s: f64,
    pub(super) from_motion: bool,
}

/// Walk from Stand: [`LAUNCH_DURATION_S`], [`LAUNCH_ORBIT_EARLIEST_S`], from rest.
pub(super) const FROM_STAND: LaunchTiming = LaunchTiming {
    duration_s: LAUNCH_DURATION_S,
    earliest_s: LAUNCH_ORBIT_EARLIEST_S,
    from_motion: false,
};

/// The start of a walk from Stand: both feet down, the torso carried forward over the stance
/// foot (a quintic in time, joint targets by inverse kinematics, gravity fed forward), then the
/// rear foot lifts.
#[derive(Clone, Copy, Debug)]
pub(super) struct Launch {
    pub(super) start_t_s: f64,
    /// The quintic's duration and the earliest hand-over onto the orbit ([`FROM_STAND`] from
    /// Stand; a relaunch is quicker).
    pub(super) timing: LaunchTiming,
    pub(super) from: TorsoPose,
    /// The torso's rate at the start (zero from Stand: at rest), m/s, m/s, rad/s.
    pub(super) from_rate: TorsoPose,
    /// The quintic's end pose (a catch: only its pitch; x and height follow the catch).
    pub(super) to: TorsoPose,
    /// Forward torso speed at the launch's end, m/s (a catch: unused, 0).
    pub(super) speed_mps: f64,
    /// The planned orbit's σ*(θ) of the gait walked (`None`: the launch runs its whole time).
    pub(super) orbit: Option<OrbitTable>,
    /// The rear foot relative to the stance foot, m.
    pub(super) other_foot_xz_m: [f64; 2],
    /// The last joint solution (the next tick's Newton start), model rad.
    pub(super) leg_q: [f64; LEG_SLOTS],
    /// Integral of the torso pose error (joint targets aim past the plan by this), and when it
    /// was last updated.
    pub(super) correction: TorsoPose,
    pub(super) last_t_s: f64,
    /// A step-back catch: the torso's x follows its pendulum instead of the quintic.
    pub(super) catch: Option<super::pendulum::Catch>,
}

/// After a launch, the first step's outputs start from the launch's end pose and blend into
/// the gait's: y = y^d(τ) + (1 − b(τ))·offset, b a minimum-jerk ramp from `from_phase`.
#[derive(Clone, Copy, Debug)]
pub(super) struct StartBlend {
    pub(super) from_phase: f64,
    pub(super) offset: [f64; OUTPUTS],
    /// Phase over which the outputs other than the swing knee blend in.
    pub(super) span: f64,
}

impl StartBlend {
    /// A blend from `offset` starting at `from_phase`, over [`START_BLEND_SPAN`] of phase, or
    /// proportionally more for offsets beyond [`START_BLEND_OFFSET_RAD`] (at most until
    /// [`START_BLEND_END_PHASE`]).
    pub(super) fn new(from_phase: f64, offset: [f64; OUTPUTS]) -> Self {
        let largest = offset.iter().fold(0.0_f64, |m, o| m.max(o.abs()));
        let wanted = START_BLEND_SPAN * (largest / START_BLEND_OFFSET_RAD).max(1.0);
        let room = (START_BLEND_END_PHASE - from_phase).max(START_BLEND_SPAN);
        Self {
            from_phase,
            offset,
            span: wanted.min(room),
        }
    }
}

/// The braking step of a Stop: a longer step whose touchdown leaves the walking speed inside
/// what double support can absorb (see [`braking_touchdown`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Lunge {
    /// Offset of the outputs (stance hip, stance knee, swing hip, swing knee) at its touchdown
    /// from the gait's touchdown pose y^d(1), rad.
    pub(super) dy_end: [f64; OUTPUTS],
    /// Stance-leg angle at its touchdown, rad (replaces θ⁻ for the phase).
    pub(super) theta_rad: f64,
}

#[derive(Clone, Copy, Debug)]
pub(super) struct Ramp {
    pub(super) start_t_s: f64,
    pub(super) duration_s: f64,
    pub(super) from: [f64; SLOTS],
    pub(super) to: [f64; SLOTS],
}
