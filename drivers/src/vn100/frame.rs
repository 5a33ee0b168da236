//! The VN-100's binary output frame, sans IO: [`encode`] a [`Measurement`] into a frame and
//! [`Parser`] frames back out of a byte stream (resynchronising after garbage, a frame split
//! across reads, counters of what it dropped).
//!
//! A frame (VN-100 user manual UM001, "Binary Output Message Format"), all numbers
//! little-endian except the CRC:
//! ```text
//! 0xFA | groups (u8) | one u16 field word per group | payload: the fields in bit order | CRC-16 (big-endian)
//! ```
//! This driver reads the common group only (groups byte `0x01`) and, in it, the fields of
//! [`Fields`]: time since start-up (u64, ns), yaw/pitch/roll (3 × f32, degrees), quaternion
//! (4 × f32, vector part first, scalar last), angular rate (3 × f32, rad/s, body frame) and
//! acceleration (3 × f32, m/s², body frame, specific force: −g on a flat sensor's z, which points
//! down). A frame naming any other group or field is refused as a bad header (its length would be
//! unknown to us), so garbage must match a known header *and* the CRC to pass.
//!
//! The CRC is CRC-16-CCITT with polynomial 0x1021 and initial value 0 (the "XMODEM" variant),
//! over every byte after the sync byte; the CRC of a whole valid frame after the sync byte,
//! CRC included, is 0.

/// The sync byte that starts every binary frame.
pub const SYNC: u8 = 0xFA;
/// The groups byte of a frame with the common group only (group 1, bit 0).
pub const COMMON_GROUP: u8 = 0x01;
/// The longest frame this parser reads (every field of [`Fields`]), bytes.
pub const MAX_FRAME_LEN: usize = 4 + 8 + 12 + 16 + 12 + 12 + 2;

/// Fields of the common group (bits of its field word) that this driver reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Fields(u16);

/// Field bits and payload sizes, in payload order.
const FIELD_SIZES: [(u16, usize); 5] = [
    (1 << 0, 8),  // TimeStartup
    (1 << 3, 12), // YawPitchRoll
    (1 << 4, 16), // Quaternion
    (1 << 5, 12), // AngularRate
    (1 << 8, 12), // Accel
];

impl Fields {
    /// Time since the sensor started, u64, ns.
    pub const TIME_STARTUP: Self = Self(1 << 0);
    /// Yaw, pitch, roll, 3 × f32, degrees.
    pub const YAW_PITCH_ROLL: Self = Self(1 << 3);
    /// Attitude quaternion, 4 × f32 (x, y, z, w).
    pub const QUATERNION: Self = Self(1 << 4);
    /// Compensated angular rate in the body frame, 3 × f32, rad/s.
    pub const ANGULAR_RATE: Self = Self(1 << 5);
    /// Compensated acceleration (specific force) in the body frame, 3 × f32, m/s².
    pub const ACCEL: Self = Self(1 << 8);
    /// Every field this parser reads.
    pub const ALL: Self = Self(0x0001 | 0x0008 | 0x0010 | 0x0020 | 0x0100);
    /// What the driver asks the VN-100 for: time stamp, attitude, angular rate and
    /// acceleration (field word `0x0129`).
    pub const DRIVER: Self = Self(0x0001 | 0x0008 | 0x0020 | 0x0100);

    /// The field word `bits` if it is non-empty and names only fields of [`Fields::ALL`].
    pub fn from_bits(bits: u16) -> Option<Self> {
        (bits != 0 && bits & !Self::ALL.0 == 0).then_some(Self(bits))
    }

    /// The field word.
    pub fn bits(self) -> u16 {
        self.0
    }

    /// Whether every field of `other` is in `self`.
    pub fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// Bytes of the payload.
    pub fn payload_len(self) -> usize {
        FIELD_SIZES
            .iter()
            .filter(|(bit, _)| self.0 & bit != 0)
            .map(|(_, n)| n)
            .sum()
    }

