//! The sensors besides the motors: the IMU trait and its samples, plus the pairing of a
//! [`MotorBus`] with an [`Imu`] into one loop backend.
//!
//! The loop driver takes one backend that is both a [`MotorBus`] and an [`Imu`]:
//! * real hardware: [`WithImu`] pairs a `SocketCanBus` with an IMU driver;
//! * simulation: the robot simulator owns both the joints and the torso, so a
//!   `SimBus<P>` whose plant `P` implements [`Imu`] is itself a backend (blanket impl below);
//! * tests: [`WithImu`] of a `SimBus<InertiaDampingPlant>` and a [`StaticImu`].

use core::time::Duration;
use drivers::a1::{Command, Reply};
use drivers::bus::{ExchangeReport, Lifecycle, MotorBus, MotorSpec};
use drivers::sim_bus::{JointPlant, SimBus};

/// One IMU sample in the torso frame (pitch about +y as in [`model::kinematics`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuSample {
    /// Time the sample was taken, s (same clock as the controller's `t_s`).
    pub t_s: f64,
    /// Gyro pitch rate, rad/s.
    pub gyro_pitch_rad_s: f64,
    /// Specific force along torso x, m/s².
    pub accel_x_mps2: f64,
    /// Specific force along torso z, m/s².
    pub accel_z_mps2: f64,
}

/// A source of IMU samples, polled once per tick. Must not block for long nor allocate.
pub trait Imu {
    /// The newest sample if one arrived since the last call (`None`: nothing new). `t_s` is
    /// the loop's time, for backends that stamp samples themselves.
    fn read_imu(&mut self, t_s: f64) -> Option<ImuSample>;

    /// The true torso pitch, rad, where the backend knows it (a simulator); `None` on hardware.
    /// Used only to score the estimator, never by the controller.
    fn true_pitch_rad(&self) -> Option<f64> {
        None
    }
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
    fn read_imu(&mut self, t_s: f64) -> Option<ImuSample> {
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

impl<B: MotorBus, I> MotorBus for WithImu<B, I> {
    fn state(&self) -> Lifecycle {
        self.bus.state()
    }
    fn bus_count(&self) -> usize {
        self.bus.bus_count()
    }
    fn configure(&mut self, motors: &[MotorSpec]) -> drivers::bus::Result<()> {
        self.bus.configure(motors)
    }
    fn activate(&mut self) -> drivers::bus::Result<()> {
        self.bus.activate()
    }
    fn exchange(
        &mut self,
        commands: &[Command],
        replies: &mut [Reply],
        budget: Duration,
    ) -> drivers::bus::Result<ExchangeReport> {
        self.bus.exchange(commands, replies, budget)
    }
    fn deactivate(&mut self) -> drivers::bus::Result<()> {
        self.bus.deactivate()
    }
}

impl<B, I: Imu> Imu for WithImu<B, I> {
    fn read_imu(&mut self, t_s: f64) -> Option<ImuSample> {
        self.imu.read_imu(t_s)
    }
    fn true_pitch_rad(&self) -> Option<f64> {
        self.imu.true_pitch_rad()
    }
}

/// A simulated bus whose plant also simulates the torso IMU (the robot simulator).
impl<P: JointPlant + Imu> Imu for SimBus<P> {
    fn read_imu(&mut self, t_s: f64) -> Option<ImuSample> {
        self.plant_mut().read_imu(t_s)
    }
    fn true_pitch_rad(&self) -> Option<f64> {
        self.plant().true_pitch_rad()
    }
}
