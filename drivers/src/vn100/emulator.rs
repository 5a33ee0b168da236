//! An emulated VN-100 (`adam emulate imu`): it answers the driver's configuration commands
//! like the sensor and then streams binary frames at the configured rate, fed by the simulator's
//! IMU model ([`crate::imu::NoisyImu`] on a torso at rest, optionally swaying in pitch), with
//! faults injected on purpose: bursts of garbage between frames, a byte dropped from a frame,
//! a byte changed in a frame. It counts what it sent and what it spoilt, so a test can compare
//! with what the driver received and counted.
//!
//! [`Emulator`] is the sans-IO core (commands in, replies and byte chunks out); [`Pty`] and
//! [`serve`] put it on the master side of a pseudo-terminal pair, whose slave path the driver
//! opens as if it were `/dev/ttyUSB0`.
//!
//! The first and the last frame are never spoilt: the driver counts a frame as missed from the
//! time stamps of the frames on either side of it.

use super::ascii::{self, LineScanner, Sentence};
use super::frame::{encode, Fields, Measurement, MAX_FRAME_LEN, SYNC};
use super::mounting::Mounting;
use crate::imu::{ImuNoise, ImuSample, NoisyImu};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fs::File;
use std::io::{Read, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Standard gravity used for the emulated specific force, m/s².
const GRAVITY_MPS2: f64 = 9.81;
/// The emulated sensor's time since start-up at its first frame, ns.
const FIRST_TIME_NS: u64 = 1_000_000_000;
/// Longest burst of garbage, bytes.
const MAX_GARBAGE: usize = 48;

/// What the emulator feeds and spoils.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmulatorOptions {
    /// Seed of the noise and of the faults.
    pub seed: u64,
    /// Probability per frame of a burst of 1–48 garbage bytes before it (random bytes, often
    /// the sync byte and a valid-looking header among them).
    pub garbage_probability: f64,
    /// Probability per frame that one of its bytes is dropped.
    pub drop_probability: f64,
    /// Probability per frame that one of its bytes is changed.
    pub flip_probability: f64,
    /// The IMU noise put on the truth.
    pub noise: ImuNoise,
    /// Torso pitch at rest, rad (+ leaning forward).
    pub pitch_rad: f64,
    /// Amplitude of a pitch sway around it, rad (0: still).
    pub sway_amplitude_rad: f64,
    /// Frequency of the sway, Hz.
    pub sway_hz: f64,
    /// How the emulated sensor sits in the torso.
    pub mounting: Mounting,
}

impl Default for EmulatorOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            garbage_probability: 0.0,
            drop_probability: 0.0,
            flip_probability: 0.0,
            noise: ImuNoise::default(),
            pitch_rad: 0.05,
            sway_amplitude_rad: 0.0,
            sway_hz: 1.0,
            mounting: Mounting::DEFAULT,
        }
    }
}

/// What the emulator has sent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EmulatorCounts {
    /// Frames sent (intact or spoilt).
    pub frames_sent: u64,
    /// Frames sent intact.
    pub frames_intact: u64,
    /// Frames sent with a byte dropped.
    pub frames_dropped_byte: u64,
    /// Frames sent with a byte changed.
    pub frames_flipped: u64,
    /// Garbage bytes sent between frames.
    pub garbage_bytes: u64,
    /// Commands answered.
    pub commands: u64,
}

impl std::fmt::Display for EmulatorCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "frames sent {}, intact {}, dropped byte {}, changed byte {}, garbage bytes {}, commands {}",
            self.frames_sent,
            self.frames_intact,
            self.frames_dropped_byte,
            self.frames_flipped,
            self.garbage_bytes,
            self.commands
        )
    }
}

/// The emulated sensor (sans IO).
pub struct Emulator {
    options: EmulatorOptions,
    rng: ChaCha8Rng,
    imu: NoisyImu,
    rate_hz: Option<f64>,
    fields: Fields,
    k: u64,
    counts: EmulatorCounts,
}

impl Emulator {
    /// A sensor that streams nothing until binary output 1 is written.
    pub fn new(options: EmulatorOptions) -> Self {
        Self {
            options,
            rng: ChaCha8Rng::seed_from_u64(options.seed ^ 0x5eed_f00d),
            imu: NoisyImu::new(options.noise, options.seed),
            rate_hz: None,
            fields: Fields::DRIVER,
            k: 0,
            counts: EmulatorCounts::default(),
        }
    }

    /// The binary output rate once configured, Hz.
    pub fn rate_hz(&self) -> Option<f64> {
        self.rate_hz
    }

    /// What was sent so far.
    pub fn counts(&self) -> EmulatorCounts {
        self.counts
    }

