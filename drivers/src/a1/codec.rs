//! Sans-IO encoder and decoder for A1-over-CAN frames (layout in the [module docs](super)).
//!
//! Nothing here touches a socket, allocates or formats a string: a [`Command`] becomes a
//! [`Frame`] (`id` + `[u8; 8]`), and bytes that came off a bus become a typed [`Reply`] or a
//! typed [`DecodeError`].

use thiserror::Error;

/// Gear ratio of the A1 planetary reduction (motor turns per output turn).
pub const GEAR_RATIO: f64 = 9.1;
/// Peak output torque of the A1, joint side \[N·m\].
pub const MAX_TORQUE_NM: f64 = 33.5;
/// No-load output speed of the A1, joint side \[rad/s\].
pub const MAX_SPEED_RAD_S: f64 = 21.0;

/// Largest motor id: ids live in the low 7 bits of the CAN id.
pub const MAX_MOTOR_ID: u8 = 0x7F;
/// Base CAN id of special frames (enable / disable / set zero): `0x080 + motor id`.
pub const SPECIAL_ID_BASE: u32 = 0x080;
/// Base CAN id of host → motor command frames: `0x100 + motor id`.
pub const COMMAND_ID_BASE: u32 = 0x100;
/// Base CAN id of motor → host reply frames: `0x180 + motor id`.
pub const REPLY_ID_BASE: u32 = 0x180;
/// Every A1 frame carries exactly this many data bytes.
pub const FRAME_LEN: usize = 8;

/// Address of one motor on a CAN bus, `0..=`[`MAX_MOTOR_ID`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MotorId(u8);

impl MotorId {
    /// A motor id, or `None` if `id > MAX_MOTOR_ID`.
    pub const fn new(id: u8) -> Option<Self> {
        if id <= MAX_MOTOR_ID {
            Some(Self(id))
        } else {
            None
        }
    }

    /// The raw id, `0..=MAX_MOTOR_ID`.
    pub const fn get(self) -> u8 {
        self.0
    }

    /// CAN id of command frames to this motor.
    pub const fn command_id(self) -> u32 {
        COMMAND_ID_BASE + self.0 as u32
    }

    /// CAN id of reply frames from this motor.
    pub const fn reply_id(self) -> u32 {
        REPLY_ID_BASE + self.0 as u32
    }

    /// CAN id of special frames (enable / disable / set zero) to this motor.
    pub const fn special_id(self) -> u32 {
        SPECIAL_ID_BASE + self.0 as u32
    }
}

impl core::fmt::Display for MotorId {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "motor {}", self.0)
    }
}

/// What the motor does with a command frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Windings shorted, no drive: passive back-EMF braking. Only `mode` is used.
    Brake = 0,
    /// Damping: `tau = kd * (0 - dq)`; `q_des`, `dq_des`, `kp` and `tau_ff` are ignored.
    Damping = 1,
    /// Position–velocity PD with feed-forward:
    /// `tau = kp (q_des - q) + kd (dq_des - dq) + tau_ff`.
    PositionVelocity = 2,
}

impl Mode {
    /// The 2-bit wire value.
    pub const fn to_bits(self) -> u8 {
        self as u8
    }

    /// Mode from its 2-bit wire value; `3` is reserved and yields `None`.
    pub const fn from_bits(bits: u8) -> Option<Self> {
        match bits {
            0 => Some(Self::Brake),
            1 => Some(Self::Damping),
            2 => Some(Self::PositionVelocity),
            _ => None,
        }
    }
}

/// Special frames, sent on `SPECIAL_ID_BASE + motor id`; byte 0 is the opcode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Special {
    /// Leave the disabled state: the motor starts obeying command frames (it stays in
    /// damping until the first command).
    Enable = 1,
    /// Go to the disabled state: damping with the firmware's default gain, commands ignored.
    Disable = 2,
    /// Declare the present output position to be `q = 0`.
    SetZero = 3,
}

impl Special {
    /// Opcode byte.
    pub const fn opcode(self) -> u8 {
        self as u8
    }

    /// Special from its opcode byte.
    pub const fn from_opcode(opcode: u8) -> Option<Self> {
        match opcode {
            1 => Some(Self::Enable),
            2 => Some(Self::Disable),
            3 => Some(Self::SetZero),
            _ => None,
        }
    }
}

