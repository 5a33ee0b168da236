//! `SimBus`: simulated A1 firmware behind the real CAN codec.
//!
//! Every exchange runs the full byte path: the bus encodes each [`Command`] into a CAN
//! frame, the simulated firmware decodes the frame, samples its state, encodes a reply
//! frame, and the bus decodes that reply. Bus time is the exact length of those frames
//! (stuff bits and CRC included, [`crate::timing::frame_bits_exact`]); the buses run in
//! parallel, and an exchange whose busiest bus exceeds the budget is
//! [`BusError::DeadlineExceeded`].
//!
//! # Data flow of one `exchange` (control period `T`, firmware tick `h = T / n`)
//! ```text
//! Command --encode--> frame --firmware decode--> inbox   (applied from the next period)
//!                                      \--> sample state --encode--> reply frame --decode--> Reply
//! then n times: each firmware: measure (encoder) -> torque (mode, PD) -> limits -> heat
//!               plant.step(torques, h)
//! then each firmware latches its inbox as the active command
//! ```
//! So a command sent in exchange `k` acts during period `k + 1` and shows in the reply of
//! exchange `k + 2`: one control tick of communication latency on top of the sample
//! delay.
//!
//! The motors are simulated A1 firmware ([`crate::sim::firmware`]); the joint each one drives is
//! a [`JointPlant`]: [`crate::sim::plant::InertiaDampingPlant`] or the whole robot,
//! [`crate::sim::robot::RobotSim`].
//!
//! # Fault injection (off by default; seeded, so the same seed gives the same faults)
//! * Wire ([`WireFaults`], [`SimBus::set_wire_faults`]): frames lost, corrupted or delayed
//!   ([`crate::sim::wire`]: each frame, in each direction, lost or corrupted, each reply delayed,
//!   with the probabilities set; a reply missing or late past the budget is missing).
//! * Motors: [`SimBus::set_silent`] (a cut cable), [`SimBus::set_error_flags`] (firmware fault
//!   bits in every reply), [`SimBus::set_temperature_c`] (a hot winding; the thermal model
//!   carries on from there). [`SimBus::wire_stats`] counts what the wire did.

use crate::a1::{self, Command, ErrorFlags, Frame, MotorId, Reply, Special};
use crate::bus::{BusError, ExchangeReport, Lifecycle, MotorBus, MotorSpec, MotorTable};
use crate::frame_log::{FrameDirection, FrameLog, LoggedFrame};
use crate::imu::{Imu, ImuError, ImuSample};
use crate::lifecycle::{self, LifecycleParts, SpecialRounds};
use crate::sim::firmware::{A1Model, EncoderMount, Firmware, SimMotor, TickPeriod};
use crate::sim::plant::JointPlant;
use crate::sim::wire::{
    corrupt, Corruption, Direction, TapEntry, WireFault, WireFaults, WireStats, WireTap,
};
use crate::timing::{bits_to_duration, frame_bits_exact};
use core::time::Duration;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

/// Most buses one `SimBus` models.
pub const MAX_BUSES: usize = 8;

/// Configuration of a [`SimBus`].
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Control (exchange) rate \[Hz\]; each exchange advances the simulation by one period.
    pub control_rate_hz: f64,
    /// CAN bitrate \[bit/s\].
    pub bitrate_bps: u32,
    /// Number of buses.
    pub bus_count: usize,
    /// Motors present on the buses (configure may name others: those stay silent).
    pub motors: Vec<SimMotor>,
    /// Motor model (the same for all).
    pub model: A1Model,
    /// Seed of all noise.
    pub seed: u64,
}

/// A [`SimConfig`] that cannot be simulated.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SimError {
    /// The firmware rate is not an integer multiple of the control rate.
    #[error(
        "firmware rate {firmware_rate_hz} Hz is not a positive integer multiple of the \
         control rate {control_rate_hz} Hz"
    )]
    Rates {
        /// Control rate \[Hz\].
        control_rate_hz: f64,
        /// Firmware rate \[Hz\].
        firmware_rate_hz: f64,
    },
    /// Bus count outside `1..=MAX_BUSES` or a zero bitrate.
    #[error(
        "{bus_count} buses at {bitrate_bps} bit/s: need 1..={MAX_BUSES} buses and a bitrate > 0"
    )]
    Buses {
        /// Bus count.
        bus_count: usize,
        /// Bitrate.
        bitrate_bps: u32,
    },
    /// A motor's bus or joint does not exist, or two motors share an id or a joint.
    #[error("simulated {motor} (bus {bus}, joint {joint}) is misplaced: {reason}")]
    Motor {
        /// Motor.
        motor: MotorId,
        /// Its bus.
        bus: usize,
        /// Its joint.
        joint: usize,
        /// What is wrong.
        reason: &'static str,
    },
}

