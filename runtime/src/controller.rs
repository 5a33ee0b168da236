//! The controller: pure, sans-IO logic of one control tick.
//!
//! ```text
//! TickInput { t_s, motor samples[14], IMU sample?, operator command?, overrun streak }
//!   │  motor → model angles (direction, offset)        IMU → PitchEstimator (θ̂, θ̂̇, b̂)
//!   ▼
//! operator command → state machine (Idle → Ramp → Stand → Walk → Stop → Stand … Damping)
//!   ▼
//! SafetyMonitor::check ── trip? ──▶ Damping (latched, reason in Status::trip)
//!   ▼
//! Walk/Stop: q = [0, 0, θ̂, legs…] → θ(q), θ̇ (model::phase) → τ, τ̇ → y^d(τ), ẏ^d = y^d'(τ)·τ̇
//!            swing-foot height + τ ≥ τ_switch, debounced → stance switch (relabel outputs)
//! Ramp: minimum-jerk move from the measured pose to y^d(0); Stand: hold y^d(0)
//! Walk from Stand: 1 s launch in double support, then the first step blends into y^d(τ)
//! Stop: the step under way ends; one braking step (θ⁻ → θ_brake, outputs blended into its
//!       landing pose); 5 ms after its touchdown, Stand holds the landed joint angles
//!   ▼
//! TickOutput { commands[14] (PD or damping, motor side), status }
//! ```
//! `tick` never allocates, locks, sleeps or reads a clock: time is `TickInput::t_s`.
//!
//! Motor slots: 0..4 are the leg joints (left hip, left knee, right hip, right knee); 4..14 the
//! held joints of the config, in order. Slots without a motor (fewer held joints, or held
//! motors absent in simulation) have `present == false` in the [`SlotLayout`].
//!
//! # Walk from Stand: a launch
//! At rest in double support the state-based phase has no momentum to run on. On Walk the
//! controller first carries the torso forward with both feet down (1 s: a quintic from rest
//! to 4 cm behind the stance foot, arriving at 0.2 m/s;
//! joint targets by `double_support` inverse kinematics, gravity fed forward, PI feedback on
//! the measured torso pose), then lifts the rear foot: the first step starts at the measured
//! phase, its outputs blending (minimum jerk) from the launch's end pose into y^d(τ). From
//! there the gait's stable orbit takes over (`runtime/tests/stand_sim.rs`).
//!
//! # Stop: why a braking step
//! The gait lands each step with the torso moving at ~0.40 m/s. With point feet, double support
//! can only bring the robot to rest if its capture point `x + ẋ/ω` (ω = √(g/h)) lies between the
//! feet; over a 0.15 m step it lies about 3 cm beyond the front foot, so holding any pose after
//! a normal step vaults the robot over it (measured). The braking step lands the front foot
//! `walk.stop_step_length_m` (0.30 m) ahead instead: the step's stance-leg angle runs on to the
//! braking pose's θ (so τ still ends at 1) and, from τ = 0.3, the outputs blend (minimum jerk)
//! from y^d(τ) into that pose, found by inverse kinematics at start-up
//! (`double_support`: both feet down, the torso where the gait's first pose has it relative to
//! the feet, lowered to keep the legs' reach). The longer landing loses more speed in the
//! impact and leaves the capture point inside the feet; Stand then holds the landed joint
//! angles and the robot rocks from foot to foot a few times and comes to rest
//! (`runtime/tests/stop_sim.rs`).

use crate::config::{PhaseSource, RuntimeConfig, LEG_JOINT_NAMES};
use crate::double_support::{self, Geometry, TorsoPose};
use crate::estimator::{EstimatorParams, PitchEstimator};
use crate::io::ImuSample;
use crate::safety::{SafetyInput, SafetyMonitor, Trip};
use crate::{Result, RuntimeError};
use model::bezier::{self, MAX_BEZIER_DEGREE};
use model::gait::{GaitFile, PhaseDefinition, MAX_FEEDFORWARD_SAMPLES};
use model::robot::{Legs, MAX_DOF};
use model::{PlanarModel, Side};

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

/// Operator requests, delivered through [`crate::operator`] without blocking the tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OperatorCommand {
    /// Idle → Ramp (to the gait's first pose, then Stand).
    Start,
    /// Stand → Walk.
    Walk,
    /// Walk → Stop: finish the step, take the braking step, then Stand.
    Stop,
    /// Any → Damping, orderly (no trip).
    Damp,
    /// Damping → Idle, clearing a latched trip.
    Reset,
    /// Any → Damping with [`Trip::EStop`].
    EStop,
}

impl OperatorCommand {
    /// Every command, in declaration order.
    pub const ALL: [OperatorCommand; 6] = [
        OperatorCommand::Start,
        OperatorCommand::Walk,
        OperatorCommand::Stop,
        OperatorCommand::Damp,
        OperatorCommand::Reset,
        OperatorCommand::EStop,
    ];

    /// Name for logs (`start`, `walk`, `stop`, `damp`, `reset`, `estop`).
    pub fn name(self) -> &'static str {
        match self {
            OperatorCommand::Start => "start",
            OperatorCommand::Walk => "walk",
            OperatorCommand::Stop => "stop",
            OperatorCommand::Damp => "damp",
            OperatorCommand::Reset => "reset",
            OperatorCommand::EStop => "estop",
        }
    }

    /// The command of a [`OperatorCommand::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// State of the controller's state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum ControlState {
    /// Motors damped, waiting for `Start`.
    Idle = 0,
    /// Moving smoothly to the gait's first pose.
    Ramp = 1,
    /// Holding the first pose.
    Stand = 2,
    /// Walking the gait.
    Walk = 3,
    /// Walking until the current step ends, then one braking step, then Stand.
    Stop = 4,
    /// Every motor damped; latched until `Reset`.
    Damping = 5,
}

impl ControlState {
    /// Name for logs.
    pub fn name(self) -> &'static str {
        match self {
            ControlState::Idle => "idle",
            ControlState::Ramp => "ramp",
            ControlState::Stand => "stand",
            ControlState::Walk => "walk",
            ControlState::Stop => "stop",
            ControlState::Damping => "damping",
        }
    }

    /// Whether the motors are position-controlled (and the safety monitor armed).
    pub fn is_driven(self) -> bool {
        matches!(
            self,
            ControlState::Ramp | ControlState::Stand | ControlState::Walk | ControlState::Stop
        )
    }
}

/// How a motor is commanded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandMode {
    /// `τ = −kd·dq`.
    Damping,
    /// `τ = kp(q* − q) + kd(dq* − dq) + τ_ff`.
    Pd,
}

/// One motor command (motor-side units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointCommand {
    /// Mode.
    pub mode: CommandMode,
    /// Desired position, rad.
    pub q_des_rad: f64,
    /// Desired velocity, rad/s.
    pub dq_des_rad_s: f64,
    /// Stiffness, N·m/rad.
    pub kp_nm_per_rad: f64,
    /// Damping, N·m·s/rad.
    pub kd_nm_s_per_rad: f64,
    /// Feed-forward torque, N·m.
    pub tau_ff_nm: f64,
}

impl JointCommand {
    /// Damping with gain `kd`.
    pub const fn damping(kd_nm_s_per_rad: f64) -> Self {
        Self {
            mode: CommandMode::Damping,
            q_des_rad: 0.0,
            dq_des_rad_s: 0.0,
            kp_nm_per_rad: 0.0,
            kd_nm_s_per_rad,
            tau_ff_nm: 0.0,
        }
    }

    /// The torque this command asks for at the measured state, N·m (for telemetry).
    pub fn torque_at(&self, q_rad: f64, dq_rad_s: f64) -> f64 {
        match self.mode {
            CommandMode::Damping => -self.kd_nm_s_per_rad * dq_rad_s,
            CommandMode::Pd => {
                self.kp_nm_per_rad * (self.q_des_rad - q_rad)
                    + self.kd_nm_s_per_rad * (self.dq_des_rad_s - dq_rad_s)
                    + self.tau_ff_nm
            }
        }
    }
}

/// Everything the controller reads in one tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickInput {
    /// Controller time, s.
    pub t_s: f64,
    /// Motor samples by slot.
    pub motors: [MotorSample; SLOTS],
    /// IMU sample that arrived this tick.
    pub imu: Option<ImuSample>,
    /// Operator command that arrived this tick.
    pub operator: Option<OperatorCommand>,
    /// Consecutive deadline overruns of the loop.
    pub overrun_streak: u32,
}

impl Default for TickInput {
    fn default() -> Self {
        Self {
            t_s: 0.0,
            motors: [MotorSample::default(); SLOTS],
            imu: None,
            operator: None,
            overrun_streak: 0,
        }
    }
}

/// What the controller did this tick, for telemetry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    /// State after this tick.
    pub state: ControlState,
    /// A transition that happened this tick (from, to).
    pub transition: Option<(ControlState, ControlState)>,
    /// Stance leg.
    pub stance: Side,
    /// Completed steps since Walk began.
    pub steps: u32,
    /// Phase τ (unclamped).
    pub phase: f64,
    /// τ̇, 1/s.
    pub phase_rate_per_s: f64,
    /// Desired outputs y^d (stance hip, stance knee, swing hip, swing knee), rad.
    pub y_des_rad: [f64; OUTPUTS],
    /// ẏ^d, rad/s.
    pub dy_des_rad_s: [f64; OUTPUTS],
    /// Actual outputs y^a, rad.
    pub y_act_rad: [f64; OUTPUTS],
    /// Swing foot height above the stance foot, m.
    pub swing_foot_height_m: f64,
    /// Estimated torso pitch, rad.
    pub pitch_rad: f64,
    /// Bias-corrected pitch rate, rad/s.
    pub pitch_rate_rad_s: f64,
    /// Gyro bias estimate, rad/s.
    pub gyro_bias_rad_s: f64,
    /// Latched safety trip.
    pub trip: Option<Trip>,
    /// The trip happened this tick.
    pub new_trip: bool,
    /// Model-side leg joint angles, rad.
    pub leg_q_rad: [f64; LEG_SLOTS],
}