/// One numeric field of a frame (used to name saturated or NaN fields).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Field {
    /// Command: desired position.
    QDes = 0,
    /// Command: desired velocity.
    DqDes = 1,
    /// Command: stiffness.
    Kp = 2,
    /// Command: damping gain.
    Kd = 3,
    /// Command: feed-forward torque.
    TauFf = 4,
    /// Reply: measured position.
    Q = 5,
    /// Reply: measured velocity.
    Dq = 6,
    /// Reply: estimated output torque.
    Tau = 7,
    /// Reply: winding temperature.
    Temperature = 8,
}

impl core::fmt::Display for Field {
    /// The field's name as in [`Command`] and [`Reply`], with its unit.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::QDes => "q_des_rad",
            Self::DqDes => "dq_des_rad_s",
            Self::Kp => "kp_nm_per_rad",
            Self::Kd => "kd_nm_s_per_rad",
            Self::TauFf => "tau_ff_nm",
            Self::Q => "q_rad",
            Self::Dq => "dq_rad_s",
            Self::Tau => "tau_nm",
            Self::Temperature => "temperature_c",
        })
    }
}

/// Fixed-point layout of one field: `physical = raw * quantum + min`, with
/// `quantum = (max - min) / 2^bits`, raw unsigned, little-endian ("Intel") bit numbering
/// in the 64-bit payload.
///
/// The representable values are `min ..= max - quantum`; with a symmetric range, zero is
/// exactly `raw = 2^(bits-1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldSpec {
    /// Which field.
    pub field: Field,
    /// Position of the least significant bit in the payload (bit 0 = LSB of byte 0).
    pub start_bit: u32,
    /// Width in bits.
    pub bits: u32,
    /// Physical value of `raw = 0`.
    pub min: f64,
    /// Upper end of the range: one quantum above the largest representable value.
    pub max: f64,
}

impl FieldSpec {
    /// Size of one step \[field unit\].
    pub fn quantum(&self) -> f64 {
        (self.max - self.min) / (1u64 << self.bits) as f64
    }

    /// Largest raw value.
    pub const fn raw_max(&self) -> u64 {
        (1u64 << self.bits) - 1
    }

    /// Largest representable physical value.
    pub fn max_representable(&self) -> f64 {
        self.decode_raw(self.raw_max())
    }

    /// Raw value nearest `x`, saturated to the field; `(raw, saturated)`. NaN must be
    /// rejected by the caller.
    pub fn encode_raw(&self, x: f64) -> (u64, bool) {
        let steps = ((x - self.min) / self.quantum()).round();
        if steps < 0.0 {
            (0, true)
        } else if steps > self.raw_max() as f64 {
            (self.raw_max(), true)
        } else {
            // In range and integral: the cast is exact.
            (steps as u64, false)
        }
    }

    /// Physical value of a raw value.
    pub fn decode_raw(&self, raw: u64) -> f64 {
        raw as f64 * self.quantum() + self.min
    }

    fn mask(&self) -> u64 {
        self.raw_max() << self.start_bit
    }

    fn extract(&self, payload: u64) -> u64 {
        (payload >> self.start_bit) & self.raw_max()
    }

    fn insert(&self, payload: u64, raw: u64) -> u64 {
        (payload & !self.mask()) | ((raw & self.raw_max()) << self.start_bit)
    }
}

const fn spec(field: Field, start_bit: u32, bits: u32, min: f64, max: f64) -> FieldSpec {
    FieldSpec {
        field,
        start_bit,
        bits,
        min,
        max,
    }
}

/// Position range, both directions \[rad\]: about ±2 output turns, beyond every ADAM joint
/// limit (all within ±π), 0.38 mrad per step.
pub const Q_RANGE_RAD: f64 = 12.5;
/// Stiffness range upper end \[N·m/rad\]: 0.12 N·m/rad per step.
pub const KP_MAX_NM_PER_RAD: f64 = 500.0;
/// Damping-gain range upper end \[N·m·s/rad\]: 0.0098 N·m·s/rad per step.
pub const KD_MAX_NM_S_PER_RAD: f64 = 10.0;

