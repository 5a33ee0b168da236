//! What the loop runs on: a [`Backend`] is a [`MotorBus`] and an [`Imu`] (the drivers' one IMU
//! trait), with the ground truth where a simulator knows it.
//!
//! * real hardware: [`WithImu`] pairs a `SocketCanBus` with an IMU driver;
//! * simulation: the robot simulator owns both the joints and the torso, so a `SimBus<RobotSim>`
//!   is itself a backend ([`crate::sim::run`]);
//! * tests: [`WithImu`] of a `SimBus<InertiaDampingPlant>` and a [`StaticImu`].

use drivers::bus::{BusWrapper, MotorBus};
use drivers::imu::{Imu, ImuError, ImuSample};

/// What the loop runs on: the motors ([`MotorBus`]) and the torso IMU ([`Imu`]) of one robot,
/// and, where a simulator knows it, the ground truth that scores the estimator.
pub trait Backend: MotorBus + Imu {
    /// The true torso pitch, rad, where the backend knows it (a simulator); `None` on hardware.
    /// Used only to score the estimator, never by the controller.
    fn true_pitch_rad(&self) -> Option<f64> {
        None
    }

    /// The robot's true position along the treadmill's belt (+ forward of the belt's centre,
    /// where a simulated run starts), m, where the backend knows it (a simulator); `None` on hardware. Logged beside the
    /// speed control's estimate, never used by the controller.
    fn true_belt_position_m(&self) -> Option<f64> {
        None
    }

    /// Sees where the controller is in its walk after each tick: a simulator starts faults at a
    /// phase point of a step with it ([`crate::sim::faults::Fault::PushAtPhase`]). Never feeds
    /// back into the controller; hardware ignores it. Called in the tick: must not allocate or
    /// block.
    fn observe(&mut self, _progress: &WalkProgress) {}
}

/// Where the controller is in its walk after a tick (what [`Backend::observe`] sees).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WalkProgress {
    /// The controller is in Walk.
    pub walking: bool,
    /// Completed steps since Walk began.
    pub steps: u32,
    /// Phase τ of the present step (unclamped).
    pub phase: f64,
}

/// An IMU at rest at a fixed pitch (for tests and bench runs without robot dynamics), its gyro
/// dithered by [`test_dither_rad_s`] so that it does not look frozen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticImu {
    /// Pitch, rad.
    pub pitch_rad: f64,
    /// Constant gyro bias, rad/s.
    pub gyro_bias_rad_s: f64,
}

/// A gyro dither of ±1 µrad/s alternating every millisecond: a real IMU's noise never repeats
/// a sample bit for bit, and the safety monitor treats a repeating IMU as frozen (stale).
pub fn test_dither_rad_s(t_s: f64) -> f64 {
    if (t_s * 1e3).round() as i64 % 2 == 0 {
        1e-6
    } else {
        -1e-6
    }
}

impl Imu for StaticImu {
    /// Without a clock of its own: the sample at the time `out` is stamped with.
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        if let Some(sample) = self.read_at(out.t_s) {
            *out = sample;
        }
        Ok(())
    }
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        let g = crate::estimator::GRAVITY_MPS2;
        Some(ImuSample {
            t_s,
            gyro_pitch_rad_s: self.gyro_bias_rad_s + test_dither_rad_s(t_s),
            accel_x_mps2: -g * self.pitch_rad.sin(),
            accel_z_mps2: g * self.pitch_rad.cos(),
        })
    }
}

/// A motor bus and a separate IMU, as one loop backend.
pub struct WithImu<B, I> {
    /// The motors.
    pub bus: B,
    /// The IMU.
    pub imu: I,
}

impl<B: MotorBus, I> BusWrapper for WithImu<B, I> {
    type Inner = B;
    fn inner(&self) -> &B {
        &self.bus
    }
    fn inner_mut(&mut self) -> &mut B {
        &mut self.bus
    }
}

impl<B, I: Imu> Imu for WithImu<B, I> {
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        self.imu.read(out)
    }
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        self.imu.read_at(t_s)
    }
}

/// A bus and a separate IMU: hardware, or a bench without robot dynamics (no ground truth).
impl<B: MotorBus, I: Imu> Backend for WithImu<B, I> {}
