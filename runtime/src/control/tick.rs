//! What one control tick reads and writes: [`TickInput`], [`TickOutput`] (joint commands and
//! [`Status`]), the operator's commands and the states of the state machine.

use crate::safety::Trip;
use crate::slots::{MotorSample, LEG_SLOTS, OUTPUTS, SLOTS};
use drivers::imu::ImuSample;
use model::Side;

/// Operator requests, delivered through [`crate::operator`] without blocking the tick.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// The treadmill's belt speed is now `speed_mps` (m/s, the belt surface moving backwards):
    /// the speed control follows it and keeps the robot at the belt's centre.
    Belt {
        /// Belt speed, m/s.
        speed_mps: f64,
    },
    /// Walk this much faster than the belt (a steady offset of the commanded speed), m/s.
    Offset {
        /// Speed offset, m/s.
        speed_mps: f64,
    },
    /// Change the speed offset by this much (the keyboard's `+`/`-`), m/s.
    Nudge {
        /// Change of the speed offset, m/s.
        delta_mps: f64,
    },
}

impl OperatorCommand {
    /// Every command without a value, in declaration order.
    pub const ALL: [OperatorCommand; 6] = [
        OperatorCommand::Start,
        OperatorCommand::Walk,
        OperatorCommand::Stop,
        OperatorCommand::Damp,
        OperatorCommand::Reset,
        OperatorCommand::EStop,
    ];

    /// The names of the commands with a value (`belt 0.25`, `offset 0.05`, `nudge -0.025`).
    pub const VALUED: [&'static str; 3] = ["belt", "offset", "nudge"];

    /// Name for logs (`start`, `walk`, `stop`, `damp`, `reset`, `estop`, `belt`, `offset`,
    /// `nudge`); [`OperatorCommand::text`] adds the value.
    pub fn name(self) -> &'static str {
        match self {
            OperatorCommand::Start => "start",
            OperatorCommand::Walk => "walk",
            OperatorCommand::Stop => "stop",
            OperatorCommand::Damp => "damp",
            OperatorCommand::Reset => "reset",
            OperatorCommand::EStop => "estop",
            OperatorCommand::Belt { .. } => "belt",
            OperatorCommand::Offset { .. } => "offset",
            OperatorCommand::Nudge { .. } => "nudge",
        }
    }

    /// The value of a valued command, m/s.
    pub fn value_mps(self) -> Option<f64> {
        match self {
            OperatorCommand::Belt { speed_mps } | OperatorCommand::Offset { speed_mps } => {
                Some(speed_mps)
            }
            OperatorCommand::Nudge { delta_mps } => Some(delta_mps),
            _ => None,
        }
    }

    /// The command of a [`OperatorCommand::name`] without a value.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The valued command `name` with `value_mps` (`None`: not a valued name).
    pub fn with_value(name: &str, value_mps: f64) -> Option<Self> {
        match name {
            "belt" => Some(OperatorCommand::Belt {
                speed_mps: value_mps,
            }),
            "offset" => Some(OperatorCommand::Offset {
                speed_mps: value_mps,
            }),
            "nudge" => Some(OperatorCommand::Nudge {
                delta_mps: value_mps,
            }),
            _ => None,
        }
    }

    /// The command as text: its name, then its value in shortest round-trip form
    /// (`belt 0.25`): [`OperatorCommand::parse`] reads it back bit for bit (logs, replay).
    pub fn text(self) -> String {
        match self.value_mps() {
            Some(v) => format!("{} {v}", self.name()),
            None => self.name().to_string(),
        }
    }

    /// Parses `name` or `name value` ([`OperatorCommand::text`]); the error says what is wrong.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut words = text.split_whitespace();
        let name = words.next().unwrap_or("");
        let value = words.next();
        if let Some(extra) = words.next() {
            return Err(format!("unexpected `{extra}` after the command"));
        }
        match (Self::from_name(name), value) {
            (Some(c), None) => return Ok(c),
            (Some(_), Some(v)) => return Err(format!("`{name}` takes no value (got `{v}`)")),
            (None, _) => {}
        }
        if !Self::VALUED.contains(&name) {
            return Err(format!(
                "unknown command `{name}` (start, walk, stop, damp, reset, estop, belt <m/s>, \
                 offset <m/s>, nudge <m/s>)"
            ));
        }
        let Some(v) = value else {
            return Err(format!("`{name}` needs a speed in m/s, e.g. `{name} 0.25`"));
        };
        let value_mps: f64 = v
            .parse()
            .map_err(|_| format!("`{name}`: `{v}` is not a number (m/s)"))?;
        if !value_mps.is_finite() {
            return Err(format!("`{name}`: {v} is not a finite speed"));
        }
        Self::with_value(name, value_mps).ok_or_else(|| format!("unknown command `{name}`"))
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
    /// Relaunches from double support after a stalled step since start-up
    /// (`runtime::control::recovery`).
    pub recoveries: u32,
    /// Step-back catches since start-up: a step whose phase ran back, its swing foot set down
    /// behind and the robot carried forward again from double support
    /// (`runtime::control::recovery`).
    pub catches: u32,
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
    /// The speed control after the last impact ([`SpeedStatus::UNKNOWN`] without one).
    pub speed: SpeedStatus,
    /// An impact updated [`Status::speed`] this tick (a step was measured).
    pub speed_update: bool,
}

/// The treadmill speed control after an impact (`runtime::control::speed`): what the operator
/// set, what the last step measured and what the next step walks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedStatus {
    /// Belt speed set by the operator, m/s (NaN: none yet).
    pub belt_mps: f64,
    /// Speed offset set by the operator, m/s.
    pub offset_mps: f64,
    /// Commanded speed before clamping to the library's range, m/s.
    pub requested_mps: f64,
    /// Commanded walking speed (belt + offset − position loop, clamped), m/s.
    pub commanded_mps: f64,
    /// The last step's measured speed over the belt (length / duration), m/s.
    pub step_speed_mps: f64,
    /// The last step's length (front foot minus rear foot at the impact, leg kinematics), m.
    pub step_length_m: f64,
    /// The last step's duration (impact to impact), s.
    pub step_duration_s: f64,
    /// Estimated position on the belt (+ forward of where speed control began), m.
    pub position_m: f64,
    /// Speed of the library gait the next step walks (interpolated), m/s.
    pub library_mps: f64,
    /// The regulator's integral term, m/s.
    pub integral_mps: f64,
    /// The requested speed was outside the library's range and clamped.
    pub clamped: bool,
    /// How much longer than its gait's the next step lands (the step lever), m.
    pub step_offset_m: f64,
    /// How far the next step leans the torso forward (the step lean; − back), rad.
    pub step_lean_rad: f64,
}

impl SpeedStatus {
    /// Nothing known yet.
    pub const UNKNOWN: Self = Self {
        belt_mps: f64::NAN,
        offset_mps: 0.0,
        requested_mps: f64::NAN,
        commanded_mps: f64::NAN,
        step_speed_mps: f64::NAN,
        step_length_m: f64::NAN,
        step_duration_s: f64::NAN,
        position_m: 0.0,
        library_mps: f64::NAN,
        integral_mps: 0.0,
        clamped: false,
        step_offset_m: 0.0,
        step_lean_rad: 0.0,
    };
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
                recoveries: 0,
                catches: 0,
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
                speed: SpeedStatus::UNKNOWN,
                speed_update: false,
            },
        }
    }
}