/// Command `q_des` \[rad\].
pub const CMD_Q_DES: FieldSpec = spec(Field::QDes, 0, 16, -Q_RANGE_RAD, Q_RANGE_RAD);
/// Command `dq_des` \[rad/s\].
pub const CMD_DQ_DES: FieldSpec = spec(Field::DqDes, 16, 12, -MAX_SPEED_RAD_S, MAX_SPEED_RAD_S);
/// Command `kp` \[N·m/rad\].
pub const CMD_KP: FieldSpec = spec(Field::Kp, 28, 12, 0.0, KP_MAX_NM_PER_RAD);
/// Command `kd` \[N·m·s/rad\].
pub const CMD_KD: FieldSpec = spec(Field::Kd, 40, 10, 0.0, KD_MAX_NM_S_PER_RAD);
/// Command `tau_ff` \[N·m\].
pub const CMD_TAU_FF: FieldSpec = spec(Field::TauFf, 50, 12, -MAX_TORQUE_NM, MAX_TORQUE_NM);
/// Command mode: bits 62–63.
pub const CMD_MODE_START_BIT: u32 = 62;

/// Reply `q` \[rad\].
pub const REPLY_Q: FieldSpec = spec(Field::Q, 0, 16, -Q_RANGE_RAD, Q_RANGE_RAD);
/// Reply `dq` \[rad/s\].
pub const REPLY_DQ: FieldSpec = spec(Field::Dq, 16, 12, -MAX_SPEED_RAD_S, MAX_SPEED_RAD_S);
/// Reply `tau` \[N·m\].
pub const REPLY_TAU: FieldSpec = spec(Field::Tau, 28, 12, -MAX_TORQUE_NM, MAX_TORQUE_NM);
/// Reply temperature \[°C\]: 1 °C per step from −40 °C.
pub const REPLY_TEMPERATURE: FieldSpec = spec(Field::Temperature, 40, 8, -40.0, 216.0);
/// Reply error flags: bits 48–55.
pub const REPLY_ERRORS_START_BIT: u32 = 48;
/// Reply mode echo: bits 56–57.
pub const REPLY_MODE_START_BIT: u32 = 56;
/// Reply enabled flag: bit 58.
pub const REPLY_ENABLED_BIT: u32 = 58;

/// The five numeric fields of a command frame, in wire order.
pub const COMMAND_FIELDS: [FieldSpec; 5] = [CMD_Q_DES, CMD_DQ_DES, CMD_KP, CMD_KD, CMD_TAU_FF];
/// The four numeric fields of a reply frame, in wire order.
pub const REPLY_FIELDS: [FieldSpec; 4] = [REPLY_Q, REPLY_DQ, REPLY_TAU, REPLY_TEMPERATURE];

/// A raw classic CAN frame as the codec sees it: 11-bit standard id and 8 data bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Frame {
    /// 11-bit standard identifier.
    pub id: u32,
    /// Payload (always 8 bytes for A1 frames).
    pub data: [u8; FRAME_LEN],
}

/// Host → motor command (joint-side units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Addressed motor.
    pub motor: MotorId,
    /// Control mode.
    pub mode: Mode,
    /// Desired position \[rad\].
    pub q_des_rad: f64,
    /// Desired velocity \[rad/s\].
    pub dq_des_rad_s: f64,
    /// Stiffness \[N·m/rad\].
    pub kp_nm_per_rad: f64,
    /// Damping gain \[N·m·s/rad\].
    pub kd_nm_s_per_rad: f64,
    /// Feed-forward torque \[N·m\].
    pub tau_ff_nm: f64,
}

impl Command {
    /// Passive braking (windings shorted).
    pub const fn brake(motor: MotorId) -> Self {
        Self {
            motor,
            mode: Mode::Brake,
            q_des_rad: 0.0,
            dq_des_rad_s: 0.0,
            kp_nm_per_rad: 0.0,
            kd_nm_s_per_rad: 0.0,
            tau_ff_nm: 0.0,
        }
    }

    /// Pure damping `tau = -kd dq`.
    pub const fn damping(motor: MotorId, kd_nm_s_per_rad: f64) -> Self {
        Self {
            mode: Mode::Damping,
            kd_nm_s_per_rad,
            ..Self::brake(motor)
        }
    }

