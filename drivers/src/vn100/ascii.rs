//! The VN-100's ASCII commands, sans IO: the configuration the driver sends and the replies it
//! reads back (VN-100 user manual UM001, "Write Register Command").
//!
//! A sentence is `$` body `*` checksum `\r\n`, the checksum the XOR of the body's bytes as two
//! hex digits. A write is `$VNWRG,<register>,<values…>`; the sensor answers with the same
//! sentence (the register's new values) or `$VNERR,<code>`.
//!
//! The driver writes three registers:
//! * 5, serial baud rate (only when the sensor is still at another rate);
//! * 6, asynchronous ASCII output type, set to 0 (off: its lines would only be garbage between
//!   binary frames);
//! * 75, binary output 1: `AsyncMode` 3 (both serial ports: whichever the host is on),
//!   `RateDivisor` (800 Hz / divisor), `OutputGroup` 01 (common group), the field word
//!   ([`Fields::DRIVER`] = `0129`: time since start-up, yaw/pitch/roll, angular rate,
//!   acceleration).

use super::frame::Fields;

/// The VN-100's IMU rate, Hz: binary output runs at this rate over the rate divisor.
pub const IMU_RATE_HZ: f64 = 800.0;
/// Register: serial baud rate.
pub const REG_BAUD: u8 = 5;
/// Register: asynchronous ASCII output type.
pub const REG_ASYNC_ASCII: u8 = 6;
/// Register: binary output 1.
pub const REG_BINARY_OUTPUT_1: u8 = 75;
/// Longest sentence accepted, bytes.
pub const MAX_SENTENCE_LEN: usize = 256;

/// XOR of the bytes of `body` (between `$` and `*`).
pub fn checksum(body: &str) -> u8 {
    body.bytes().fold(0, |acc, b| acc ^ b)
}

/// `$<body>*<checksum>\r\n`.
pub fn sentence(body: &str) -> String {
    format!("${body}*{:02X}\r\n", checksum(body))
}

/// Write `values` to `register`.
pub fn write_register(register: u8, values: &[String]) -> String {
    let mut body = format!("VNWRG,{register:02}");
    for v in values {
        body.push(',');
        body.push_str(v);
    }
    sentence(&body)
}

/// Set the sensor's serial baud rate.
pub fn set_baud(baud_bps: u32) -> String {
    write_register(REG_BAUD, &[baud_bps.to_string()])
}

/// Turn the asynchronous ASCII output off.
pub fn async_ascii_off() -> String {
    write_register(REG_ASYNC_ASCII, &["0".into()])
}

/// Binary output 1 on both serial ports at 800 Hz / `rate_divisor` with the common-group
/// `fields`.
pub fn binary_output(rate_divisor: u16, fields: Fields) -> String {
    write_register(
        REG_BINARY_OUTPUT_1,
        &[
            "3".into(),
            rate_divisor.to_string(),
            "01".into(),
            format!("{:04X}", fields.bits()),
        ],
    )
}

/// A sentence read back, checksum checked.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sentence {
    /// What follows `$` up to the first comma, e.g. `VNWRG` or `VNERR`.
    pub header: String,
    /// The comma-separated values after the header.
    pub values: Vec<String>,
}

impl Sentence {
    /// Parses one line (`$…*XX`, with or without its line end); `None` if it is not a
    /// sentence or its checksum does not hold.
    pub fn parse(line: &str) -> Option<Self> {
        let line = line.trim_end_matches(['\r', '\n']);
        let body_and_sum = line.strip_prefix('$')?;
        let (body, sum) = body_and_sum.rsplit_once('*')?;
        let sum = u8::from_str_radix(sum, 16)
            .ok()
            .filter(|_| sum.len() == 2)?;
        if sum != checksum(body) {
            return None;
        }
        let mut parts = body.split(',');
        let header = parts.next()?.to_string();
        Some(Self {
            header,
            values: parts.map(str::to_string).collect(),
        })
    }

    /// The register a `VNWRG` sentence writes (or a reply confirms).
    pub fn written_register(&self) -> Option<u8> {
        (self.header == "VNWRG")
            .then(|| self.values.first()?.parse().ok())
            .flatten()
    }

    /// The error code of a `VNERR` sentence.
    pub fn error_code(&self) -> Option<u8> {
        (self.header == "VNERR")
            .then(|| self.values.first()?.parse().ok())
            .flatten()
    }
}

/// Splits a byte stream into candidate sentences: from a `$` to the line end, printable ASCII
/// only, at most [`MAX_SENTENCE_LEN`] bytes; anything else (binary frames) is passed over.
#[derive(Clone, Debug, Default)]
pub struct LineScanner {
    line: Vec<u8>,
    in_line: bool,
}

impl LineScanner {
    /// Takes one byte; returns a completed sentence whose checksum holds.
    pub fn push(&mut self, b: u8) -> Option<Sentence> {
        match b {
            b'$' => {
                self.line.clear();
                self.line.push(b);
                self.in_line = true;
            }
            b'\n' if self.in_line => {
                self.in_line = false;
                return std::str::from_utf8(&self.line)
                    .ok()
                    .and_then(Sentence::parse);
            }
            b'\r' => {}
            0x20..=0x7E if self.in_line && self.line.len() < MAX_SENTENCE_LEN => self.line.push(b),
            _ => self.in_line = false,
        }
        None
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn commands_carry_the_xor_checksum_and_parse_back() {
        let cmd = binary_output(1, Fields::DRIVER);
        assert!(cmd.starts_with("$VNWRG,75,3,1,01,0129*"), "{cmd}");
        assert!(cmd.ends_with("\r\n"));
        let s = Sentence::parse(&cmd).unwrap();
        assert_eq!(s.written_register(), Some(75));
        assert_eq!(s.values, ["75", "3", "1", "01", "0129"]);
        // The manual's own example reply (VN-200 manual UM004, register 6): `$VNRRG,06,0*69`.
        assert_eq!(checksum("VNRRG,06,0"), 0x69);
        assert!(Sentence::parse("$VNRRG,06,0*69").is_some());
        assert_eq!(async_ascii_off(), sentence("VNWRG,06,0"));
        assert_eq!(set_baud(921_600), sentence("VNWRG,05,921600"));
    }

    #[test]
    fn a_wrong_checksum_or_garbage_is_not_a_sentence() {
        let mut cmd = async_ascii_off();
        assert!(Sentence::parse(&cmd).is_some());
        cmd.replace_range(7..8, "7");
        assert_eq!(Sentence::parse(&cmd), None);
        assert_eq!(Sentence::parse("VNWRG,06,0*00"), None);
        assert_eq!(Sentence::parse("$VNWRG,06,0*0"), None);
        let err = Sentence::parse(&sentence("VNERR,03")).unwrap();
        assert_eq!(err.error_code(), Some(3));
    }

    #[test]
    fn the_scanner_finds_sentences_between_binary_bytes() {
        let mut bytes = vec![0xFA, 0x01, b'$', 0x29, 0x01];
        bytes.extend(async_ascii_off().bytes());
        bytes.extend([0xFA, b'$', b'V', 0x00]);
        bytes.extend(binary_output(2, Fields::DRIVER).bytes());
        let mut scanner = LineScanner::default();
        let found: Vec<_> = bytes.iter().filter_map(|&b| scanner.push(b)).collect();
        let regs: Vec<_> = found.iter().map(|s| s.written_register()).collect();
        assert_eq!(regs, [Some(6), Some(75)]);
    }
}
