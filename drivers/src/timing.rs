//! How long A1 traffic occupies a classic CAN bus, and which loop rates the buses can carry.
//!
//! # Derivation
//! A classic CAN data frame with an 11-bit id and `n` data bytes is, bit by bit:
//!
//! | field | bits | stuffed? |
//! |---|---|---|
//! | start of frame | 1 | yes |
//! | identifier | 11 | yes |
//! | RTR, IDE, r0 | 3 | yes |
//! | DLC | 4 | yes |
//! | data | 8n | yes |
//! | CRC | 15 | yes |
//! | CRC delimiter, ACK slot, ACK delimiter | 3 | no |
//! | end of frame | 7 | no |
//! | interframe space (before the next frame) | 3 | no |
//! | **total without stuffing** | **47 + 8n** | |
//!
//! After five equal bits the transmitter inserts one opposite *stuff bit*. Over the
//! `34 + 8n` stuffed bits the worst case is `⌊(34 + 8n − 1) / 4⌋` stuff bits (the first
//! run needs five bits, each later one four, because a stuff bit starts the next run).
//! [`frame_bits_exact`] instead counts the stuff bits of an actual frame, CRC included. The
//! simulated bus ([`crate::sim::bus::SimBus`]) charges every frame it carries with it.
//!
//! | at 1 Mbit/s, n = 8 | bits | time |
//! |---|---|---|
//! | one frame, no stuffing (incl. IFS) | 111 | 111 µs |
//! | one frame, worst-case stuffing (+24) | 135 | 135 µs |
//! | command + reply, no stuffing | 222 | 222 µs |
//! | command + reply, worst case | 270 | 270 µs |
//! | motors per bus at 1 kHz, no stuffing: ⌊1000 / 222⌋ | | 4 |
//! | motors per bus at 1 kHz, worst case: ⌊1000 / 270⌋ | | 3 |
//!
//! Each motor needs one command and one reply per control cycle, and the buses of the
//! limbs run in parallel, so the per-bus occupancy is `motors × exchange time`.
//! [`validate`] demands that this fits in one period **under worst-case stuffing** (a
//! deadline that only holds for lucky bit patterns is not a deadline); at 1 kHz that means
//! at most 3 motors per bus, at 4 motors per bus the highest rate is 925 Hz.
//! [`validate_with`] accepts [`Stuffing::None`] for a nominal estimate. Not included:
//! the motors' turnaround (reply latency after a command) and the host's scheduling
//! jitter; both eat into the remaining slack reported in [`BusBudget`].

use core::time::Duration;
use thiserror::Error;

/// Default classic CAN bitrate \[bit/s\].
pub const DEFAULT_BITRATE_BPS: u32 = 1_000_000;
/// Data bytes of every A1 frame.
pub const A1_FRAME_BYTES: u32 = 8;
/// Interframe space \[bits\].
pub const INTERFRAME_BITS: u32 = 3;

/// Which stuff-bit count to assume.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stuffing {
    /// No stuff bits (a lower bound, what a naive estimate uses).
    None,
    /// The largest possible number of stuff bits (an upper bound).
    WorstCase,
}

impl Stuffing {
    /// The assumption in words.
    pub fn name(self) -> &'static str {
        match self {
            Stuffing::None => "no",
            Stuffing::WorstCase => "worst-case",
        }
    }
}

/// Bits of a standard-id data frame with `data_bytes` bytes, interframe space included.
pub const fn frame_bits(data_bytes: u32, stuffing: Stuffing) -> u32 {
    let unstuffed = 47 + 8 * data_bytes;
    match stuffing {
        Stuffing::None => unstuffed,
        Stuffing::WorstCase => unstuffed + (34 + 8 * data_bytes - 1) / 4,
    }
}

/// CAN CRC-15 generator polynomial (x¹⁵ + x¹⁴ + x¹⁰ + x⁸ + x⁷ + x⁴ + x³ + 1, top bit implied).
const CRC15_POLY: u16 = 0x4599;

/// The CRC-15 register after one bit (MSB first, no init, no final xor).
const fn crc15_bit(crc: u16, bit: bool) -> u16 {
    let feedback = bit ^ ((crc >> 14) & 1 == 1);
    let shifted = (crc << 1) & 0x7FFF;
    if feedback {
        shifted ^ CRC15_POLY
    } else {
        shifted
    }
}

