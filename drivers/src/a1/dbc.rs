//! The DBC description of our A1 frames (`drivers/a1_can.dbc`): renderer and a small parser.
//!
//! [`render`] writes the DBC text from the codec's field tables, so the shipped file can be
//! re-minted when the layout changes (`ADAM_REMINT_DBC=1 cargo test -p drivers dbc`).
//! [`parse`] reads the subset of DBC we use — `BO_` messages and their `SG_` signals, in
//! either byte order, signed or unsigned — and [`Signal::decode`] applies the DBC semantics
//! (start bit, length, byte order, factor, offset) independently of the codec's bit
//! packing. The test below decodes random frames both ways and compares. Off line, the
//! file can also be checked with `cantools` (PyPI).

use super::codec::{
    FieldSpec, CMD_MODE_START_BIT, COMMAND_FIELDS, FRAME_LEN, REPLY_ENABLED_BIT,
    REPLY_ERRORS_START_BIT, REPLY_FIELDS, REPLY_MODE_START_BIT,
};
use super::MotorId;
use core::fmt::Write as _;
use thiserror::Error;

/// Motor ids the shipped DBC file describes (one message per id and frame kind).
pub const DBC_MOTOR_IDS: core::ops::RangeInclusive<u8> = 0..=15;

/// Byte order of a DBC signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ByteOrder {
    /// `@1`: Intel, little endian; the start bit is the least significant bit.
    LittleEndian,
    /// `@0`: Motorola, big endian; the start bit is the most significant bit
    /// (in the DBC's bit numbering: bit 7 of byte 0 is 7, bit 0 of byte 1 is 8).
    BigEndian,
}

/// One `SG_` line.
#[derive(Debug, Clone, PartialEq)]
pub struct Signal {
    /// Signal name.
    pub name: String,
    /// Start bit as written in the file.
    pub start_bit: u32,
    /// Length in bits (1–64).
    pub length: u32,
    /// Byte order.
    pub byte_order: ByteOrder,
    /// Two's-complement signed raw value.
    pub signed: bool,
    /// `physical = raw * factor + offset`.
    pub factor: f64,
    /// See `factor`.
    pub offset: f64,
    /// Documented minimum.
    pub min: f64,
    /// Documented maximum.
    pub max: f64,
    /// Unit string.
    pub unit: String,
}

impl Signal {
    /// Raw (unscaled, sign-extended) value of this signal in `data`.
    pub fn raw(&self, data: &[u8]) -> Option<i128> {
        let mut bytes = [0u8; 8];
        let n = data.len().min(8);
        bytes[..n].copy_from_slice(&data[..n]);
        let len = self.length;
        if len == 0 || len > 64 {
            return None;
        }
        let mask = if len == 64 {
            u64::MAX
        } else {
            (1u64 << len) - 1
        };
        let unsigned = match self.byte_order {
            ByteOrder::LittleEndian => {
                if self.start_bit + len > 64 {
                    return None;
                }
                (u64::from_le_bytes(bytes) >> self.start_bit) & mask
            }
            ByteOrder::BigEndian => {
                // Position of the MSB counted from the first transmitted bit (byte 0 bit 7).
                let msb = (self.start_bit / 8) * 8 + (7 - self.start_bit % 8);
                let lsb = msb + len - 1;
                if lsb > 63 {
                    return None;
                }
                (u64::from_be_bytes(bytes) >> (63 - lsb)) & mask
            }
        };
        let value = i128::from(unsigned);
        Some(if self.signed && (unsigned >> (len - 1)) & 1 == 1 {
            value - (1i128 << len)
        } else {
            value
        })
    }

    /// Physical value of this signal in `data`.
    pub fn decode(&self, data: &[u8]) -> Option<f64> {
        self.raw(data)
            .map(|raw| raw as f64 * self.factor + self.offset)
    }
}

/// One `BO_` message.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// CAN id.
    pub id: u32,
    /// Message name.
    pub name: String,
    /// DLC.
    pub length: usize,
    /// Signals in file order.
    pub signals: Vec<Signal>,
}

impl Message {
    /// Signal by name.
    pub fn signal(&self, name: &str) -> Option<&Signal> {
        self.signals.iter().find(|s| s.name == name)
    }
}

/// A DBC line we could not read.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("DBC line {line}: {reason}: `{text}`")]
pub struct DbcError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong.
    pub reason: &'static str,
    /// The offending line.
    pub text: String,
}