/// A [`MotorBus`] over simulated A1 firmware and a [`JointPlant`].
pub struct SimBus<P: JointPlant> {
    config: SimConfig,
    plant: P,
    firmware: Vec<Firmware>,
    table: MotorTable,
    state: Lifecycle,
    rng: ChaCha8Rng,
    substeps: usize,
    ticks: u64,
    torques_nm: Vec<f64>,
    tap: Option<WireTap>,
    wire_faults: WireFaults,
    fault_rng: ChaCha8Rng,
    wire_stats: WireStats,
    frames: FrameLog,
}

/// Mixed into the seed of the fault stream, so it differs from the noise stream.
const FAULT_STREAM: u64 = 0xFA17_5EED_0000_0001;

impl<P: JointPlant> SimBus<P> {
    /// A simulation of `config.motors` driving `plant`.
    pub fn new(config: SimConfig, plant: P) -> Result<Self, SimError> {
        let ratio = config.model.firmware_rate_hz / config.control_rate_hz;
        if !(ratio.is_finite() && ratio >= 1.0 && (ratio - ratio.round()).abs() < 1e-9) {
            return Err(SimError::Rates {
                control_rate_hz: config.control_rate_hz,
                firmware_rate_hz: config.model.firmware_rate_hz,
            });
        }
        if config.bus_count == 0 || config.bus_count > MAX_BUSES || config.bitrate_bps == 0 {
            return Err(SimError::Buses {
                bus_count: config.bus_count,
                bitrate_bps: config.bitrate_bps,
            });
        }
        for (i, m) in config.motors.iter().enumerate() {
            let misplaced = |reason| SimError::Motor {
                motor: m.spec.id,
                bus: m.spec.bus,
                joint: m.joint,
                reason,
            };
            if m.spec.bus >= config.bus_count {
                return Err(misplaced("no such bus"));
            }
            if m.joint >= plant.joint_count() {
                return Err(misplaced("no such joint"));
            }
            let earlier = &config.motors[..i];
            if earlier.iter().any(|o| o.spec.id == m.spec.id) {
                return Err(misplaced("motor id used twice"));
            }
            if earlier.iter().any(|o| o.joint == m.joint) {
                return Err(misplaced("joint driven twice"));
            }
        }
        let firmware = config
            .motors
            .iter()
            .map(|m| Firmware::new(*m, &config.model, plant.position_rad(m.joint)))
            .collect();
        Ok(Self {
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            substeps: ratio.round() as usize,
            ticks: 0,
            torques_nm: vec![0.0; plant.joint_count()],
            firmware,
            plant,
            table: MotorTable::default(),
            state: Lifecycle::Unconfigured,
            tap: None,
            wire_faults: WireFaults::NONE,
            fault_rng: ChaCha8Rng::seed_from_u64(config.seed ^ FAULT_STREAM),
            wire_stats: WireStats::default(),
            frames: FrameLog::default(),
            config,
        })
    }

    /// Fault injection: faults of the wire from the next exchange on (lifecycle frames, enable
    /// and disable, stay clean). Refuses a field out of range, naming it.
    pub fn set_wire_faults(&mut self, faults: WireFaults) -> Result<(), (&'static str, f64)> {
        if let Some(bad) = faults.invalid_field() {
            return Err(bad);
        }
        self.wire_faults = faults;
        Ok(())
    }

    /// What the wire did so far.
    pub fn wire_stats(&self) -> WireStats {
        self.wire_stats
    }