/// `CRC15_BYTE[b]`: the register after the eight bits of `b` from a zero register. By
/// linearity, a byte `b` moves a register `r` to `(r << 8) ^ CRC15_BYTE[(r >> 7) ^ b]`.
static CRC15_BYTE: [u16; 256] = {
    let mut table = [0u16; 256];
    let mut b = 0;
    while b < 256 {
        let mut crc = 0;
        let mut i = 8;
        while i > 0 {
            i -= 1;
            crc = crc15_bit(crc, (b >> i) & 1 == 1);
        }
        table[b] = crc;
        b += 1;
    }
    table
};

/// States of the bit stuffer: 0 before the first bit, else `1 + 4·bit + (run length − 1)` for
/// the last bit on the wire and the length (1 to 4) of its run.
const STUFF_STATES: usize = 9;

/// The stuffer after one more frame bit: whether it inserted a stuff bit, and its new state.
/// After five equal bits it inserts the opposite bit, which starts a new run of length one.
const fn stuff_step(state: u8, bit: u8) -> (u8, u8) {
    let (last, len) = if state == 0 {
        (2, 0)
    } else {
        ((state - 1) / 4, (state - 1) % 4 + 1)
    };
    let (mut last, mut len) = if bit == last {
        (last, len + 1)
    } else {
        (bit, 1)
    };
    let mut stuffed = 0;
    if len == 5 {
        stuffed = 1;
        last ^= 1;
        len = 1;
    }
    (stuffed, 1 + 4 * last + (len - 1))
}

/// `STUFF_BYTE[state][b]`: the stuff bits inserted while sending the byte `b` (MSB first)
/// from `state`, and the state after it.
static STUFF_BYTE: [[(u8, u8); 256]; STUFF_STATES] = {
    let mut table = [[(0u8, 0u8); 256]; STUFF_STATES];
    let mut state = 0;
    while state < STUFF_STATES {
        let mut b = 0;
        while b < 256 {
            let (mut stuffed, mut s) = (0, state as u8);
            let mut i = 8;
            while i > 0 {
                i -= 1;
                let (k, next) = stuff_step(s, ((b >> i) & 1) as u8);
                stuffed += k;
                s = next;
            }
            table[state][b] = (stuffed, s);
            b += 1;
        }
        state += 1;
    }
    table
};

/// Bits of this actual standard-id data frame on the wire, stuff bits and interframe
/// space included; `None` if `id > 0x7FF` or `data.len() > 8`. Allocation-free and
/// table-driven: the simulated bus counts every frame it carries.
pub fn frame_bits_exact(id: u32, data: &[u8]) -> Option<u32> {
    if id > 0x7FF || data.len() > 8 {
        return None;
    }
    let dlc = data.len() as u32;
    // The stuffed bits, MSB first in `word`: SOF 0, id, RTR 0, IDE 0, r0 0, DLC (19 bits),
    // the data, then the CRC; at most 19 + 64 + 15 = 98 bits.
    let mut word = u128::from(id << 7 | dlc);
    // CRC: the first three header bits (SOF and the id's top two), then whole bytes.
    let mut crc = 0u16;
    for i in (16..19).rev() {
        crc = crc15_bit(crc, (word >> i) & 1 == 1);
    }
    let byte_crc = |crc: u16, byte: u8| {
        ((crc << 8) & 0x7FFF) ^ CRC15_BYTE[usize::from(((crc >> 7) as u8) ^ byte)]
    };
    crc = byte_crc(crc, (word >> 8) as u8);
    crc = byte_crc(crc, word as u8);
    for &byte in data {
        crc = byte_crc(crc, byte);
        word = word << 8 | u128::from(byte);
    }
    word = word << 15 | u128::from(crc);
    // Stuff bits: a byte at a time through the stuffing table, then the last two bits
    // (34 + 8n stuffed bits are 4 + n bytes and two bits).
    let n = 19 + 8 * data.len() + 15;
    let mut state = 0;
    let mut stuff_bits = 0;
    for k in 1..=n / 8 {
        let byte = (word >> (n - 8 * k)) as u8;
        let (stuffed, next) = STUFF_BYTE[usize::from(state)][usize::from(byte)];
        stuff_bits += u32::from(stuffed);
        state = next;
    }
    for i in (0..n % 8).rev() {
        let (stuffed, next) = stuff_step(state, (word >> i) as u8 & 1);
        stuff_bits += u32::from(stuffed);
        state = next;
    }
    Some(frame_bits(dlc, Stuffing::None) + stuff_bits)
}