    /// Position–velocity PD with feed-forward torque.
    pub const fn pd(
        motor: MotorId,
        q_des_rad: f64,
        dq_des_rad_s: f64,
        kp_nm_per_rad: f64,
        kd_nm_s_per_rad: f64,
        tau_ff_nm: f64,
    ) -> Self {
        Self {
            motor,
            mode: Mode::PositionVelocity,
            q_des_rad,
            dq_des_rad_s,
            kp_nm_per_rad,
            kd_nm_s_per_rad,
            tau_ff_nm,
        }
    }

    fn field_values(&self) -> [f64; 5] {
        [
            self.q_des_rad,
            self.dq_des_rad_s,
            self.kp_nm_per_rad,
            self.kd_nm_s_per_rad,
            self.tau_ff_nm,
        ]
    }
}

/// Motor fault bits carried in every reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ErrorFlags(pub u8);

impl ErrorFlags {
    /// No fault.
    pub const NONE: Self = Self(0);
    /// Winding temperature above the firmware limit; the motor has stopped driving.
    pub const OVER_TEMPERATURE: Self = Self(1 << 0);
    /// Phase current above the firmware limit.
    pub const OVER_CURRENT: Self = Self(1 << 1);
    /// Supply voltage out of range.
    pub const BAD_VOLTAGE: Self = Self(1 << 2);
    /// Encoder fault.
    pub const ENCODER: Self = Self(1 << 3);

    /// All of `other`'s bits are set.
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// No bit set.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Union.
    pub const fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }
}

impl core::fmt::Display for ErrorFlags {
    /// The faults in words (`over-temperature, encoder`), `none` when empty.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let names = [
            (Self::OVER_TEMPERATURE, "over-temperature"),
            (Self::OVER_CURRENT, "over-current"),
            (Self::BAD_VOLTAGE, "bad voltage"),
            (Self::ENCODER, "encoder fault"),
        ];
        let mut first = true;
        for (flag, name) in names {
            if self.contains(flag) {
                write!(f, "{}{name}", if first { "" } else { ", " })?;
                first = false;
            }
        }
        let unknown = self.0 & !0b1111;
        if unknown != 0 {
            write!(
                f,
                "{}unknown bits 0x{unknown:02x}",
                if first { "" } else { ", " }
            )?;
            first = false;
        }
        if first {
            f.write_str("none")?;
        }
        Ok(())
    }
}

/// Motor → host reply (joint-side units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reply {
    /// Replying motor.
    pub motor: MotorId,
    /// Mode the motor is in.
    pub mode: Mode,
    /// Whether the motor is enabled (obeys command frames).
    pub enabled: bool,
    /// Measured position \[rad\].
    pub q_rad: f64,
    /// Measured velocity \[rad/s\].
    pub dq_rad_s: f64,
    /// Estimated output torque \[N·m\].
    pub tau_nm: f64,
    /// Winding temperature \[°C\].
    pub temperature_c: f64,
    /// Fault bits.
    pub errors: ErrorFlags,
}

impl Reply {
    /// A placeholder reply (all zero, brake, disabled): initial value of reply buffers.
    pub const fn zeroed(motor: MotorId) -> Self {
        Self {
            motor,
            mode: Mode::Brake,
            enabled: false,
            q_rad: 0.0,
            dq_rad_s: 0.0,
            tau_nm: 0.0,
            temperature_c: 0.0,
            errors: ErrorFlags::NONE,
        }
    }

    fn field_values(&self) -> [f64; 4] {
        [self.q_rad, self.dq_rad_s, self.tau_nm, self.temperature_c]
    }
}

/// Which fields were clamped to their range while encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Saturation(u16);

impl Saturation {
    /// Nothing saturated.
    pub const NONE: Self = Self(0);

    /// Whether `field` was clamped.
    pub const fn contains(self, field: Field) -> bool {
        self.0 & (1 << field as u16) != 0
    }

    /// Whether any field was clamped.
    pub const fn any(self) -> bool {
        self.0 != 0
    }

    /// Mark `field` as clamped.
    pub const fn with(self, field: Field) -> Self {
        Self(self.0 | (1 << field as u16))
    }
}

