//! Fault injection on the simulated robot: [`FaultySim`] starts and ends the faults of a
//! profile's seeded schedule at simulated time, runs the belt's speed profile, lands pushes at
//! a phase point of a step (watching the controller's status), and records the ground truth of
//! the treadmill ([`TruthSample`]); [`FaultClock`] wakes the loop late inside overrun faults.

use crate::backend::{Backend, WalkProgress};
use crate::rt_loop::Clock;
use crate::sim::faults::{Fault, FaultProfile, ScheduledFault};
use crate::{Result, RuntimeError, Setup};
use drivers::a1::{ErrorFlags, MotorId};
use drivers::bus::BusWrapper;
use drivers::imu::{Imu, ImuError, ImuFault, ImuSample};
use drivers::sim::bus::SimBus;
use drivers::sim::robot::RobotSim;

/// The simulated robot with faults applied on schedule: a loop backend ([`MotorBus`](drivers::bus::MotorBus) + [`Imu`]).
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
    /// The belt's target speed before a belt-step fault began, m/s (where it returns).
    belt_speed_mps: f64,
    half_period_s: f64,
    pub(super) started: u64,
    /// The belt's profile: target speeds from times, s, m/s; the next one to apply.
    belt_profile: Vec<(f64, f64)>,
    next_belt: usize,
    /// A push waiting for its phase point.
    pending_push: Option<PendingPush>,
    /// Ground truth every `trace_period_s` (capacity reserved up front: no allocation).
    pub(super) trace: Vec<TruthSample>,
    trace_period_s: f64,
    next_trace_s: f64,
}

/// A push armed by [`crate::sim::faults::Fault::PushAtPhase`]: it lands when the first step
/// that begins after it was armed reaches `phase`.
#[derive(Clone, Copy, Debug)]
struct PendingPush {
    force_xz_n: [f64; 2],
    duration_s: f64,
    phase: f64,
    /// The controller's step count when the push was armed (`None`: not seen yet).
    steps_at_arm: Option<u32>,
}

/// The treadmill's ground truth at one instant of a simulated run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSample {
    /// Simulated time, s.
    pub t_s: f64,
    /// Belt speed, m/s (the surface moving backwards).
    pub belt_speed_mps: f64,
    /// The hip's position on the belt, forward of its centre, m.
    pub position_on_belt_m: f64,
    /// The hip's world velocity, forward, m/s.
    pub base_velocity_mps: f64,
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
            belt_speed_mps: bus.plant().belt_speed_mps(),
            belt_profile: Vec::new(),
            next_belt: 0,
            pending_push: None,
            trace: Vec::new(),
            trace_period_s: f64::INFINITY,
            next_trace_s: 0.0,
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

    /// Run the belt's speed profile: from each pair's time the belt ramps toward its speed
    /// (the simulator's ramp acceleration).
    pub fn with_belt_profile(mut self, points: &[(f64, f64)]) -> Self {
        self.belt_profile = points.to_vec();
        self
    }

    /// Record the ground truth every `period_s` over a run of `duration_s`
    /// ([`FaultySim::trace`]).
    pub fn with_truth_trace(mut self, duration_s: f64, period_s: f64) -> Self {
        let n = (duration_s / period_s).ceil().max(0.0) as usize + 2;
        self.trace = Vec::with_capacity(n);
        self.trace_period_s = period_s;
        self
    }

    /// The ground truth recorded so far.
    pub fn trace(&self) -> &[TruthSample] {
        &self.trace
    }

    /// Heal the faults that have ended and apply those that have begun at `t_s`; run the belt
    /// profile; record the truth.
    fn apply(&mut self, t_s: f64) {
        let now = t_s + self.half_period_s;
        while self.next_belt < self.belt_profile.len() && self.belt_profile[self.next_belt].0 <= now
        {
            let v = self.belt_profile[self.next_belt].1;
            self.next_belt += 1;
            // The profile was validated (finite speeds).
            let _ = self.bus.plant_mut().set_belt_target_speed(v);
        }
        if t_s + self.half_period_s >= self.next_trace_s && self.trace.len() < self.trace.capacity()
        {
            let sim = self.bus.plant();
            self.trace.push(TruthSample {
                t_s,
                belt_speed_mps: sim.belt_speed_mps(),
                position_on_belt_m: sim.position_on_belt_m(),
                base_velocity_mps: sim.base_velocity_mps()[0],
            });
            self.next_trace_s += self.trace_period_s;
        }
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
            if let Fault::PushAtPhase {
                force_x_n,
                force_z_n,
                phase,
            } = f.fault
            {
                self.pending_push = Some(PendingPush {
                    force_xz_n: [force_x_n, force_z_n],
                    duration_s: f.end_s - f.start_s,
                    phase,
                    steps_at_arm: None,
                });
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
                if on {
                    self.belt_speed_mps = self.bus.plant().belt_target_speed_mps();
                }
                let v = if on { speed_mps } else { self.belt_speed_mps };
                // A finite speed cannot be refused; a faulted simulator reports itself
                // through `SimEvent::Fault`.
                let _ = self.bus.plant_mut().set_belt_speed(v);
            }
            // The clock's fault; a push ends by itself (and one at a phase waits for it).
            Fault::Overrun { .. } | Fault::Push { .. } | Fault::PushAtPhase { .. } => {}
        }
    }
}

/// The simulator's bus, the faults due applied before each exchange.
impl BusWrapper for FaultySim {
    type Inner = SimBus<RobotSim>;
    fn inner(&self) -> &Self::Inner {
        &self.bus
    }
    fn inner_mut(&mut self) -> &mut Self::Inner {
        &mut self.bus
    }
    fn before_exchange(&mut self) {
        let t_s = self.bus.time_s();
        self.apply(t_s);
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

    /// Lands a waiting push once a step that began after it was armed reaches its phase.
    fn observe(&mut self, status: &WalkProgress) {
        let Some(p) = self.pending_push.as_mut() else {
            return;
        };
        let Some(steps_at_arm) = p.steps_at_arm else {
            p.steps_at_arm = Some(status.steps);
            return;
        };
        if status.walking && status.steps != steps_at_arm && status.phase >= p.phase {
            let (force, duration) = (p.force_xz_n, p.duration_s);
            self.pending_push = None;
            // Finite values: the profile was validated.
            let _ = self.bus.plant_mut().push(force, duration);
        }
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
