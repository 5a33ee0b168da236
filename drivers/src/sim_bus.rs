//! `SimBus`: simulated A1 firmware behind the real CAN codec.
//!
//! Every exchange runs the full byte path: the bus encodes each [`Command`] into a CAN
//! frame, the simulated firmware decodes the frame, samples its state, encodes a reply
//! frame, and the bus decodes that reply. Bus time is the exact length of those frames
//! (stuff bits and CRC included, [`crate::timing::frame_bits_exact`]); the buses run in
//! parallel, and an exchange whose busiest bus exceeds the budget is
//! [`BusError::DeadlineExceeded`].
//!
//! # Data flow of one `exchange` (control period `T`, firmware tick `h = T / n`)
//! ```text
//! Command --encode--> frame --firmware decode--> inbox   (applied from the next period)
//!                                      \--> sample state --encode--> reply frame --decode--> Reply
//! then n times: each firmware: measure (encoder) -> torque (mode, PD) -> limits -> heat
//!               plant.step(torques, h)
//! then each firmware latches its inbox as the active command
//! ```
//! So a command sent in exchange `k` acts during period `k + 1` and shows in the reply of
//! exchange `k + 2`: one control tick of communication latency on top of the sample
//! delay.
//!
//! # Motor model ([`A1Model`], defaults in brackets; assumptions are marked)
//! * Firmware tick 10 kHz: the PD runs on the motor side at every tick with the torque
//!   held constant in between (zero-order hold); the plant integrates each tick.
//!   Joint-side gains are applied to joint-side quantities, which is the same law as
//!   `kp/N²`, `kd/N²` on the motor side.
//! * Encoder: motor-side, 32768 counts per motor turn (assumption), i.e. 2.1e-5 rad at
//!   the joint, plus seeded Gaussian noise (0.3 counts rms). Velocity: finite difference
//!   of counts, first-order low-pass at 500 Hz (assumption).
//! * Torque limits at the joint: |τ| ≤ 33.5 N·m; in the motoring quadrant (τ·ω > 0) the
//!   available torque is 33.5 N·m up to a corner speed of 10.5 rad/s, then falls linearly
//!   to zero at the no-load speed 21 rad/s (assumed voltage-limited DC-motor envelope;
//!   corner at half the no-load speed). Braking torque is limited by 33.5 N·m only.
//! * Modes: brake = passive back-EMF damping `τ = −N²·Kt²/R · ω` (2.8 N·m·s/rad);
//!   damping = `−kd·ω̂`; PD = `kp(q* − q̂) + kd(ω* − ω̂) + τ_ff`.
//! * Thermal: one node, `C dT/dt = I²R − (T − T_amb)/R_th`, `I = τ / (N·Kt)`, integrated
//!   exactly per tick. Assumed Kt = 0.092 N·m/A (motor side, 40 A at peak torque),
//!   R = 0.25 Ω, R_th = 1.5 K/W, C = 60 J/K (time constant 90 s), T_amb = 25 °C. At 90 °C
//!   the firmware raises `OVER_TEMPERATURE` and switches its output off (phases open,
//!   zero torque: braking would keep heating a back-driven winding) until it cools to
//!   80 °C; a continuous 10.9 N·m keeps it just below the limit.
//! * Lifecycle: the motor starts disabled (damping with 1.5 N·m·s/rad); *enable* lets it
//!   obey commands (damping until the first one arrives); *disable* returns to damping at
//!   once; *set zero* declares the present position zero. Malformed frames are ignored
//!   without reply, like real firmware.
//!
//! The joint the motor drives is a [`JointPlant`]: [`InertiaDampingPlant`] here, the robot
//! simulator later.
//!
//! # Fault injection (off by default; seeded, so the same seed gives the same faults)
//! * Wire ([`WireFaults`], [`SimBus::set_wire_faults`]): each frame, in each direction, is lost
//!   with `loss_probability` or corrupted with `corrupt_probability`; each reply is delayed by
//!   `delay_s` with `delay_probability`. A corrupted frame carries damage the A1 codec can see
//!   (a cut data length, a reserved mode, an id outside its kind's range: bit flips inside the
//!   payload are caught by the CAN CRC in the controller and become a loss); the firmware and
//!   the host decoder reject it, so its reply is missing. A delayed reply that arrives after the
//!   exchange budget is missing too (the real bus drains it at the next exchange). The fault
//!   generator has its own seeded stream: enabling faults leaves the sensor noise unchanged.
//! * Motors: [`SimBus::set_silent`] (a cut cable), [`SimBus::set_error_flags`] (firmware fault
//!   bits in every reply), [`SimBus::set_temperature_c`] (a hot winding; the thermal model
//!   carries on from there). [`SimBus::wire_stats`] counts what the wire did.

use crate::a1::{
    self, decode_host_frame, encode_reply, Command, ErrorFlags, Frame, HostFrame, Mode, MotorId,
    Reply, Special,
};
use crate::bus::{BusError, ExchangeReport, Lifecycle, MotorBus, MotorSpec, MotorTable, Operation};
use crate::noise::gaussian;
use crate::timing::{bits_to_duration, frame_bits_exact};
use core::time::Duration;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::{Arc, Mutex};
use thiserror::Error;

/// Most buses one `SimBus` models.
pub const MAX_BUSES: usize = 8;

/// The mechanics the motors drive: joint positions and velocities, torques in.
///
/// Implement this for the robot simulator to put the whole robot behind a [`SimBus`].
pub trait JointPlant {
    /// Number of joints.
    fn joint_count(&self) -> usize;
    /// Joint position \[rad\].
    fn position_rad(&self, joint: usize) -> f64;
    /// Joint velocity \[rad/s\].
    fn velocity_rad_s(&self, joint: usize) -> f64;
    /// Advance by `dt_s` with `torque_nm[j]` applied to joint `j`, held constant.
    /// `torque_nm.len() == joint_count()`; joints without a motor get zero.
    fn step(&mut self, torque_nm: &[f64], dt_s: f64);
}

impl<P: JointPlant + ?Sized> JointPlant for Box<P> {
    fn joint_count(&self) -> usize {
        (**self).joint_count()
    }
    fn position_rad(&self, joint: usize) -> f64 {
        (**self).position_rad(joint)
    }
    fn velocity_rad_s(&self, joint: usize) -> f64 {
        (**self).velocity_rad_s(joint)
    }
    fn step(&mut self, torque_nm: &[f64], dt_s: f64) {
        (**self).step(torque_nm, dt_s)
    }
}

/// One independent joint: `J q̈ = τ + τ_load − b q̇`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidJoint {
    /// Inertia about the joint axis, reflected rotor included \[kg·m²\].
    pub inertia_kg_m2: f64,
    /// Viscous friction \[N·m·s/rad\].
    pub damping_nm_s_per_rad: f64,
    /// Constant external torque, e.g. a gravity load \[N·m\].
    pub load_torque_nm: f64,
}

/// Independent rigid joints, integrated exactly for a torque held over each step.
#[derive(Debug, Clone, PartialEq)]
pub struct InertiaDampingPlant {
    joints: Vec<RigidJoint>,
    q_rad: Vec<f64>,
    dq_rad_s: Vec<f64>,
}

impl InertiaDampingPlant {
    /// Joints at rest at zero; `None` if an inertia is not positive or a damping negative.
    pub fn new(joints: Vec<RigidJoint>) -> Option<Self> {
        let valid = joints.iter().all(|j| {
            j.inertia_kg_m2 > 0.0
                && j.inertia_kg_m2.is_finite()
                && j.damping_nm_s_per_rad >= 0.0
                && j.damping_nm_s_per_rad.is_finite()
                && j.load_torque_nm.is_finite()
        });
        valid.then(|| Self {
            q_rad: vec![0.0; joints.len()],
            dq_rad_s: vec![0.0; joints.len()],
            joints,
        })
    }