/// Parse the `BO_`/`SG_` subset of a DBC file; other sections are skipped.
pub fn parse(text: &str) -> Result<Vec<Message>, DbcError> {
    let mut messages: Vec<Message> = Vec::new();
    for (index, raw_line) in text.lines().enumerate() {
        let line = raw_line.trim();
        let err = |reason| DbcError {
            line: index + 1,
            reason,
            text: raw_line.to_owned(),
        };
        if let Some(rest) = line.strip_prefix("BO_ ") {
            let (head, tail) = rest.split_once(':').ok_or_else(|| err("missing ':'"))?;
            let mut head = head.split_whitespace();
            let id = head
                .next()
                .and_then(|s| s.parse::<u32>().ok())
                .ok_or_else(|| err("bad message id"))?;
            let name = head.next().ok_or_else(|| err("missing name"))?.to_owned();
            let length = tail
                .split_whitespace()
                .next()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| err("bad DLC"))?;
            messages.push(Message {
                id,
                name,
                length,
                signals: Vec::new(),
            });
        } else if let Some(rest) = line.strip_prefix("SG_ ") {
            let message = messages
                .last_mut()
                .ok_or_else(|| err("signal outside a message"))?;
            message
                .signals
                .push(parse_signal(rest).ok_or_else(|| err("bad signal"))?);
        }
    }
    Ok(messages)
}

fn parse_signal(rest: &str) -> Option<Signal> {
    // name [mux] : start|len@order sign (factor,offset) [min|max] "unit" receivers
    let (name_part, def) = rest.split_once(':')?;
    let name = name_part.split_whitespace().next()?.to_owned();
    let def = def.trim();
    let (layout, def) = def.split_once(' ')?;
    let (start, layout) = layout.split_once('|')?;
    let (length, layout) = layout.split_once('@')?;
    let mut order_sign = layout.chars();
    let byte_order = match order_sign.next()? {
        '1' => ByteOrder::LittleEndian,
        '0' => ByteOrder::BigEndian,
        _ => return None,
    };
    let signed = match order_sign.next()? {
        '-' => true,
        '+' => false,
        _ => return None,
    };
    let def = def.trim().strip_prefix('(')?;
    let (scale, def) = def.split_once(')')?;
    let (factor, offset) = scale.split_once(',')?;
    let def = def.trim().strip_prefix('[')?;
    let (range, def) = def.split_once(']')?;
    let (min, max) = range.split_once('|')?;
    let def = def.trim().strip_prefix('"')?;
    let (unit, _receivers) = def.split_once('"')?;
    Some(Signal {
        name,
        start_bit: start.trim().parse().ok()?,
        length: length.trim().parse().ok()?,
        byte_order,
        signed,
        factor: factor.trim().parse().ok()?,
        offset: offset.trim().parse().ok()?,
        min: min.trim().parse().ok()?,
        max: max.trim().parse().ok()?,
        unit: unit.to_owned(),
    })
}

fn field_name(spec: &FieldSpec) -> &'static str {
    use super::Field::*;
    match spec.field {
        QDes => "q_des",
        DqDes => "dq_des",
        Kp => "kp",
        Kd => "kd",
        TauFf => "tau_ff",
        Q => "q",
        Dq => "dq",
        Tau => "tau",
        Temperature => "temperature",
    }
}

fn field_unit(spec: &FieldSpec) -> &'static str {
    use super::Field::*;
    match spec.field {
        QDes | Q => "rad",
        DqDes | Dq => "rad/s",
        Kp => "Nm/rad",
        Kd => "Nms/rad",
        TauFf | Tau => "Nm",
        Temperature => "degC",
    }
}

fn write_field(out: &mut String, spec: &FieldSpec, receiver: &str) {
    let _ = writeln!(
        out,
        " SG_ {} : {}|{}@1+ ({},{}) [{}|{}] \"{}\" {}",
        field_name(spec),
        spec.start_bit,
        spec.bits,
        spec.quantum(),
        spec.min,
        spec.min,
        spec.max_representable(),
        field_unit(spec),
        receiver
    );
}

