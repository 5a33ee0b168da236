//! The VN-100 on a serial port: [`Vn100::open`] opens and configures it, then it is an
//! [`Imu`]: each read takes the bytes waiting on the port (never blocking: it reads only what
//! `FIONREAD` says is there, into a buffer on the stack), parses them and maps the newest frame
//! to the runtime's [`ImuSample`]. Nothing allocates after `open`.
//!
//! Beyond the parser's counters ([`ParserStats`]), the driver checks each frame's time stamp
//! against the configured rate: a gap of k periods counts k − 1 missed frames; a time stamp off
//! that grid (a corrupt frame whose CRC happened to hold) is refused and counted implausible.

use super::ascii::{self, LineScanner};
use super::frame::{Fields, Measurement, Parser, ParserStats};
use super::mounting::Mounting;
use super::{Vn100Error, Vn100Options};
use crate::imu::{Imu, ImuError, ImuSample};
use serialport::{SerialPort, TTYPort};
use std::io::{Read, Write};
use std::time::{Duration, Instant};

/// What the driver has counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Vn100Stats {
    /// The parser's counters.
    pub parser: ParserStats,
    /// Frames taken as samples.
    pub samples: u64,
    /// Frames missing by their neighbours' time stamps.
    pub frames_missed: u64,
    /// Frames refused: time stamp not on the rate's grid after the last one.
    pub implausible: u64,
    /// Frames without the fields the driver needs (angular rate, acceleration, time).
    pub wrong_fields: u64,
    /// Reads of the port that failed.
    pub read_errors: u64,
}

/// Bytes read from the port per call at most (on the stack).
const READ_CHUNK: usize = 1024;

/// The VN-100 driver over a serial port.
pub struct Vn100 {
    port: TTYPort,
    path: String,
    parser: Parser,
    mounting: Mounting,
    period_ns: u64,
    last_time_ns: Option<u64>,
    pending_anchor_ns: Option<u64>,
    latest: Option<Measurement>,
    fresh: bool,
    sample: Option<ImuSample>,
    stats: Vn100Stats,
}

impl Vn100 {
    /// Opens the serial port at `path`, configures the sensor (asynchronous ASCII off, binary
    /// output 1 with [`Fields::DRIVER`] at `options.rate_hz`) and waits for its replies.
    /// If it does not answer at `options.baud_bps`, tries `options.factory_baud_bps` and sets
    /// the baud rate first. Errors name the port.
    pub fn open(path: &str, options: &Vn100Options) -> Result<Self, Vn100Error> {
        let divisor = options.rate_divisor()?;
        let port = serialport::new(path, options.baud_bps)
            .timeout(Duration::from_millis(20))
            .open_native()
            .map_err(|source| Vn100Error::Open {
                port: path.to_string(),
                reason: source.description,
            })?;
        let mut driver = Self {
            port,
            path: path.to_string(),
            parser: Parser::expecting(Fields::DRIVER),
            mounting: options.mounting,
            period_ns: (1e9 / options.rate_hz).round() as u64,
            last_time_ns: None,
            pending_anchor_ns: None,
            latest: None,
            fresh: false,
            sample: None,
            stats: Vn100Stats::default(),
        };
        let wait = options.reply_timeout;
        let mut bauds = vec![options.baud_bps];
        if options.factory_baud_bps != options.baud_bps {
            bauds.push(options.factory_baud_bps);
        }
        let mut last_error = None;
        for &baud in &bauds {
            driver.set_baud(baud)?;
            if baud != options.baud_bps {
                match driver.command(&ascii::set_baud(options.baud_bps), ascii::REG_BAUD, wait) {
                    Ok(()) => driver.set_baud(options.baud_bps)?,
                    Err(e) => {
                        last_error = Some(e);
                        continue;
                    }
                }
            }
            let configured = driver
                .command(&ascii::async_ascii_off(), ascii::REG_ASYNC_ASCII, wait)
                .and_then(|()| {
                    driver.command(
                        &ascii::binary_output(divisor, Fields::DRIVER),
                        ascii::REG_BINARY_OUTPUT_1,
                        wait,
                    )
                });
            match configured {
                Ok(()) => return Ok(driver),
                Err(e @ Vn100Error::Device { .. }) => return Err(e),
                Err(e) => last_error = Some(e),
            }
        }
        Err(last_error.unwrap_or(Vn100Error::NoReply {
            port: path.to_string(),
            command: "none".into(),
            waited_s: 0.0,
        }))
    }

    fn set_baud(&mut self, baud_bps: u32) -> Result<(), Vn100Error> {
        self.port
            .set_baud_rate(baud_bps)
            .map_err(|e| Vn100Error::Io {
                port: self.path.clone(),
                what: format!("setting {baud_bps} baud"),
                reason: e.description,
            })
    }