    /// Set one joint's state.
    pub fn set_state(&mut self, joint: usize, q_rad: f64, dq_rad_s: f64) {
        self.q_rad[joint] = q_rad;
        self.dq_rad_s[joint] = dq_rad_s;
    }

    /// Change one joint's external load.
    pub fn set_load(&mut self, joint: usize, load_torque_nm: f64) {
        self.joints[joint].load_torque_nm = load_torque_nm;
    }
}

impl JointPlant for InertiaDampingPlant {
    fn joint_count(&self) -> usize {
        self.joints.len()
    }
    fn position_rad(&self, joint: usize) -> f64 {
        self.q_rad[joint]
    }
    fn velocity_rad_s(&self, joint: usize) -> f64 {
        self.dq_rad_s[joint]
    }
    fn step(&mut self, torque_nm: &[f64], dt_s: f64) {
        for (j, joint) in self.joints.iter().enumerate() {
            let u = torque_nm.get(j).copied().unwrap_or(0.0) + joint.load_torque_nm;
            let (q0, v0) = (self.q_rad[j], self.dq_rad_s[j]);
            let rate = joint.damping_nm_s_per_rad / joint.inertia_kg_m2;
            if rate * dt_s > 1e-9 {
                // v(t) = v∞ + (v0 − v∞) e^{−rate t},  v∞ = u / b.
                let v_inf = u / joint.damping_nm_s_per_rad;
                let decay = (-rate * dt_s).exp();
                self.dq_rad_s[j] = v_inf + (v0 - v_inf) * decay;
                self.q_rad[j] = q0 + v_inf * dt_s + (v0 - v_inf) * (1.0 - decay) / rate;
            } else {
                let a = (u - joint.damping_nm_s_per_rad * v0) / joint.inertia_kg_m2;
                self.dq_rad_s[j] = v0 + a * dt_s;
                self.q_rad[j] = q0 + v0 * dt_s + 0.5 * a * dt_s * dt_s;
            }
        }
    }
}

/// Parameters of the simulated A1 (joint side unless marked motor side).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct A1Model {
    /// Gear ratio.
    pub gear_ratio: f64,
    /// Peak torque \[N·m\].
    pub max_torque_nm: f64,
    /// No-load speed \[rad/s\].
    pub no_load_speed_rad_s: f64,
    /// Speed up to which the full torque is available \[rad/s\].
    pub corner_speed_rad_s: f64,
    /// Firmware (PD) rate \[Hz\].
    pub firmware_rate_hz: f64,
    /// Encoder counts per motor turn.
    pub encoder_counts_per_rev: u32,
    /// Encoder noise, rms \[counts\].
    pub encoder_noise_counts: f64,
    /// Velocity low-pass cutoff \[Hz\].
    pub velocity_filter_hz: f64,
    /// Motor-side torque constant \[N·m/A\].
    pub torque_constant_nm_per_a: f64,
    /// Winding resistance \[Ω\].
    pub winding_resistance_ohm: f64,
    /// Winding-to-ambient thermal resistance \[K/W\].
    pub thermal_resistance_k_per_w: f64,
    /// Winding heat capacity \[J/K\].
    pub thermal_capacitance_j_per_k: f64,
    /// Ambient temperature \[°C\].
    pub ambient_c: f64,
    /// Over-temperature trip \[°C\].
    pub over_temperature_c: f64,
    /// Over-temperature release \[°C\].
    pub recover_temperature_c: f64,
    /// Damping gain when disabled \[N·m·s/rad\].
    pub disable_damping_nm_s_per_rad: f64,
}

impl Default for A1Model {
    fn default() -> Self {
        Self {
            gear_ratio: a1::GEAR_RATIO,
            max_torque_nm: a1::MAX_TORQUE_NM,
            no_load_speed_rad_s: a1::MAX_SPEED_RAD_S,
            corner_speed_rad_s: a1::MAX_SPEED_RAD_S / 2.0,
            firmware_rate_hz: 10_000.0,
            encoder_counts_per_rev: 32_768,
            encoder_noise_counts: 0.3,
            velocity_filter_hz: 500.0,
            torque_constant_nm_per_a: 0.092,
            winding_resistance_ohm: 0.25,
            thermal_resistance_k_per_w: 1.5,
            thermal_capacitance_j_per_k: 60.0,
            ambient_c: 25.0,
            over_temperature_c: 90.0,
            recover_temperature_c: 80.0,
            disable_damping_nm_s_per_rad: DISABLE_DAMPING_NM_S_PER_RAD,
        }
    }
}

/// Damping gain of a disabled A1 (what *disable*, `deactivate` and `Drop` leave) \[N·m·s/rad\].
pub const DISABLE_DAMPING_NM_S_PER_RAD: f64 = 1.5;

impl A1Model {
    /// Passive braking coefficient with shorted windings, `N² Kt² / R` \[N·m·s/rad\].
    pub fn brake_damping_nm_s_per_rad(&self) -> f64 {
        let kt = self.torque_constant_nm_per_a * self.gear_ratio;
        kt * kt / self.winding_resistance_ohm
    }

    /// Largest torque magnitude available at joint speed `speed_rad_s` in the motoring
    /// quadrant \[N·m\].
    pub fn motoring_torque_limit_nm(&self, speed_rad_s: f64) -> f64 {
        let w = speed_rad_s.abs();
        if w <= self.corner_speed_rad_s {
            self.max_torque_nm
        } else {
            let span = self.no_load_speed_rad_s - self.corner_speed_rad_s;
            (self.max_torque_nm * (self.no_load_speed_rad_s - w) / span).max(0.0)
        }
    }

    /// Clamp a torque request to the torque–speed envelope.
    pub fn limit_torque_nm(&self, tau_nm: f64, speed_rad_s: f64) -> f64 {
        let limit = if tau_nm * speed_rad_s > 0.0 {
            self.motoring_torque_limit_nm(speed_rad_s)
        } else {
            self.max_torque_nm
        };
        tau_nm.clamp(-limit, limit)
    }

    /// Copper loss at joint torque `tau_nm` \[W\].
    pub fn copper_loss_w(&self, tau_nm: f64) -> f64 {
        let current_a = tau_nm / (self.gear_ratio * self.torque_constant_nm_per_a);
        current_a * current_a * self.winding_resistance_ohm
    }

    fn joint_rad_per_count(&self) -> f64 {
        core::f64::consts::TAU / f64::from(self.encoder_counts_per_rev) / self.gear_ratio
    }
}

/// A simulated motor: where it is and which joint it drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimMotor {
    /// Bus index and id.
    pub spec: MotorSpec,
    /// Joint of the plant it drives.
    pub joint: usize,
}

/// Configuration of a [`SimBus`].
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Control (exchange) rate \[Hz\]; each exchange advances the simulation by one period.
    pub control_rate_hz: f64,
    /// CAN bitrate \[bit/s\].
    pub bitrate_bps: u32,
    /// Number of buses.
    pub bus_count: usize,
    /// Motors present on the buses (configure may name others: those stay silent).
    pub motors: Vec<SimMotor>,
    /// Motor model (the same for all).
    pub model: A1Model,
    /// Seed of all noise.
    pub seed: u64,
}

/// A [`SimConfig`] that cannot be simulated.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SimError {
    /// The firmware rate is not an integer multiple of the control rate.
    #[error(
        "firmware rate {firmware_rate_hz} Hz is not a positive integer multiple of the \
         control rate {control_rate_hz} Hz"
    )]
    Rates {
        /// Control rate \[Hz\].
        control_rate_hz: f64,
        /// Firmware rate \[Hz\].
        firmware_rate_hz: f64,
    },
    /// Bus count outside `1..=MAX_BUSES` or a zero bitrate.
    #[error(
        "{bus_count} buses at {bitrate_bps} bit/s: need 1..={MAX_BUSES} buses and a bitrate > 0"
    )]
    Buses {
        /// Bus count.
        bus_count: usize,
        /// Bitrate.
        bitrate_bps: u32,
    },
    /// A motor's bus or joint does not exist, or two motors share an id or a joint.
    #[error("simulated {motor} (bus {bus}, joint {joint}) is misplaced: {reason}")]
    Motor {
        /// Motor.
        motor: MotorId,
        /// Its bus.
        bus: usize,
        /// Its joint.
        joint: usize,
        /// What is wrong.
        reason: &'static str,
    },
}

