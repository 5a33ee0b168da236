//! Unit and property tests of the A1 codec: quanta, field layout, known bytes, saturation,
//! distinct decode errors, round trips within half a quantum.

use super::*;
use proptest::prelude::*;

fn m(id: u8) -> MotorId {
    MotorId::new(id).unwrap()
}

#[test]
fn quanta_are_exact_binary_fractions() {
    // Chosen ranges make every DBC factor a short exact decimal.
    assert_eq!(CMD_Q_DES.quantum(), 0.000_381_469_726_562_5);
    assert_eq!(CMD_DQ_DES.quantum(), 0.010_253_906_25);
    assert_eq!(CMD_KP.quantum(), 0.122_070_312_5);
    assert_eq!(CMD_KD.quantum(), 0.009_765_625);
    assert_eq!(CMD_TAU_FF.quantum(), 0.016_357_421_875);
    assert_eq!(REPLY_TEMPERATURE.quantum(), 1.0);
}

#[test]
fn fields_tile_the_payload_without_overlap() {
    let mut used = 0u64;
    for spec in COMMAND_FIELDS {
        assert_eq!(used & spec.mask(), 0, "{:?} overlaps", spec.field);
        used |= spec.mask();
    }
    used |= 0b11 << CMD_MODE_START_BIT;
    assert_eq!(used, u64::MAX, "command frame uses all 64 bits");
    let mut used = 0u64;
    for spec in REPLY_FIELDS {
        assert_eq!(used & spec.mask(), 0, "{:?} overlaps", spec.field);
        used |= spec.mask();
    }
    for (bit, width) in [
        (REPLY_ERRORS_START_BIT, 8),
        (REPLY_MODE_START_BIT, 2),
        (REPLY_ENABLED_BIT, 1),
    ] {
        let mask = ((1u64 << width) - 1) << bit;
        assert_eq!(used & mask, 0);
        used |= mask;
    }
    assert_eq!(used, (1u64 << 59) - 1, "bits 59..63 reserved");
}

#[test]
fn zero_is_exact_for_signed_fields() {
    let c = Command::pd(m(3), 0.0, 0.0, 0.0, 0.0, 0.0);
    let e = encode_command(&c).unwrap();
    let d = decode_command(e.frame.id, &e.frame.data).unwrap();
    assert_eq!(d, c);
    assert!(!e.saturated.any());
}

#[test]
fn known_frame_bytes() {
    // Hand-computed: q_des = 0 -> raw 0x8000; dq_des = 0 -> 0x800; kp = 0.1220703125*100
    // -> raw 100 = 0x064; kd = 0 -> 0; tau = 0 -> 0x800; mode 2.
    let c = Command::pd(m(5), 0.0, 0.0, 100.0 * CMD_KP.quantum(), 0.0, 0.0);
    let e = encode_command(&c).unwrap();
    assert_eq!(e.frame.id, 0x105);
    let expected: u64 = 0x8000 | (0x800 << 16) | (0x064 << 28) | (0x800 << 50) | (2u64 << 62);
    assert_eq!(e.frame.data, expected.to_le_bytes());
}

#[test]
fn encoding_saturates_and_names_the_fields() {
    let c = Command::pd(m(1), 100.0, -1e9, 1e6, -1.0, f64::INFINITY);
    let e = encode_command(&c).unwrap();
    for f in [
        Field::QDes,
        Field::DqDes,
        Field::Kp,
        Field::Kd,
        Field::TauFf,
    ] {
        assert!(e.saturated.contains(f), "{f:?}");
    }
    let d = decode_command(e.frame.id, &e.frame.data).unwrap();
    assert_eq!(d.q_des_rad, CMD_Q_DES.max_representable());
    assert_eq!(d.dq_des_rad_s, -MAX_SPEED_RAD_S);
    assert_eq!(d.kp_nm_per_rad, CMD_KP.max_representable());
    assert_eq!(d.kd_nm_s_per_rad, 0.0);
    assert_eq!(d.tau_ff_nm, CMD_TAU_FF.max_representable());
    // Only the clamped field is reported.
    let e = encode_command(&Command::pd(m(1), 0.5, 0.0, 50.0, 1.0, 40.0)).unwrap();
    assert_eq!(e.saturated, Saturation::NONE.with(Field::TauFf));
}