/// Duration of `bits` bit times at `bitrate_bps`, rounded up to the nanosecond.
pub fn bits_to_duration(bits: u32, bitrate_bps: u32) -> Duration {
    let nanos = (u64::from(bits) * 1_000_000_000).div_ceil(u64::from(bitrate_bps.max(1)));
    Duration::from_nanos(nanos)
}

/// Time one A1 frame occupies the bus.
pub fn frame_time(bitrate_bps: u32, stuffing: Stuffing) -> Duration {
    bits_to_duration(frame_bits(A1_FRAME_BYTES, stuffing), bitrate_bps)
}

/// Time one command + reply exchange occupies the bus.
pub fn exchange_time(bitrate_bps: u32, stuffing: Stuffing) -> Duration {
    bits_to_duration(2 * frame_bits(A1_FRAME_BYTES, stuffing), bitrate_bps)
}

/// Most motors one bus can serve once per period at `rate_hz` (0 for an invalid rate).
pub fn max_motors_per_bus(rate_hz: f64, bitrate_bps: u32, stuffing: Stuffing) -> usize {
    if !(rate_hz.is_finite() && rate_hz > 0.0) || bitrate_bps == 0 {
        return 0;
    }
    let bits_per_period = f64::from(bitrate_bps) / rate_hz;
    (bits_per_period / f64::from(2 * frame_bits(A1_FRAME_BYTES, stuffing))).floor() as usize
}

/// How a configuration uses its buses, for logs and dashboards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BusBudget {
    /// Control period.
    pub period: Duration,
    /// Per-bus occupancy, no stuffing.
    pub bus_time_nominal: Duration,
    /// Per-bus occupancy, worst-case stuffing.
    pub bus_time_worst: Duration,
    /// `bus_time_worst / period`, ≤ 1 when valid.
    pub worst_utilization: f64,
}

/// A loop rate the buses cannot carry, or a meaningless argument.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum TimingError {
    /// The loop rate is not a positive finite number, or so small that its period does not
    /// fit a [`Duration`].
    #[error("loop rate {rate_hz} Hz is not a positive finite number with a representable period")]
    InvalidRate {
        /// Offending rate \[Hz\].
        rate_hz: f64,
    },
    /// The bitrate is zero or above the classic CAN maximum of 1 Mbit/s.
    #[error("CAN bitrate {bitrate_bps} bit/s is outside 1..=1000000")]
    InvalidBitrate {
        /// Offending bitrate \[bit/s\].
        bitrate_bps: u32,
    },
    /// The exchanges of one cycle do not fit in the period.
    #[error(
        "{motors_per_bus} motors per bus at {rate_hz} Hz need {needed_us:.0} µs of bus time \
         per {period_us:.0} µs period at {bitrate_bps} bit/s ({} stuffing); \
         at most {max_motors} motors per bus fit, or lower the rate to {max_rate_hz:.0} Hz",
        .stuffing.name()
    )]
    Overloaded {
        /// Requested loop rate \[Hz\].
        rate_hz: f64,
        /// Requested motors per bus.
        motors_per_bus: usize,
        /// Bitrate \[bit/s\].
        bitrate_bps: u32,
        /// Stuffing assumption.
        stuffing: Stuffing,
        /// Bus time needed per cycle \[µs\].
        needed_us: f64,
        /// Period \[µs\].
        period_us: f64,
        /// Largest motor count that fits at this rate.
        max_motors: usize,
        /// Highest rate that fits this motor count \[Hz\].
        max_rate_hz: f64,
    },
}

/// Check that `motors_per_bus` motors can each exchange a command and a reply every
/// cycle at `rate_hz` on a `bitrate_bps` bus, assuming worst-case bit stuffing.
pub fn validate(
    rate_hz: f64,
    motors_per_bus: usize,
    bitrate_bps: u32,
) -> Result<BusBudget, TimingError> {
    validate_with(rate_hz, motors_per_bus, bitrate_bps, Stuffing::WorstCase)
}