/// The kinds of A1 frame, distinguished by CAN id range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameKind {
    /// `0x080 + id`: enable / disable / set zero.
    Special,
    /// `0x100 + id`: host → motor command.
    Command,
    /// `0x180 + id`: motor → host reply.
    Reply,
}

impl core::fmt::Display for FrameKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Special => "special",
            Self::Command => "command",
            Self::Reply => "reply",
        })
    }
}

/// Why bytes are not a valid A1 frame of the expected kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum DecodeError {
    /// The CAN id is not in the id range of the expected frame kind ("not for me").
    #[error("CAN id {id:#x} is not an A1 {expected} frame")]
    WrongId {
        /// Received CAN id.
        id: u32,
        /// Kind the caller expected.
        expected: FrameKind,
    },
    /// The data length is not 8.
    #[error("A1 frame {id:#x} has {len} data bytes, expected 8")]
    WrongLength {
        /// Received CAN id.
        id: u32,
        /// Received data length.
        len: usize,
    },
    /// The 2-bit mode field holds the reserved value.
    #[error("A1 frame {id:#x} carries unknown mode {mode}")]
    UnknownMode {
        /// Received CAN id.
        id: u32,
        /// Raw mode bits.
        mode: u8,
    },
    /// A special frame with an unknown opcode.
    #[error("A1 special frame {id:#x} carries unknown opcode {opcode:#04x}")]
    UnknownOpcode {
        /// Received CAN id.
        id: u32,
        /// Raw opcode byte.
        opcode: u8,
    },
}

/// Why a command or reply cannot be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum EncodeError {
    /// A field is NaN (a NaN command is a bug upstream, never silently sent).
    #[error("{motor}: field {field} is NaN")]
    NotANumber {
        /// Addressed motor.
        motor: MotorId,
        /// Offending field.
        field: Field,
    },
}

/// An encoded frame and the fields that were clamped to fit it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Encoded {
    /// The frame to send.
    pub frame: Frame,
    /// Fields that were out of range and clamped (never wrapped).
    pub saturated: Saturation,
}

/// A decoded host → motor frame (what the motor firmware sees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HostFrame {
    /// A command frame.
    Command(Command),
    /// A special frame.
    Special {
        /// Addressed motor.
        motor: MotorId,
        /// What to do.
        special: Special,
    },
}

/// Kind and motor of an A1 CAN id, or `None` for a foreign id.
pub const fn classify(id: u32) -> Option<(FrameKind, MotorId)> {
    let kind = match id & !(MAX_MOTOR_ID as u32) {
        SPECIAL_ID_BASE => FrameKind::Special,
        COMMAND_ID_BASE => FrameKind::Command,
        REPLY_ID_BASE => FrameKind::Reply,
        _ => return None,
    };
    Some((kind, MotorId((id & MAX_MOTOR_ID as u32) as u8)))
}

fn encode_fields<const N: usize>(
    motor: MotorId,
    specs: &[FieldSpec; N],
    values: [f64; N],
    mut payload: u64,
) -> Result<(u64, Saturation), EncodeError> {
    let mut saturated = Saturation::NONE;
    for (spec, value) in specs.iter().zip(values) {
        if value.is_nan() {
            return Err(EncodeError::NotANumber {
                motor,
                field: spec.field,
            });
        }
        let (raw, clamped) = spec.encode_raw(value);
        if clamped {
            saturated = saturated.with(spec.field);
        }
        payload = spec.insert(payload, raw);
    }
    Ok((payload, saturated))
}

/// Encode a command frame; out-of-range fields are clamped and reported.
pub fn encode_command(command: &Command) -> Result<Encoded, EncodeError> {
    let mode = u64::from(command.mode.to_bits()) << CMD_MODE_START_BIT;
    let (payload, saturated) =
        encode_fields(command.motor, &COMMAND_FIELDS, command.field_values(), mode)?;
    Ok(Encoded {
        frame: Frame {
            id: command.motor.command_id(),
            data: payload.to_le_bytes(),
        },
        saturated,
    })
}

/// Encode a special frame (byte 0 = opcode, bytes 1–7 zero).
pub const fn encode_special(motor: MotorId, special: Special) -> Frame {
    let mut data = [0u8; FRAME_LEN];
    data[0] = special.opcode();
    Frame {
        id: motor.special_id(),
        data,
    }
}