/// Direction of a frame on the simulated wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Host → motor.
    ToMotor,
    /// Motor → host.
    ToHost,
}

/// One frame seen on the simulated wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TapEntry {
    /// Bus index.
    pub bus: usize,
    /// Direction.
    pub direction: Direction,
    /// The frame.
    pub frame: Frame,
}

/// Faults of the simulated CAN wire (probabilities per frame, in `[0, 1]`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WireFaults {
    /// A frame (command or reply) vanishes.
    pub loss_probability: f64,
    /// A frame (command or reply) arrives damaged and is rejected by its decoder.
    pub corrupt_probability: f64,
    /// A reply is delayed by `delay_s`.
    pub delay_probability: f64,
    /// Delay of a delayed reply \[s\].
    pub delay_s: f64,
}

impl WireFaults {
    /// A clean wire.
    pub const NONE: Self = Self {
        loss_probability: 0.0,
        corrupt_probability: 0.0,
        delay_probability: 0.0,
        delay_s: 0.0,
    };

    /// The first field out of range, as (name, value).
    pub fn invalid_field(&self) -> Option<(&'static str, f64)> {
        let probabilities = [
            ("loss_probability", self.loss_probability),
            ("corrupt_probability", self.corrupt_probability),
            ("delay_probability", self.delay_probability),
        ];
        probabilities
            .into_iter()
            .find(|(_, p)| !(0.0..=1.0).contains(p))
            .or_else(|| {
                (!(self.delay_s.is_finite() && self.delay_s >= 0.0))
                    .then_some(("delay_s", self.delay_s))
            })
    }
}

/// Damage a corrupted frame carries, each one a distinct codec rejection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Corruption {
    /// The data length code is cut to this many bytes (`DecodeError::WrongLength`).
    Length(usize),
    /// The mode field holds the reserved value (`DecodeError::UnknownMode`); on a special frame
    /// the opcode byte is garbled instead (`DecodeError::UnknownOpcode`).
    ReservedMode,
    /// The id is moved out of its kind's range (`DecodeError::WrongId`).
    Id,
}

/// Apply `damage` to `frame`: the id and the bytes as received (pure; the decoders reject them).
pub fn corrupt(frame: &Frame, damage: Corruption) -> (u32, [u8; a1::codec::FRAME_LEN], usize) {
    let mut data = frame.data;
    let mut id = frame.id;
    let mut len = data.len();
    match damage {
        Corruption::Length(n) => len = n.min(data.len() - 1),
        Corruption::ReservedMode => match a1::codec::classify(frame.id) {
            Some((a1::codec::FrameKind::Special, _)) => data[0] = 0xEE,
            Some((a1::codec::FrameKind::Command, _)) => {
                let payload = u64::from_le_bytes(data) | (0b11 << a1::codec::CMD_MODE_START_BIT);
                data = payload.to_le_bytes();
            }
            _ => {
                let payload = u64::from_le_bytes(data) | (0b11 << a1::codec::REPLY_MODE_START_BIT);
                data = payload.to_le_bytes();
            }
        },
        // Bit 10 set: above every A1 id range (standard ids are 11 bits).
        Corruption::Id => id |= 0x700,
    }
    (id, data, len)
}

/// What the simulated wire did (counts of frames).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WireStats {
    /// Frames lost (either direction).
    pub lost: u64,
    /// Frames corrupted and rejected by a decoder (either direction).
    pub corrupted: u64,
    /// Replies delayed.
    pub delayed: u64,
    /// Delayed replies that arrived after the exchange budget (missing).
    pub delayed_late: u64,
}

impl core::ops::AddAssign for WireStats {
    fn add_assign(&mut self, other: Self) {
        self.lost += other.lost;
        self.corrupted += other.corrupted;
        self.delayed += other.delayed;
        self.delayed_late += other.delayed_late;
    }
}

/// A shared recorder of the simulated wire (diagnostics and conformance tests only: it
/// locks and grows a `Vec`, so leave it off in real-time use).
pub type WireTap = Arc<Mutex<Vec<TapEntry>>>;

#[derive(Debug, Clone)]
struct Firmware {
    motor: SimMotor,
    enabled: bool,
    active: Command,
    inbox: Option<Command>,
    silent: bool,
    zero_offset_rad: f64,
    prev_counts: i64,
    q_abs_rad: f64,
    dq_filtered_rad_s: f64,
    tau_nm: f64,
    temperature_c: f64,
    overheated: bool,
    injected_errors: ErrorFlags,
}

impl Firmware {
    fn new(motor: SimMotor, model: &A1Model, q_rad: f64) -> Self {
        let counts = (q_rad / model.joint_rad_per_count()).round() as i64;
        Self {
            motor,
            enabled: false,
            active: Command::damping(motor.spec.id, model.disable_damping_nm_s_per_rad),
            inbox: None,
            silent: false,
            zero_offset_rad: 0.0,
            prev_counts: counts,
            q_abs_rad: counts as f64 * model.joint_rad_per_count(),
            dq_filtered_rad_s: 0.0,
            tau_nm: 0.0,
            temperature_c: model.ambient_c,
            overheated: false,
            injected_errors: ErrorFlags::NONE,
        }
    }

    fn disable(&mut self, model: &A1Model) {
        self.enabled = false;
        self.inbox = None;
        self.active = Command::damping(self.motor.spec.id, model.disable_damping_nm_s_per_rad);
    }

    /// Handle the id and bytes of a host frame as received (possibly damaged on the wire); the
    /// reply frame, if any.
    fn receive(&mut self, id: u32, data: &[u8], model: &A1Model) -> Option<Frame> {
        if self.silent {
            return None;
        }
        match decode_host_frame(id, data).ok()? {
            HostFrame::Command(command) if command.motor == self.motor.spec.id => {
                if self.enabled {
                    self.inbox = Some(command);
                }
            }
            HostFrame::Special { motor, special } if motor == self.motor.spec.id => match special {
                Special::Enable if !self.overheated => {
                    self.disable(model);
                    self.enabled = true;
                }
                Special::Enable => {}
                Special::Disable => self.disable(model),
                Special::SetZero => self.zero_offset_rad = self.q_abs_rad,
            },
            _ => return None,
        }
        let reply = self.reply();
        // Replies are in range by construction except under faults; saturation is fine.
        encode_reply(&reply).ok().map(|e| e.frame)
    }

    fn mode(&self) -> Mode {
        self.active.mode
    }

    fn reply(&self) -> Reply {
        let errors = if self.overheated {
            ErrorFlags(ErrorFlags::OVER_TEMPERATURE.0 | self.injected_errors.0)
        } else {
            self.injected_errors
        };
        Reply {
            motor: self.motor.spec.id,
            mode: self.mode(),
            enabled: self.enabled,
            q_rad: self.q_abs_rad - self.zero_offset_rad,
            dq_rad_s: self.dq_filtered_rad_s,
            tau_nm: self.tau_nm,
            temperature_c: self.temperature_c,
            errors,
        }
    }