    /// The sensor's answer to a command: the sentence echoed for a register it writes (5, 6,
    /// 75), `$VNERR` otherwise (8: register, 7: parameter, 4: command). Writing register 75
    /// starts the stream.
    pub fn reply(&mut self, s: &Sentence) -> String {
        self.counts.commands += 1;
        let echo = || ascii::sentence(&format!("{},{}", s.header, s.values.join(",")));
        match s.written_register() {
            Some(ascii::REG_BAUD | ascii::REG_ASYNC_ASCII) => echo(),
            Some(ascii::REG_BINARY_OUTPUT_1) => {
                let v = &s.values;
                let divisor = v
                    .get(2)
                    .and_then(|d| d.parse::<u16>().ok())
                    .filter(|&d| d > 0);
                let fields = v
                    .get(4)
                    .and_then(|f| u16::from_str_radix(f, 16).ok())
                    .and_then(Fields::from_bits);
                match (divisor, v.get(3).map(String::as_str), fields) {
                    (Some(d), Some("01" | "1"), Some(f)) if v.len() == 5 => {
                        self.rate_hz = Some(ascii::IMU_RATE_HZ / f64::from(d));
                        self.fields = f;
                        echo()
                    }
                    _ => ascii::sentence("VNERR,07"),
                }
            }
            Some(_) => ascii::sentence("VNERR,08"),
            None => ascii::sentence("VNERR,04"),
        }
    }

    /// The torso's true sample at `t_s`: at rest at the configured pitch, swaying if asked.
    fn truth(&self, t_s: f64) -> (ImuSample, f64) {
        let o = &self.options;
        let w = 2.0 * std::f64::consts::PI * o.sway_hz;
        let pitch = o.pitch_rad + o.sway_amplitude_rad * (w * t_s).sin();
        let rate = o.sway_amplitude_rad * w * (w * t_s).cos();
        let sample = ImuSample {
            t_s,
            gyro_pitch_rad_s: rate,
            accel_x_mps2: -GRAVITY_MPS2 * pitch.sin(),
            accel_z_mps2: GRAVITY_MPS2 * pitch.cos(),
        };
        (sample, pitch)
    }

    /// The next frame's measurement (time stamp, attitude, noisy rate and specific force).
    fn next_measurement(&mut self, period_ns: u64) -> Measurement {
        let time_ns = FIRST_TIME_NS + self.k * period_ns;
        let (truth, pitch) = self.truth(self.k as f64 * period_ns as f64 * 1e-9);
        let mut noisy = ImuSample::default();
        self.imu.measure(&truth, &mut noisy);
        let (rate, accel) = self.options.mounting.to_sensor(&noisy);
        Measurement {
            fields: self.fields,
            time_startup_ns: time_ns,
            // Upright with x forward: a forward lean is a negative (nose-down) VN pitch.
            yaw_pitch_roll_deg: [0.0, (-pitch.to_degrees()) as f32, 0.0],
            quaternion: [
                0.0,
                (-pitch / 2.0).sin() as f32,
                0.0,
                (pitch / 2.0).cos() as f32,
            ],
            angular_rate_rad_s: rate,
            accel_mps2: accel,
        }
    }

    /// Appends the bytes of the next frame period to `out`: maybe garbage, then the frame,
    /// maybe spoilt (never the first, nor the one with `last` set). `None` before the stream
    /// is configured.
    pub fn next_chunk(&mut self, last: bool, out: &mut Vec<u8>) -> Option<()> {
        let rate = self.rate_hz?;
        let period_ns = (1e9 / rate).round() as u64;
        let o = self.options;
        let spoil = self.k > 0 && !last;
        if spoil && self.rng.random_bool(o.garbage_probability) {
            let n = self.rng.random_range(1..=MAX_GARBAGE);
            for _ in 0..n {
                // A quarter sync bytes, some valid-looking headers: the parser's resync is tried.
                let b = match self.rng.random_range(0..8) {
                    0 | 1 => SYNC,
                    2 => 0x01,
                    _ => self.rng.random(),
                };
                out.push(b);
            }
            self.counts.garbage_bytes += n as u64;
        }
        let m = self.next_measurement(period_ns);
        let mut frame = [0u8; MAX_FRAME_LEN];
        let len = encode(&m, &mut frame)?;
        let frame = &mut frame[..len];
        self.k += 1;
        self.counts.frames_sent += 1;
        if spoil && self.rng.random_bool(o.drop_probability) {
            let at = self.rng.random_range(0..len);
            out.extend_from_slice(&frame[..at]);
            out.extend_from_slice(&frame[at + 1..]);
            self.counts.frames_dropped_byte += 1;
        } else if spoil && self.rng.random_bool(o.flip_probability) {
            let at = self.rng.random_range(0..len);
            frame[at] ^= self.rng.random_range(1..=255u8);
            out.extend_from_slice(frame);
            self.counts.frames_flipped += 1;
        } else {
            out.extend_from_slice(frame);
            self.counts.frames_intact += 1;
        }
        Some(())
    }
}

