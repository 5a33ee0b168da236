//! The emulator's IMU sample as three extended CAN frames (an emulator convention, not a
//! device protocol: on ADAM the IMU is a VN-100 on its own serial line).
//!
//! `adam emulate motors` appends, to the reply packet of every control period it simulates,
//! the simulated torso IMU's sample as three extended-id data frames of 8 bytes, each one
//! `f64` little endian: [`IMU_GYRO_ID`] pitch rate \[rad/s\], [`IMU_ACCEL_X_ID`] and
//! [`IMU_ACCEL_Z_ID`] specific force \[m/s²\]. `f64` so that the host reads the simulator's
//! values bit for bit (a run over UDP then matches the in-process run). The ids are outside
//! the A1's 11-bit ranges, so a motor never sees them as its own.

use super::cannelloni::{CanFrame, FrameRef};
use crate::imu::ImuSample;

/// Extended id of the pitch-rate frame.
pub const IMU_GYRO_ID: u32 = 0x1AD1_0000;
/// Extended id of the x specific-force frame.
pub const IMU_ACCEL_X_ID: u32 = 0x1AD1_0001;
/// Extended id of the z specific-force frame.
pub const IMU_ACCEL_Z_ID: u32 = 0x1AD1_0002;

/// The three frames of a sample (time stamps are the reader's).
pub fn encode(sample: &ImuSample) -> [CanFrame; 3] {
    let frame = |id, x: f64| CanFrame::extended(id, &x.to_le_bytes());
    let fallback = CanFrame {
        can_id: 0,
        len: 0,
        data: [0; 8],
    };
    [
        frame(IMU_GYRO_ID, sample.gyro_pitch_rad_s).unwrap_or(fallback),
        frame(IMU_ACCEL_X_ID, sample.accel_x_mps2).unwrap_or(fallback),
        frame(IMU_ACCEL_Z_ID, sample.accel_z_mps2).unwrap_or(fallback),
    ]
}

/// Which channel a frame carries (0 gyro, 1 accel x, 2 accel z) and its value; `None` if it
/// is not an IMU frame of this convention.
pub fn decode(frame: &FrameRef<'_>) -> Option<(usize, f64)> {
    if !frame.is_extended() || frame.is_remote() || frame.is_error() || frame.fd_flags.is_some() {
        return None;
    }
    let channel = match frame.id() {
        IMU_GYRO_ID => 0,
        IMU_ACCEL_X_ID => 1,
        IMU_ACCEL_Z_ID => 2,
        _ => return None,
    };
    let bytes: [u8; 8] = frame.data.try_into().ok()?;
    Some((channel, f64::from_le_bytes(bytes)))
}

/// Collects the three channels of one packet into a sample.
#[derive(Debug, Clone, Copy, Default)]
pub struct ImuAssembler {
    values: [Option<f64>; 3],
}

impl ImuAssembler {
    /// Take one frame; true if it was an IMU frame.
    pub fn take(&mut self, frame: &FrameRef<'_>) -> bool {
        match decode(frame) {
            Some((channel, value)) => {
                self.values[channel] = Some(value);
                true
            }
            None => false,
        }
    }

    /// The sample, if all three channels came.
    pub fn sample(&self) -> Option<ImuSample> {
        match self.values {
            [Some(gyro), Some(ax), Some(az)] => Some(ImuSample {
                t_s: 0.0,
                gyro_pitch_rad_s: gyro,
                accel_x_mps2: ax,
                accel_z_mps2: az,
            }),
            _ => None,
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_crosses_bit_for_bit_and_other_frames_are_not_imu() {
        let s = ImuSample {
            t_s: 0.0,
            gyro_pitch_rad_s: -0.123_456_789_012_345_67,
            accel_x_mps2: 1e-300,
            accel_z_mps2: 9.81,
        };
        let mut a = ImuAssembler::default();
        for f in encode(&s) {
            assert!(a.take(&f.as_ref()));
        }
        assert_eq!(a.sample(), Some(s));
        let reply = CanFrame::standard(0x181, &[0; 8]).unwrap();
        assert!(decode(&reply.as_ref()).is_none());
        let short = CanFrame::extended(IMU_GYRO_ID, &[0; 4]).unwrap();
        assert!(decode(&short.as_ref()).is_none());
        let mut partial = ImuAssembler::default();
        partial.take(&encode(&s)[0].as_ref());
        assert_eq!(partial.sample(), None);
    }
}