    /// Fault injection: firmware fault bits reported in every reply of `motor` (in addition to
    /// its own over-temperature bit); `ErrorFlags::NONE` clears them. The motor keeps driving.
    /// Returns false if there is no such simulated motor.
    pub fn set_error_flags(&mut self, motor: MotorId, flags: ErrorFlags) -> bool {
        match self.firmware.iter_mut().find(|f| f.motor.spec.id == motor) {
            Some(f) => {
                f.injected_errors = flags;
                true
            }
            None => false,
        }
    }

    /// Fault injection: set the winding temperature of `motor` (a hot motor); the thermal model
    /// and the firmware's over-temperature switch carry on from there. Returns false if there
    /// is no such simulated motor or the temperature is not finite.
    pub fn set_temperature_c(&mut self, motor: MotorId, temperature_c: f64) -> bool {
        if !temperature_c.is_finite() {
            return false;
        }
        match self.firmware.iter_mut().find(|f| f.motor.spec.id == motor) {
            Some(f) => {
                f.temperature_c = temperature_c;
                true
            }
            None => false,
        }
    }

    /// Fault injection for calibration: mount `motor` on its joint as `mount` says (flipped,
    /// its zero elsewhere). Returns false if there is no such simulated motor or the mount is
    /// not a direction of ±1 and a finite angle.
    pub fn set_encoder_mount(&mut self, motor: MotorId, mount: EncoderMount) -> bool {
        if !(mount.direction.abs() == 1.0 && mount.joint_rad_at_zero.is_finite()) {
            return false;
        }
        match self.firmware.iter_mut().find(|f| f.motor.spec.id == motor) {
            Some(f) => {
                f.mount = mount;
                true
            }
            None => false,
        }
    }

    /// Record every frame on the simulated wire into `tap` (diagnostics, tests).
    pub fn set_tap(&mut self, tap: Option<WireTap>) {
        self.tap = tap;
    }

    /// Simulated time: exchanges so far × control period \[s\].
    pub fn time_s(&self) -> f64 {
        self.ticks as f64 / self.config.control_rate_hz
    }

    /// The plant (to read the true state).
    pub fn plant(&self) -> &P {
        &self.plant
    }

