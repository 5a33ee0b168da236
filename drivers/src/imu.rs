//! The torso IMU in the sagittal plane: the [`Imu`] trait the runtime reads (the simulator's and
//! any real IMU's one trait), and a seeded noise model ([`NoisyImu`]) the simulator puts on its
//! ground truth.
//!
//! A sample is the pitch rate (gyro about +y) and the specific force `a − g` in the torso frame
//! (x forward, z up along the torso when upright), at the IMU's mounting point. Reading writes
//! into a slot the caller owns; nothing allocates.
//!
//! Noise model (defaults in [`ImuNoise::default`] are assumptions of a typical MEMS IMU at a
//! 1 kHz loop rate, not a datasheet): each read adds independent Gaussian white noise to each
//! channel, and a gyro bias that starts at `gyro_bias_rad_s` and random-walks with
//! `gyro_bias_walk_rad_s_per_sqrt_s · √Δt` between reads. The accelerometer has no bias.
//!
//! Faults ([`ImuFault`], applied by the simulator on top of the noisy sample): a dropout (no
//! sample: [`ImuError::Timeout`]), a spike (the gyro reads a huge rate) and a frozen output (the
//! last good sample, repeated with fresh time stamps).

use crate::noise::gaussian;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

/// One IMU reading.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImuSample {
    /// Time the sample was taken \[s\] (the reader's clock: simulated time in simulation).
    pub t_s: f64,
    /// Pitch rate about +y \[rad/s\].
    pub gyro_pitch_rad_s: f64,
    /// Specific force along the torso x axis \[m/s²\].
    pub accel_x_mps2: f64,
    /// Specific force along the torso z axis \[m/s²\] (+g when standing still upright).
    pub accel_z_mps2: f64,
}

/// Why no sample could be read. `Copy`, no heap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum ImuError {
    /// No IMU is attached to this source (a simulator built without one).
    #[error("no IMU attached")]
    NotAttached,
    /// The device produced no new sample in time.
    #[error("IMU sample timed out")]
    Timeout,
}

/// A source of IMU samples: the simulated IMU or, later, a real one. The runtime's loop reads
/// it once per tick with [`Imu::read_at`]; it must not block for long nor allocate.
pub trait Imu {
    /// Write the latest sample into `out`; allocates nothing.
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError>;

    /// The latest sample for a reader whose clock reads `t_s` \[s\] (the runtime's loop time),
    /// stamped `t_s`; `None` if there is none (the loop does not tell a dropout from a missing
    /// IMU). By default [`Imu::read`], restamped; a source without a clock of its own (a test
    /// IMU at rest) computes its sample at `t_s`.
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        let mut sample = ImuSample::default();
        self.read(&mut sample).ok()?;
        Some(ImuSample {
            t_s,
            gyro_pitch_rad_s: sample.gyro_pitch_rad_s,
            accel_x_mps2: sample.accel_x_mps2,
            accel_z_mps2: sample.accel_z_mps2,
        })
    }
}

/// A fault of the IMU's output.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum ImuFault {
    /// Healthy.
    #[default]
    None,
    /// No sample arrives.
    Dropout,
    /// The gyro reads this much more than the truth \[rad/s\].
    Spike {
        /// Added pitch rate \[rad/s\].
        gyro_rad_s: f64,
    },
    /// The output repeats the last sample before the fault (time stamps still advance).
    Frozen,
}

impl ImuFault {
    /// The sample the host reads: `fresh` (this period's healthy sample) under this fault,
    /// `held` the last sample delivered before the fault began. Pure; nothing allocates.
    pub fn apply(
        &self,
        fresh: &ImuSample,
        held: &ImuSample,
        out: &mut ImuSample,
    ) -> Result<(), ImuError> {
        match *self {
            ImuFault::None => *out = *fresh,
            ImuFault::Dropout => return Err(ImuError::Timeout),
            ImuFault::Spike { gyro_rad_s } => {
                *out = *fresh;
                out.gyro_pitch_rad_s += gyro_rad_s;
            }
            ImuFault::Frozen => {
                *out = *held;
                out.t_s = fresh.t_s;
            }
        }
        Ok(())
    }
}

/// IMU noise parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuNoise {
    /// Gyro white noise, rms per sample \[rad/s\].
    pub gyro_noise_rad_s: f64,
    /// Initial (constant, if the walk is 0) gyro bias \[rad/s\].
    pub gyro_bias_rad_s: f64,
    /// Gyro bias random walk \[rad/s/√s\].
    pub gyro_bias_walk_rad_s_per_sqrt_s: f64,
    /// Accelerometer white noise, rms per sample and axis \[m/s²\].
    pub accel_noise_mps2: f64,
}

impl Default for ImuNoise {
    fn default() -> Self {
        Self {
            gyro_noise_rad_s: 0.005,
            gyro_bias_rad_s: 0.002,
            gyro_bias_walk_rad_s_per_sqrt_s: 1e-4,
            accel_noise_mps2: 0.05,
        }
    }
}

impl ImuNoise {
    /// No noise and no bias: the IMU returns the ground truth.
    pub const NONE: Self = Self {
        gyro_noise_rad_s: 0.0,
        gyro_bias_rad_s: 0.0,
        gyro_bias_walk_rad_s_per_sqrt_s: 0.0,
        accel_noise_mps2: 0.0,
    };
}

/// Seeded noise on a true sample.
#[derive(Debug, Clone)]
pub struct NoisyImu {
    noise: ImuNoise,
    rng: ChaCha8Rng,
    bias_rad_s: f64,
    last_t_s: Option<f64>,
}