/// [`validate`] with an explicit stuffing assumption.
pub fn validate_with(
    rate_hz: f64,
    motors_per_bus: usize,
    bitrate_bps: u32,
    stuffing: Stuffing,
) -> Result<BusBudget, TimingError> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(TimingError::InvalidRate { rate_hz });
    }
    if bitrate_bps == 0 || bitrate_bps > 1_000_000 {
        return Err(TimingError::InvalidBitrate { bitrate_bps });
    }
    let period_s = 1.0 / rate_hz;
    let Ok(period) = Duration::try_from_secs_f64(period_s) else {
        return Err(TimingError::InvalidRate { rate_hz });
    };
    let bus_time = |s| exchange_time(bitrate_bps, s).as_secs_f64() * motors_per_bus as f64;
    let needed_s = bus_time(stuffing);
    if needed_s > period_s {
        let exchange_s = exchange_time(bitrate_bps, stuffing).as_secs_f64();
        return Err(TimingError::Overloaded {
            rate_hz,
            motors_per_bus,
            bitrate_bps,
            stuffing,
            needed_us: needed_s * 1e6,
            period_us: period_s * 1e6,
            max_motors: max_motors_per_bus(rate_hz, bitrate_bps, stuffing),
            max_rate_hz: 1.0 / (exchange_s * motors_per_bus as f64),
        });
    }
    Ok(BusBudget {
        period,
        bus_time_nominal: Duration::from_secs_f64(bus_time(Stuffing::None)),
        bus_time_worst: Duration::from_secs_f64(bus_time(Stuffing::WorstCase)),
        worst_utilization: bus_time(Stuffing::WorstCase) / period_s,
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::a1::{encode_command, Command, MotorId};
    use rand::{Rng, SeedableRng};

    const MBIT: u32 = 1_000_000;

    /// CRC-15 over a bit sequence, bit by bit: the definition.
    fn crc15(bits: impl Iterator<Item = bool>) -> u16 {
        bits.fold(0, crc15_bit)
    }

    /// The frame length bit by bit, the independent reference of [`frame_bits_exact`]: the
    /// frame as a bit vector, its CRC by the definition, then every run counted.
    fn frame_bits_by_definition(id: u32, data: &[u8]) -> u32 {
        let mut bits = Vec::new();
        let mut push = |value: u32, width: u32| {
            bits.extend((0..width).rev().map(|i| (value >> i) & 1 == 1));
        };
        push(0, 1);
        push(id, 11);
        push(0, 3);
        push(data.len() as u32, 4);
        for &byte in data {
            push(u32::from(byte), 8);
        }
        let crc = crc15(bits.iter().copied());
        bits.extend((0..15).rev().map(|i| (crc >> i) & 1 == 1));
        let mut stuffed: Vec<bool> = Vec::new();
        for bit in bits {
            stuffed.push(bit);
            let n = stuffed.len();
            if n >= 5 && stuffed[n - 5..].iter().all(|&b| b == bit) {
                stuffed.push(!bit);
            }
        }
        47 + 8 * data.len() as u32 + (stuffed.len() as u32 - (34 + 8 * data.len() as u32))
    }

    #[test]
    fn exact_frame_length_matches_the_bit_by_bit_definition() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for len in 0..=8 {
            for _ in 0..2000 {
                let id = rng.random_range(0..0x800);
                // Sparse and dense payloads too, where the long runs are.
                let data: Vec<u8> = (0..len)
                    .map(|_| match rng.random_range(0..4) {
                        0 => 0x00,
                        1 => 0xFF,
                        _ => rng.random(),
                    })
                    .collect();
                assert_eq!(
                    frame_bits_exact(id, &data),
                    Some(frame_bits_by_definition(id, &data)),
                    "id {id:#x} data {data:02x?}"
                );
            }
        }
    }

    #[test]
    fn frame_figures_match_hand_computation() {
        // 1+11+3+4+64+15+3+7+3 = 111; stuffable 1+11+3+4+64+15 = 98 -> (98-1)/4 = 24.
        assert_eq!(frame_bits(8, Stuffing::None), 111);
        assert_eq!(frame_bits(8, Stuffing::WorstCase), 135);
        assert_eq!(frame_bits(0, Stuffing::None), 47);
        assert_eq!(frame_bits(0, Stuffing::WorstCase), 47 + 8);
        assert_eq!(frame_time(MBIT, Stuffing::None), Duration::from_micros(111));
        assert_eq!(
            frame_time(MBIT, Stuffing::WorstCase),
            Duration::from_micros(135)
        );
        assert_eq!(
            exchange_time(MBIT, Stuffing::None),
            Duration::from_micros(222)
        );
        assert_eq!(
            exchange_time(MBIT, Stuffing::WorstCase),
            Duration::from_micros(270)
        );
        assert_eq!(
            exchange_time(500_000, Stuffing::None),
            Duration::from_micros(444)
        );
    }

    #[test]
    fn motors_per_bus_match_hand_computation() {
        assert_eq!(max_motors_per_bus(1000.0, MBIT, Stuffing::None), 4); // 1000/222
        assert_eq!(max_motors_per_bus(1000.0, MBIT, Stuffing::WorstCase), 3); // 1000/270
        assert_eq!(max_motors_per_bus(500.0, MBIT, Stuffing::WorstCase), 7); // 2000/270
        assert_eq!(max_motors_per_bus(1000.0, 500_000, Stuffing::None), 2); // 1000/444
        assert_eq!(max_motors_per_bus(f64::NAN, MBIT, Stuffing::None), 0);
    }

    #[test]
    fn validate_accepts_what_fits_and_explains_what_does_not() {
        let b = validate(1000.0, 3, MBIT).unwrap();
        assert_eq!(b.bus_time_worst, Duration::from_micros(810));
        assert_eq!(b.bus_time_nominal, Duration::from_micros(666));
        assert!((b.worst_utilization - 0.81).abs() < 1e-12);
        let e = validate(1000.0, 4, MBIT).unwrap_err();
        match e {
            TimingError::Overloaded {
                needed_us,
                max_motors,
                max_rate_hz,
                ..
            } => {
                assert!((needed_us - 1080.0).abs() < 1e-6);
                assert_eq!(max_motors, 3);
                assert!((max_rate_hz - 925.9).abs() < 0.1); // 1 / (4 × 270 µs)
            }
            other => panic!("{other:?}"),
        }
        let text = e.to_string();
        assert!(text.contains("4 motors per bus at 1000 Hz"), "{text}");
        assert!(text.contains("1080 µs"), "{text}");
        assert!(validate(925.0, 4, MBIT).is_ok());
        assert!(validate_with(1000.0, 4, MBIT, Stuffing::None).is_ok());
        // Zero, and rates so small that the period overflows a Duration (1e-320 Hz is a
        // 1e320 s period; found by the hostile-input property test).
        for rate_hz in [0.0, 1e-320, 1e-300, f64::MIN_POSITIVE] {
            assert!(
                matches!(
                    validate(rate_hz, 1, MBIT),
                    Err(TimingError::InvalidRate { .. })
                ),
                "{rate_hz}"
            );
        }
        assert!(matches!(
            validate(1000.0, 1, 2_000_000),
            Err(TimingError::InvalidBitrate { .. })
        ));
    }

    #[test]
    fn crc15_definition_and_stuffing_of_a_known_frame() {
        // The register after a single 1 bit is the generator polynomial.
        assert_eq!(crc15(core::iter::once(true)), 0x4599);
        // The byte table is the bitwise register.
        for b in 0..=255u8 {
            let bits = (0..8).rev().map(|i| (b >> i) & 1 == 1);
            assert_eq!(CRC15_BYTE[usize::from(b)], crc15(bits), "{b}");
        }
        // A message followed by its CRC leaves remainder zero (no init, no final xor).
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..100 {
            let msg: Vec<bool> = (0..83).map(|_| rng.random()).collect();
            let crc = crc15(msg.iter().copied());
            let with_crc = msg
                .iter()
                .copied()
                .chain((0..15).rev().map(|i| (crc >> i) & 1 == 1));
            assert_eq!(crc15(with_crc), 0);
        }
        // Id 0, DLC 0: 19 zero header bits, CRC 0, so 34 zeros: a stuff bit (a one) after
        // every fifth zero, 34 / 5 = 6 stuff bits.
        assert_eq!(frame_bits_exact(0, &[]), Some(47 + 6));
    }

    #[test]
    fn exact_frame_length_lies_between_the_bounds() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let lo = frame_bits(8, Stuffing::None);
        let hi = frame_bits(8, Stuffing::WorstCase);
        for _ in 0..10_000 {
            let id = rng.random_range(0..0x800);
            let data: [u8; 8] = rng.random();
            let bits = frame_bits_exact(id, &data).unwrap();
            assert!((lo..=hi).contains(&bits), "{bits}");
        }
        // All-zero payload stuffs heavily; a typical A1 command is far from the bound.
        let zeros = frame_bits_exact(0x100, &[0; 8]).unwrap();
        // 64 zero data bits alone force a stuff bit every 5 bits: at least 12.
        assert!(zeros >= 111 + 12, "{zeros}");
        let m = MotorId::new(1).unwrap();
        let cmd = encode_command(&Command::pd(m, 0.3, 0.0, 60.0, 2.0, 1.0)).unwrap();
        let bits = frame_bits_exact(cmd.frame.id, &cmd.frame.data).unwrap();
        assert!((lo..hi).contains(&bits), "{bits}");
        assert_eq!(frame_bits_exact(0x800, &[]), None);
    }
}