/// Everything the controller writes in one tick.
#[derive(Clone, Copy, Debug)]
pub struct TickOutput {
    /// Commands by slot (ignored for slots that are not present).
    pub commands: [JointCommand; SLOTS],
    /// Status for telemetry.
    pub status: Status,
}

impl Default for TickOutput {
    fn default() -> Self {
        Self {
            commands: [JointCommand::damping(0.0); SLOTS],
            status: Status {
                state: ControlState::Idle,
                transition: None,
                stance: Side::Left,
                steps: 0,
                phase: 0.0,
                phase_rate_per_s: 0.0,
                y_des_rad: [0.0; OUTPUTS],
                dy_des_rad_s: [0.0; OUTPUTS],
                y_act_rad: [0.0; OUTPUTS],
                swing_foot_height_m: 0.0,
                pitch_rad: 0.0,
                pitch_rate_rad_s: 0.0,
                gyro_bias_rad_s: 0.0,
                trip: None,
                new_trip: false,
                leg_q_rad: [0.0; LEG_SLOTS],
            },
        }
    }
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
    /// The layout of a config; `with_held` = whether the held motors are driven.
    pub fn new(config: &RuntimeConfig, with_held: bool) -> Self {
        let mut l = Self {
            present: [false; SLOTS],
            direction: [1.0; LEG_SLOTS],
            offset_rad: [0.0; LEG_SLOTS],
            held_center_rad: [0.0; SLOTS],
            held_tolerance_rad: [0.0; SLOTS],
            held_kp: [0.0; SLOTS],
            held_kd: [0.0; SLOTS],
        };
        for (k, m) in config.leg_motors.iter().enumerate() {
            l.present[k] = true;
            l.direction[k] = m.direction;
            l.offset_rad[k] = m.offset_rad;
        }
        for (i, h) in config.held.iter().enumerate().take(MAX_HELD) {
            let s = LEG_SLOTS + i;
            l.present[s] = with_held;
            l.held_center_rad[s] = h.position_rad;
            l.held_tolerance_rad[s] = h.tolerance_rad;
            l.held_kp[s] = h.kp_nm_per_rad;
            l.held_kd[s] = h.kd_nm_s_per_rad;
        }
        l
    }

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

/// The gait as the controller evaluates it: fixed arrays, no heap.
#[derive(Clone, Copy, Debug)]
struct GaitTable {
    alpha: [[f64; MAX_BEZIER_DEGREE + 1]; OUTPUTS],
    alpha_len: usize,
    /// `out_slot[stance][i]`: the leg slot of output i when `stance` (0 left, 1 right) stands.
    out_slot: [[usize; OUTPUTS]; 2],
    theta_plus_rad: f64,
    theta_minus_rad: f64,
    step_duration_s: f64,
    first_stance: Side,
    /// Planned torso pitch and pitch rate at the start of the step (from `initial_state`).
    initial_pitch: Option<(f64, f64)>,
    /// The gait's feed-forward table: phases and torques per output (first `ff_len` rows).
    ff_phase: [f64; MAX_FEEDFORWARD_SAMPLES],
    ff_torque_nm: [[f64; OUTPUTS]; MAX_FEEDFORWARD_SAMPLES],
    ff_len: usize,
}

fn side_index(s: Side) -> usize {
    match s {
        Side::Left => 0,
        Side::Right => 1,
    }
}

impl GaitTable {
    fn new(gait: &GaitFile, model: &PlanarModel, legs: &Legs) -> Result<Self> {
        if gait.outputs.len() != OUTPUTS {
            return Err(RuntimeError::Gait {
                reason: format!(
                    "{} outputs, the controller drives {OUTPUTS}",
                    gait.outputs.len()
                ),
            });
        }
        let mut out_slot = [[0; OUTPUTS]; 2];
        for stance in [Side::Left, Side::Right] {
            let mut used = [false; LEG_SLOTS];
            for (i, o) in gait.outputs.iter().enumerate() {
                let name = o.joint_name(stance);
                let slot = LEG_JOINT_NAMES
                    .iter()
                    .position(|n| *n == name)
                    .ok_or_else(|| RuntimeError::Gait {
                        reason: format!("output {} drives {name}, not a leg motor", o.name),
                    })?;
                if used[slot] {
                    return Err(RuntimeError::Gait {
                        reason: format!("two outputs drive {name}"),
                    });
                }
                used[slot] = true;
                out_slot[side_index(stance)][i] = slot;
            }
        }
        let (theta_plus_rad, theta_minus_rad) = match gait.phase {
            PhaseDefinition::StateBased {
                theta_plus_rad,
                theta_minus_rad,
            } => (theta_plus_rad, theta_minus_rad),
            // A time-based gait still has a stance-leg angle range; the state-based option
            // needs it, so measure it from the gait's end poses.
            PhaseDefinition::TimeBased => (f64::NAN, f64::NAN),
        };
        let mut alpha = [[0.0; MAX_BEZIER_DEGREE + 1]; OUTPUTS];
        for (i, row) in gait.bezier.alpha.iter().enumerate() {
            alpha[i][..row.len()].copy_from_slice(row);
        }
        let _ = (model, legs);
        let mut ff_phase = [0.0; MAX_FEEDFORWARD_SAMPLES];
        let mut ff_torque_nm = [[0.0; OUTPUTS]; MAX_FEEDFORWARD_SAMPLES];
        let mut ff_len = 0;
        if let Some(ff) = &gait.feedforward {
            // GaitFile::validate bounds the table to MAX_FEEDFORWARD_SAMPLES rows of OUTPUTS.
            for (k, (t, row)) in ff.phase.iter().zip(&ff.torque_nm).enumerate() {
                if k >= MAX_FEEDFORWARD_SAMPLES || row.len() != OUTPUTS {
                    return Err(RuntimeError::Gait {
                        reason: format!("feedforward.torque_nm[{k}] has the wrong shape"),
                    });
                }
                ff_phase[k] = *t;
                ff_torque_nm[k].copy_from_slice(row);
                ff_len = k + 1;
            }
        }
        Ok(Self {
            ff_phase,
            ff_torque_nm,
            ff_len,
            alpha,
            alpha_len: gait.bezier.degree + 1,
            out_slot,
            theta_plus_rad,
            theta_minus_rad,
            step_duration_s: gait.step_duration_s,
            first_stance: gait.stance_leg,
            initial_pitch: gait
                .initial_state
                .as_ref()
                .and_then(|s| Some((*s.q.get(2)?, *s.dq.get(2)?))),
        })
    }

    fn eval(&self, i: usize, s: f64) -> (f64, f64) {
        let a = &self.alpha[i][..self.alpha_len];
        (bezier::eval(a, s), bezier::eval_d1(a, s))
    }