    /// Bytes of the whole frame: sync, groups, field word, payload, CRC.
    pub fn frame_len(self) -> usize {
        4 + self.payload_len() + 2
    }
}

/// One binary output frame of the common group, decoded. Fields not in `fields` are zero.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Measurement {
    /// Which fields the frame carried.
    pub fields: Fields,
    /// Time since the sensor started, ns.
    pub time_startup_ns: u64,
    /// Yaw, pitch, roll, degrees (the VN-100's attitude solution, its body frame).
    pub yaw_pitch_roll_deg: [f32; 3],
    /// Attitude quaternion (x, y, z, w: vector part first).
    pub quaternion: [f32; 4],
    /// Angular rate about the VN-100's x, y, z, rad/s.
    pub angular_rate_rad_s: [f32; 3],
    /// Specific force along the VN-100's x, y, z, m/s² (−g on z when flat at rest).
    pub accel_mps2: [f32; 3],
}

/// The CRC-16-CCITT table (polynomial 0x1021, MSB first), one entry per leading byte.
const CRC_TABLE: [u16; 256] = {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = (i as u16) << 8;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
};

/// CRC-16-CCITT (polynomial 0x1021, initial value 0, MSB first) of `bytes`.
pub fn crc16(bytes: &[u8]) -> u16 {
    bytes.iter().fold(0u16, |crc, &b| {
        (crc << 8) ^ CRC_TABLE[usize::from((crc >> 8) as u8 ^ b)]
    })
}

/// Writes the frame of `m` (its `fields`, which must be non-empty and within
/// [`Fields::ALL`]) into `out`; returns its length, or `None` for fields it cannot encode.
pub fn encode(m: &Measurement, out: &mut [u8; MAX_FRAME_LEN]) -> Option<usize> {
    let fields = Fields::from_bits(m.fields.bits())?;
    let len = fields.frame_len();
    out[0] = SYNC;
    out[1] = COMMON_GROUP;
    out[2..4].copy_from_slice(&fields.bits().to_le_bytes());
    let mut at = 4;
    let mut put = |bytes: &[u8]| {
        out[at..at + bytes.len()].copy_from_slice(bytes);
        at += bytes.len();
    };
    if fields.contains(Fields::TIME_STARTUP) {
        put(&m.time_startup_ns.to_le_bytes());
    }
    let floats = [
        (Fields::YAW_PITCH_ROLL, &m.yaw_pitch_roll_deg[..]),
        (Fields::QUATERNION, &m.quaternion[..]),
        (Fields::ANGULAR_RATE, &m.angular_rate_rad_s[..]),
        (Fields::ACCEL, &m.accel_mps2[..]),
    ];
    for (field, values) in floats {
        if fields.contains(field) {
            for v in values {
                put(&v.to_le_bytes());
            }
        }
    }
    let crc = crc16(&out[1..len - 2]);
    out[len - 2..len].copy_from_slice(&crc.to_be_bytes());
    Some(len)
}

/// Decodes the payload of a frame of `fields` (length already checked).
fn decode(fields: Fields, payload: &[u8]) -> Measurement {
    let mut m = Measurement {
        fields,
        ..Measurement::default()
    };
    let mut at = 0;
    let mut take = |n: usize| {
        let s = &payload[at..at + n];
        at += n;
        s
    };
    let f32_at = |s: &[u8], k: usize| {
        f32::from_le_bytes([s[4 * k], s[4 * k + 1], s[4 * k + 2], s[4 * k + 3]])
    };
    if fields.contains(Fields::TIME_STARTUP) {
        let s = take(8);
        let mut b = [0u8; 8];
        b.copy_from_slice(s);
        m.time_startup_ns = u64::from_le_bytes(b);
    }
    if fields.contains(Fields::YAW_PITCH_ROLL) {
        let s = take(12);
        m.yaw_pitch_roll_deg = [0, 1, 2].map(|k| f32_at(s, k));
    }
    if fields.contains(Fields::QUATERNION) {
        let s = take(16);
        m.quaternion = [0, 1, 2, 3].map(|k| f32_at(s, k));
    }
    if fields.contains(Fields::ANGULAR_RATE) {
        let s = take(12);
        m.angular_rate_rad_s = [0, 1, 2].map(|k| f32_at(s, k));
    }
    if fields.contains(Fields::ACCEL) {
        let s = take(12);
        m.accel_mps2 = [0, 1, 2].map(|k| f32_at(s, k));
    }
    m
}