    /// One firmware tick: measure, compute and limit the torque, heat up. Returns the
    /// joint torque to hold over the tick.
    fn tick(
        &mut self,
        q_rad: f64,
        dq_rad_s: f64,
        period: &TickPeriod,
        model: &A1Model,
        rng: &mut ChaCha8Rng,
    ) -> f64 {
        let noise = gaussian(rng) * model.encoder_noise_counts;
        let counts = (q_rad * period.counts_per_joint_rad + noise).round() as i64;
        self.q_abs_rad = counts as f64 * period.joint_rad_per_count;
        let raw_velocity =
            (counts - self.prev_counts) as f64 * period.joint_rad_s_per_count_per_tick;
        self.prev_counts = counts;
        self.dq_filtered_rad_s +=
            period.velocity_filter_gain * (raw_velocity - self.dq_filtered_rad_s);

        let q_hat = self.q_abs_rad - self.zero_offset_rad;
        let dq_hat = self.dq_filtered_rad_s;
        let c = &self.active;
        let request = if self.overheated {
            0.0
        } else {
            match self.mode() {
                // Passive: physics of shorted windings, from the true speed.
                Mode::Brake => -model.brake_damping_nm_s_per_rad() * dq_rad_s,
                Mode::Damping => -c.kd_nm_s_per_rad * dq_hat,
                Mode::PositionVelocity => {
                    c.kp_nm_per_rad * (c.q_des_rad - q_hat)
                        + c.kd_nm_s_per_rad * (c.dq_des_rad_s - dq_hat)
                        + c.tau_ff_nm
                }
            }
        };
        self.tau_nm = model.limit_torque_nm(request, dq_rad_s);

        // Exact first-order thermal step with the loss held over the tick.
        let steady_c = model.ambient_c + self.tau_nm * self.tau_nm * period.heating_k_per_nm2;
        self.temperature_c = steady_c + (self.temperature_c - steady_c) * period.thermal_decay;
        if self.temperature_c >= model.over_temperature_c {
            self.overheated = true;
        } else if self.temperature_c < model.recover_temperature_c {
            self.overheated = false;
        }
        self.tau_nm
    }

    fn latch(&mut self) {
        if let Some(command) = self.inbox.take() {
            self.active = command;
        }
    }
}

/// The firmware tick and the discrete-time factors that depend only on it and the model.
struct TickPeriod {
    dt_s: f64,
    /// Encoder resolution at the joint \[rad\].
    joint_rad_per_count: f64,
    /// Its reciprocal \[1/rad\] (the tick multiplies: no division on its serial path).
    counts_per_joint_rad: f64,
    /// A count per tick as a joint speed \[rad/s\].
    joint_rad_s_per_count_per_tick: f64,
    /// Steady excess winding temperature per (N·m)² of joint torque \[K/(N·m)²\]: the copper
    /// loss is quadratic in the torque.
    heating_k_per_nm2: f64,
    /// Gain of the first-order velocity low-pass over one tick.
    velocity_filter_gain: f64,
    /// Decay of the winding's excess temperature over one tick.
    thermal_decay: f64,
}

impl TickPeriod {
    fn new(model: &A1Model) -> Self {
        let dt_s = 1.0 / model.firmware_rate_hz;
        let tau_th = model.thermal_resistance_k_per_w * model.thermal_capacitance_j_per_k;
        Self {
            dt_s,
            joint_rad_per_count: model.joint_rad_per_count(),
            counts_per_joint_rad: 1.0 / model.joint_rad_per_count(),
            joint_rad_s_per_count_per_tick: model.joint_rad_per_count() * model.firmware_rate_hz,
            heating_k_per_nm2: model.copper_loss_w(1.0) * model.thermal_resistance_k_per_w,
            velocity_filter_gain: 1.0
                - (-core::f64::consts::TAU * model.velocity_filter_hz * dt_s).exp(),
            thermal_decay: (-dt_s / tau_th).exp(),
        }
    }
}

/// What the wire did to one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum WireFault {
    Lost,
    Corrupted(Corruption),
}

/// A [`MotorBus`] over simulated A1 firmware and a [`JointPlant`].
pub struct SimBus<P: JointPlant> {
    config: SimConfig,
    plant: P,
    firmware: Vec<Firmware>,
    table: MotorTable,
    state: Lifecycle,
    rng: ChaCha8Rng,
    substeps: usize,
    ticks: u64,
    torques_nm: Vec<f64>,
    tap: Option<WireTap>,
    wire_faults: WireFaults,
    fault_rng: ChaCha8Rng,
    wire_stats: WireStats,
}

/// Mixed into the seed of the fault stream, so it differs from the noise stream.
const FAULT_STREAM: u64 = 0xFA17_5EED_0000_0001;

impl<P: JointPlant> SimBus<P> {
    /// A simulation of `config.motors` driving `plant`.
    pub fn new(config: SimConfig, plant: P) -> Result<Self, SimError> {
        let ratio = config.model.firmware_rate_hz / config.control_rate_hz;
        if !(ratio.is_finite() && ratio >= 1.0 && (ratio - ratio.round()).abs() < 1e-9) {
            return Err(SimError::Rates {
                control_rate_hz: config.control_rate_hz,
                firmware_rate_hz: config.model.firmware_rate_hz,
            });
        }
        if config.bus_count == 0 || config.bus_count > MAX_BUSES || config.bitrate_bps == 0 {
            return Err(SimError::Buses {
                bus_count: config.bus_count,
                bitrate_bps: config.bitrate_bps,
            });
        }
        for (i, m) in config.motors.iter().enumerate() {
            let misplaced = |reason| SimError::Motor {
                motor: m.spec.id,
                bus: m.spec.bus,
                joint: m.joint,
                reason,
            };
            if m.spec.bus >= config.bus_count {
                return Err(misplaced("no such bus"));
            }
            if m.joint >= plant.joint_count() {
                return Err(misplaced("no such joint"));
            }
            let earlier = &config.motors[..i];
            if earlier.iter().any(|o| o.spec.id == m.spec.id) {
                return Err(misplaced("motor id used twice"));
            }
            if earlier.iter().any(|o| o.joint == m.joint) {
                return Err(misplaced("joint driven twice"));
            }
        }
        let firmware = config
            .motors
            .iter()
            .map(|m| Firmware::new(*m, &config.model, plant.position_rad(m.joint)))
            .collect();
        Ok(Self {
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            substeps: ratio.round() as usize,
            ticks: 0,
            torques_nm: vec![0.0; plant.joint_count()],
            firmware,
            plant,
            table: MotorTable::default(),
            state: Lifecycle::Unconfigured,
            tap: None,
            wire_faults: WireFaults::NONE,
            fault_rng: ChaCha8Rng::seed_from_u64(config.seed ^ FAULT_STREAM),
            wire_stats: WireStats::default(),
            config,
        })
    }

    /// Fault injection: faults of the wire from the next exchange on (lifecycle frames, enable
    /// and disable, stay clean). Refuses a field out of range, naming it.
    pub fn set_wire_faults(&mut self, faults: WireFaults) -> Result<(), (&'static str, f64)> {
        if let Some(bad) = faults.invalid_field() {
            return Err(bad);
        }
        self.wire_faults = faults;
        Ok(())
    }

    /// What the wire did so far.
    pub fn wire_stats(&self) -> WireStats {
        self.wire_stats
    }

    /// Fault injection: firmware fault bits reported in every reply of `motor` (in addition to
    /// its own over-temperature bit); `ErrorFlags::NONE` clears them. The motor keeps driving.
    /// Returns false if there is no such simulated motor.
    pub fn set_error_flags(&mut self, motor: MotorId, flags: ErrorFlags) -> bool {
        match self.firmware.iter_mut().find(|f| f.motor.spec.id == motor) {
            Some(f) => {
                f.injected_errors = flags;
                true
            }
            None => false,
        }
    }

    /// Fault injection: set the winding temperature of `motor` (a hot motor); the thermal model
    /// and the firmware's over-temperature switch carry on from there. Returns false if there
    /// is no such simulated motor or the temperature is not finite.
    pub fn set_temperature_c(&mut self, motor: MotorId, temperature_c: f64) -> bool {
        if !temperature_c.is_finite() {
            return false;
        }
        match self.firmware.iter_mut().find(|f| f.motor.spec.id == motor) {
            Some(f) => {
                f.temperature_c = temperature_c;
                true
            }
            None => false,
        }
    }