/// Encode a reply frame (motor firmware side); out-of-range fields are clamped and reported.
pub fn encode_reply(reply: &Reply) -> Result<Encoded, EncodeError> {
    let payload = (u64::from(reply.errors.0) << REPLY_ERRORS_START_BIT)
        | (u64::from(reply.mode.to_bits()) << REPLY_MODE_START_BIT)
        | (u64::from(reply.enabled) << REPLY_ENABLED_BIT);
    let (payload, saturated) =
        encode_fields(reply.motor, &REPLY_FIELDS, reply.field_values(), payload)?;
    Ok(Encoded {
        frame: Frame {
            id: reply.motor.reply_id(),
            data: payload.to_le_bytes(),
        },
        saturated,
    })
}

fn payload_of(id: u32, data: &[u8]) -> Result<u64, DecodeError> {
    let bytes: [u8; FRAME_LEN] = data.try_into().map_err(|_| DecodeError::WrongLength {
        id,
        len: data.len(),
    })?;
    Ok(u64::from_le_bytes(bytes))
}

fn expect_kind(id: u32, expected: FrameKind) -> Result<MotorId, DecodeError> {
    match classify(id) {
        Some((kind, motor)) if kind == expected => Ok(motor),
        _ => Err(DecodeError::WrongId { id, expected }),
    }
}

/// Decode a reply frame received on the bus.
pub fn decode_reply(id: u32, data: &[u8]) -> Result<Reply, DecodeError> {
    let motor = expect_kind(id, FrameKind::Reply)?;
    let payload = payload_of(id, data)?;
    let mode_bits = ((payload >> REPLY_MODE_START_BIT) & 0b11) as u8;
    let mode = Mode::from_bits(mode_bits).ok_or(DecodeError::UnknownMode {
        id,
        mode: mode_bits,
    })?;
    let field = |spec: &FieldSpec| spec.decode_raw(spec.extract(payload));
    Ok(Reply {
        motor,
        mode,
        enabled: (payload >> REPLY_ENABLED_BIT) & 1 == 1,
        q_rad: field(&REPLY_Q),
        dq_rad_s: field(&REPLY_DQ),
        tau_nm: field(&REPLY_TAU),
        temperature_c: field(&REPLY_TEMPERATURE),
        errors: ErrorFlags((payload >> REPLY_ERRORS_START_BIT) as u8),
    })
}

/// Decode a command frame (motor firmware side).
pub fn decode_command(id: u32, data: &[u8]) -> Result<Command, DecodeError> {
    let motor = expect_kind(id, FrameKind::Command)?;
    let payload = payload_of(id, data)?;
    let mode_bits = ((payload >> CMD_MODE_START_BIT) & 0b11) as u8;
    let mode = Mode::from_bits(mode_bits).ok_or(DecodeError::UnknownMode {
        id,
        mode: mode_bits,
    })?;
    let field = |spec: &FieldSpec| spec.decode_raw(spec.extract(payload));
    Ok(Command {
        motor,
        mode,
        q_des_rad: field(&CMD_Q_DES),
        dq_des_rad_s: field(&CMD_DQ_DES),
        kp_nm_per_rad: field(&CMD_KP),
        kd_nm_s_per_rad: field(&CMD_KD),
        tau_ff_nm: field(&CMD_TAU_FF),
    })
}

/// Decode a special frame (motor firmware side).
pub fn decode_special(id: u32, data: &[u8]) -> Result<(MotorId, Special), DecodeError> {
    let motor = expect_kind(id, FrameKind::Special)?;
    let payload = payload_of(id, data)?;
    let opcode = payload as u8;
    let special = Special::from_opcode(opcode).ok_or(DecodeError::UnknownOpcode { id, opcode })?;
    Ok((motor, special))
}

/// Decode any host → motor frame (command or special), as the motor firmware does.
pub fn decode_host_frame(id: u32, data: &[u8]) -> Result<HostFrame, DecodeError> {
    match classify(id) {
        Some((FrameKind::Special, _)) => {
            decode_special(id, data).map(|(motor, special)| HostFrame::Special { motor, special })
        }
        _ => decode_command(id, data).map(HostFrame::Command),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests;