    /// The planned torque of each output at phase `s`, N·m (zeros without a table).
    fn feedforward(&self, s: f64) -> [f64; OUTPUTS] {
        let mut out = [0.0; OUTPUTS];
        let n = self.ff_len;
        model::gait::interpolate(&self.ff_phase[..n], &self.ff_torque_nm[..n], s, &mut out);
        out
    }
}

/// The torso pose of the gait's first pose relative to its stance foot (the planned pitch;
/// level if the gait has no initial state), and where the other foot is.
fn first_pose_torso(geometry: &Geometry, gait: &GaitTable) -> Option<(TorsoPose, [f64; 2])> {
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
fn braking_touchdown(geometry: &Geometry, gait: &GaitTable, length_m: f64) -> Option<Lunge> {
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
fn min_jerk(u: f64) -> (f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let u2 = u * u;
    (
        u2 * u * (10.0 - 15.0 * u + 6.0 * u2),
        30.0 * u2 * (1.0 - 2.0 * u + u2),
    )
}

/// A minimum-jerk blend weight over phase: 0 at `from`, 1 at `from + span`, at phase `s`; and
/// its time derivative at phase rate `rate` (0 outside the ramp, or outside the step).
fn blend_weight(s: f64, from: f64, span: f64, inside: bool, rate: f64) -> (f64, f64) {
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
const PLANNED_PITCH_SIGMA_RAD: f64 = 0.002;

/// The braking step follows the gait up to this phase, then blends into its touchdown pose.
const BRAKE_BLEND_FROM: f64 = 0.3;

/// A launch carries the torso to this far behind the stance foot, m: the robot then needs
/// little speed to pass over it (README: the range that walked while tuning).
const LAUNCH_BEHIND_M: f64 = 0.04;
/// ... arriving at this forward speed, m/s.
const LAUNCH_SPEED_MPS: f64 = 0.2;
/// ... in this long, s.
const LAUNCH_DURATION_S: f64 = 1.0;
/// ... with the torso no higher than keeps the rear leg within this fraction of its reach.
const LAUNCH_REACH_FRACTION: f64 = 0.995;
/// Gains of the launch's torso pose feedback: proportional, and integral (1/s).
const LAUNCH_POSE_KP: f64 = 0.9;
const LAUNCH_POSE_KI_PER_S: f64 = 3.0;
/// After a launch, the first step's outputs blend into the gait's over this much phase...
const START_BLEND_SPAN: f64 = 0.3;
/// ... and the swing knee's over this much.
const START_KNEE_BLEND_SPAN: f64 = 0.2;

/// Stand starts this long after the braking step's touchdown, s: the motor replies then
/// report the post-impact pose.
const STAND_DELAY_S: f64 = 0.005;

/// Peak of ds/du of [`min_jerk`].
const MIN_JERK_PEAK_RATE: f64 = 1.875;

/// The start of a walk from Stand: both feet down, the torso carried forward over the stance
/// foot (a quintic in time, joint targets by inverse kinematics, gravity fed forward), then the
/// rear foot lifts.
#[derive(Clone, Copy, Debug)]
struct Launch {
    start_t_s: f64,
    from: TorsoPose,
    to: TorsoPose,
    /// The rear foot relative to the stance foot, m.
    other_foot_xz_m: [f64; 2],
    /// The last joint solution (the next tick's Newton start), model rad.
    leg_q: [f64; LEG_SLOTS],
    /// Integral of the torso pose error (joint targets aim past the plan by this), and when it
    /// was last updated.
    correction: TorsoPose,
    last_t_s: f64,
}

/// After a launch, the first step's outputs start from the launch's end pose and blend into
/// the gait's: y = y^d(τ) + (1 − b(τ))·offset, b a minimum-jerk ramp from `from_phase`.
#[derive(Clone, Copy, Debug)]
struct StartBlend {
    from_phase: f64,
    offset: [f64; OUTPUTS],
}

/// The braking step of a Stop: a longer step whose touchdown leaves the walking speed inside
/// what double support can absorb (see [`braking_touchdown`]).
#[derive(Clone, Copy, Debug)]
struct Lunge {
    /// Offset of the outputs (stance hip, stance knee, swing hip, swing knee) at its touchdown
    /// from the gait's touchdown pose y^d(1), rad.
    dy_end: [f64; OUTPUTS],
    /// Stance-leg angle at its touchdown, rad (replaces θ⁻ for the phase).
    theta_rad: f64,
}

#[derive(Clone, Copy, Debug)]
struct Ramp {
    start_t_s: f64,
    duration_s: f64,
    from: [f64; SLOTS],
    to: [f64; SLOTS],
}

/// The controller. Build once at start-up ([`Controller::new`]); call [`Controller::tick`]
/// every period.
#[derive(Clone, Debug)]
pub struct Controller {
    model: PlanarModel,
    legs: Legs,
    dof: usize,
    q_template: [f64; MAX_DOF],
    leg_coord: [usize; LEG_SLOTS],
    gait: GaitTable,
    layout: SlotLayout,
    phase_source: PhaseSource,
    kp: [f64; LEG_SLOTS],
    kd: [f64; LEG_SLOTS],
    feedforward_nm: [f64; OUTPUTS],
    plan_feedforward_scale: f64,
    damping_kd: f64,
    ramp_min_duration_s: f64,
    ramp_max_speed_rad_s: f64,
    switch_min_phase: f64,
    touchdown_height_m: f64,
    touchdown_max_descent_mps: f64,
    touchdown_below_m: f64,
    touchdown_impact_accel_mps2: f64,
    impact_min_phase: f64,
    reference_lead_s: f64,
    touchdown_debounce_ticks: u32,
    max_phase_rate_per_s: f64,
    phase_observer_hz: f64,
    estimator: PitchEstimator,
    accel_while_walking: bool,
    touchdown_pitch_sigma_rad: f64,
    safety: SafetyMonitor,
    // Run-time state.
    state: ControlState,
    stance: Side,
    steps: u32,
    step_start_t_s: f64,
    /// A step lasting longer than this trips [`Trip::StepTimeout`], s.
    step_timeout_s: f64,
    touchdown_ticks: u32,
    /// (time, swing-foot height) at the previous walking tick.
    last_foot: Option<(f64, f64)>,
    /// Phase observer state: (τ̂, τ̂̇, time of the last update) once walking.
    phase_hat: Option<(f64, f64, f64)>,
    ramp: Ramp,
    /// Stand after a Stop holds these leg joint angles, model rad (`None`: Stand holds the
    /// gait's first pose, as after Ramp).
    stand_hold: Option<[f64; LEG_SLOTS]>,
    /// When the braking step of a Stop touched down (Stand starts [`STAND_DELAY_S`] later).
    stop_touchdown_t_s: Option<f64>,
    /// The braking step of a Stop: its touchdown pose and stance-leg angle.
    lunge: Lunge,
    /// The current step is the braking step.
    braking: bool,
    /// Walk was asked for in Stand: the launch starts at this tick.
    launch_requested: bool,
    launch: Option<Launch>,
    start_blend: Option<StartBlend>,
    /// Longest hip-to-foot distance the legs reach (thigh + shin), m.
    leg_reach_m: f64,
    trip: Option<Trip>,
    motors: [MotorSample; SLOTS],
    last_imu_t_s: Option<f64>,
}

impl Controller {
    /// A controller for `gait` on `model` with `config`; `with_held` = whether the held
    /// motors are driven (false in simulations without them). Allocates; call at start-up.
    pub fn new(
        config: &RuntimeConfig,
        gait: &GaitFile,
        model: PlanarModel,
        with_held: bool,
    ) -> Result<Self> {
        config.validate("runtime config")?;
        model.check_capacity()?;
        let legs = model.legs()?;
        let dof = model.dof();
        let nominal = model.nominal_pose()?;
        let q = model.with_design(
            &nominal,
            gait.design.thigh_length_m,
            gait.design.shin_length_m,
        )?;
        let mut q_template = [0.0; MAX_DOF];
        q_template[..dof].copy_from_slice(&q);
        q_template[0] = 0.0;
        q_template[1] = 0.0;
        let mut leg_coord = [0; LEG_SLOTS];
        for (k, name) in LEG_JOINT_NAMES.iter().enumerate() {
            leg_coord[k] = model.joints[model.require_joint(name)?].coordinate;
        }
        let gait_table = GaitTable::new(gait, &model, &legs)?;
        if config.walk.phase == PhaseSource::StateBased && !gait_table.theta_plus_rad.is_finite() {
            return Err(RuntimeError::Gait {
                reason: "walk.phase = state_based needs a state-based gait (θ⁺, θ⁻)".into(),
            });
        }
        if config.gains.plan_feedforward_scale > 0.0 && gait_table.ff_len == 0 {
            return Err(RuntimeError::Gait {
                reason: format!(
                    "gains.plan_feedforward_scale = {} but the gait file has no feedforward \
                     table: re-plan it with `adam plan`, or set the scale to 0 (PD only)",
                    config.gains.plan_feedforward_scale
                ),
            });
        }
        let geometry = Geometry {
            model: &model,
            legs: &legs,
            dof,
            q_template: &q_template,
            leg_coord: &leg_coord,
        };
        let stop_step_m = config.walk.stop_step_length_m;
        let lunge = braking_touchdown(&geometry, &gait_table, stop_step_m).ok_or_else(|| {
            RuntimeError::InvalidField {
                origin: "runtime config".into(),
                field: "walk.stop_step_length_m".into(),
                value: stop_step_m.to_string(),
                reason: format!(
                    "the braking step's touchdown pose is out of the legs' reach \
                         (thigh {:.3} m, shin {:.3} m)",
                    gait.design.thigh_length_m, gait.design.shin_length_m
                ),
            }
        })?;
        let layout = SlotLayout::new(config, with_held);
        let zero_ramp = Ramp {
            start_t_s: 0.0,
            duration_s: 0.0,
            from: [0.0; SLOTS],
            to: [0.0; SLOTS],
        };
        Ok(Self {
            legs,
            dof,
            q_template,
            leg_coord,
            gait: gait_table,
            layout,
            phase_source: config.walk.phase,
            kp: config.gains.kp_nm_per_rad,
            kd: config.gains.kd_nm_s_per_rad,
            feedforward_nm: config.gains.walk_feedforward_nm,
            plan_feedforward_scale: config.gains.plan_feedforward_scale,
            damping_kd: config.gains.damping_kd_nm_s_per_rad,
            ramp_min_duration_s: config.ramp.min_duration_s,
            ramp_max_speed_rad_s: config.ramp.max_speed_rad_s,
            switch_min_phase: config.walk.switch_min_phase,
            touchdown_height_m: config.walk.touchdown_height_m,
            touchdown_max_descent_mps: config.walk.touchdown_max_descent_mps,
            touchdown_below_m: config.walk.touchdown_below_m,
            touchdown_impact_accel_mps2: config.walk.touchdown_impact_accel_mps2,
            impact_min_phase: config.walk.impact_min_phase,
            reference_lead_s: config.walk.reference_lead_s,
            touchdown_debounce_ticks: config.walk.touchdown_debounce_ticks,
            max_phase_rate_per_s: config.walk.max_phase_rate_per_s,
            phase_observer_hz: config.walk.phase_observer_hz,
            estimator: PitchEstimator::new(EstimatorParams::from(&config.estimator)),
            accel_while_walking: config.estimator.accel_while_walking,
            touchdown_pitch_sigma_rad: config.estimator.touchdown_pitch_sigma_rad,
            safety: SafetyMonitor::new(
                config.safety.clone(),
                config.loop_.max_overrun_streak,
                layout,
            ),
            state: ControlState::Idle,
            stance: gait.stance_leg,
            steps: 0,
            step_start_t_s: 0.0,
            step_timeout_s: config.safety.max_step_duration_factor * gait.step_duration_s,
            touchdown_ticks: 0,
            last_foot: None,
            phase_hat: None,
            ramp: zero_ramp,
            stand_hold: None,
            stop_touchdown_t_s: None,
            lunge,
            braking: false,
            launch_requested: false,
            launch: None,
            start_blend: None,
            leg_reach_m: gait.design.thigh_length_m + gait.design.shin_length_m,
            trip: None,
            motors: [MotorSample::default(); SLOTS],
            last_imu_t_s: None,
            model,
        })
    }

    /// Current state.
    pub fn state(&self) -> ControlState {
        self.state
    }

    /// Slot layout.
    pub fn layout(&self) -> &SlotLayout {
        &self.layout
    }

    /// Current stance leg.
    pub fn stance(&self) -> Side {
        self.stance
    }

    /// The latched trip, if any.
    pub fn trip(&self) -> Option<Trip> {
        self.trip
    }

    /// Enter Walk at `t_s` with the gait's first stance leg, as if the previous step had just
    /// ended: for a backend that starts in the gait's planned post-impact state (a simulator set
    /// to the gait file's `initial_state`), where Ramp and Stand would have no meaning. The pitch
    /// estimator starts from the planned pitch: mid-step, the accelerometer does not see gravity
    /// alone. Only from Idle with no latched trip; returns whether Walk was entered.
    pub fn begin_walk_at_step_start(&mut self, t_s: f64, status: &mut Status) -> bool {
        if self.state != ControlState::Idle || self.trip.is_some() {
            return false;
        }
        if let Some((pitch_rad, rate_rad_s)) = self.gait.initial_pitch {
            self.estimator
                .initialize(pitch_rad, rate_rad_s, PLANNED_PITCH_SIGMA_RAD);
        }
        self.stance = self.gait.first_stance;
        self.step_start_t_s = t_s;
        self.touchdown_ticks = 0;
        self.last_foot = None;
        self.phase_hat = None;
        self.steps = 0;
        self.enter(ControlState::Walk, status);
        true
    }

    /// The gait's first pose by slot (motor side for every slot), as Ramp targets it.
    pub fn first_pose(&self) -> [f64; SLOTS] {
        self.stand_pose(self.gait.first_stance)
    }

    fn stand_pose(&self, stance: Side) -> [f64; SLOTS] {
        let mut pose = self.layout.held_center_rad;
        for i in 0..OUTPUTS {
            let slot = self.gait.out_slot[side_index(stance)][i];
            let (y, _) = self.gait.eval(i, 0.0);
            pose[slot] = self.to_motor(slot, y);
        }
        pose
    }

    fn to_motor(&self, slot: usize, model_rad: f64) -> f64 {
        self.layout.motor_rad(slot, model_rad)
    }

    fn to_model(&self, slot: usize, motor_rad: f64) -> f64 {
        self.layout.model_rad(slot, motor_rad)
    }

    fn enter(&mut self, to: ControlState, status: &mut Status) {
        if to != self.state {
            status.transition = Some((self.state, to));
            self.state = to;
        }
    }

    fn begin_ramp(&mut self, t_s: f64) {
        let to = self.stand_pose(self.stance);
        let mut from = to;
        let mut largest = 0.0_f64;
        for slot in 0..SLOTS {
            if self.layout.present[slot] {
                from[slot] = self.motors[slot].q_rad;
                largest = largest.max((to[slot] - from[slot]).abs());
            }
        }
        // Minimum-jerk peak speed is 1.875·Δq/T: lengthen T to respect the speed limit.
        let duration_s = self
            .ramp_min_duration_s
            .max(MIN_JERK_PEAK_RATE * largest / self.ramp_max_speed_rad_s);
        self.ramp = Ramp {
            start_t_s: t_s,
            duration_s,
            from,
            to,
        };
    }

    fn handle_operator(&mut self, cmd: OperatorCommand, t_s: f64, status: &mut Status) {
        use ControlState as S;
        match (cmd, self.state) {
            (OperatorCommand::EStop, _) => {
                if self.trip.is_none() {
                    self.trip = Some(Trip::EStop);
                    status.new_trip = true;
                }
                self.enter(S::Damping, status);
            }
            (OperatorCommand::Damp, _) => self.enter(S::Damping, status),
            (OperatorCommand::Start, S::Idle) => {
                self.stance = self.gait.first_stance;
                self.stand_hold = None;
                self.begin_ramp(t_s);
                self.enter(S::Ramp, status);
            }
            (OperatorCommand::Walk, S::Stand) => {
                self.step_start_t_s = t_s;
                self.touchdown_ticks = 0;
                self.steps = 0;
                self.launch_requested = true;
                self.enter(S::Walk, status);
            }
            (OperatorCommand::Stop, S::Walk) => {
                self.stop_touchdown_t_s = None;
                self.braking = false;
                self.enter(S::Stop, status);
            }
            (OperatorCommand::Reset, S::Damping) => {
                self.trip = None;
                self.safety.reset_counters();
                self.enter(S::Idle, status);
            }
            _ => {} // not meaningful in this state: ignored
        }
    }

    /// One control tick. Never allocates, locks, sleeps or reads a clock.
    pub fn tick(&mut self, input: &TickInput, out: &mut TickOutput) {
        let t = input.t_s;
        let status = &mut out.status;
        status.transition = None;
        status.new_trip = false;
        // Motors: keep the last known values of silent ones.
        for slot in 0..SLOTS {
            let m = input.motors[slot];
            if m.fresh {
                self.motors[slot] = m;
            } else {
                self.motors[slot].fresh = false;
            }
        }
        let mut leg_q = [0.0; LEG_SLOTS];
        let mut leg_dq = [0.0; LEG_SLOTS];
        for k in 0..LEG_SLOTS {
            leg_q[k] = self.to_model(k, self.motors[k].q_rad);
            leg_dq[k] = self.layout.direction[k] * self.motors[k].dq_rad_s;
        }
        // Estimator.
        // An implausible sample (a glitch; safety counts them) is not integrated.
        if let Some(imu) = input.imu.as_ref().filter(|i| self.safety.gyro_plausible(i)) {
            let dt = self.last_imu_t_s.map_or(0.0, |t0| imu.t_s - t0);
            let walking = matches!(self.state, ControlState::Walk | ControlState::Stop);
            self.estimator.update_with(
                imu.gyro_pitch_rad_s,
                imu.accel_x_mps2,
                imu.accel_z_mps2,
                dt,
                !walking || self.accel_while_walking,
            );
            self.last_imu_t_s = Some(imu.t_s);
        }
        // Operator, then safety (a trip overrides any request).
        if let Some(cmd) = input.operator {
            self.handle_operator(cmd, t, status);
        }
        let safety_in = SafetyInput {
            t_s: t,
            motors: &self.motors,
            leg_q_rad: &leg_q,
            imu: input.imu.as_ref(),
            pitch_rad: self.estimator.pitch_rad(),
            overrun_streak: input.overrun_streak,
        };
        if let Some(trip) = self.safety.check(&safety_in, self.state.is_driven()) {
            if self.trip.is_none() {
                self.trip = Some(trip);
                status.new_trip = true;
            }
            self.enter(ControlState::Damping, status);
        }
        // A stalled walk: the step has lasted several times the gait's.
        if matches!(self.state, ControlState::Walk | ControlState::Stop) {
            let elapsed_s = t - self.step_start_t_s;
            if elapsed_s > self.step_timeout_s {
                if self.trip.is_none() {
                    self.trip = Some(Trip::StepTimeout {
                        elapsed_s,
                        limit_s: self.step_timeout_s,
                    });
                    status.new_trip = true;
                }
                self.enter(ControlState::Damping, status);
            }
        }
        if self.state == ControlState::Ramp && t - self.ramp.start_t_s >= self.ramp.duration_s {
            self.enter(ControlState::Stand, status);
        }

        // Commands.
        let mut y_des = [0.0; OUTPUTS];
        let mut dy_des = [0.0; OUTPUTS];
        let (mut phase, mut phase_rate, mut foot_h) = (0.0, 0.0, f64::NAN);
        match self.state {
            ControlState::Idle | ControlState::Damping => {
                out.commands = [JointCommand::damping(self.damping_kd); SLOTS];
            }
            ControlState::Ramp => {
                let r = self.ramp;
                let u = if r.duration_s > 0.0 {
                    (t - r.start_t_s) / r.duration_s
                } else {
                    1.0
                };
                let (s, ds_du) = min_jerk(u);
                let du_dt = if r.duration_s > 0.0 {
                    1.0 / r.duration_s
                } else {
                    0.0
                };
                for slot in 0..SLOTS {
                    let dq = r.to[slot] - r.from[slot];
                    out.commands[slot] =
                        self.pd(slot, r.from[slot] + s * dq, dq * ds_du * du_dt, 0.0);
                }
            }
            ControlState::Stand => self.stand_commands(&mut out.commands),
            ControlState::Walk if self.launch_requested || self.launch.is_some() => {
                if self.launch_requested {
                    self.launch_requested = false;
                    self.begin_launch(t, &leg_q, &leg_dq);
                }
                if self
                    .launch
                    .is_some_and(|l| t - l.start_t_s < LAUNCH_DURATION_S)
                {
                    self.launch_commands(t, &leg_q, &leg_dq, &mut out.commands);
                    // The phase is reported (the stance-leg angle), not yet used.
                    let eval = self.walk_references(t, &leg_q, &leg_dq);
                    (phase, phase_rate, foot_h) = (eval.phase, eval.phase_rate, eval.foot_height_m);
                } else {
                    let eval = self.walk_references(t, &leg_q, &leg_dq);
                    let stance = side_index(self.stance);
                    let mut offset = [0.0; OUTPUTS];
                    for (i, o) in offset.iter_mut().enumerate() {
                        *o = leg_q[self.gait.out_slot[stance][i]] - eval.y[i];
                    }
                    self.start_blend = Some(StartBlend {
                        from_phase: eval.phase.clamp(0.0, 1.0),
                        offset,
                    });
                    // The first step starts now (the step timeout and a time-based phase
                    // count from here).
                    self.step_start_t_s = t;
                    self.launch = None;
                    self.last_foot = None;
                    // The same measured phase, now with the blend.
                    let eval = self.references(eval.phase, eval.phase_rate, eval.foot_height_m);
                    (y_des, dy_des) = (eval.y, eval.dy);
                    (phase, phase_rate, foot_h) = (eval.phase, eval.phase_rate, eval.foot_height_m);
                    self.walk_commands(&eval, &mut out.commands);
                }
            }
            ControlState::Walk | ControlState::Stop => {
                let mut eval = self.walk_references(t, &leg_q, &leg_dq);
                self.observe_phase(t, &mut eval);
                // The foot is down once it stops descending near the ground (a kinematic
                // height alone would switch millimetres early, before the impact).
                let descent_mps = match self.last_foot {
                    Some((t0, h0)) if t > t0 => (h0 - eval.foot_height_m) / (t - t0),
                    _ => f64::INFINITY,
                };
                self.last_foot = Some((t, eval.foot_height_m));
                // The impact itself: a spike of the accelerometer (the IMU averages over its
                // sample period, so the impulse shows in one sample).
                let impact = input.imu.as_ref().is_some_and(|imu| {
                    (imu.accel_x_mps2.hypot(imu.accel_z_mps2) - crate::estimator::GRAVITY_MPS2)
                        .abs()
                        >= self.touchdown_impact_accel_mps2
                });
                // The impact spike late in the step, with the swing foot near the ground, is the
                // touchdown, even a little before τ = 1 (the feet are both down only then: the
                // pitch that levels them is measured at this very sample).
                let near = eval.foot_height_m <= self.touchdown_height_m;
                let impact_switch = impact && near && eval.phase >= self.impact_min_phase;
                // Without a spike: τ ≥ τ_switch and the foot stopped descending, or lies below
                // the stance foot (the old stance foot lifting off after the impact), debounced.
                let landed = descent_mps <= self.touchdown_max_descent_mps
                    || eval.foot_height_m <= -self.touchdown_below_m;
                if eval.touchdown && landed {
                    self.touchdown_ticks += 1;
                } else {
                    self.touchdown_ticks = 0;
                }
                if impact_switch || self.touchdown_ticks >= self.touchdown_debounce_ticks {
                    if impact_switch {
                        let pitch = self.touchdown_pitch_rad(&leg_q);
                        self.estimator
                            .measure_pitch(pitch, self.touchdown_pitch_sigma_rad);
                    }
                    // Impact: relabel the legs and start the next step.
                    self.stance = self.stance.other();
                    self.start_blend = None;
                    self.step_start_t_s = t;
                    self.touchdown_ticks = 0;
                    self.last_foot = None;
                    self.steps = self.steps.saturating_add(1);
                    // Stop: the step under way ends, then the braking step, then Stand.
                    if self.state == ControlState::Stop {
                        if self.braking {
                            self.stop_touchdown_t_s = Some(t);
                        }
                        self.braking = !self.braking;
                    }
                    // The new step starts at the measured phase, at the speed of the old one.
                    let rate = self.phase_hat.map_or(0.0, |(_, r, _)| r);
                    eval = self.walk_references(t, &leg_q, &leg_dq);
                    self.phase_hat = Some((eval.phase, rate, t));
                    self.observe_phase(t, &mut eval);
                }
                (y_des, dy_des) = (eval.y, eval.dy);
                (phase, phase_rate, foot_h) = (eval.phase, eval.phase_rate, eval.foot_height_m);
                // The braking step has landed: once the motors report the post-impact pose (the
                // replies lag the impact by a tick), Stand holds it.
                if self.state == ControlState::Stop
                    && self
                        .stop_touchdown_t_s
                        .is_some_and(|t0| t - t0 >= STAND_DELAY_S - 1e-9)
                {
                    self.stand_hold = Some(leg_q);
                    self.enter(ControlState::Stand, status);
                }
                if self.state == ControlState::Stand {
                    self.stand_commands(&mut out.commands);
                } else {
                    self.walk_commands(&eval, &mut out.commands);
                }
            }
        }
        let stance = side_index(self.stance);
        let mut y_act = [0.0; OUTPUTS];
        for (i, y) in y_act.iter_mut().enumerate() {
            *y = leg_q[self.gait.out_slot[stance][i]];
        }
        *status = Status {
            state: self.state,
            transition: status.transition,
            stance: self.stance,
            steps: self.steps,
            phase,
            phase_rate_per_s: phase_rate,
            y_des_rad: y_des,
            dy_des_rad_s: dy_des,
            y_act_rad: y_act,
            swing_foot_height_m: foot_h,
            pitch_rad: self.estimator.pitch_rad(),
            pitch_rate_rad_s: self.estimator.pitch_rate_rad_s(),
            gyro_bias_rad_s: self.estimator.gyro_bias_rad_s(),
            trip: self.trip,
            new_trip: status.new_trip,
            leg_q_rad: leg_q,
        };
    }

    /// Walk and Stop: PD on the desired outputs (relabeled to the stance leg's slots) with the
    /// plan's feed-forward; the held joints at their positions.
    fn walk_commands(&self, eval: &WalkEval, commands: &mut [JointCommand; SLOTS]) {
        let stance = side_index(self.stance);
        for i in 0..OUTPUTS {
            let slot = self.gait.out_slot[stance][i];
            let dir = self.layout.direction[slot];
            let ff = self.feedforward_nm[i] + self.plan_feedforward_scale * eval.feedforward_nm[i];
            commands[slot] = self.pd(
                slot,
                self.to_motor(slot, eval.y[i]),
                dir * eval.dy[i],
                dir * ff,
            );
        }
        self.hold_commands(commands);
    }

    fn hold_commands(&self, commands: &mut [JointCommand; SLOTS]) {
        for (slot, command) in commands.iter_mut().enumerate().skip(LEG_SLOTS) {
            *command = self.pd(slot, self.layout.held_center_rad[slot], 0.0, 0.0);
        }
    }

    /// Stand: after a Stop, the joint angles of the braking step's landing; otherwise the
    /// gait's first pose.
    fn stand_commands(&self, commands: &mut [JointCommand; SLOTS]) {
        match self.stand_hold {
            Some(leg_q) => {
                for (k, &q) in leg_q.iter().enumerate() {
                    commands[k] = self.pd(k, self.to_motor(k, q), 0.0, 0.0);
                }
                self.hold_commands(commands);
            }
            None => {
                let pose = self.stand_pose(self.stance);
                for (slot, &q) in pose.iter().enumerate() {
                    commands[slot] = self.pd(slot, q, 0.0, 0.0);
                }
            }
        }
    }

    /// The kinematics of double support on this robot.
    fn geometry(&self) -> Geometry<'_> {
        Geometry {
            model: &self.model,
            legs: &self.legs,
            dof: self.dof,
            q_template: &self.q_template,
            leg_coord: &self.leg_coord,
        }
    }

    /// Starts a launch from the measured double-support pose at rest: the torso moves forward
    /// to [`LAUNCH_BEHIND_M`] behind the stance foot, no higher than keeps the rear leg within
    /// [`LAUNCH_REACH_FRACTION`] of its reach, arriving at [`LAUNCH_SPEED_MPS`].
    fn begin_launch(&mut self, t_s: f64, leg_q: &[f64; LEG_SLOTS], leg_dq: &[f64; LEG_SLOTS]) {
        let measured = self.geometry().measure(
            self.stance,
            self.estimator.pitch_rad(),
            self.estimator.pitch_rate_rad_s(),
            leg_q,
            leg_dq,
        );
        self.launch = measured.map(|m| {
            let x = -LAUNCH_BEHIND_M;
            let reach = LAUNCH_REACH_FRACTION * self.leg_reach_m;
            let dx = x - m.other_foot_xz_m[0];
            let z = m.pose[1].min((reach * reach - dx * dx).max(0.0).sqrt());
            Launch {
                start_t_s: t_s,
                from: m.pose,
                to: [x, z, m.pose[2]],
                other_foot_xz_m: m.other_foot_xz_m,
                leg_q: *leg_q,
                correction: [0.0; 3],
                last_t_s: t_s,
            }
        });
    }

    /// The launch's joint targets at `t_s`: both feet held, the torso on its quintic (pitch
    /// and height held), gravity fed forward.
    fn launch_commands(
        &mut self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
        commands: &mut [JointCommand; SLOTS],
    ) {
        let Some(mut launch) = self.launch else {
            return;
        };
        let dt = t_s - launch.start_t_s;
        let mut pose = [0.0; 3];
        let mut rate = [0.0; 3];
        let end_rate = [LAUNCH_SPEED_MPS, 0.0, 0.0];
        for k in 0..3 {
            (pose[k], rate[k]) = double_support::quintic(
                launch.from[k],
                0.0,
                launch.to[k],
                end_rate[k],
                LAUNCH_DURATION_S,
                dt,
            );
        }
        let geometry = self.geometry();
        // Pose feedback (PI): the joints' compliance lets the torso sag off its plan (4° of
        // pitch over the launch without it); the joint targets aim past the plan by the
        // error. The proportional gain stays below 1: stable even if the joints followed their
        // targets within a tick.
        let h = (t_s - launch.last_t_s).clamp(0.0, 0.1);
        launch.last_t_s = t_s;
        let pitch = self.estimator.pitch_rad();
        let pitch_rate = self.estimator.pitch_rate_rad_s();
        let mut error = [0.0; 3];
        if let Some(m) = geometry.measure(self.stance, pitch, pitch_rate, leg_q, leg_dq) {
            for k in 0..3 {
                error[k] = pose[k] - m.pose[k];
                launch.correction[k] += LAUNCH_POSE_KI_PER_S * h * error[k];
            }
        }
        let mut pose_cmd = pose;
        for k in 0..3 {
            pose_cmd[k] += launch.correction[k] + error[k] * LAUNCH_POSE_KP;
        }
        let solved = geometry.solve(
            self.stance,
            pose_cmd,
            rate,
            launch.other_foot_xz_m,
            &launch.leg_q,
        );
        // Out of reach (not on a launch within LAUNCH_REACH_FRACTION): hold the last solution.
        let (q_des, dq_des) = solved.unwrap_or((launch.leg_q, [0.0; LEG_SLOTS]));
        let ff = geometry
            .gravity_torques(self.stance, pose, &q_des)
            .unwrap_or([0.0; LEG_SLOTS]);
        launch.leg_q = q_des;
        self.launch = Some(launch);
        for k in 0..LEG_SLOTS {
            let dir = self.layout.direction[k];
            commands[k] = self.pd(k, self.to_motor(k, q_des[k]), dir * dq_des[k], dir * ff[k]);
        }
        self.hold_commands(commands);
    }

    /// PD command for a slot with the slot's gains (leg gains or held gains).
    fn pd(&self, slot: usize, q_des: f64, dq_des: f64, tau_ff: f64) -> JointCommand {
        let (kp, kd) = if slot < LEG_SLOTS {
            (self.kp[slot], self.kd[slot])
        } else {
            (self.layout.held_kp[slot], self.layout.held_kd[slot])
        };
        JointCommand {
            mode: CommandMode::Pd,
            q_des_rad: q_des,
            dq_des_rad_s: dq_des,
            kp_nm_per_rad: kp,
            kd_nm_s_per_rad: kd,
            tau_ff_nm: tau_ff,
        }
    }

    /// The phase observer: replaces the measured τ, τ̇ of `eval` by the observer's estimate
    /// and recomputes the references from it (a no-op when `walk.phase_observer_hz` is 0).
    ///
    /// τ̂̇ = r̂ + 2ω(τ − τ̂), r̂̇ = ω²(τ − τ̂): critically damped at ω = 2π f, so a phase that
    /// grows at a constant rate is tracked without lag, while pitch wobble faster than f is
    /// filtered out of y^d(τ̂) and ẏ^d = y^d'(τ̂) r̂.
    fn observe_phase(&mut self, t_s: f64, eval: &mut WalkEval) {
        if self.phase_observer_hz <= 0.0 || !eval.phase.is_finite() {
            return;
        }
        let w = 2.0 * std::f64::consts::PI * self.phase_observer_hz;
        let (mut tau, mut rate) = match self.phase_hat {
            Some((tau, rate, t0)) => {
                let dt = (t_s - t0).clamp(0.0, 0.1);
                // Semi-implicit Euler, substepped so ω·h stays ≤ 0.2 at any tick rate.
                let n = ((w * dt / 0.2).ceil() as usize).clamp(1, 64);
                let h = dt / n as f64;
                let (mut tau, mut rate) = (tau, rate);
                for _ in 0..n {
                    let e = eval.phase - tau;
                    rate += h * w * w * e;
                    tau += h * (rate + 2.0 * w * e);
                }
                (tau, rate)
            }
            None => (eval.phase, eval.phase_rate),
        };
        rate = rate.clamp(-self.max_phase_rate_per_s, self.max_phase_rate_per_s);
        if !tau.is_finite() || !rate.is_finite() {
            (tau, rate) = (eval.phase, eval.phase_rate);
        }
        self.phase_hat = Some((tau, rate, t_s));
        let measured_touchdown = eval.foot_height_m <= self.touchdown_height_m;
        *eval = self.references(tau, rate, eval.foot_height_m);
        eval.touchdown = tau >= self.switch_min_phase && measured_touchdown;
    }

    /// Height of the swing foot above the stance foot at torso pitch `pitch_rad`, m (NaN if the
    /// kinematics fails, which fixed sizes rule out).
    fn foot_height_at(&self, pitch_rad: f64, leg_q: &[f64; LEG_SLOTS]) -> f64 {
        let mut q = self.q_template;
        q[2] = pitch_rad;
        for k in 0..LEG_SLOTS {
            q[self.leg_coord[k]] = leg_q[k];
        }
        let swing = self.stance.other();
        self.model
            .body_poses(&q[..self.dof])
            .map(|st| {
                self.model
                    .frame_position_in(&st, self.legs.side(swing).foot)[1]
                    - self
                        .model
                        .frame_position_in(&st, self.legs.side(self.stance).foot)[1]
            })
            .unwrap_or(f64::NAN)
    }

    /// The torso pitch at which both feet are at the same height for these joint angles (both
    /// on the flat ground at a touchdown), by Newton from the current estimate, rad (NaN if the
    /// feet are too close together in x for the pitch to be observable).
    fn touchdown_pitch_rad(&self, leg_q: &[f64; LEG_SLOTS]) -> f64 {
        let mut pitch = self.estimator.pitch_rad();
        for _ in 0..3 {
            let h = self.foot_height_at(pitch, leg_q);
            let eps = 1e-6;
            let slope = (self.foot_height_at(pitch + eps, leg_q) - h) / eps;
            // |dh/dθ| is the horizontal distance between the feet: ≥ 5 cm for a real step.
            if slope.abs().partial_cmp(&0.05) != Some(std::cmp::Ordering::Greater) || !h.is_finite()
            {
                return f64::NAN;
            }
            pitch -= h / slope;
        }
        pitch
    }

    /// Desired outputs, their rates and the feed-forward at phase `phase` and rate `rate`.
    fn references(&self, phase: f64, rate: f64, foot_height_m: f64) -> WalkEval {
        let rate = rate.clamp(-self.max_phase_rate_per_s, self.max_phase_rate_per_s);
        // Latency compensation: the command acts a few milliseconds after the sample it was
        // computed from, so the references are taken that much further along the step.
        let s = if phase.is_finite() {
            let ahead = if rate > 0.0 {
                phase + self.reference_lead_s * rate
            } else {
                phase
            };
            ahead.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let inside = (0.0..=1.0).contains(&phase);
        let mut y = [0.0; OUTPUTS];
        let mut dy = [0.0; OUTPUTS];
        for i in 0..OUTPUTS {
            let (v, d) = self.gait.eval(i, s);
            y[i] = v;
            // Outside [0, 1] the reference is held at its end value: no velocity.
            dy[i] = if inside { d * rate } else { 0.0 };
        }
        // The first step after a launch: from the launch's end pose into the gait's outputs.
        if let Some(blend) = self.start_blend {
            for i in 0..OUTPUTS {
                // The swing knee bends sooner (the foot clears the ground), then the rest.
                let span = if i == 3 {
                    START_KNEE_BLEND_SPAN
                } else {
                    START_BLEND_SPAN
                };
                let (b, db) = blend_weight(s, blend.from_phase, span, inside, rate);
                y[i] += (1.0 - b) * blend.offset[i];
                dy[i] -= db * blend.offset[i];
            }
        }
        // The braking step: the gait's outputs, stretched over the longer stance-leg swing,
        // blend into the braking touchdown pose over the second part of the step.
        if self.braking {
            let lunge = &self.lunge;
            let (b, db) = blend_weight(s, BRAKE_BLEND_FROM, 1.0 - BRAKE_BLEND_FROM, inside, rate);
            for i in 0..OUTPUTS {
                y[i] += b * lunge.dy_end[i];
                dy[i] += db * lunge.dy_end[i];
            }
        }
        let touchdown = phase >= self.switch_min_phase && foot_height_m <= self.touchdown_height_m;
        WalkEval {
            feedforward_nm: self.gait.feedforward(s),
            phase,
            phase_rate: rate,
            y,
            dy,
            foot_height_m,
            touchdown,
        }
    }

    /// Phase, desired outputs and the touchdown condition for the current stance leg.
    fn walk_references(
        &self,
        t_s: f64,
        leg_q: &[f64; LEG_SLOTS],
        leg_dq: &[f64; LEG_SLOTS],
    ) -> WalkEval {
        let dof = self.dof;
        let mut q = self.q_template;
        let mut dq = [0.0; MAX_DOF];
        q[2] = self.estimator.pitch_rad();
        dq[2] = self.estimator.pitch_rate_rad_s();
        for k in 0..LEG_SLOTS {
            q[self.leg_coord[k]] = leg_q[k];
            dq[self.leg_coord[k]] = leg_dq[k];
        }
        let swing = self.stance.other();
        // Sizes are fixed at construction, so these calls cannot fail; NaN marks "unknown".
        let foot_height_m = self
            .model
            .body_poses(&q[..dof])
            .map(|st| {
                let zs = self
                    .model
                    .frame_position_in(&st, self.legs.side(swing).foot)[1];
                let zf = self
                    .model
                    .frame_position_in(&st, self.legs.side(self.stance).foot)[1];
                zs - zf
            })
            .unwrap_or(f64::NAN);
        let (phase, rate) = match self.phase_source {
            PhaseSource::StateBased => {
                // The braking step ends at its own, larger stance-leg angle.
                let theta_end = if self.braking {
                    self.lunge.theta_rad
                } else {
                    self.gait.theta_minus_rad
                };
                let span = theta_end - self.gait.theta_plus_rad;
                let (theta, theta_rate) = self
                    .model
                    .stance_leg_angle_rate(&q[..dof], &dq[..dof], &self.legs, self.stance)
                    .unwrap_or((f64::NAN, 0.0));
                (
                    model::phase::state_phase(theta, self.gait.theta_plus_rad, theta_end),
                    theta_rate / span,
                )
            }
            PhaseSource::TimeBased => (
                model::phase::time_phase(t_s - self.step_start_t_s, self.gait.step_duration_s),
                1.0 / self.gait.step_duration_s,
            ),
        };
        self.references(phase, rate, foot_height_m)
    }
}

#[derive(Clone, Copy, Debug)]
struct WalkEval {
    /// The plan's torque per output at this phase, N·m.
    feedforward_nm: [f64; OUTPUTS],
    phase: f64,
    phase_rate: f64,
    y: [f64; OUTPUTS],
    dy: [f64; OUTPUTS],
    foot_height_m: f64,
    touchdown: bool,
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::needless_range_loop)]
mod tests {
    use super::*;
    use crate::estimator::GRAVITY_MPS2;
    use crate::Setup;

    /// A controller whose motors track the previous tick's commands exactly (no dynamics) and
    /// whose IMU reads a constant pitch.
    struct Harness {
        c: Controller,
        input: TickInput,
        out: TickOutput,
        dt_s: f64,
        pitch_rad: f64,
        imu_on: bool,
    }

    impl Harness {
        fn new(phase: PhaseSource) -> Self {
            let mut setup = Setup::shipped().unwrap();
            setup.config.walk.phase = phase;
            let c = setup.controller(false).unwrap();
            let mut input = TickInput::default();
            for m in input.motors.iter_mut().take(LEG_SLOTS) {
                *m = MotorSample {
                    fresh: true,
                    temperature_c: 30.0,
                    ..MotorSample::default()
                };
            }
            // The planned torso pitch at the start of the step.
            let pitch_rad = setup.gait.initial_state.as_ref().map_or(0.0, |s| s.q[2]);
            Self {
                c,
                input,
                out: TickOutput::default(),
                dt_s: 1e-3,
                pitch_rad,
                imu_on: true,
            }
        }

        fn step(&mut self, op: Option<OperatorCommand>) -> Status {
            self.step_with(op, |_| {})
        }

        /// A step with `tweak` applied to the inputs last (fault injection).
        fn step_with(&mut self, op: Option<OperatorCommand>, tweak: impl Fn(&mut Self)) -> Status {
            for slot in 0..LEG_SLOTS {
                let cmd = self.out.commands[slot];
                let m = &mut self.input.motors[slot];
                if cmd.mode == CommandMode::Pd {
                    m.q_rad = cmd.q_des_rad;
                    m.dq_rad_s = cmd.dq_des_rad_s;
                }
            }
            self.input.t_s += self.dt_s;
            self.input.imu = self.imu_on.then_some(ImuSample {
                t_s: self.input.t_s,
                gyro_pitch_rad_s: crate::io::test_dither_rad_s(self.input.t_s),
                accel_x_mps2: -GRAVITY_MPS2 * self.pitch_rad.sin(),
                accel_z_mps2: GRAVITY_MPS2 * self.pitch_rad.cos(),
            });
            self.input.operator = op;
            tweak(self);
            self.c.tick(&self.input, &mut self.out);
            self.out.status
        }

        fn run(&mut self, seconds: f64) -> Status {
            let n = (seconds / self.dt_s).round() as usize;
            for _ in 0..n {
                self.step(None);
            }
            self.out.status
        }

        fn go_stand(&mut self) {
            self.step(None);
            assert_eq!(
                self.step(Some(OperatorCommand::Start)).state,
                ControlState::Ramp
            );
            assert_eq!(self.run(2.5).state, ControlState::Stand);
        }
    }

    #[test]
    fn idle_ramp_stand_walk_stop_stand_damp_and_estop() {
        let mut h = Harness::new(PhaseSource::TimeBased);
        let s = h.step(None);
        assert_eq!(s.state, ControlState::Idle);
        assert!(h
            .out
            .commands
            .iter()
            .all(|c| c.mode == CommandMode::Damping));
        // Walk is ignored while idle.
        assert_eq!(
            h.step(Some(OperatorCommand::Walk)).state,
            ControlState::Idle
        );
        let s = h.step(Some(OperatorCommand::Start));
        assert_eq!(s.transition, Some((ControlState::Idle, ControlState::Ramp)));
        // Ramp: from straight legs (0) to the first pose; never faster than the limit.
        let first = h.c.first_pose();
        let mut peak_speed = 0.0_f64;
        let mut t_stand = None;
        for _ in 0..3000 {
            let s = h.step(None);
            for c in &h.out.commands[..LEG_SLOTS] {
                peak_speed = peak_speed.max(c.dq_des_rad_s.abs());
            }
            if s.state == ControlState::Stand && t_stand.is_none() {
                t_stand = Some(h.input.t_s);
            }
        }
        // Largest move ≈ 0.18 rad → 1.875·0.18/0.5 < 2 s minimum: the ramp takes 2 s.
        let t_stand = t_stand.unwrap();
        assert!((t_stand - (0.002 + 2.0)).abs() < 2.5e-3, "{t_stand}");
        assert!(peak_speed <= 0.5 + 1e-9, "{peak_speed}");
        for k in 0..LEG_SLOTS {
            assert!((h.input.motors[k].q_rad - first[k]).abs() < 1e-9);
        }
        // Walk: first the launch (both feet down, the torso carried forward), then a stance
        // switch every step duration (+ debounce, time-based phase from the lift-off).
        let stance0 = h.c.stance();
        assert_eq!(
            h.step(Some(OperatorCommand::Walk)).state,
            ControlState::Walk
        );
        assert!(h.c.launch.is_some());
        let s = h.run(LAUNCH_DURATION_S - 0.002);
        assert_eq!((s.state, s.stance), (ControlState::Walk, stance0));
        assert!(h.c.launch.is_some());
        h.run(0.003);
        assert!(h.c.launch.is_none() && h.c.start_blend.is_some());
        let step_s = Setup::shipped().unwrap().gait.step_duration_s;
        let mut switches = Vec::new();
        let mut prev = stance0;
        // Ticks at 1 kHz for a little over two steps.
        for _ in 0..(2.15 * step_s * 1000.0) as usize {
            let s = h.step(None);
            if s.stance != prev {
                switches.push(h.input.t_s);
                prev = s.stance;
            }
        }
        assert_eq!(switches.len(), 2, "{switches:?}");
        let period = switches[1] - switches[0];
        // Step T from the shipped gait; touchdown needs τ ≥ 1 then 3 debounced ticks.
        assert!((period - (step_s + 0.003)).abs() < 1.5e-3, "{period}");
        assert_eq!(h.out.status.steps, 2);
        // Stop: finish the step, take the braking step (its references blend into the longer
        // landing pose), then Stand holding the landing pose, two stance switches later.
        let stance_before = h.c.stance();
        assert_eq!(
            h.step(Some(OperatorCommand::Stop)).state,
            ControlState::Stop
        );
        let s = h.run(step_s + 0.05);
        assert_eq!(
            (s.state, s.stance),
            (ControlState::Stop, stance_before.other())
        );
        let mut landing = None;
        for _ in 0..(step_s * 1000.0) as usize + 100 {
            let s = h.step(None);
            if s.state == ControlState::Stop {
                // The braking step's references: y^d plus the blended offset (at the phase
                // the latency compensation leads to).
                let lead = s.phase + h.c.reference_lead_s * s.phase_rate_per_s.max(0.0);
                let lead = lead.clamp(0.0, 1.0);
                let u = ((lead - BRAKE_BLEND_FROM) / (1.0 - BRAKE_BLEND_FROM)).clamp(0.0, 1.0);
                for i in 0..OUTPUTS {
                    let want = h.c.gait.eval(i, lead).0 + min_jerk(u).0 * h.c.lunge.dy_end[i];
                    assert!((s.y_des_rad[i] - want).abs() < 1e-9, "{i} {s:?}");
                }
            } else if landing.is_none() {
                assert_eq!(s.state, ControlState::Stand);
                landing = Some(h.input.motors);
            }
        }
        let landing = landing.expect("Stand after the braking step");
        assert_eq!(h.c.stance(), stance_before);
        assert!(
            h.c.lunge.dy_end.iter().any(|d| d.abs() > 0.05),
            "{:?}",
            h.c.lunge
        );
        // Stand holds the landing pose.
        for k in 0..LEG_SLOTS {
            assert!((h.out.commands[k].q_des_rad - landing[k].q_rad).abs() < 1e-3);
        }
        // Orderly damping, then reset.
        assert_eq!(
            h.step(Some(OperatorCommand::Damp)).state,
            ControlState::Damping
        );
        assert_eq!(h.out.status.trip, None);
        assert_eq!(
            h.step(Some(OperatorCommand::Reset)).state,
            ControlState::Idle
        );
        // E-stop from Walk.
        h.step(Some(OperatorCommand::Start));
        h.run(2.5);
        h.step(Some(OperatorCommand::Walk));
        h.run(0.2);
        let s = h.step(Some(OperatorCommand::EStop));
        assert_eq!(s.state, ControlState::Damping);
        assert_eq!(s.trip, Some(Trip::EStop));
        assert!(s.new_trip);
        assert!(h
            .out
            .commands
            .iter()
            .all(|c| c.mode == CommandMode::Damping));
        // Latched: Start does nothing until Reset.
        assert_eq!(
            h.step(Some(OperatorCommand::Start)).state,
            ControlState::Damping
        );
        let s = h.step(Some(OperatorCommand::Reset));
        assert_eq!((s.state, s.trip), (ControlState::Idle, None));
    }

    #[test]
    fn walking_outputs_follow_the_bezier_with_the_legs_relabeled() {
        let mut h = Harness::new(PhaseSource::TimeBased);
        h.go_stand();
        h.step(Some(OperatorCommand::Walk));
        // The launch, then the first step (which blends from the launch's pose): from the
        // second step on, the outputs are the gait's.
        let setup = Setup::shipped().unwrap();
        h.run(LAUNCH_DURATION_S + setup.gait.step_duration_s + 0.01);
        assert_eq!(h.c.stance(), Side::Left);
        assert!(h.c.start_blend.is_none());
        let t0 = h.c.step_start_t_s;
        let s = h.run(t0 + 0.3 - h.input.t_s);
        let tau = s.phase;
        assert!(
            (tau - 0.3 / setup.gait.step_duration_s).abs() < 3e-3,
            "{tau}"
        );
        // The references are taken τ̇·lead ahead (latency compensation).
        let ahead = tau + setup.config.walk.reference_lead_s / setup.gait.step_duration_s;
        for i in 0..OUTPUTS {
            let a = &setup.gait.bezier.alpha[i];
            assert!((s.y_des_rad[i] - bezier::eval(a, ahead)).abs() < 1e-12);
            let dy = bezier::eval_d1(a, ahead) / setup.gait.step_duration_s;
            assert!((s.dy_des_rad_s[i] - dy).abs() < 1e-9);
        }
        // The left leg stands: stance hip is slot 0.
        assert_eq!(s.stance, Side::Left);
        assert_eq!(h.out.commands[0].q_des_rad, s.y_des_rad[0]);
        assert_eq!(h.out.commands[3].q_des_rad, s.y_des_rad[3]);
        // After the switch the right leg stands: stance hip is slot 2.
        let s = h.run(setup.gait.step_duration_s - 0.3 + 0.1);
        assert_eq!(s.stance, Side::Right);
        assert_eq!(h.out.commands[2].q_des_rad, s.y_des_rad[0]);
        assert_eq!(h.out.commands[0].q_des_rad, s.y_des_rad[2]);
    }

    #[test]
    fn state_based_phase_matches_the_model_stance_leg_angle() {
        let mut h = Harness::new(PhaseSource::StateBased);
        h.go_stand();
        let s = h.step(Some(OperatorCommand::Walk));
        // At the first pose the stance-leg angle is θ⁺ up to the torso pitch of the IMU, so
        // τ ≈ 0 (|Δθ| small against θ⁻ − θ⁺ = 0.307 rad).
        assert!(s.phase.abs() < 0.1, "{}", s.phase);
        let setup = Setup::shipped().unwrap();
        let model = &setup.model;
        let mut q = setup.gait.initial_state.clone().unwrap().q;
        let legs = model.legs().unwrap();
        for (k, name) in LEG_JOINT_NAMES.iter().enumerate() {
            q[model.joints[model.require_joint(name).unwrap()].coordinate] = s.leg_q_rad[k];
        }
        q[2] = s.pitch_rad;
        let theta = model.stance_leg_angle(&q, &legs, Side::Right).unwrap();
        let PhaseDefinition::StateBased {
            theta_plus_rad,
            theta_minus_rad,
        } = setup.gait.phase
        else {
            panic!()
        };
        let expected = (theta - theta_plus_rad) / (theta_minus_rad - theta_plus_rad);
        assert!(
            (s.phase - expected).abs() < 1e-12,
            "{} vs {expected}",
            s.phase
        );
    }

    fn tripped(h: &mut Harness, max_ticks: usize, tweak: impl Fn(&mut Harness)) -> (Trip, usize) {
        for n in 1..=max_ticks {
            let s = h.step_with(None, &tweak);
            if s.state == ControlState::Damping {
                assert!(s.new_trip);
                assert!(h
                    .out
                    .commands
                    .iter()
                    .all(|c| c.mode == CommandMode::Damping));
                return (s.trip.unwrap(), n);
            }
        }
        panic!("no trip in {max_ticks} ticks");
    }

    #[test]
    fn every_safety_trip_goes_to_damping_with_its_reason() {
        let standing = || {
            let mut h = Harness::new(PhaseSource::TimeBased);
            h.go_stand();
            h
        };
        let mut h = standing();
        let (t, n) = tripped(&mut h, 5, |h| h.input.motors[1].q_rad = 3.0);
        assert_eq!(n, 1);
        assert!(
            matches!(t, Trip::JointLimit { slot: 1, q_rad, upper_rad, .. } if q_rad == 3.0 && upper_rad == 2.2),
            "{t:?}"
        );

        let mut h = standing();
        let (t, n) = tripped(&mut h, 100, |h| h.input.motors[3].tau_nm = -33.4);
        assert_eq!(n, 50, "persistent: exactly torque_saturation_ticks");
        assert!(
            matches!(
                t,
                Trip::TorqueSaturation {
                    slot: 3,
                    ticks: 50,
                    ..
                }
            ),
            "{t:?}"
        );

        let mut h = standing();
        h.pitch_rad = 0.9;
        let (t, _) = tripped(&mut h, 5000, |_| {});
        assert!(
            matches!(t, Trip::Fall { pitch_rad, limit_rad } if pitch_rad > 0.6 && limit_rad == 0.6),
            "{t:?}"
        );

        let mut h = standing();
        let (t, _) = tripped(&mut h, 5, |h| h.input.motors[0].temperature_c = 91.0);
        assert!(
            matches!(t, Trip::OverTemperature { slot: 0, temperature_c, .. } if temperature_c == 91.0),
            "{t:?}"
        );

        let mut h = standing();
        let (t, _) = tripped(&mut h, 5, |h| h.input.motors[2].errors = 0b10);
        assert_eq!(t, Trip::MotorFault { slot: 2, flags: 2 });

        let mut h = standing();
        let (t, n) = tripped(&mut h, 50, |h| h.input.motors[2].fresh = false);
        assert_eq!(
            (t, n),
            (
                Trip::MissingReplies {
                    slot: 2,
                    consecutive: 5
                },
                5
            )
        );

        let mut h = standing();
        h.imu_on = false;
        let (t, n) = tripped(&mut h, 100, |_| {});
        assert!(matches!(t, Trip::ImuStale { .. }), "{t:?}");
        assert!((20..=22).contains(&n), "stale after 0.02 s: {n}");

        // One implausible sample (an impact spike) does not trip; a run of them does.
        let mut h = standing();
        let spike = |h: &mut Harness| {
            if let Some(imu) = h.input.imu.as_mut() {
                imu.gyro_pitch_rad_s = 100.0;
            }
        };
        for _ in 0..4 {
            assert_eq!(h.step_with(None, spike).trip, None);
        }
        assert_eq!(h.step(None).trip, None, "a good sample resets the count");
        let (t, n) = tripped(&mut h, 10, spike);
        assert_eq!(n, 5, "the fifth implausible sample in a row trips: {t:?}");
        assert!(
            matches!(t, Trip::ImuImplausible { gyro_rad_s, accel_norm_mps2 } if gyro_rad_s == 100.0 && (accel_norm_mps2 - GRAVITY_MPS2).abs() < 1e-9),
            "{t:?}"
        );

        let mut h = standing();
        let (t, n) = tripped(&mut h, 5, |h| h.input.overrun_streak = 20);
        assert_eq!(
            (t, n),
            (
                Trip::OverrunStreak {
                    streak: 20,
                    limit: 20
                },
                1
            )
        );
    }

    #[test]
    fn idle_is_not_armed() {
        let mut h = Harness::new(PhaseSource::TimeBased);
        h.input.motors[0].temperature_c = 120.0;
        assert_eq!(h.run(0.1).state, ControlState::Idle);
        // Armed on Start: trips at once.
        let s = h.step(Some(OperatorCommand::Start));
        assert_eq!(s.state, ControlState::Damping);
        assert!(matches!(s.trip, Some(Trip::OverTemperature { .. })));
    }

    #[test]
    fn a_braking_step_out_of_the_legs_reach_is_refused_by_name() {
        let setup = Setup::shipped().unwrap();
        let mut config = setup.config.clone();
        // Legs of 0.7 m cannot straddle 1.6 m.
        config.walk.stop_step_length_m = 1.6;
        let err = Controller::new(&config, &setup.gait, setup.model.clone(), false)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("walk.stop_step_length_m") && err.contains("1.6"),
            "{err}"
        );
        // The shipped length is reachable and lengthens the swing: the braking pose's θ lies
        // beyond the gait's θ⁻.
        let c = Controller::new(&setup.config, &setup.gait, setup.model.clone(), false).unwrap();
        assert!(
            c.lunge.theta_rad > c.gait.theta_minus_rad + 0.05,
            "{:?}",
            c.lunge
        );
    }

    #[test]
    fn min_jerk_is_smooth_and_peaks_at_1_875() {
        assert_eq!(min_jerk(0.0), (0.0, 0.0));
        assert_eq!(min_jerk(1.0).0, 1.0);
        assert!((min_jerk(0.5).1 - MIN_JERK_PEAK_RATE).abs() < 1e-12);
        let h = 1e-6;
        let fd = (min_jerk(0.3 + h).0 - min_jerk(0.3 - h).0) / (2.0 * h);
        assert!((fd - min_jerk(0.3).1).abs() < 1e-8);
    }
}
