//! The VectorNav VN-100 torso IMU: a sans-IO parser of its binary output ([`frame`]), the ASCII
//! commands that configure it ([`ascii`]), how it is mounted in the torso ([`mounting`]), the
//! driver over a serial port ([`port::Vn100`], an [`crate::imu::Imu`]) and an emulated VN-100
//! on a pseudo-terminal ([`emulator`], `adam emulate imu`).
//!
//! ```text
//! serial port ─▶ Vn100::poll (FIONREAD, read into a stack buffer) ─▶ frame::Parser
//!   (sync 0xFA, groups, fields, CRC-16; resync after garbage) ─▶ Measurement
//!   ─▶ time-stamp check (missed / implausible) ─▶ Mounting::to_sample ─▶ ImuSample
//! ```
//!
//! **What is asked of the sensor** (at [`port::Vn100::open`]): register 6 = 0 (no ASCII
//! output), register 75 = binary output 1 on both serial ports at 800 Hz / divisor with the
//! common group's time since start-up, yaw/pitch/roll, angular rate and acceleration (50 bytes
//! a frame: 40 kB/s at 800 Hz, 400 kbit/s with start and stop bits, so 921 600 baud; the factory
//! rate, 115 200 baud, carries
//! at most ~230 frames/s: the driver sets the baud rate first, register 5, if the sensor only
//! answers at its factory rate). The runtime uses the angular rate and acceleration only (its
//! own pitch estimator fuses them); the attitude is kept for logs and checks.
//!
//! **Axes**: the VN-100's frame is x forward, y right, z down; [`mounting::Mounting`] says
//! which of its axes are the robot's forward and up axes (config `[imu]`), and the robot's
//! pitch axis (+y, to its left) follows. Upright with x forward: pitch rate = −ω_y.

pub mod ascii;
pub mod emulator;
pub mod frame;
pub mod mounting;
pub mod port;

use mounting::Mounting;
use std::time::Duration;
use thiserror::Error;

/// How the driver sets the VN-100 up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vn100Options {
    /// Baud rate to run at, bit/s.
    pub baud_bps: u32,
    /// Baud rate the sensor answers at when not yet set up (factory: 115 200), bit/s.
    pub factory_baud_bps: u32,
    /// Binary output rate, Hz: 800 over a whole divisor, at least 400 (800 or 400).
    pub rate_hz: f64,
    /// Which VN-100 axes are the robot's forward and up.
    pub mounting: Mounting,
    /// How long to wait for each reply while configuring.
    pub reply_timeout: Duration,
}

impl Default for Vn100Options {
    fn default() -> Self {
        Self {
            baud_bps: 921_600,
            factory_baud_bps: 115_200,
            rate_hz: 800.0,
            mounting: Mounting::DEFAULT,
            reply_timeout: Duration::from_millis(500),
        }
    }
}

/// The lowest binary output rate the runtime accepts, Hz (the control loop runs at 1 kHz).
pub const MIN_RATE_HZ: f64 = 400.0;

impl Vn100Options {
    /// The rate divisor of `rate_hz` (800 Hz / divisor); refused unless whole and the rate is
    /// at least [`MIN_RATE_HZ`].
    pub fn rate_divisor(&self) -> Result<u16, Vn100Error> {
        let d = ascii::IMU_RATE_HZ / self.rate_hz;
        let whole = d.round();
        if self.rate_hz.is_finite()
            && self.rate_hz >= MIN_RATE_HZ
            && self.rate_hz <= ascii::IMU_RATE_HZ
            && (d - whole).abs() < 1e-9
        {
            Ok(whole as u16)
        } else {
            Err(Vn100Error::Rate {
                rate_hz: self.rate_hz,
            })
        }
    }
}

/// What can go wrong opening or configuring the VN-100. Every variant names the port.
#[derive(Debug, Error)]
pub enum Vn100Error {
    /// The serial port could not be opened.
    #[error("cannot open the VN-100's serial port `{port}`: {reason}")]
    Open {
        /// The port's path.
        port: String,
        /// What the OS said.
        reason: String,
    },
    /// Reading or writing the port failed.
    #[error("VN-100 on `{port}`: {what}: {reason}")]
    Io {
        /// The port's path.
        port: String,
        /// What was being done.
        what: String,
        /// What the OS said.
        reason: String,
    },
    /// The sensor did not confirm a command in time.
    #[error("VN-100 on `{port}`: no reply to `{command}` within {waited_s} s (is it a VN-100, powered, at the configured baud rate?)")]
    NoReply {
        /// The port's path.
        port: String,
        /// The command sent.
        command: String,
        /// How long the driver waited, s.
        waited_s: f64,
    },
    /// The sensor answered a command with an error.
    #[error("VN-100 on `{port}` refused `{command}` with error code {code}")]
    Device {
        /// The port's path.
        port: String,
        /// The command sent.
        command: String,
        /// The sensor's error code (`$VNERR`).
        code: u8,
    },
    /// A binary output rate the sensor cannot run or the runtime cannot use.
    #[error("VN-100 rate {rate_hz} Hz: must be 800 Hz over a whole divisor and at least 400 Hz (800 or 400)")]
    Rate {
        /// The rate asked for, Hz.
        rate_hz: f64,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_are_800_over_a_whole_divisor_and_at_least_400() {
        let at = |rate_hz| Vn100Options {
            rate_hz,
            ..Vn100Options::default()
        };
        assert_eq!(at(800.0).rate_divisor().ok(), Some(1));
        assert_eq!(at(400.0).rate_divisor().ok(), Some(2));
        for bad in [200.0, 500.0, 1000.0, f64::NAN, -800.0] {
            let e = at(bad).rate_divisor().err().map(|e| e.to_string());
            assert!(e.is_some_and(|e| e.contains("Hz")), "{bad}");
        }
    }
}