#[test]
fn nan_is_refused_with_the_field() {
    let c = Command::pd(m(2), 0.0, 0.0, f64::NAN, 0.0, 0.0);
    assert_eq!(
        encode_command(&c),
        Err(EncodeError::NotANumber {
            motor: m(2),
            field: Field::Kp
        })
    );
    // Named as in `Command`, not in Rust's Debug form (issue #27).
    let message = encode_command(&c).unwrap_err().to_string();
    assert_eq!(message, "motor 2: field kp_nm_per_rad is NaN");
}

#[test]
fn decode_errors_are_distinct() {
    let e = encode_command(&Command::damping(m(4), 2.0)).unwrap().frame;
    // A command is not a reply: "not for me".
    assert_eq!(
        decode_reply(e.id, &e.data),
        Err(DecodeError::WrongId {
            id: 0x104,
            expected: FrameKind::Reply
        })
    );
    assert_eq!(
        decode_command(e.id, &e.data[..7]),
        Err(DecodeError::WrongLength { id: 0x104, len: 7 })
    );
    let mut bad = e.data;
    bad[7] |= 0xC0; // mode bits = 3
    assert_eq!(
        decode_command(e.id, &bad),
        Err(DecodeError::UnknownMode { id: 0x104, mode: 3 })
    );
    let s = encode_special(m(4), Special::SetZero);
    assert_eq!(s.id, 0x084);
    assert_eq!(decode_special(s.id, &s.data), Ok((m(4), Special::SetZero)));
    let mut bad = s.data;
    bad[0] = 9;
    assert_eq!(
        decode_host_frame(s.id, &bad),
        Err(DecodeError::UnknownOpcode {
            id: 0x084,
            opcode: 9
        })
    );
    assert!(matches!(
        decode_host_frame(0x7FF, &s.data),
        Err(DecodeError::WrongId { id: 0x7FF, .. })
    ));
}

#[test]
fn reply_round_trip_with_flags() {
    let r = Reply {
        motor: m(0x7F),
        mode: Mode::Damping,
        enabled: true,
        q_rad: -1.25,
        dq_rad_s: 3.0,
        tau_nm: -12.0,
        temperature_c: 71.0,
        errors: ErrorFlags::OVER_TEMPERATURE.union(ErrorFlags::ENCODER),
    };
    let e = encode_reply(&r).unwrap();
    assert_eq!(e.frame.id, 0x1FF);
    let d = decode_reply(e.frame.id, &e.frame.data).unwrap();
    assert_eq!(d.motor, r.motor);
    assert_eq!(d.mode, r.mode);
    assert!(d.enabled);
    assert_eq!(d.errors, r.errors);
    assert_eq!(d.temperature_c, 71.0);
    assert!((d.q_rad - r.q_rad).abs() <= REPLY_Q.quantum() / 2.0);
    assert!((d.dq_rad_s - r.dq_rad_s).abs() <= REPLY_DQ.quantum() / 2.0);
    assert!((d.tau_nm - r.tau_nm).abs() <= REPLY_TAU.quantum() / 2.0);
}

#[test]
fn classify_covers_exactly_three_id_ranges() {
    let mut counts = [0usize; 3];
    for id in 0..0x800u32 {
        if let Some((kind, motor)) = classify(id) {
            counts[kind as usize] += 1;
            let back = match kind {
                FrameKind::Special => motor.special_id(),
                FrameKind::Command => motor.command_id(),
                FrameKind::Reply => motor.reply_id(),
            };
            assert_eq!(back, id);
        }
    }
    assert_eq!(counts, [128, 128, 128]);
    assert_eq!(classify(0x8000_0100), None);
}

fn in_range(spec: FieldSpec) -> impl Strategy<Value = f64> {
    spec.min..=spec.max_representable()
}

