//! The Unitree A1 actuator reached over classic CAN: frame layout and codec.
//!
//! # The link we assume (our assumption, not Unitree's)
//! The A1's own link is **RS-485**, with Unitree's serial motor protocol; the A1 has no CAN
//! port. adam-hzd **assumes** a per-limb bridge that puts the A1s of one limb on one classic
//! CAN bus (8-byte frames, 11-bit ids, 1 Mbit/s by default) and speaks exactly the framing
//! this module defines, translating each frame into an A1 RS-485 command and each motor answer
//! into a reply frame. That framing borrows the *idea* of the MIT Cheetah motor driver's
//! protocol (packed fixed-point fields in one 8-byte frame, escape frames for
//! enable/disable/zero) but its layout, ids and ranges are our own: no existing firmware
//! speaks it, none ships with adam-hzd, and none can be bought. A lab that runs this runtime
//! on ADAM's A1s needs one of:
//! * a bridge it builds and flashes itself: a microcontroller with an RS-485 transceiver for
//!   the A1s and a CAN transceiver for the host, running firmware that implements the frame
//!   table below (`drivers/a1_can.dbc` is the same table for CAN tools) on one side and
//!   Unitree's A1 serial protocol on the other;
//! * or a `MotorBus` of its own over the RS-485 link (a USB–RS-485 adapter and Unitree's
//!   protocol), in place of `SocketCanBus`: the controller only sees the trait.
//!
//! The host side is then SocketCAN (`SocketCanBus`), or CAN over UDP through a CAN-to-Ethernet
//! gateway running cannelloni ([`crate::udp`]). The DBC's comment says the same.
//! [`codec`] is sans-IO: it turns [`Command`]s into [`Frame`]s and bytes into [`Reply`]s
//! or typed [`DecodeError`]s, with no socket, no allocation and no string formatting.
//! `drivers/a1_can.dbc` describes the same frames for standard CAN tools, and a test
//! decodes random frames through the DBC and through the codec and compares.
//!
//! # Units
//! Every value on the wire is **joint side** (after the 9.1:1 gearbox): rad, rad/s, N·m,
//! N·m/rad, N·m·s/rad, °C. The firmware converts to motor side (`q_motor = 9.1 q`,
//! `tau_motor = tau / 9.1`, `kp_motor = kp / 9.1²`).
//!
//! # CAN ids (11-bit standard)
//! | id | direction | frame |
//! |---|---|---|
//! | `0x080 + m` | host → motor `m` | special (enable / disable / set zero) |
//! | `0x100 + m` | host → motor `m` | command |
//! | `0x180 + m` | motor `m` → host | reply (one per command or special frame) |
//!
//! `m` is the motor id, `0..=0x7F`. Special frames have the highest priority (lowest id),
//! so a disable wins arbitration over a command. Every frame has DLC 8.
//!
//! # Fixed-point fields
//! The 8 data bytes are read as one little-endian `u64` (byte 0 = bits 0–7); a field of
//! `n` bits starting at bit `s` is `(payload >> s) & (2^n - 1)` (the DBC "Intel" order).
//! `physical = raw * quantum + min`, `quantum = (max - min) / 2^n`, raw unsigned. So the
//! representable values are `min ..= max - quantum`, zero is exact for signed fields, and
//! each quantum is an exact binary fraction (the DBC factors are exact decimals).
//! Encoding rounds to the nearest step and **saturates** out-of-range values to the end
//! of the range (never wraps), reporting the clamped fields in a [`Saturation`];
//! NaN is refused ([`EncodeError::NotANumber`]).
//!
//! ## Command frame (`0x100 + m`)
//! | bits | field | unit | min | max | quantum |
//! |---|---|---|---|---|---|
//! | 0–15 (16) | `q_des` | rad | −12.5 | 12.5 | 0.000381 |
//! | 16–27 (12) | `dq_des` | rad/s | −21 | 21 | 0.01025 |
//! | 28–39 (12) | `kp` | N·m/rad | 0 | 500 | 0.1221 |
//! | 40–49 (10) | `kd` | N·m·s/rad | 0 | 10 | 0.009766 |
//! | 50–61 (12) | `tau_ff` | N·m | −33.5 | 33.5 | 0.01636 |
//! | 62–63 (2) | mode | — | 0 brake, 1 damping, 2 PD, 3 reserved (rejected) | | |
//!
//! ## Reply frame (`0x180 + m`)
//! | bits | field | unit | min | max | quantum |
//! |---|---|---|---|---|---|
//! | 0–15 (16) | `q` | rad | −12.5 | 12.5 | 0.000381 |
//! | 16–27 (12) | `dq` | rad/s | −21 | 21 | 0.01025 |
//! | 28–39 (12) | `tau` | N·m | −33.5 | 33.5 | 0.01636 |
//! | 40–47 (8) | temperature | °C | −40 | 216 | 1 |
//! | 48–55 (8) | error flags | — | bit 0 over-temperature, 1 over-current, 2 voltage, 3 encoder | | |
//! | 56–57 (2) | mode echo | — | as in the command; 3 rejected | | |
//! | 58 (1) | enabled | — | 1 = obeys commands | | |
//! | 59–63 | reserved | — | sent as 0, ignored | | |
//!
//! ## Special frame (`0x080 + m`)
//! | byte | value |
//! |---|---|
//! | 0 | opcode: `0x01` enable, `0x02` disable (→ damping with the firmware's default gain), `0x03` set zero; others rejected |
//! | 1–7 | reserved, sent as 0, ignored |
//!
//! # Why these ranges
//! * `tau`, `dq`: the A1 limits (33.5 N·m peak, 21 rad/s no-load), so a saturated torque
//!   command can never ask more than the motor has.
//! * `q`: ±12.5 rad ≈ ±2 output turns, beyond every ADAM joint limit (all within ±π) with
//!   room for a wrapped multi-turn reading; 0.38 mrad per step.
//! * `kp` 0–500 N·m/rad: a 0.1 rad error saturates the torque at kp = 335, so larger
//!   stiffness only matters for tiny errors; 0.12 N·m/rad per step.
//! * `kd` 0–10 N·m·s/rad: 10 N·m·s/rad at the 21 rad/s limit is 210 N·m, six times the
//!   torque limit; 0.01 N·m·s/rad per step.
//!
//! # Decoding errors
//! A frame with an id outside the expected range is [`DecodeError::WrongId`] ("not for
//! me", the bus layer ignores foreign traffic), a DLC other than 8 is
//! [`DecodeError::WrongLength`], a reserved mode is [`DecodeError::UnknownMode`], an
//! unknown special opcode is [`DecodeError::UnknownOpcode`]. All are small `Copy` values.

pub mod codec;
pub mod dbc;

pub use codec::{
    classify, decode_command, decode_host_frame, decode_reply, decode_special, encode_command,
    encode_reply, encode_special, Command, DecodeError, EncodeError, Encoded, ErrorFlags, Field,
    Frame, FrameKind, HostFrame, Mode, MotorId, Reply, Saturation, Special, GEAR_RATIO,
    MAX_SPEED_RAD_S, MAX_TORQUE_NM,
};