/// What the parser has seen so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ParserStats {
    /// Frames whose header and CRC held.
    pub frames_ok: u64,
    /// Candidates (a sync byte and a known header) whose CRC failed.
    pub crc_failures: u64,
    /// Sync bytes followed by a groups byte or field word this parser does not read.
    pub bad_headers: u64,
    /// Bytes passed over while looking for a frame (garbage, ASCII, failed candidates' sync bytes).
    pub bytes_skipped: u64,
}

/// Bytes the parser holds: several of the longest frames, so a push always has room.
const BUFFER_LEN: usize = 8 * MAX_FRAME_LEN;

/// The sans-IO frame parser: [`Parser::push`] bytes as they come (any split), take frames with
/// [`Parser::next_frame`] (or both with [`Parser::feed`]). Fixed buffer, no allocation.
///
/// At each sync byte with a known header it waits for the whole frame, then checks the CRC;
/// a candidate that fails gives up only its sync byte and the search resumes from the next
/// byte, so a real frame hidden behind a false candidate is still found.
#[derive(Clone, Debug)]
pub struct Parser {
    expected: Option<Fields>,
    buf: [u8; BUFFER_LEN],
    start: usize,
    end: usize,
    stats: ParserStats,
}

impl Default for Parser {
    fn default() -> Self {
        Self::new()
    }
}

impl Parser {
    /// An empty parser of frames with any fields of [`Fields::ALL`].
    pub fn new() -> Self {
        Self {
            expected: None,
            buf: [0; BUFFER_LEN],
            start: 0,
            end: 0,
            stats: ParserStats::default(),
        }
    }