impl NoisyImu {
    /// A noise source; the same seed gives the same noise sequence.
    pub fn new(noise: ImuNoise, seed: u64) -> Self {
        Self {
            noise,
            rng: ChaCha8Rng::seed_from_u64(seed),
            bias_rad_s: noise.gyro_bias_rad_s,
            last_t_s: None,
        }
    }

    /// The present gyro bias \[rad/s\] (ground truth, for tests and estimator evaluation).
    pub fn gyro_bias_rad_s(&self) -> f64 {
        self.bias_rad_s
    }

    /// `out` = `truth` plus noise; the bias walks by the time since the previous call.
    pub fn measure(&mut self, truth: &ImuSample, out: &mut ImuSample) {
        let dt_s = self.last_t_s.map_or(0.0, |t| (truth.t_s - t).max(0.0));
        self.last_t_s = Some(truth.t_s);
        self.bias_rad_s +=
            self.noise.gyro_bias_walk_rad_s_per_sqrt_s * dt_s.sqrt() * gaussian(&mut self.rng);
        *out = ImuSample {
            t_s: truth.t_s,
            gyro_pitch_rad_s: truth.gyro_pitch_rad_s
                + self.bias_rad_s
                + self.noise.gyro_noise_rad_s * gaussian(&mut self.rng),
            accel_x_mps2: truth.accel_x_mps2
                + self.noise.accel_noise_mps2 * gaussian(&mut self.rng),
            accel_z_mps2: truth.accel_z_mps2
                + self.noise.accel_noise_mps2 * gaussian(&mut self.rng),
        };
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn noise_statistics_match_the_parameters() {
        let noise = ImuNoise {
            gyro_noise_rad_s: 0.01,
            gyro_bias_rad_s: 0.003,
            gyro_bias_walk_rad_s_per_sqrt_s: 0.0,
            accel_noise_mps2: 0.2,
        };
        let mut imu = NoisyImu::new(noise, 7);
        let n = 20_000;
        let (mut sg, mut sg2, mut sa2) = (0.0, 0.0, 0.0);
        let mut out = ImuSample::default();
        for k in 0..n {
            let truth = ImuSample {
                t_s: k as f64 * 1e-3,
                gyro_pitch_rad_s: 0.5,
                accel_x_mps2: 0.0,
                accel_z_mps2: 9.81,
            };
            imu.measure(&truth, &mut out);
            let e = out.gyro_pitch_rad_s - 0.5;
            sg += e;
            sg2 += e * e;
            sa2 += (out.accel_z_mps2 - 9.81).powi(2);
        }
        let mean = sg / n as f64;
        let sd = (sg2 / n as f64 - mean * mean).sqrt();
        // Standard error of the mean 0.01/√20000 = 7e-5: allow 5σ.
        assert!((mean - 0.003).abs() < 3.5e-4, "{mean}");
        // Relative standard error of an sd estimate ≈ 1/√(2n) = 0.5 %: allow 3 %.
        assert!((sd / 0.01 - 1.0).abs() < 0.03, "{sd}");
        assert!(((sa2 / n as f64).sqrt() / 0.2 - 1.0).abs() < 0.03);
    }

    #[test]
    fn faults_drop_spike_or_freeze_the_sample() {
        let fresh = ImuSample {
            t_s: 2.0,
            gyro_pitch_rad_s: 0.1,
            accel_x_mps2: 0.3,
            accel_z_mps2: 9.8,
        };
        let held = ImuSample {
            t_s: 1.0,
            gyro_pitch_rad_s: -0.2,
            accel_x_mps2: 1.0,
            accel_z_mps2: 9.0,
        };
        let mut out = ImuSample::default();
        ImuFault::None.apply(&fresh, &held, &mut out).unwrap();
        assert_eq!(out, fresh);
        assert_eq!(
            ImuFault::Dropout.apply(&fresh, &held, &mut out),
            Err(ImuError::Timeout)
        );
        ImuFault::Spike { gyro_rad_s: 50.0 }
            .apply(&fresh, &held, &mut out)
            .unwrap();
        assert_eq!(out.gyro_pitch_rad_s, 50.1);
        assert_eq!(out.accel_z_mps2, 9.8);
        ImuFault::Frozen.apply(&fresh, &held, &mut out).unwrap();
        assert_eq!(out, ImuSample { t_s: 2.0, ..held });
    }

    #[test]
    fn bias_walk_grows_like_sqrt_time_and_is_seeded() {
        // Var(bias(T)) = walk² T: over many independent seeds, rms after 100 s ≈ walk · 10.
        let noise = ImuNoise {
            gyro_noise_rad_s: 0.0,
            gyro_bias_rad_s: 0.0,
            gyro_bias_walk_rad_s_per_sqrt_s: 1e-3,
            accel_noise_mps2: 0.0,
        };
        let mut sum2 = 0.0;
        let seeds = 400;
        for seed in 0..seeds {
            let mut imu = NoisyImu::new(noise, seed);
            let mut out = ImuSample::default();
            for k in 0..=100 {
                let truth = ImuSample {
                    t_s: k as f64,
                    ..ImuSample::default()
                };
                imu.measure(&truth, &mut out);
            }
            sum2 += imu.gyro_bias_rad_s().powi(2);
        }
        let rms = (sum2 / seeds as f64).sqrt();
        // Relative standard error of an rms over 400 samples ≈ 3.5 %: allow 15 %.
        assert!((rms / 1e-2 - 1.0).abs() < 0.15, "{rms}");
        let run = |seed| {
            let mut imu = NoisyImu::new(ImuNoise::default(), seed);
            let mut out = ImuSample::default();
            imu.measure(&ImuSample::default(), &mut out);
            out.gyro_pitch_rad_s.to_bits()
        };
        assert_eq!(run(3), run(3));
        assert_ne!(run(3), run(4));
    }
}
