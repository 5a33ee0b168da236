//! How the VN-100 sits in the torso: which of its axes is the robot's forward (x) and up (z)
//! axis; the robot's pitch axis (+y, to the left) follows as up × forward.
//!
//! The VN-100's body frame (printed on its case) is x forward, y right, z down. Mounted that
//! way (the default, [`Mounting::DEFAULT`]): robot x = VN +x, robot z = VN −z, so the robot's
//! pitch axis is VN −y: pitch rate = −ω_y, specific force x = a_x, z = −a_z (+g upright at rest).

use super::frame::Measurement;
use crate::imu::ImuSample;

/// One of the VN-100's axes with a sign, e.g. `-z`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Axis {
    /// 0 = x, 1 = y, 2 = z.
    index: usize,
    /// +1 or −1.
    sign: i8,
}

impl Axis {
    /// `+x`, `-y`, `z` (= `+z`) …; `None` for anything else.
    pub fn parse(text: &str) -> Option<Self> {
        let t = text.trim();
        let (sign, name) = match t.as_bytes().first()? {
            b'+' => (1, &t[1..]),
            b'-' => (-1, &t[1..]),
            _ => (1, t),
        };
        let index = ["x", "y", "z"].iter().position(|a| *a == name)?;
        Some(Self { index, sign })
    }

    /// The axis as written in a config: `+x`, `-z`, ….
    pub fn name(self) -> &'static str {
        const NAMES: [[&str; 3]; 2] = [["-x", "-y", "-z"], ["+x", "+y", "+z"]];
        NAMES[usize::from(self.sign > 0)][self.index]
    }

    /// The unit vector in the VN-100's frame.
    fn unit(self) -> [f64; 3] {
        let mut v = [0.0; 3];
        v[self.index] = f64::from(self.sign);
        v
    }

    /// The axis along a unit vector of ±x, ±y, ±z.
    fn of_unit(v: [f64; 3]) -> Self {
        let index = (0..3)
            .max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
            .unwrap_or(0);
        Self {
            index,
            sign: if v[index] < 0.0 { -1 } else { 1 },
        }
    }
}

/// Why a mounting is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "forward axis {forward} and up axis {up} of the VN-100 must be two different axes (x, y or z)"
)]
pub struct MountingError {
    /// The forward axis asked for.
    pub forward: &'static str,
    /// The up axis asked for.
    pub up: &'static str,
}

/// The VN-100's axes that are the robot's forward and up axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mounting {
    forward: Axis,
    up: Axis,
}

fn dot(a: [f64; 3], b: [f32; 3]) -> f64 {
    a[0] * f64::from(b[0]) + a[1] * f64::from(b[1]) + a[2] * f64::from(b[2])
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl Mounting {
    /// The VN-100 upright with its x forward: robot x = VN +x, robot z = VN −z (pitch axis VN −y).
    pub const DEFAULT: Self = Self {
        forward: Axis { index: 0, sign: 1 },
        up: Axis { index: 2, sign: -1 },
    };

    /// A mounting; the two axes must differ (not the same axis with either sign).
    pub fn new(forward: Axis, up: Axis) -> Result<Self, MountingError> {
        if forward.index == up.index {
            return Err(MountingError {
                forward: forward.name(),
                up: up.name(),
            });
        }
        Ok(Self { forward, up })
    }

    /// The VN-100 axis along the robot's forward x.
    pub fn forward(self) -> Axis {
        self.forward
    }

    /// The VN-100 axis along the robot's up z.
    pub fn up(self) -> Axis {
        self.up
    }

    /// The VN-100 axis along the robot's pitch axis +y (= up × forward, to the robot's left).
    pub fn pitch_axis(self) -> Axis {
        Axis::of_unit(cross(self.up.unit(), self.forward.unit()))
    }

    /// The runtime's sample of a VN-100 measurement, stamped `t_s`.
    pub fn to_sample(self, m: &Measurement, t_s: f64) -> ImuSample {
        ImuSample {
            t_s,
            gyro_pitch_rad_s: dot(self.pitch_axis().unit(), m.angular_rate_rad_s),
            accel_x_mps2: dot(self.forward.unit(), m.accel_mps2),
            accel_z_mps2: dot(self.up.unit(), m.accel_mps2),
        }
    }

    /// The VN-100's angular rate and specific force (its axes, rad/s and m/s²) of a planar
    /// torso sample (the emulator's inverse of [`Mounting::to_sample`]).
    pub fn to_sensor(self, s: &ImuSample) -> ([f32; 3], [f32; 3]) {
        let (y, x, z) = (
            self.pitch_axis().unit(),
            self.forward.unit(),
            self.up.unit(),
        );
        let rate = [0, 1, 2].map(|k| (y[k] * s.gyro_pitch_rad_s) as f32);
        let accel = [0, 1, 2].map(|k| (x[k] * s.accel_x_mps2 + z[k] * s.accel_z_mps2) as f32);
        (rate, accel)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn the_default_mounting_reads_plus_g_up_and_pitch_about_minus_y() {
        let m = Mounting::DEFAULT;
        assert_eq!(m.pitch_axis().name(), "-y");
        let flat = Measurement {
            angular_rate_rad_s: [0.0, 0.5, 0.0],
            accel_mps2: [0.0, 0.0, -9.81],
            ..Measurement::default()
        };
        let s = m.to_sample(&flat, 1.0);
        assert!((s.accel_z_mps2 - 9.81).abs() < 1e-6);
        assert!((s.gyro_pitch_rad_s + 0.5).abs() < 1e-9);
    }

    #[test]
    fn every_mounting_round_trips_and_is_right_handed() {
        let names = ["+x", "-x", "+y", "-y", "+z", "-z"];
        for f in names {
            for u in names {
                let (fa, ua) = (Axis::parse(f).unwrap(), Axis::parse(u).unwrap());
                let Ok(m) = Mounting::new(fa, ua) else {
                    assert_eq!(f[1..], u[1..]);
                    continue;
                };
                // Robot x × y = z, in the sensor's frame.
                let z = cross(fa.unit(), m.pitch_axis().unit());
                assert_eq!(z, ua.unit(), "{f} {u}");
                let s = ImuSample {
                    t_s: 0.0,
                    gyro_pitch_rad_s: 0.3,
                    accel_x_mps2: -1.5,
                    accel_z_mps2: 9.7,
                };
                let (rate, accel) = m.to_sensor(&s);
                let back = m.to_sample(
                    &Measurement {
                        angular_rate_rad_s: rate,
                        accel_mps2: accel,
                        ..Measurement::default()
                    },
                    0.0,
                );
                assert!((back.gyro_pitch_rad_s - 0.3).abs() < 1e-6);
                assert!((back.accel_x_mps2 + 1.5).abs() < 1e-6);
                assert!((back.accel_z_mps2 - 9.7).abs() < 1e-5);
            }
        }
        assert_eq!(Axis::parse("z").unwrap().name(), "+z");
        assert_eq!(Axis::parse("w"), None);
        assert_eq!(Axis::parse("+-x"), None);
    }
}