    /// An empty parser of frames with exactly `fields` (the output the driver configured):
    /// a corrupt field word is a bad header, never a frame of another length.
    pub fn expecting(fields: Fields) -> Self {
        Self {
            expected: Some(fields),
            ..Self::new()
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> ParserStats {
        self.stats
    }

    /// Bytes held, waiting for the rest of a frame.
    pub fn buffered(&self) -> usize {
        self.end - self.start
    }

    /// Takes as many bytes of `input` as fit (at least `BUFFER_LEN − MAX_FRAME_LEN` once the
    /// frames before have been taken); returns how many.
    pub fn push(&mut self, input: &[u8]) -> usize {
        if self.start > 0 && BUFFER_LEN - self.end < input.len() {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        let n = input.len().min(BUFFER_LEN - self.end);
        self.buf[self.end..self.end + n].copy_from_slice(&input[..n]);
        self.end += n;
        n
    }

    /// Pushes all of `input`, calling `on_frame` with each frame completed.
    pub fn feed(&mut self, mut input: &[u8], mut on_frame: impl FnMut(Measurement)) {
        while !input.is_empty() {
            let n = self.push(input);
            input = &input[n..];
            while let Some(m) = self.next_frame() {
                on_frame(m);
            }
        }
    }

    /// The next complete frame in the bytes held, or `None` until more bytes come.
    pub fn next_frame(&mut self) -> Option<Measurement> {
        loop {
            let held = &self.buf[self.start..self.end];
            let Some(at) = held.iter().position(|&b| b == SYNC) else {
                self.stats.bytes_skipped += held.len() as u64;
                self.start = 0;
                self.end = 0;
                return None;
            };
            self.stats.bytes_skipped += at as u64;
            self.start += at;
            let held = &self.buf[self.start..self.end];
            if held.len() < 4 {
                return None;
            }
            let fields = (held[1] == COMMON_GROUP)
                .then(|| Fields::from_bits(u16::from_le_bytes([held[2], held[3]])))
                .flatten()
                .filter(|f| self.expected.is_none_or(|e| e == *f));
            let Some(fields) = fields else {
                self.stats.bad_headers += 1;
                self.give_up_sync();
                continue;
            };
            let len = fields.frame_len();
            if held.len() < len {
                return None;
            }
            if crc16(&held[1..len]) != 0 {
                self.stats.crc_failures += 1;
                self.give_up_sync();
                continue;
            }
            let m = decode(fields, &held[4..len - 2]);
            self.start += len;
            self.stats.frames_ok += 1;
            return Some(m);
        }
    }

    /// A failed candidate: skip its sync byte only.
    fn give_up_sync(&mut self) {
        self.stats.bytes_skipped += 1;
        self.start += 1;
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn sample(k: u64) -> Measurement {
        Measurement {
            fields: Fields::DRIVER,
            time_startup_ns: 1_250_000 * k,
            yaw_pitch_roll_deg: [10.0, -3.5, 0.25],
            angular_rate_rad_s: [0.01, -0.2, 0.003],
            accel_mps2: [0.6, 0.01, -9.79],
            ..Measurement::default()
        }
    }

    fn frame(m: &Measurement) -> Vec<u8> {
        let mut out = [0; MAX_FRAME_LEN];
        let n = encode(m, &mut out).unwrap();
        out[..n].to_vec()
    }

    #[test]
    fn crc_is_ccitt_xmodem_check_value_and_zero_over_a_frame() {
        // The catalogued check value of CRC-16/XMODEM over "123456789".
        assert_eq!(crc16(b"123456789"), 0x31C3);
        let f = frame(&sample(1));
        assert_eq!(crc16(&f[1..]), 0);
        assert_eq!(f.len(), 50);
        assert_eq!(&f[..4], &[0xFA, 0x01, 0x29, 0x01]);
    }

    #[test]
    fn a_frame_split_at_every_point_parses_once() {
        let f = frame(&sample(3));
        for cut in 0..=f.len() {
            let mut p = Parser::new();
            let mut got = Vec::new();
            p.feed(&f[..cut], |m| got.push(m));
            assert!(got.is_empty() || cut == f.len());
            p.feed(&f[cut..], |m| got.push(m));
            assert_eq!(got, vec![sample(3)], "cut at {cut}");
            assert_eq!(p.stats().bytes_skipped, 0);
        }
    }

    #[test]
    fn garbage_and_a_false_header_are_skipped_and_counted() {
        let mut bytes = vec![0x00, 0x24, 0xFA, 0x02, 0x00]; // 0xFA + an unknown group
        bytes.extend([0xFA, 0x01, 0x29, 0x01, 0x55]); // a known header, then the real frame
        bytes.extend(frame(&sample(1)));
        let mut flipped = frame(&sample(2));
        flipped[20] ^= 0x10;
        bytes.extend(&flipped);
        bytes.extend(frame(&sample(3)));
        let mut p = Parser::new();
        let mut got = Vec::new();
        p.feed(&bytes, |m| got.push(m));
        assert_eq!(got, vec![sample(1), sample(3)]);
        let s = p.stats();
        assert_eq!(s.frames_ok, 2);
        assert!(s.crc_failures >= 2, "{s:?}"); // the false header and the flipped frame
        assert_eq!(s.bad_headers, 1);
        assert_eq!(p.buffered(), 0);
    }

    #[test]
    fn unknown_fields_are_refused() {
        assert_eq!(Fields::from_bits(0), None);
        assert_eq!(Fields::from_bits(1 << 1), None);
        assert_eq!(Fields::from_bits(0x8001), None);
        assert_eq!(Fields::DRIVER.bits(), 0x0129);
        assert_eq!(Fields::ALL.frame_len(), MAX_FRAME_LEN);
    }
}
