//! The `[imu]` section: the torso IMU on the robot, a VectorNav VN-100 (`adam run --backend can
//! --imu vn100:/dev/ttyUSB0`; [`drivers::vn100`]). How it is mounted (which of its axes are the
//! robot's forward and up axes; the pitch axis follows), its baud rate and output rate.
//! Absent: the VN-100 upright with its x forward, 921 600 baud, 800 Hz.

use crate::RuntimeError;
use drivers::vn100::mounting::{Axis, Mounting};
use drivers::vn100::Vn100Options;
use serde::{Deserialize, Serialize};

/// Baud rates the VN-100 runs at, bit/s (its user manual's serial baud rate register).
pub const VN100_BAUD_RATES_BPS: [u32; 9] = [
    9600, 19200, 38400, 57600, 115_200, 128_000, 230_400, 460_800, 921_600,
];

/// The torso IMU.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImuConfig {
    /// The VN-100 axis along the robot's forward x: `+x`, `-x`, `+y`, `-y`, `+z` or `-z` (its
    /// own frame: x forward, y right, z down, as printed on the case).
    pub forward_axis: String,
    /// The VN-100 axis along the robot's up z (a different axis from `forward_axis`). The
    /// robot's pitch axis +y (to its left) is up × forward: VN −y for `+x` / `-z`.
    pub up_axis: String,
    /// Baud rate to run the serial line at, bit/s (one of [`VN100_BAUD_RATES_BPS`], enough for
    /// `rate_hz` frames of 50 bytes at 10 bits a byte).
    pub baud_bps: u32,
    /// Baud rate the sensor answers at before it is set up (factory: 115 200), bit/s.
    pub factory_baud_bps: u32,
    /// Binary output rate, Hz: 800 or 400 (800 Hz over a whole divisor, at least 400).
    pub rate_hz: f64,
}

impl Default for ImuConfig {
    fn default() -> Self {
        Self {
            forward_axis: "+x".into(),
            up_axis: "-z".into(),
            baud_bps: 921_600,
            factory_baud_bps: 115_200,
            rate_hz: 800.0,
        }
    }
}

impl ImuConfig {
    /// The driver's options; errors name `origin`, the field and the value.
    pub fn vn100_options(&self, origin: &str) -> crate::Result<Vn100Options> {
        let bad = |field: &str, value: String, reason: String| RuntimeError::InvalidField {
            origin: origin.to_string(),
            field: format!("imu.{field}"),
            value,
            reason,
        };
        let axis = |field: &str, text: &str| {
            Axis::parse(text).ok_or_else(|| {
                bad(
                    field,
                    format!("\"{text}\""),
                    "must be a VN-100 axis: +x, -x, +y, -y, +z or -z".into(),
                )
            })
        };
        let forward = axis("forward_axis", &self.forward_axis)?;
        let up = axis("up_axis", &self.up_axis)?;
        let mounting = Mounting::new(forward, up)
            .map_err(|e| bad("up_axis", format!("\"{}\"", self.up_axis), e.to_string()))?;
        for (field, baud) in [
            ("baud_bps", self.baud_bps),
            ("factory_baud_bps", self.factory_baud_bps),
        ] {
            if !VN100_BAUD_RATES_BPS.contains(&baud) {
                return Err(bad(
                    field,
                    baud.to_string(),
                    format!("the VN-100 runs at {VN100_BAUD_RATES_BPS:?} bit/s"),
                ));
            }
        }
        let options = Vn100Options {
            baud_bps: self.baud_bps,
            factory_baud_bps: self.factory_baud_bps,
            rate_hz: self.rate_hz,
            mounting,
            ..Vn100Options::default()
        };
        options
            .rate_divisor()
            .map_err(|e| bad("rate_hz", self.rate_hz.to_string(), e.to_string()))?;
        let frame_bits = drivers::vn100::frame::Fields::DRIVER.frame_len() as f64 * 10.0;
        if frame_bits * self.rate_hz > f64::from(self.baud_bps) {
            return Err(bad(
                "baud_bps",
                self.baud_bps.to_string(),
                format!(
                    "{} Hz of {}-bit frames need {} bit/s",
                    self.rate_hz,
                    frame_bits,
                    frame_bits * self.rate_hz
                ),
            ));
        }
        Ok(options)
    }

    /// Checks every field ([`ImuConfig::vn100_options`]).
    pub fn validate(&self, origin: &str) -> crate::Result<()> {
        self.vn100_options(origin).map(|_| ())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(c: &ImuConfig) -> String {
        c.validate("adam.toml")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    }

    #[test]
    fn the_default_is_the_vn100_upright_x_forward_at_800_hz() {
        let o = ImuConfig::default().vn100_options("x").expect("valid");
        assert_eq!(o.mounting.pitch_axis().name(), "-y");
        assert_eq!(o.rate_divisor().ok(), Some(1));
    }

    #[test]
    fn bad_axes_bauds_and_rates_are_named() {
        let base = ImuConfig::default();
        let e = refused(&ImuConfig {
            forward_axis: "+w".into(),
            ..base.clone()
        });
        assert!(
            e.contains("imu.forward_axis") && e.contains("\"+w\""),
            "{e}"
        );
        let e = refused(&ImuConfig {
            up_axis: "-x".into(),
            ..base.clone()
        });
        assert!(
            e.contains("imu.up_axis") && e.contains("different axes"),
            "{e}"
        );
        let e = refused(&ImuConfig {
            baud_bps: 100_000,
            ..base.clone()
        });
        assert!(e.contains("imu.baud_bps") && e.contains("100000"), "{e}");
        let e = refused(&ImuConfig {
            baud_bps: 115_200,
            ..base.clone()
        });
        assert!(
            e.contains("imu.baud_bps") && e.contains("400000 bit/s"),
            "{e}"
        );
        let e = refused(&ImuConfig {
            rate_hz: 200.0,
            ..base
        });
        assert!(e.contains("imu.rate_hz") && e.contains("200"), "{e}");
    }
}