    /// Sends `command` and waits up to `wait` for the reply that confirms `register` (or an
    /// error reply). Bytes after the reply go to the frame parser.
    fn command(&mut self, command: &str, register: u8, wait: Duration) -> Result<(), Vn100Error> {
        let shown = command.trim_end().to_string();
        let io = |e: std::io::Error, path: &str| Vn100Error::Io {
            port: path.to_string(),
            what: format!("writing `{shown}`"),
            reason: e.to_string(),
        };
        self.port
            .write_all(command.as_bytes())
            .map_err(|e| io(e, &self.path))?;
        let _ = self.port.flush();
        let deadline = Instant::now() + wait;
        let mut scanner = LineScanner::default();
        let mut buf = [0u8; 256];
        while Instant::now() < deadline {
            let n = match self.port.read(&mut buf) {
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => continue,
                Err(e) => {
                    return Err(Vn100Error::Io {
                        port: self.path.clone(),
                        what: format!("reading the reply to `{shown}`"),
                        reason: e.to_string(),
                    })
                }
            };
            for (i, &b) in buf[..n].iter().enumerate() {
                let Some(s) = scanner.push(b) else { continue };
                if let Some(code) = s.error_code() {
                    return Err(Vn100Error::Device {
                        port: self.path.clone(),
                        command: shown,
                        code,
                    });
                }
                if s.written_register() == Some(register) {
                    self.ingest(&buf[i + 1..n]);
                    return Ok(());
                }
            }
        }
        Err(Vn100Error::NoReply {
            port: self.path.clone(),
            command: shown,
            waited_s: wait.as_secs_f64(),
        })
    }

    /// The serial port's path.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The counters so far.
    pub fn stats(&self) -> Vn100Stats {
        Vn100Stats {
            parser: self.parser.stats(),
            ..self.stats
        }
    }

    /// The newest frame taken (all its fields: attitude too).
    pub fn latest(&self) -> Option<&Measurement> {
        self.latest.as_ref()
    }

    /// Reads what is waiting on the port without blocking and parses it; returns the number of
    /// frames taken. Allocates nothing.
    pub fn poll(&mut self) -> usize {
        let mut taken = 0;
        let mut buf = [0u8; READ_CHUNK];
        loop {
            let waiting = match self.port.bytes_to_read() {
                Ok(n) => n as usize,
                Err(_) => {
                    self.stats.read_errors += 1;
                    return taken;
                }
            };
            if waiting == 0 {
                return taken;
            }
            let n = match self.port.read(&mut buf[..waiting.min(READ_CHUNK)]) {
                Ok(n) => n,
                Err(_) => {
                    self.stats.read_errors += 1;
                    return taken;
                }
            };
            if n == 0 {
                return taken;
            }
            taken += self.ingest(&buf[..n]);
        }
    }

    /// Parses `bytes` and takes the frames in them; returns how many were taken.
    fn ingest(&mut self, mut bytes: &[u8]) -> usize {
        let mut taken = 0;
        while !bytes.is_empty() {
            let k = self.parser.push(bytes);
            bytes = &bytes[k..];
            while let Some(m) = self.parser.next_frame() {
                taken += usize::from(self.take(m));
            }
        }
        taken
    }

    /// Checks a parsed frame's fields and time stamp; keeps it if they hold.
    fn take(&mut self, m: Measurement) -> bool {
        if !m.fields.contains(Fields::DRIVER) {
            self.stats.wrong_fields += 1;
            return false;
        }
        let t = m.time_startup_ns;
        if let Some(last) = self.last_time_ns {
            match periods_after(last, t, self.period_ns) {
                Some(k) => self.stats.frames_missed += k - 1,
                None => {
                    // A second frame on the grid of an implausible one: the sensor restarted.
                    let restart = self
                        .pending_anchor_ns
                        .is_some_and(|p| periods_after(p, t, self.period_ns).is_some());
                    if !restart {
                        self.stats.implausible += 1;
                        self.pending_anchor_ns = Some(t);
                        return false;
                    }
                }
            }
        }
        self.pending_anchor_ns = None;
        self.last_time_ns = Some(t);
        self.latest = Some(m);
        self.fresh = true;
        self.stats.samples += 1;
        true
    }
}

/// How many periods `t` is after `last` if it lies on the grid (within a quarter period).
fn periods_after(last: u64, t: u64, period_ns: u64) -> Option<u64> {
    let dt = t.checked_sub(last)?;
    let k = (dt + period_ns / 2) / period_ns;
    let off = dt.abs_diff(k * period_ns);
    (k >= 1 && off <= period_ns / 4).then_some(k)
}

impl Imu for Vn100 {
    /// The newest sample, stamped when a read first saw it (its `t_s` then is this read's
    /// `out.t_s`); [`ImuError::Timeout`] before the first frame.
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        let t = out.t_s;
        *out = self.read_at(t).ok_or(ImuError::Timeout)?;
        Ok(())
    }

    /// The newest sample in the loop's clock: a frame new since the last read is stamped
    /// `t_s`; without one, the last sample is returned as it was (same values, same stamp), so
    /// the safety monitor sees a silent sensor go stale.
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        self.poll();
        if self.fresh {
            self.fresh = false;
            let m = self.latest?;
            self.sample = Some(self.mounting.to_sample(&m, t_s));
        }
        self.sample
    }
}

#[cfg(test)]
mod tests {
    use super::periods_after;

    #[test]
    fn time_stamps_on_the_grid_count_missed_frames_and_off_grid_ones_are_refused() {
        let p = 1_250_000;
        assert_eq!(periods_after(0, p, p), Some(1));
        assert_eq!(periods_after(0, 3 * p + 1000, p), Some(3));
        assert_eq!(periods_after(0, p / 2, p), None);
        assert_eq!(periods_after(5 * p, 4 * p, p), None);
        assert_eq!(periods_after(0, 0, p), None);
        assert_eq!(periods_after(0, 2 * p + p / 3, p), None);
    }
}