fn any_mode() -> impl Strategy<Value = Mode> {
    prop_oneof![
        Just(Mode::Brake),
        Just(Mode::Damping),
        Just(Mode::PositionVelocity)
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn command_round_trip_within_half_a_quantum(
        id in 0..=MAX_MOTOR_ID, mode in any_mode(),
        q in in_range(CMD_Q_DES), dq in in_range(CMD_DQ_DES), kp in in_range(CMD_KP),
        kd in in_range(CMD_KD), tau in in_range(CMD_TAU_FF),
    ) {
        let c = Command { motor: m(id), mode, q_des_rad: q, dq_des_rad_s: dq,
            kp_nm_per_rad: kp, kd_nm_s_per_rad: kd, tau_ff_nm: tau };
        let e = encode_command(&c).unwrap();
        prop_assert!(!e.saturated.any());
        let d = decode_command(e.frame.id, &e.frame.data).unwrap();
        prop_assert_eq!(d.motor, c.motor);
        prop_assert_eq!(d.mode, c.mode);
        for (spec, (a, b)) in COMMAND_FIELDS.iter().zip(c.field_values().into_iter().zip(d.field_values())) {
            // Round to nearest: half a step, plus a few ulps of float arithmetic.
            prop_assert!((a - b).abs() <= spec.quantum() * 0.5 + 1e-12, "{:?}: {} vs {}", spec.field, a, b);
        }
    }

    #[test]
    fn reply_round_trip_within_half_a_quantum(
        id in 0..=MAX_MOTOR_ID, mode in any_mode(), enabled: bool, errors: u8,
        q in in_range(REPLY_Q), dq in in_range(REPLY_DQ), tau in in_range(REPLY_TAU),
        temp in in_range(REPLY_TEMPERATURE),
    ) {
        let r = Reply { motor: m(id), mode, enabled, q_rad: q, dq_rad_s: dq, tau_nm: tau,
            temperature_c: temp, errors: ErrorFlags(errors) };
        let e = encode_reply(&r).unwrap();
        prop_assert!(!e.saturated.any());
        let d = decode_reply(e.frame.id, &e.frame.data).unwrap();
        prop_assert_eq!((d.motor, d.mode, d.enabled, d.errors), (r.motor, r.mode, r.enabled, r.errors));
        for (spec, (a, b)) in REPLY_FIELDS.iter().zip(r.field_values().into_iter().zip(d.field_values())) {
            prop_assert!((a - b).abs() <= spec.quantum() * 0.5 + 1e-12, "{:?}: {} vs {}", spec.field, a, b);
        }
    }

    #[test]
    fn out_of_range_saturates_to_the_nearest_end(x in -1e12f64..1e12) {
        for spec in COMMAND_FIELDS.iter().chain(REPLY_FIELDS.iter()) {
            let (raw, sat) = spec.encode_raw(x);
            let back = spec.decode_raw(raw);
            let clamped = x.clamp(spec.min, spec.max_representable());
            prop_assert!((back - clamped).abs() <= spec.quantum() * 0.5 + 1e-9);
            if x < spec.min - spec.quantum() || x > spec.max {
                prop_assert!(sat);
            }
            if sat {
                prop_assert!(raw == 0 || raw == spec.raw_max());
            }
        }
    }

    #[test]
    fn decode_never_panics(id: u32, data in proptest::collection::vec(any::<u8>(), 0..=64)) {
        let _ = decode_reply(id, &data);
        let _ = decode_command(id, &data);
        let _ = decode_special(id, &data);
        let _ = decode_host_frame(id, &data);
        let _ = classify(id);
    }

    #[test]
    fn every_valid_reply_reencodes_to_the_same_bytes(id in 0..=MAX_MOTOR_ID, bytes: [u8; 8]) {
        // A decoded reply is exactly representable: re-encoding gives the same payload,
        // up to the reserved bits 59..63 which are sent as zero.
        let rid = m(id).reply_id();
        if let Ok(r) = decode_reply(rid, &bytes) {
            let e = encode_reply(&r).unwrap();
            prop_assert!(!e.saturated.any());
            let mask = (1u64 << 59) - 1;
            prop_assert_eq!(u64::from_le_bytes(e.frame.data), u64::from_le_bytes(bytes) & mask);
        }
    }
}
