//! The simulated A1 motor firmware: the motor model ([`A1Model`]) and the firmware that runs it
//! at every 10 kHz tick (encoder, PD, torque–speed envelope, heat, lifecycle frames).
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
//! * Mounting ([`EncoderMount`], a fault for calibration tests): the motor may be mounted on its
//!   joint the other way round and with its zero elsewhere: it reads and commands the motor
//!   angle `m = direction · (q − joint_rad_at_zero)` and drives the joint with
//!   `direction · τ_m`. Default: `m = q` (how the runtime's identity calibration sees it).

use crate::a1::{
    self, decode_host_frame, encode_reply, Command, ErrorFlags, Frame, HostFrame, Mode, Reply,
    Special,
};
use crate::bus::MotorSpec;
use crate::noise::gaussian;
use rand_chacha::ChaCha8Rng;

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

/// How a simulated motor sits on its joint: `m = direction · (q − joint_rad_at_zero)` (motor
/// angle `m`, joint angle `q`), the joint torque `direction · τ_m`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncoderMount {
    /// +1, or −1 for a motor mounted the other way round.
    pub direction: f64,
    /// The joint angle at which the motor reads zero \[rad\].
    pub joint_rad_at_zero: f64,
}

impl Default for EncoderMount {
    fn default() -> Self {
        Self {
            direction: 1.0,
            joint_rad_at_zero: 0.0,
        }
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

#[derive(Debug, Clone)]
pub(super) struct Firmware {
    pub(super) motor: SimMotor,
    enabled: bool,
    active: Command,
    inbox: Option<Command>,
    pub(super) silent: bool,
    zero_offset_rad: f64,
    pub(super) mount: EncoderMount,
    prev_counts: i64,
    q_abs_rad: f64,
    dq_filtered_rad_s: f64,
    tau_nm: f64,
    pub(super) temperature_c: f64,
    overheated: bool,
    pub(super) injected_errors: ErrorFlags,
}

impl Firmware {
    pub(super) fn new(motor: SimMotor, model: &A1Model, q_rad: f64) -> Self {
        let counts = (q_rad / model.joint_rad_per_count()).round() as i64;
        Self {
            motor,
            enabled: false,
            active: Command::damping(motor.spec.id, model.disable_damping_nm_s_per_rad),
            inbox: None,
            silent: false,
            zero_offset_rad: 0.0,
            mount: EncoderMount::default(),
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
    pub(super) fn receive(&mut self, id: u32, data: &[u8], model: &A1Model) -> Option<Frame> {
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
                Special::SetZero => self.zero_offset_rad = self.motor_abs_rad(),
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
            q_rad: self.motor_abs_rad() - self.zero_offset_rad,
            dq_rad_s: self.mount.direction * self.dq_filtered_rad_s,
            tau_nm: self.tau_nm,
            temperature_c: self.temperature_c,
            errors,
        }
    }

    /// One firmware tick: measure, compute and limit the torque, heat up. Returns the
    /// joint torque to hold over the tick.
    pub(super) fn tick(
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

        // Motor side (the mount): the PD, the reply and the torque limit see the motor's angle.
        let direction = self.mount.direction;
        let q_hat = self.motor_abs_rad() - self.zero_offset_rad;
        let dq_hat = direction * self.dq_filtered_rad_s;
        let dq_rad_s = direction * dq_rad_s;
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
        direction * self.tau_nm
    }

    /// The motor's angle before any *set zero*: the joint angle through the mount \[rad\].
    fn motor_abs_rad(&self) -> f64 {
        self.mount.direction * (self.q_abs_rad - self.mount.joint_rad_at_zero)
    }

    pub(super) fn latch(&mut self) {
        if let Some(command) = self.inbox.take() {
            self.active = command;
        }
    }
}

/// The firmware tick and the discrete-time factors that depend only on it and the model.
pub(super) struct TickPeriod {
    pub(super) dt_s: f64,
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
    pub(super) fn new(model: &A1Model) -> Self {
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

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::a1::MotorId;

    impl Firmware {
        /// [`Firmware::receive`] of an intact frame.
        fn receive_frame(&mut self, frame: &Frame, model: &A1Model) -> Option<Frame> {
            self.receive(frame.id, &frame.data, model)
        }
    }

    fn id(n: u8) -> MotorId {
        MotorId::new(n).unwrap()
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
    fn a_flipped_mount_reads_the_motor_angle_and_drives_the_joint_the_other_way() {
        let model = A1Model::default();
        let motor = SimMotor {
            spec: MotorSpec { bus: 0, id: id(3) },
            joint: 0,
        };
        let mut fw = Firmware::new(motor, &model, 0.8);
        fw.mount = EncoderMount {
            direction: -1.0,
            joint_rad_at_zero: 0.3,
        };
        let period = TickPeriod::new(&model);
        let mut rng = <ChaCha8Rng as rand::SeedableRng>::seed_from_u64(1);
        fw.tick(0.8, 0.0, &period, &model, &mut rng);
        // m = −(q − 0.3) = −0.5 rad.
        let q = fw.reply().q_rad;
        assert!((q + 0.5).abs() < 1e-3, "{q}");
        // A motor-side push toward +m drives the joint toward −q.
        fw.enabled = true;
        fw.active = Command::pd(id(3), 0.0, 0.0, 0.0, 0.0, 5.0);
        let joint_nm = fw.tick(0.8, 0.0, &period, &model, &mut rng);
        assert_eq!(joint_nm, -5.0);
        assert_eq!(fw.reply().tau_nm, 5.0);
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
}