/// The DBC text for motor ids [`DBC_MOTOR_IDS`] (what `drivers/a1_can.dbc` must contain).
pub fn render() -> String {
    let mut out = String::new();
    out.push_str("VERSION \"adam-hzd A1-over-CAN 1\"\n\nNS_ :\n\nBS_:\n\nBU_: HOST A1\n\n");
    for id in DBC_MOTOR_IDS.filter_map(MotorId::new) {
        let m = id.get();
        let _ = writeln!(out, "BO_ {} A1_SPECIAL_{m:02}: 8 HOST", id.special_id());
        out.push_str(" SG_ opcode : 0|8@1+ (1,0) [1|3] \"\" A1\n\n");
        let _ = writeln!(out, "BO_ {} A1_COMMAND_{m:02}: 8 HOST", id.command_id());
        for spec in &COMMAND_FIELDS {
            write_field(&mut out, spec, "A1");
        }
        let _ = writeln!(
            out,
            " SG_ mode : {CMD_MODE_START_BIT}|2@1+ (1,0) [0|2] \"\" A1\n"
        );
        let _ = writeln!(out, "BO_ {} A1_REPLY_{m:02}: 8 A1", id.reply_id());
        for spec in &REPLY_FIELDS {
            write_field(&mut out, spec, "HOST");
        }
        let _ = writeln!(
            out,
            " SG_ error_flags : {REPLY_ERRORS_START_BIT}|8@1+ (1,0) [0|255] \"\" HOST"
        );
        let _ = writeln!(
            out,
            " SG_ mode : {REPLY_MODE_START_BIT}|2@1+ (1,0) [0|2] \"\" HOST"
        );
        let _ = writeln!(
            out,
            " SG_ enabled : {REPLY_ENABLED_BIT}|1@1+ (1,0) [0|1] \"\" HOST\n"
        );
    }
    out.push_str(
        "CM_ \"OUR ASSUMPTION, not a Unitree protocol. The Unitree A1 actuator's own link is \
         RS-485 (Unitree's serial motor protocol), not CAN. This file describes the classic-CAN \
         framing (11-bit ids, DLC 8) that adam-hzd assumes a per-limb RS-485-to-CAN bridge \
         speaks for ADAM's A1s; the layout is adam-hzd's own (packed like the MIT Cheetah \
         motor protocol, but not compatible with it). No bridge firmware speaking it ships with \
         adam-hzd or is sold: a lab flashes its own bridge (a microcontroller with an RS-485 and \
         a CAN transceiver that turns each frame below into an A1 RS-485 command and the motor's \
         answer into a reply frame), or writes a MotorBus over the RS-485 link directly. \
         Joint-side units. Layout: drivers::a1 module docs.\";\n",
    );
    for id in DBC_MOTOR_IDS.filter_map(MotorId::new) {
        let _ = writeln!(
            out,
            "VAL_ {} opcode 1 \"enable\" 2 \"disable\" 3 \"set_zero\" ;",
            id.special_id()
        );
        let _ = writeln!(
            out,
            "VAL_ {} mode 0 \"brake\" 1 \"damping\" 2 \"position_velocity\" ;",
            id.command_id()
        );
        let _ = writeln!(
            out,
            "VAL_ {} mode 0 \"brake\" 1 \"damping\" 2 \"position_velocity\" ;",
            id.reply_id()
        );
    }
    debug_assert_eq!(FRAME_LEN, 8);
    out
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::super::codec::*;
    use super::*;
    use rand::{Rng, SeedableRng};

    const SHIPPED: &str = include_str!("../../a1_can.dbc");

    /// Golden file. To re-mint after a layout change:
    /// `ADAM_REMINT_DBC=1 cargo test -p drivers dbc_file_is_current`.
    #[test]
    fn dbc_file_is_current() {
        let rendered = render();
        if std::env::var_os("ADAM_REMINT_DBC").is_some() {
            let path = concat!(env!("CARGO_MANIFEST_DIR"), "/a1_can.dbc");
            std::fs::write(path, &rendered).unwrap();
        }
        assert!(
            SHIPPED == rendered,
            "drivers/a1_can.dbc is stale; re-mint with ADAM_REMINT_DBC=1"
        );
    }

    #[test]
    fn parser_reads_both_byte_orders() {
        // Hand-made: 0x1234 Motorola at start bit 7 (MSB of byte 0) -> bytes 12 34;
        // -2 as a signed 8-bit Intel signal in byte 2; a 4-bit Motorola field at bits 3..0
        // of byte 3 (start bit 27 = bit 3 of byte 3).
        let text = "BO_ 10 T: 8 X\n SG_ be : 7|16@0+ (1,0) [0|0] \"\" Y\n \
                    SG_ le : 16|8@1- (0.5,1) [0|0] \"u\" Y\n SG_ nib : 27|4@0+ (1,0) [0|0] \"\" Y\n";
        let msgs = parse(text).unwrap();
        let msg = &msgs[0];
        let data = [0x12, 0x34, 0xFE, 0x0B, 0, 0, 0, 0];
        assert_eq!(msg.signal("be").unwrap().raw(&data), Some(0x1234));
        assert_eq!(msg.signal("le").unwrap().decode(&data), Some(0.0)); // -2*0.5+1
        assert_eq!(msg.signal("nib").unwrap().raw(&data), Some(0xB));
        assert!(parse("BO_ x T: 8 X\n").is_err());
        assert!(parse(" SG_ a : 0|8@1+ (1,0) [0|0] \"\" Y\n").is_err());
    }

    /// Golden bytes from an independent tool: `cantools` (PyPI 45.1) loaded
    /// `drivers/a1_can.dbc` and encoded A1_REPLY_05 with q = 1, dq = −2, tau = 3,
    /// temperature = 50, error_flags = 1, mode = 1, enabled = 1. Re-mint with
    /// `db.get_message_by_name('A1_REPLY_05').encode({...}).hex()`.
    #[test]
    fn cantools_encoded_reply_decodes_with_the_codec() {
        let bytes = [0x3d, 0x8a, 0x3d, 0x77, 0x8b, 0x5a, 0x01, 0x05];
        let r = decode_reply(0x185, &bytes).unwrap();
        assert_eq!(r.motor, MotorId::new(5).unwrap());
        assert!((r.q_rad - 1.0).abs() <= REPLY_Q.quantum() / 2.0);
        assert!((r.dq_rad_s + 2.0).abs() <= REPLY_DQ.quantum() / 2.0);
        assert!((r.tau_nm - 3.0).abs() <= REPLY_TAU.quantum() / 2.0);
        assert_eq!(r.temperature_c, 50.0);
        assert_eq!(r.errors, crate::a1::ErrorFlags::OVER_TEMPERATURE);
        assert_eq!(r.mode, crate::a1::Mode::Damping);
        assert!(r.enabled);
    }

    #[test]
    fn shipped_dbc_decodes_like_the_codec() {
        let msgs = parse(SHIPPED).unwrap();
        assert_eq!(msgs.len(), 3 * DBC_MOTOR_IDS.count());
        let find = |id: u32| msgs.iter().find(|m| m.id == id).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs());
        let mut checked = 0;
        for _ in 0..5000 {
            let motor = MotorId::new(rng.random_range(DBC_MOTOR_IDS)).unwrap();
            let bytes: [u8; 8] = rng.random();
            // Replies: any payload with a valid mode decodes.
            if let Ok(r) = decode_reply(motor.reply_id(), &bytes) {
                let msg = find(motor.reply_id());
                assert_eq!(msg.length, 8);
                let sig = |n: &str| msg.signal(n).unwrap().decode(&bytes).unwrap();
                assert!(close(sig("q"), r.q_rad));
                assert!(close(sig("dq"), r.dq_rad_s));
                assert!(close(sig("tau"), r.tau_nm));
                assert!(close(sig("temperature"), r.temperature_c));
                assert_eq!(sig("error_flags"), f64::from(r.errors.0));
                assert_eq!(sig("mode"), f64::from(r.mode.to_bits()));
                assert_eq!(sig("enabled"), f64::from(u8::from(r.enabled)));
                checked += 1;
            }
            if let Ok(c) = decode_command(motor.command_id(), &bytes) {
                let msg = find(motor.command_id());
                let sig = |n: &str| msg.signal(n).unwrap().decode(&bytes).unwrap();
                assert!(close(sig("q_des"), c.q_des_rad));
                assert!(close(sig("dq_des"), c.dq_des_rad_s));
                assert!(close(sig("kp"), c.kp_nm_per_rad));
                assert!(close(sig("kd"), c.kd_nm_s_per_rad));
                assert!(close(sig("tau_ff"), c.tau_ff_nm));
                assert_eq!(sig("mode"), f64::from(c.mode.to_bits()));
                checked += 1;
            }
            let special =
                [Special::Enable, Special::Disable, Special::SetZero][rng.random_range(0..3)];
            let frame = encode_special(motor, special);
            let msg = find(frame.id);
            assert_eq!(
                msg.signal("opcode").unwrap().decode(&frame.data),
                Some(f64::from(special.opcode()))
            );
        }
        // 3 of 4 mode values are valid: about 7500 of 10000 frames decode.
        assert!(checked > 7000, "only {checked} frames checked");
    }
}