    /// The plant (to set states, loads).
    pub fn plant_mut(&mut self) -> &mut P {
        &mut self.plant
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Fault injection: a silent motor neither receives nor replies (a cut cable).
    /// Returns false if there is no such simulated motor.
    pub fn set_silent(&mut self, motor: MotorId, silent: bool) -> bool {
        match self.firmware.iter_mut().find(|f| f.motor.spec.id == motor) {
            Some(f) => {
                f.silent = silent;
                true
            }
            None => false,
        }
    }

    /// Winding temperature of a simulated motor (unquantized) \[°C\].
    pub fn temperature_c(&self, motor: MotorId) -> Option<f64> {
        self.firmware
            .iter()
            .find(|f| f.motor.spec.id == motor)
            .map(|f| f.temperature_c)
    }

    /// What the wire does to one frame: `None` delivers it intact.
    fn wire_fault(&mut self) -> Option<WireFault> {
        let f = self.wire_faults;
        if f.loss_probability > 0.0 && self.fault_rng.random::<f64>() < f.loss_probability {
            self.wire_stats.lost += 1;
            return Some(WireFault::Lost);
        }
        if f.corrupt_probability > 0.0 && self.fault_rng.random::<f64>() < f.corrupt_probability {
            self.wire_stats.corrupted += 1;
            let damage = match self.fault_rng.random_range(0..3u8) {
                0 => Corruption::Length(self.fault_rng.random_range(0..a1::codec::FRAME_LEN)),
                1 => Corruption::ReservedMode,
                _ => Corruption::Id,
            };
            return Some(WireFault::Corrupted(damage));
        }
        None
    }

    /// Deliver one host frame on `bus`; the decoded reply of the motor that answered. With
    /// `budget` (control traffic) the frame goes through the wire's faults: a command or reply
    /// may be lost, corrupted (then rejected by the firmware's or the host's decoder) or, for a
    /// reply, delayed past `budget` (then missing); without (lifecycle frames) the wire is clean.
    fn transmit(
        &mut self,
        bus: usize,
        frame: &Frame,
        bits: &mut [u32; MAX_BUSES],
        budget: Option<Duration>,
    ) -> Option<Reply> {
        let model = self.config.model;
        // Host → motor. A lost frame still took its bus time (the receiver missed it).
        bits[bus] += frame_bits_exact(frame.id, &frame.data).unwrap_or(0);
        self.log_frame(bus, FrameDirection::Tx, bits[bus], frame.id, &frame.data);
        self.record(bus, Direction::ToMotor, frame);
        let fault = budget.and_then(|_| self.wire_fault());
        let (id, data, len) = match fault {
            Some(WireFault::Lost) => return None,
            Some(WireFault::Corrupted(damage)) => corrupt(frame, damage),
            None => (frame.id, frame.data, frame.data.len()),
        };
        let reply_frame = self
            .firmware
            .iter_mut()
            .filter(|f| f.motor.spec.bus == bus)
            .find_map(|f| f.receive(id, &data[..len], &model))?;
        // Motor → host.
        bits[bus] += frame_bits_exact(reply_frame.id, &reply_frame.data).unwrap_or(0);
        self.record(bus, Direction::ToHost, &reply_frame);
        let Some(budget) = budget else {
            self.log_frame(
                bus,
                FrameDirection::Rx,
                bits[bus],
                reply_frame.id,
                &reply_frame.data,
            );
            return a1::decode_reply(reply_frame.id, &reply_frame.data).ok();
        };
        let (id, data, len) = match self.wire_fault() {
            Some(WireFault::Lost) => return None,
            Some(WireFault::Corrupted(damage)) => corrupt(&reply_frame, damage),
            None => (reply_frame.id, reply_frame.data, reply_frame.data.len()),
        };
        // What the host received, damaged or not, at the end of its bus time.
        self.log_frame(bus, FrameDirection::Rx, bits[bus], id, &data[..len]);
        let f = self.wire_faults;
        if f.delay_probability > 0.0 && self.fault_rng.random::<f64>() < f.delay_probability {
            self.wire_stats.delayed += 1;
            // A delay too long for a Duration (validated finite and ≥ 0) is late anyway.
            let delay = Duration::try_from_secs_f64(f.delay_s).unwrap_or(Duration::MAX);
            let arrival =
                bits_to_duration(bits[bus], self.config.bitrate_bps).saturating_add(delay);
            if arrival > budget {
                self.wire_stats.delayed_late += 1;
                return None;
            }
        }
        a1::decode_reply(id, &data[..len]).ok()
    }

    /// Into the frame log, stamped with the bus time at which it ended on its bus (`bits` on
    /// that bus so far, itself included).
    fn log_frame(
        &mut self,
        bus: usize,
        direction: FrameDirection,
        bits: u32,
        id: u32,
        data: &[u8],
    ) {
        let offset = bits_to_duration(bits, self.config.bitrate_bps);
        self.frames.record(bus, direction, offset, id, data);
    }

    /// Frame-level access for a server that puts this simulation behind a real transport
    /// ([`crate::udp::serve`]): deliver one host frame (id and bytes as received) on `bus` to the
    /// firmware, as the wire delivers it with no faults; the reply frame of the motor that
    /// answers, if any. Recorded on the tap. Time does not move: see
    /// [`SimBus::advance_period`].
    pub fn deliver(&mut self, bus: usize, id: u32, data: &[u8]) -> Option<Frame> {
        let model = self.config.model;
        if let Some(tap) = &self.tap {
            if let (Ok(mut log), Ok(data)) = (tap.lock(), <[u8; 8]>::try_from(data)) {
                log.push(TapEntry {
                    bus,
                    direction: Direction::ToMotor,
                    frame: Frame { id, data },
                });
            }
        }
        let reply = self
            .firmware
            .iter_mut()
            .filter(|f| f.motor.spec.bus == bus)
            .find_map(|f| f.receive(id, data, &model))?;
        self.record(bus, Direction::ToHost, &reply);
        Some(reply)
    }

    /// Advance the motors and the plant by one control period and latch the commands received
    /// (what [`MotorBus::exchange`] does after delivering its frames).
    pub fn advance_period(&mut self) {
        self.advance();
    }

    fn record(&self, bus: usize, direction: Direction, frame: &Frame) {
        if let Some(tap) = &self.tap {
            if let Ok(mut log) = tap.lock() {
                log.push(TapEntry {
                    bus,
                    direction,
                    frame: *frame,
                });
            }
        }
    }

    /// Advance motors and plant by one control period, then latch received commands.
    fn advance(&mut self) {
        let period = TickPeriod::new(&self.config.model);
        for _ in 0..self.substeps {
            self.torques_nm.fill(0.0);
            for f in &mut self.firmware {
                let j = f.motor.joint;
                let q = self.plant.position_rad(j);
                let dq = self.plant.velocity_rad_s(j);
                self.torques_nm[j] = f.tick(q, dq, &period, &self.config.model, &mut self.rng);
            }
            self.plant.step(&self.torques_nm, period.dt_s);
        }
        for f in &mut self.firmware {
            f.latch();
        }
        self.ticks += 1;
    }
}

impl<P: JointPlant> SpecialRounds for SimBus<P> {
    fn parts(&mut self) -> LifecycleParts<'_> {
        LifecycleParts {
            state: &mut self.state,
            table: &mut self.table,
            frames: &mut self.frames,
        }
    }