/// A pseudo-terminal pair in raw mode: the emulator writes the master, the driver opens
/// [`Pty::path`] (the slave) as its serial port.
pub struct Pty {
    master: File,
    // Held open so the master never sees a hang-up while the driver (re)opens the slave.
    _slave: std::os::fd::OwnedFd,
    path: PathBuf,
}

impl Pty {
    /// Opens a pair and puts the slave in raw mode (no echo, no line editing, 8 bits).
    pub fn open() -> std::io::Result<Self> {
        use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
        let pair = nix::pty::openpty(None, None)?;
        let mut t = tcgetattr(&pair.slave)?;
        cfmakeraw(&mut t);
        tcsetattr(&pair.slave, SetArg::TCSANOW, &t)?;
        let path = nix::unistd::ttyname(&pair.slave)?;
        Ok(Self {
            master: File::from(pair.master),
            _slave: pair.slave,
            path,
        })
    }

    /// The slave's path (e.g. `/dev/pts/3`): what the driver opens.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }
}

/// Serves `emulator` on `pty`: answers commands until binary output is configured, then
/// streams `duration_s` of frames at the configured rate (paced by the wall clock) and returns
/// what it sent. Blocks until a driver configures it.
pub fn serve(
    pty: &mut Pty,
    emulator: &mut Emulator,
    duration_s: f64,
) -> std::io::Result<EmulatorCounts> {
    let mut scanner = LineScanner::default();
    let mut buf = [0u8; 256];
    while emulator.rate_hz().is_none() {
        let n = pty.master.read(&mut buf)?;
        if n == 0 {
            return Err(std::io::Error::new(
                std::io::ErrorKind::UnexpectedEof,
                "the pseudo-terminal closed before the driver configured the output",
            ));
        }
        for &b in &buf[..n] {
            if let Some(s) = scanner.push(b) {
                let reply = emulator.reply(&s);
                pty.master.write_all(reply.as_bytes())?;
            }
        }
    }
    let rate = emulator.rate_hz().unwrap_or(ascii::IMU_RATE_HZ);
    let frames = (duration_s * rate).round().max(1.0) as u64;
    let start = Instant::now();
    let mut chunk = Vec::with_capacity(4 * MAX_FRAME_LEN);
    for k in 0..frames {
        let due = start + Duration::from_secs_f64(k as f64 / rate);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        chunk.clear();
        emulator.next_chunk(k + 1 == frames, &mut chunk);
        pty.master.write_all(&chunk)?;
    }
    pty.master.flush()?;
    Ok(emulator.counts())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::vn100::frame::Parser;

    #[test]
    fn the_emulator_answers_commands_and_its_frames_parse_back() {
        let mut e = Emulator::new(EmulatorOptions {
            sway_amplitude_rad: 0.1,
            ..EmulatorOptions::default()
        });
        let mut out = Vec::new();
        assert_eq!(e.next_chunk(false, &mut out), None);
        let ok = e.reply(&Sentence::parse(&ascii::binary_output(2, Fields::DRIVER)).unwrap());
        assert!(ok.starts_with("$VNWRG,75,3,2,01,0129*"), "{ok}");
        assert_eq!(e.rate_hz(), Some(400.0));
        let bad = e.reply(&Sentence::parse(&ascii::sentence("VNWRG,75,3,0,01,0129")).unwrap());
        assert!(bad.starts_with("$VNERR,07"), "{bad}");
        let reg = e.reply(&Sentence::parse(&ascii::sentence("VNWRG,99,1")).unwrap());
        assert!(reg.starts_with("$VNERR,08"), "{reg}");
        for k in 0..100 {
            e.next_chunk(k == 99, &mut out).unwrap();
        }
        let mut p = Parser::new();
        let mut got = Vec::new();
        p.feed(&out, |m| got.push(m));
        assert_eq!(got.len(), 100);
        assert_eq!(got[1].time_startup_ns - got[0].time_startup_ns, 2_500_000);
        let s = Mounting::DEFAULT.to_sample(&got[0], 0.0);
        // At rest leaning 0.05 rad forward: specific force (−g sin θ, g cos θ) plus noise.
        assert!((s.accel_z_mps2 - 9.81 * 0.05f64.cos()).abs() < 0.3, "{s:?}");
        assert!((s.accel_x_mps2 + 9.81 * 0.05f64.sin()).abs() < 0.3, "{s:?}");
        assert_eq!(e.counts().frames_intact, 100);
    }
}