    /// Record every frame on the simulated wire into `tap` (diagnostics, tests).
    pub fn set_tap(&mut self, tap: Option<WireTap>) {
        self.tap = tap;
    }

    /// Simulated time: exchanges so far × control period \[s\].
    pub fn time_s(&self) -> f64 {
        self.ticks as f64 / self.config.control_rate_hz
    }

    /// The plant (to read the true state).
    pub fn plant(&self) -> &P {
        &self.plant
    }

    /// The plant (to set states, loads).
    pub fn plant_mut(&mut self) -> &mut P {
        &mut self.plant
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Fault injection: a silent motor neither receives nor replies (a cut cable).
    /// Returns false if there is no such simulated motor.
    pub fn set_silent(&mut self, motor: MotorId, silent: bool) -> bool {
        match self.firmware.iter_mut().find(|f| f.motor.spec.id == motor) {
            Some(f) => {
                f.silent = silent;
                true
            }
            None => false,
        }
    }

    /// Winding temperature of a simulated motor (unquantized) \[°C\].
    pub fn temperature_c(&self, motor: MotorId) -> Option<f64> {
        self.firmware
            .iter()
            .find(|f| f.motor.spec.id == motor)
            .map(|f| f.temperature_c)
    }

    /// What the wire does to one frame: `None` delivers it intact.
    fn wire_fault(&mut self) -> Option<WireFault> {
        let f = self.wire_faults;
        if f.loss_probability > 0.0 && self.fault_rng.random::<f64>() < f.loss_probability {
            self.wire_stats.lost += 1;
            return Some(WireFault::Lost);
        }
        if f.corrupt_probability > 0.0 && self.fault_rng.random::<f64>() < f.corrupt_probability {
            self.wire_stats.corrupted += 1;
            let damage = match self.fault_rng.random_range(0..3u8) {
                0 => Corruption::Length(self.fault_rng.random_range(0..a1::codec::FRAME_LEN)),
                1 => Corruption::ReservedMode,
                _ => Corruption::Id,
            };
            return Some(WireFault::Corrupted(damage));
        }
        None
    }

    /// Deliver one host frame on `bus`; the decoded reply of the motor that answered. With
    /// `budget` (control traffic) the frame goes through the wire's faults: a command or reply
    /// may be lost, corrupted (then rejected by the firmware's or the host's decoder) or, for a
    /// reply, delayed past `budget` (then missing); without (lifecycle frames) the wire is clean.
    fn transmit(
        &mut self,
        bus: usize,
        frame: &Frame,
        bits: &mut [u32; MAX_BUSES],
        budget: Option<Duration>,
    ) -> Option<Reply> {
        let model = self.config.model;
        // Host → motor. A lost frame still took its bus time (the receiver missed it).
        bits[bus] += frame_bits_exact(frame.id, &frame.data).unwrap_or(0);
        self.record(bus, Direction::ToMotor, frame);
        let fault = budget.and_then(|_| self.wire_fault());
        let (id, data, len) = match fault {
            Some(WireFault::Lost) => return None,
            Some(WireFault::Corrupted(damage)) => corrupt(frame, damage),
            None => (frame.id, frame.data, frame.data.len()),
        };
        let reply_frame = self
            .firmware
            .iter_mut()
            .filter(|f| f.motor.spec.bus == bus)
            .find_map(|f| f.receive(id, &data[..len], &model))?;
        // Motor → host.
        bits[bus] += frame_bits_exact(reply_frame.id, &reply_frame.data).unwrap_or(0);
        self.record(bus, Direction::ToHost, &reply_frame);
        let Some(budget) = budget else {
            return a1::decode_reply(reply_frame.id, &reply_frame.data).ok();
        };
        let (id, data, len) = match self.wire_fault() {
            Some(WireFault::Lost) => return None,
            Some(WireFault::Corrupted(damage)) => corrupt(&reply_frame, damage),
            None => (reply_frame.id, reply_frame.data, reply_frame.data.len()),
        };
        let f = self.wire_faults;
        if f.delay_probability > 0.0 && self.fault_rng.random::<f64>() < f.delay_probability {
            self.wire_stats.delayed += 1;
            // A delay too long for a Duration (validated finite and ≥ 0) is late anyway.
            let delay = Duration::try_from_secs_f64(f.delay_s).unwrap_or(Duration::MAX);
            let arrival =
                bits_to_duration(bits[bus], self.config.bitrate_bps).saturating_add(delay);
            if arrival > budget {
                self.wire_stats.delayed_late += 1;
                return None;
            }
        }
        a1::decode_reply(id, &data[..len]).ok()
    }

    fn record(&self, bus: usize, direction: Direction, frame: &Frame) {
        if let Some(tap) = &self.tap {
            if let Ok(mut log) = tap.lock() {
                log.push(TapEntry {
                    bus,
                    direction,
                    frame: *frame,
                });
            }
        }
    }

    /// Send a special frame to every configured motor; the first silent one, if any.
    fn special_to_all(&mut self, special: Special) -> Result<(), BusError> {
        let mut first_error = None;
        let mut bits = [0; MAX_BUSES];
        let table = self.table;
        for spec in table.iter() {
            let frame = a1::encode_special(spec.id, special);
            match self.transmit(spec.bus, &frame, &mut bits, None) {
                Some(reply) if special == Special::Enable && !reply.enabled => {
                    first_error.get_or_insert(BusError::EnableRefused {
                        motor: spec.id,
                        errors: reply.errors,
                    });
                }
                Some(_) => {}
                None => {
                    first_error.get_or_insert(BusError::MissingReply {
                        motor: spec.id,
                        bus: spec.bus,
                    });
                }
            }
        }
        first_error.map_or(Ok(()), Err)
    }

    /// Advance motors and plant by one control period, then latch received commands.
    fn advance(&mut self) {
        let period = TickPeriod::new(&self.config.model);
        for _ in 0..self.substeps {
            self.torques_nm.fill(0.0);
            for f in &mut self.firmware {
                let j = f.motor.joint;
                let q = self.plant.position_rad(j);
                let dq = self.plant.velocity_rad_s(j);
                self.torques_nm[j] = f.tick(q, dq, &period, &self.config.model, &mut self.rng);
            }
            self.plant.step(&self.torques_nm, period.dt_s);
        }
        for f in &mut self.firmware {
            f.latch();
        }
        self.ticks += 1;
    }
}

impl<P: JointPlant> MotorBus for SimBus<P> {
    fn state(&self) -> Lifecycle {
        self.state
    }

    fn bus_count(&self) -> usize {
        self.config.bus_count
    }

    fn configure(&mut self, motors: &[MotorSpec]) -> Result<(), BusError> {
        if self.state == Lifecycle::Active {
            return Err(BusError::WrongState {
                operation: Operation::Configure,
                state: self.state,
            });
        }
        self.table = MotorTable::new(motors, self.config.bus_count)?;
        self.state = Lifecycle::Configured;
        Ok(())
    }

    fn activate(&mut self) -> Result<(), BusError> {
        if self.state != Lifecycle::Configured {
            return Err(BusError::WrongState {
                operation: Operation::Activate,
                state: self.state,
            });
        }
        if let Err(e) = self.special_to_all(Special::Enable) {
            // Leave nothing half enabled.
            let _ = self.special_to_all(Special::Disable);
            return Err(e);
        }
        self.state = Lifecycle::Active;
        Ok(())
    }

