//! Fault injection on the simulated robot: [`FaultySim`] starts and ends the faults of a
//! profile's seeded schedule at simulated time, and [`FaultClock`] wakes the loop late inside
//! overrun faults.

use crate::backend::Backend;
use crate::rt_loop::Clock;
use crate::sim::faults::{Fault, FaultProfile, ScheduledFault};
use crate::{Result, RuntimeError, Setup};
use core::time::Duration;
use drivers::a1::{Command, ErrorFlags, MotorId, Reply};
use drivers::bus::{ExchangeReport, Lifecycle, MotorBus, MotorSpec};
use drivers::imu::{Imu, ImuError, ImuFault, ImuSample};
use drivers::sim::bus::SimBus;
use drivers::sim::robot::RobotSim;

/// The simulated robot with faults applied on schedule: a loop backend ([`MotorBus`] + [`Imu`]).
///
/// Before each exchange, at the simulated time of the period about to run, faults whose end has
/// come are healed, then faults whose start has come are applied. A hot motor is not cooled at
/// the end of its fault (the thermal model cools it); a push ends by itself. Overlapping faults
/// of one kind: the first to end heals both (random faults never overlap).
pub struct FaultySim {
    pub(super) bus: SimBus<RobotSim>,
    schedule: Vec<ScheduledFault>,
    ended: Vec<bool>,
    next: usize,
    first_open: usize,
    motors: [MotorId; 4],
    belt_speed_mps: f64,
    half_period_s: f64,
    pub(super) started: u64,
}

impl FaultySim {
    /// Wrap `bus` with the wire faults of `profile` and the faults of `schedule`.
    pub fn new(
        setup: &Setup,
        mut bus: SimBus<RobotSim>,
        profile: &FaultProfile,
        schedule: Vec<ScheduledFault>,
    ) -> Result<Self> {
        bus.set_wire_faults(profile.wire.to_wire_faults())
            .map_err(|(field, value)| RuntimeError::InvalidField {
                origin: "fault profile".into(),
                field: format!("wire.{field}"),
                value: value.to_string(),
                reason: "out of range".into(),
            })?;
        let leg = &setup.config.leg_motors;
        let id = |slot: usize| leg[slot].spec(&format!("leg_motors[{slot}]")).map(|s| s.id);
        let motors = [id(0)?, id(1)?, id(2)?, id(3)?];
        Ok(Self {
            belt_speed_mps: bus.plant().config().belt_speed_mps,
            half_period_s: 0.5 / bus.config().control_rate_hz,
            ended: vec![false; schedule.len()],
            schedule,
            next: 0,
            first_open: 0,
            motors,
            started: 0,
            bus,
        })
    }

    /// Heal the faults that have ended and apply those that have begun at `t_s`.
    fn apply(&mut self, t_s: f64) {
        let now = t_s + self.half_period_s;
        for i in self.first_open..self.next {
            if !self.ended[i] && self.schedule[i].end_s <= now {
                self.ended[i] = true;
                self.set(self.schedule[i].fault, false);
            }
        }
        while self.first_open < self.next && self.ended[self.first_open] {
            self.first_open += 1;
        }
        while self.next < self.schedule.len() && self.schedule[self.next].start_s <= now {
            let f = self.schedule[self.next];
            self.next += 1;
            self.started += 1;
            self.set(f.fault, true);
            if let Fault::Push {
                force_x_n,
                force_z_n,
            } = f.fault
            {
                // Non-finite forces were refused by the profile's validation.
                let _ = self
                    .bus
                    .plant_mut()
                    .push([force_x_n, force_z_n], f.end_s - f.start_s);
            }
        }
    }

    /// Apply (`on`) or heal one fault.
    fn set(&mut self, fault: Fault, on: bool) {
        let imu = |f| if on { f } else { ImuFault::None };
        match fault {
            Fault::SilentMotor { slot } => {
                self.bus.set_silent(self.motors[slot], on);
            }
            Fault::HotMotor {
                slot,
                temperature_c,
            } => {
                if on {
                    self.bus.set_temperature_c(self.motors[slot], temperature_c);
                }
            }
            Fault::MotorFlags { slot, flags } => {
                let flags = if on {
                    ErrorFlags(flags)
                } else {
                    ErrorFlags::NONE
                };
                self.bus.set_error_flags(self.motors[slot], flags);
            }
            Fault::ImuDropout => self.bus.plant_mut().set_imu_fault(imu(ImuFault::Dropout)),
            Fault::ImuSpike { gyro_rad_s } => self
                .bus
                .plant_mut()
                .set_imu_fault(imu(ImuFault::Spike { gyro_rad_s })),
            Fault::ImuFrozen => self.bus.plant_mut().set_imu_fault(imu(ImuFault::Frozen)),
            Fault::BeltSpeed { speed_mps } => {
                let v = if on { speed_mps } else { self.belt_speed_mps };
                // A finite speed cannot be refused; a faulted simulator reports itself
                // through `SimEvent::Fault`.
                let _ = self.bus.plant_mut().set_belt_speed(v);
            }
            // The clock's fault; a push ends by itself.
            Fault::Overrun { .. } | Fault::Push { .. } => {}
        }
    }
}

impl MotorBus for FaultySim {
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
        let t_s = self.bus.time_s();
        self.apply(t_s);
        self.bus.exchange(commands, replies, budget)
    }
    fn deactivate(&mut self) -> drivers::bus::Result<()> {
        self.bus.deactivate()
    }
}

impl Imu for FaultySim {
    fn read(&mut self, out: &mut ImuSample) -> core::result::Result<(), ImuError> {
        self.bus.read(out)
    }
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        self.bus.read_at(t_s)
    }
}

impl Backend for FaultySim {
    fn true_pitch_rad(&self) -> Option<f64> {
        self.bus.true_pitch_rad()
    }
    fn true_belt_position_m(&self) -> Option<f64> {
        self.bus.true_belt_position_m()
    }
}

/// Simulated time that wakes the loop late inside overrun faults: a deadline `d` in
/// `[start, end)` of an [`Fault::Overrun`] wakes at `d + late`. Outside them it is
/// [`crate::rt_loop::SimulatedClock`]: sleeping jumps to the deadline, time never goes back.
#[derive(Clone, Debug, Default)]
pub struct FaultClock {
    now_s: f64,
    windows: Vec<(f64, f64, f64)>,
}

impl FaultClock {
    /// The overrun faults of `schedule`.
    pub fn new(schedule: &[ScheduledFault]) -> Self {
        let windows = schedule
            .iter()
            .filter_map(|f| match f.fault {
                Fault::Overrun { late_ms } => Some((f.start_s, f.end_s, late_ms * 1e-3)),
                _ => None,
            })
            .collect();
        Self {
            now_s: 0.0,
            windows,
        }
    }
}

impl Clock for FaultClock {
    fn now_s(&mut self) -> f64 {
        self.now_s
    }
    fn sleep_until(&mut self, deadline_s: f64) {
        let late_s = self
            .windows
            .iter()
            .find(|(a, b, _)| (*a..*b).contains(&deadline_s))
            .map_or(0.0, |w| w.2);
        self.now_s = self.now_s.max(deadline_s + late_s);
    }
    fn is_simulated(&self) -> bool {
        true
    }
}