    fn buses(&self) -> usize {
        self.config.bus_count
    }

    fn special_to_all(&mut self, special: Special) -> Result<(), BusError> {
        self.frames.clear();
        let mut first_error = None;
        let mut bits = [0; MAX_BUSES];
        let table = self.table;
        for spec in table.iter() {
            let frame = a1::encode_special(spec.id, special);
            match self.transmit(spec.bus, &frame, &mut bits, None) {
                Some(reply) if special == Special::Enable && !reply.enabled => {
                    first_error.get_or_insert(BusError::EnableRefused {
                        motor: spec.id,
                        errors: reply.errors,
                    });
                }
                Some(_) => {}
                None => {
                    first_error.get_or_insert(BusError::MissingReply {
                        motor: spec.id,
                        bus: spec.bus,
                    });
                }
            }
        }
        first_error.map_or(Ok(()), Err)
    }
}

impl<P: JointPlant> MotorBus for SimBus<P> {
    fn state(&self) -> Lifecycle {
        self.state
    }

    fn bus_count(&self) -> usize {
        self.config.bus_count
    }

    fn configure(&mut self, motors: &[MotorSpec]) -> Result<(), BusError> {
        lifecycle::configure(self, motors)
    }

    fn activate(&mut self) -> Result<(), BusError> {
        lifecycle::activate(self)
    }

    fn exchange(
        &mut self,
        commands: &[Command],
        replies: &mut [Reply],
        budget: Duration,
    ) -> Result<ExchangeReport, BusError> {
        if self.state != Lifecycle::Active {
            return Err(BusError::NotActive { state: self.state });
        }
        let (frames, buses, saturation) = self.table.prepare(commands, replies)?;
        self.frames.clear();
        let mut bits = [0u32; MAX_BUSES];
        let mut missing = None;
        for i in 0..commands.len() {
            match self.transmit(buses[i], &frames[i], &mut bits, Some(budget)) {
                Some(reply) => replies[i] = reply,
                None => {
                    missing.get_or_insert(BusError::MissingReply {
                        motor: commands[i].motor,
                        bus: buses[i],
                    });
                }
            }
        }
        self.advance();
        let busiest = bits.iter().copied().max().unwrap_or(0);
        let bus_time = bits_to_duration(busiest, self.config.bitrate_bps);
        if bus_time > budget {
            return Err(BusError::DeadlineExceeded {
                needed: bus_time,
                budget,
            });
        }
        match missing {
            Some(e) => Err(e),
            None => Ok(ExchangeReport {
                saturation,
                bus_time,
            }),
        }
    }

    fn deactivate(&mut self) -> Result<(), BusError> {
        lifecycle::deactivate(self)
    }

    fn frames(&self) -> &[LoggedFrame] {
        self.frames.frames()
    }
}

/// A simulated bus whose plant also simulates the torso IMU (the robot simulator) is that IMU.
impl<P: JointPlant + Imu> Imu for SimBus<P> {
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        self.plant_mut().read(out)
    }
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        self.plant_mut().read_at(t_s)
    }
}

impl<P: JointPlant> Drop for SimBus<P> {
    fn drop(&mut self) {
        lifecycle::disable_if_active(self);
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests;