    fn exchange(
        &mut self,
        commands: &[Command],
        replies: &mut [Reply],
        budget: Duration,
    ) -> Result<ExchangeReport, BusError> {
        if self.state != Lifecycle::Active {
            return Err(BusError::NotActive { state: self.state });
        }
        let (frames, buses, saturation) = self.table.prepare(commands, replies)?;
        let mut bits = [0u32; MAX_BUSES];
        let mut missing = None;
        for i in 0..commands.len() {
            match self.transmit(buses[i], &frames[i], &mut bits, Some(budget)) {
                Some(reply) => replies[i] = reply,
                None => {
                    missing.get_or_insert(BusError::MissingReply {
                        motor: commands[i].motor,
                        bus: buses[i],
                    });
                }
            }
        }
        self.advance();
        let busiest = bits.iter().copied().max().unwrap_or(0);
        let bus_time = bits_to_duration(busiest, self.config.bitrate_bps);
        if bus_time > budget {
            return Err(BusError::DeadlineExceeded {
                needed: bus_time,
                budget,
            });
        }
        match missing {
            Some(e) => Err(e),
            None => Ok(ExchangeReport {
                saturation,
                bus_time,
            }),
        }
    }

    fn deactivate(&mut self) -> Result<(), BusError> {
        if self.state == Lifecycle::Unconfigured {
            return Err(BusError::WrongState {
                operation: Operation::Deactivate,
                state: self.state,
            });
        }
        self.state = Lifecycle::Configured;
        self.special_to_all(Special::Disable)
    }
}

impl<P: JointPlant> Drop for SimBus<P> {
    fn drop(&mut self) {
        if self.state == Lifecycle::Active {
            let _ = self.special_to_all(Special::Disable);
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::a1::MotorId;
    use crate::timing::{frame_bits, Stuffing};

    impl Firmware {
        /// [`Firmware::receive`] of an intact frame.
        fn receive_frame(&mut self, frame: &Frame, model: &A1Model) -> Option<Frame> {
            self.receive(frame.id, &frame.data, model)
        }
    }

    const PERIOD: Duration = Duration::from_millis(1);

    fn id(n: u8) -> MotorId {
        MotorId::new(n).unwrap()
    }

    fn joint(load: f64) -> RigidJoint {
        RigidJoint {
            inertia_kg_m2: 0.05,
            damping_nm_s_per_rad: 0.05,
            load_torque_nm: load,
        }
    }

    /// `n` motors with ids 1..=n, joint i on bus i % buses.
    fn sim(n: usize, buses: usize, load: f64, seed: u64) -> SimBus<InertiaDampingPlant> {
        let motors = (0..n)
            .map(|j| SimMotor {
                spec: MotorSpec {
                    bus: j % buses,
                    id: id(j as u8 + 1),
                },
                joint: j,
            })
            .collect();
        let config = SimConfig {
            control_rate_hz: 1000.0,
            bitrate_bps: 1_000_000,
            bus_count: buses,
            motors,
            model: A1Model::default(),
            seed,
        };
        let plant = InertiaDampingPlant::new(vec![joint(load); n]).unwrap();
        SimBus::new(config, plant).unwrap()
    }

    fn active(bus: &mut SimBus<InertiaDampingPlant>) -> Vec<MotorSpec> {
        let specs: Vec<_> = bus.config().motors.iter().map(|m| m.spec).collect();
        bus.configure(&specs).unwrap();
        bus.activate().unwrap();
        specs
    }

    #[test]
    fn plant_step_matches_the_analytic_solution() {
        // From rest under constant u: v(t) = u/b (1 − e^{−bt/J}),
        // q(t) = u/b (t − J/b (1 − e^{−bt/J})). One big step vs the formula at t = 0.3 s.
        let mut p = InertiaDampingPlant::new(vec![RigidJoint {
            inertia_kg_m2: 0.2,
            damping_nm_s_per_rad: 0.5,
            load_torque_nm: -1.0,
        }])
        .unwrap();
        p.step(&[3.0], 0.3);
        let (u, b, j, t): (f64, f64, f64, f64) = (2.0, 0.5, 0.2, 0.3);
        let v = u / b * (1.0 - (-b * t / j).exp());
        let q = u / b * (t - j / b * (1.0 - (-b * t / j).exp()));
        assert!((p.velocity_rad_s(0) - v).abs() < 1e-12);
        assert!((p.position_rad(0) - q).abs() < 1e-12);
        // Splitting the step changes nothing (exact discretization), up to rounding.
        let mut p2 = InertiaDampingPlant::new(vec![RigidJoint {
            inertia_kg_m2: 0.2,
            damping_nm_s_per_rad: 0.5,
            load_torque_nm: -1.0,
        }])
        .unwrap();
        for _ in 0..3000 {
            p2.step(&[3.0], 1e-4);
        }
        assert!((p2.position_rad(0) - q).abs() < 1e-9);
        // No damping: constant acceleration.
        let mut p3 = InertiaDampingPlant::new(vec![RigidJoint {
            inertia_kg_m2: 0.5,
            damping_nm_s_per_rad: 0.0,
            load_torque_nm: 0.0,
        }])
        .unwrap();
        p3.step(&[1.0], 2.0);
        assert_eq!((p3.position_rad(0), p3.velocity_rad_s(0)), (4.0, 4.0));
        assert!(InertiaDampingPlant::new(vec![RigidJoint {
            inertia_kg_m2: 0.0,
            ..joint(0.0)
        }])
        .is_none());
    }

    #[test]
    fn torque_speed_envelope() {
        let m = A1Model::default();
        assert_eq!(m.limit_torque_nm(100.0, 0.0), 33.5);
        assert_eq!(m.limit_torque_nm(100.0, 10.0), 33.5);
        assert!((m.limit_torque_nm(100.0, 15.75) - 16.75).abs() < 1e-12); // halfway down
        assert_eq!(m.limit_torque_nm(100.0, 22.0), 0.0);
        assert_eq!(m.limit_torque_nm(-100.0, 22.0), -33.5); // braking: full torque
        assert!((m.brake_damping_nm_s_per_rad() - 2.803).abs() < 1e-3);
    }

    #[test]
    fn pd_settles_at_the_static_deflection() {
        // Steady state of kp(q* − q) + load = 0 is q = q* + load/kp.
        let (kp, kd, load) = (80.0, 2.0, 4.0);
        let mut bus = sim(1, 1, load, 1);
        active(&mut bus);
        let m = id(1);
        let mut r = [Reply::zeroed(m)];
        for _ in 0..1500 {
            bus.exchange(&[Command::pd(m, 0.3, 0.0, kp, kd, 0.0)], &mut r, PERIOD)
                .unwrap();
        }
        let expected = 0.3 + load / kp;
        // Reply quantum 0.38 mrad; encoder 0.02 mrad; noise-driven torque ripple ≪ 1 mrad.
        assert!(
            (r[0].q_rad - expected).abs() < 1e-3,
            "{} vs {expected}",
            r[0].q_rad
        );
        // Filtered velocity noise is ≈ 0.05 rad/s rms (0.3-count encoder noise
        // differentiated at 10 kHz, 500 Hz low-pass): allow 4σ, and kd·4σ on the torque.
        assert!((r[0].tau_nm + load).abs() < 0.4, "{}", r[0].tau_nm);
        assert!(r[0].dq_rad_s.abs() < 0.2, "{}", r[0].dq_rad_s);
        assert_eq!(r[0].mode, Mode::PositionVelocity);
        assert!(r[0].enabled);
    }

    #[test]
    fn torque_saturates_and_speed_tops_out_at_the_envelope() {
        let mut bus = sim(1, 1, 0.0, 2);
        active(&mut bus);
        let m = id(1);
        let mut r = [Reply::zeroed(m)];
        bus.exchange(&[Command::pd(m, 0.0, 0.0, 0.0, 0.0, 60.0)], &mut r, PERIOD)
            .unwrap();
        let mut peak_tau: f64 = 0.0;
        for _ in 0..3000 {
            let rep = bus
                .exchange(&[Command::pd(m, 0.0, 0.0, 0.0, 0.0, 60.0)], &mut r, PERIOD)
                .unwrap();
            assert!(rep.saturation[0].contains(a1::Field::TauFf));
            peak_tau = peak_tau.max(r[0].tau_nm);
        }
        assert!(peak_tau <= 33.5 && peak_tau > 33.4, "{peak_tau}");
        // Top speed: envelope torque = plant friction b·ω: 33.5(21 − ω)/10.5 = 0.05 ω.
        let w = 21.0 * 33.5 / 10.5 / (33.5 / 10.5 + 0.05);
        let v = bus.plant().velocity_rad_s(0);
        assert!((v - w).abs() < 0.05, "{v} vs {w}");
    }

    #[test]
    fn one_tick_of_latency() {
        let mut bus = sim(1, 1, 0.0, 3);
        active(&mut bus);
        let m = id(1);
        let mut r = [Reply::zeroed(m)];
        let hold = Command::pd(m, 0.0, 0.0, 50.0, 1.0, 0.0);
        for _ in 0..200 {
            bus.exchange(&[hold], &mut r, PERIOD).unwrap();
        }
        let p_before = bus.plant().position_rad(0);
        let step = Command::pd(m, 0.5, 0.0, 50.0, 1.0, 0.0);
        bus.exchange(&[step], &mut r, PERIOD).unwrap();
        let (p0, q0) = (bus.plant().position_rad(0), r[0].q_rad);
        bus.exchange(&[step], &mut r, PERIOD).unwrap();
        let (p1, q1) = (bus.plant().position_rad(0), r[0].q_rad);
        // The period after exchange k still runs the old command (latency): the joint
        // holds (jitter ≪ 0.02 mrad). The next period runs the step: 25 N·m on
        // 0.05 kg·m² moves ½·500·(1 ms)² ≈ 0.25 mrad.
        assert!((p0 - p_before).abs() < 2e-5, "{p0} vs {p_before}");
        assert!(p1 - p0 > 1.5e-4, "{p1} vs {p0}");
        // Reply k+1 is sampled before the step acts: unchanged within a reply quantum.
        assert!((q1 - q0).abs() <= a1::codec::REPLY_Q.quantum() + 1e-12);
    }

    #[test]
    fn temperature_follows_the_first_order_model_and_trips() {
        let mut bus = sim(1, 1, 0.0, 4);
        bus.config.model.thermal_capacitance_j_per_k = 0.6; // time constant 0.9 s
        bus.plant_mut().set_load(0, 15.0);
        active(&mut bus);
        let m = id(1);
        let mut r = [Reply::zeroed(m)];
        let model = bus.config().model;
        // Holding a 15 N·m load: loss 15²/(9.1·0.092)²·0.25 = 80 W, steady 145 °C.
        let p = model.copper_loss_w(15.0);
        let steady = model.ambient_c + p * model.thermal_resistance_k_per_w;
        let tau_th = model.thermal_resistance_k_per_w * model.thermal_capacitance_j_per_k;
        let hold = Command::pd(m, 0.0, 0.0, 200.0, 3.0, 0.0);
        for _ in 0..300 {
            bus.exchange(&[hold], &mut r, PERIOD).unwrap();
        }
        // After 0.3 s (torque settles in a few ms, so ~0.3 s of full loss).
        let t = 0.3;
        let analytic = steady + (model.ambient_c - steady) * (-t / tau_th).exp();
        let sim_t = bus.temperature_c(m).unwrap();
        assert!((sim_t - analytic).abs() < 1.0, "{sim_t} vs {analytic}");
        assert!((r[0].temperature_c - sim_t).abs() <= 0.5 + 1e-9);
        assert!(r[0].errors.is_empty());
        // Keep holding until it trips: flag set, motor brakes (no holding torque).
        let mut tripped = false;
        for _ in 0..2000 {
            bus.exchange(&[hold], &mut r, PERIOD).unwrap();
            if r[0].errors.contains(ErrorFlags::OVER_TEMPERATURE) {
                tripped = true;
                break;
            }
        }
        assert!(tripped);
        bus.exchange(&[hold], &mut r, PERIOD).unwrap();
        assert_eq!(r[0].tau_nm, 0.0, "output off while over temperature");
        // Cools below the release threshold, then obeys again.
        let mut released = false;
        for _ in 0..5000 {
            bus.exchange(&[hold], &mut r, PERIOD).unwrap();
            if r[0].errors.is_empty() {
                released = true;
                break;
            }
        }
        assert!(released);
        assert!(r[0].temperature_c < model.recover_temperature_c + 1.0);
    }

    #[test]
    fn same_seed_is_bit_identical_and_another_seed_is_not() {
        let run = |seed| {
            let mut bus = sim(2, 2, 1.0, seed);
            active(&mut bus);
            let cmds = [
                Command::pd(id(1), 0.2, 0.0, 40.0, 1.0, 0.0),
                Command::pd(id(2), -0.1, 0.0, 30.0, 0.8, 0.5),
            ];
            let mut r = [Reply::zeroed(id(1)); 2];
            let mut trace = Vec::new();
            for _ in 0..500 {
                bus.exchange(&cmds, &mut r, PERIOD).unwrap();
                trace.extend(
                    r.iter()
                        .flat_map(|x| [x.q_rad.to_bits(), x.dq_rad_s.to_bits()]),
                );
            }
            trace.push(bus.plant().position_rad(0).to_bits());
            trace
        };
        assert_eq!(run(11), run(11));
        assert_ne!(run(11), run(12));
    }

    #[test]
    fn silent_motor_mid_run_is_named_and_others_still_reply() {
        let mut bus = sim(3, 1, 0.0, 5);
        active(&mut bus);
        let cmds = [1, 2, 3].map(|n| Command::damping(id(n), 1.0));
        let mut r = [Reply::zeroed(id(9)); 3];
        bus.exchange(&cmds, &mut r, PERIOD).unwrap();
        assert!(bus.set_silent(id(2), true));
        r = [Reply::zeroed(id(9)); 3];
        assert_eq!(
            bus.exchange(&cmds, &mut r, PERIOD),
            Err(BusError::MissingReply {
                motor: id(2),
                bus: 0
            })
        );
        assert_eq!(r[0].motor, id(1));
        assert_eq!(r[2].motor, id(3));
        assert_eq!(r[1].motor, id(9), "untouched slot");
    }

    #[test]
    fn every_corruption_is_rejected_by_the_decoders() {
        let m = id(5);
        let reply = encode_reply(&Reply::zeroed(m)).unwrap().frame;
        let command = a1::encode_command(&Command::pd(m, 0.1, 0.0, 10.0, 0.5, 0.0))
            .unwrap()
            .frame;
        let special = a1::encode_special(m, Special::Enable);
        let damages = [
            Corruption::Length(0),
            Corruption::Length(7),
            Corruption::ReservedMode,
            Corruption::Id,
        ];
        for damage in damages {
            let (id, data, len) = corrupt(&reply, damage);
            assert!(a1::decode_reply(id, &data[..len]).is_err(), "{damage:?}");
            for host in [command, special] {
                let (id, data, len) = corrupt(&host, damage);
                assert!(decode_host_frame(id, &data[..len]).is_err(), "{damage:?}");
            }
        }
        // Length(n) never delivers all 8 bytes.
        assert_eq!(corrupt(&reply, Corruption::Length(99)).2, 7);
    }

    #[test]
    fn wire_loss_matches_its_probability_and_every_lost_frame_is_a_missing_reply() {
        let mut bus = sim(2, 2, 0.0, 21);
        active(&mut bus);
        let p = 0.1;
        bus.set_wire_faults(WireFaults {
            loss_probability: p,
            corrupt_probability: p,
            ..WireFaults::NONE
        })
        .unwrap();
        let cmds = [1, 2].map(|n| Command::damping(id(n), 1.0));
        let mut r = [Reply::zeroed(id(1)); 2];
        let n = 5_000;
        let mut missing = 0u64;
        for _ in 0..n {
            r.iter_mut().for_each(|x| x.q_rad = f64::NAN);
            let result = bus.exchange(&cmds, &mut r, PERIOD);
            let gone = r.iter().filter(|x| x.q_rad.is_nan()).count() as u64;
            assert_eq!(result.is_err(), gone > 0);
            missing += gone;
        }
        let stats = bus.wire_stats();
        // Each lost or corrupted frame costs exactly one reply (a lost command has no reply).
        assert_eq!(missing, stats.lost + stats.corrupted);
        // P(reply missing) = 1 − (1 − p)⁴ (command and reply, each lost or corrupted) = 0.344;
        // over 10 000 replies the standard error is 0.005: allow 4σ.
        let rate = missing as f64 / (2 * n) as f64;
        let expected = 1.0 - (1.0 - p).powi(4);
        assert!((rate - expected).abs() < 0.02, "{rate} vs {expected}");
        // Seeded: the same seed loses the same frames.
        let run = |seed| {
            let mut bus = sim(2, 2, 0.0, seed);
            active(&mut bus);
            bus.set_wire_faults(WireFaults {
                loss_probability: 0.05,
                ..WireFaults::NONE
            })
            .unwrap();
            let mut r = [Reply::zeroed(id(1)); 2];
            (0..300)
                .map(|_| bus.exchange(&cmds, &mut r, PERIOD).is_ok())
                .collect::<Vec<_>>()
        };
        assert_eq!(run(3), run(3));
        assert_ne!(run(3), run(4));
    }

    #[test]
    fn a_delayed_reply_is_missing_only_past_the_budget() {
        let cmds = [Command::damping(id(1), 1.0)];
        // 1e300 s does not fit a Duration: late, not a panic.
        for (delay_s, late) in [(0.5e-3, false), (1.5e-3, true), (1e300, true)] {
            let mut bus = sim(1, 1, 0.0, 22);
            active(&mut bus);
            bus.set_wire_faults(WireFaults {
                delay_probability: 1.0,
                delay_s,
                ..WireFaults::NONE
            })
            .unwrap();
            let mut r = [Reply::zeroed(id(1))];
            // One exchange is ≈ 0.22 ms of bus time: 0.22 + 0.5 < 1 ms, 0.22 + 1.5 > 1 ms.
            let result = bus.exchange(&cmds, &mut r, PERIOD);
            assert_eq!(result.is_err(), late, "delay {delay_s}");
            let stats = bus.wire_stats();
            assert_eq!(stats.delayed, 1);
            assert_eq!(stats.delayed_late, u64::from(late));
        }
        let mut bus = sim(1, 1, 0.0, 22);
        let bad = WireFaults {
            loss_probability: 1.5,
            ..WireFaults::NONE
        };
        assert_eq!(bus.set_wire_faults(bad), Err(("loss_probability", 1.5)));
    }

    #[test]
    fn injected_error_flags_and_temperature_show_in_the_replies() {
        let mut bus = sim(2, 1, 0.0, 23);
        active(&mut bus);
        let cmds = [1, 2].map(|n| Command::damping(id(n), 1.0));
        let mut r = [Reply::zeroed(id(1)); 2];
        assert!(bus.set_error_flags(id(2), ErrorFlags::ENCODER));
        assert!(bus.set_temperature_c(id(1), 87.0));
        assert!(!bus.set_temperature_c(id(9), 87.0));
        bus.exchange(&cmds, &mut r, PERIOD).unwrap();
        assert_eq!(r[1].errors, ErrorFlags::ENCODER);
        assert!(r[0].errors.is_empty());
        // Reply quantum of the temperature is 1 °C; the winding cools a little in 1 ms.
        assert!(
            (r[0].temperature_c - 87.0).abs() <= 1.0,
            "{}",
            r[0].temperature_c
        );
        bus.set_error_flags(id(2), ErrorFlags::NONE);
        bus.exchange(&cmds, &mut r, PERIOD).unwrap();
        assert!(r[1].errors.is_empty());
    }

    #[test]
    fn bus_time_is_modelled_and_overload_misses_the_deadline() {
        // 2 motors per bus on 2 buses: busiest bus carries 4 frames.
        let mut bus = sim(4, 2, 0.0, 6);
        active(&mut bus);
        let cmds = [1, 2, 3, 4].map(|n| Command::pd(id(n), 0.1, 0.0, 20.0, 0.5, 0.0));
        let mut r = [Reply::zeroed(id(1)); 4];
        let rep = bus.exchange(&cmds, &mut r, PERIOD).unwrap();
        let lo = Duration::from_micros(4 * u64::from(frame_bits(8, Stuffing::None)));
        let hi = Duration::from_micros(4 * u64::from(frame_bits(8, Stuffing::WorstCase)));
        assert!(
            rep.bus_time >= lo && rep.bus_time <= hi,
            "{:?}",
            rep.bus_time
        );
        // 5 motors on one bus need ≥ 5 × 222 µs > 1 ms.
        let mut bus = sim(5, 1, 0.0, 6);
        active(&mut bus);
        let cmds = [1, 2, 3, 4, 5].map(|n| Command::damping(id(n), 1.0));
        let mut r = [Reply::zeroed(id(1)); 5];
        match bus.exchange(&cmds, &mut r, PERIOD) {
            Err(BusError::DeadlineExceeded { needed, budget }) => {
                assert!(needed >= Duration::from_micros(5 * 222));
                assert_eq!(budget, PERIOD);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn set_zero_and_malformed_frames_in_the_firmware() {
        let model = A1Model::default();
        let motor = SimMotor {
            spec: MotorSpec { bus: 0, id: id(7) },
            joint: 0,
        };
        let mut fw = Firmware::new(motor, &model, 1.234);
        let reply = |f: Option<Frame>| {
            let f = f.unwrap();
            a1::decode_reply(f.id, &f.data).unwrap()
        };
        let r = reply(fw.receive_frame(&a1::encode_special(id(7), Special::SetZero), &model));
        assert!(
            r.q_rad.abs() <= a1::codec::REPLY_Q.quantum() / 2.0,
            "{}",
            r.q_rad
        );
        assert!(!r.enabled);
        // Disabled: commands are acknowledged but ignored.
        let cmd = a1::encode_command(&Command::pd(id(7), 1.0, 0.0, 10.0, 0.0, 0.0)).unwrap();
        assert_eq!(
            reply(fw.receive_frame(&cmd.frame, &model)).mode,
            Mode::Damping
        );
        assert!(fw.inbox.is_none());
        let r = reply(fw.receive_frame(&a1::encode_special(id(7), Special::Enable), &model));
        assert!(r.enabled);
        fw.receive_frame(&cmd.frame, &model);
        assert!(fw.inbox.is_some());
        // Another motor's frame, a bad opcode, a reserved mode: no reply.
        assert!(fw
            .receive_frame(&a1::encode_special(id(8), Special::Disable), &model)
            .is_none());
        let mut bad = a1::encode_special(id(7), Special::Disable);
        bad.data[0] = 0x55;
        assert!(fw.receive_frame(&bad, &model).is_none());
        let mut bad = cmd.frame;
        bad.data[7] |= 0xC0;
        assert!(fw.receive_frame(&bad, &model).is_none());
    }

    #[test]
    fn config_errors_name_the_culprit() {
        let plant = InertiaDampingPlant::new(vec![joint(0.0)]).unwrap();
        let mut config = SimConfig {
            control_rate_hz: 1000.0,
            bitrate_bps: 1_000_000,
            bus_count: 1,
            motors: vec![SimMotor {
                spec: MotorSpec { bus: 0, id: id(1) },
                joint: 3,
            }],
            model: A1Model::default(),
            seed: 0,
        };
        let e = SimBus::new(config.clone(), plant.clone()).err().unwrap();
        assert!(e.to_string().contains("no such joint"), "{e}");
        config.motors[0].joint = 0;
        config.control_rate_hz = 3000.0;
        assert!(matches!(
            SimBus::new(config, plant),
            Err(SimError::Rates { .. })
        ));
    }
}
