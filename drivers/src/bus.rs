//! The `MotorBus` hardware trait: a set of A1 motors on one or more CAN buses, with a
//! lifecycle that is safe by default.
//!
//! ```text
//!   Unconfigured --configure(motors)--> Configured --activate()--> Active
//!        ^                                 ^   |                      |
//!        |                                 |   +--configure (again)   | exchange(commands,
//!        |                                 +------deactivate()--------+   replies, budget)
//!                       Drop: if Active, every motor to damping
//! ```
//!
//! * `configure` records which motors the controller drives and on which bus (an index
//!   into the backend's interfaces); it sends nothing.
//! * `activate` enables every configured motor (special frame *enable*) and checks that
//!   each replies; on failure it disables them again and stays `Configured`.
//! * `exchange` sends one command per entry of `commands` and writes the reply of
//!   `commands[i].motor` into `replies[i]`, within `budget` from the call. It allocates
//!   nothing; the caller owns both slices (size them once, at start-up).
//! * `deactivate` (and `Drop` of an active bus) sends *disable* to every configured motor,
//!   which puts it in damping with the firmware's default gain.
//!
//! Errors are small `Copy` values ([`BusError`]) naming the motor or bus at fault.

use crate::a1::{self, Command, DecodeError, EncodeError, ErrorFlags, MotorId, Reply, Saturation};
use core::time::Duration;
use thiserror::Error;

/// Most motors one `MotorBus` drives (ADAM has 14 actuated joints).
pub const MAX_MOTORS: usize = 16;

/// Where a motor is: which of the backend's buses, and its id on that bus.
///
/// Motor ids are unique across all buses of one `MotorBus`, so a [`Command`] addresses a
/// motor by id alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MotorSpec {
    /// Index of the bus (interface) in the backend, `0..bus_count`.
    pub bus: usize,
    /// Motor id on that bus.
    pub id: MotorId,
}

/// Lifecycle state of a [`MotorBus`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Lifecycle {
    /// No motor set yet.
    Unconfigured,
    /// Motor set known; motors disabled (damping).
    Configured,
    /// Motors enabled; `exchange` allowed.
    Active,
}

impl Lifecycle {
    /// The state in words.
    pub fn name(self) -> &'static str {
        match self {
            Lifecycle::Unconfigured => "unconfigured",
            Lifecycle::Configured => "configured (motors disabled)",
            Lifecycle::Active => "active",
        }
    }

    /// `Ok` if `operation` may start from this state: configure from any state but active,
    /// activate only once configured, deactivate once configured or active; otherwise the
    /// error naming both. Every [`MotorBus`] guards its lifecycle with it.
    pub fn allows(self, operation: Operation) -> Result<()> {
        let allowed = match operation {
            Operation::Configure => self != Lifecycle::Active,
            Operation::Activate => self == Lifecycle::Configured,
            Operation::Deactivate => self != Lifecycle::Unconfigured,
        };
        if allowed {
            Ok(())
        } else {
            Err(BusError::WrongState {
                operation,
                state: self,
            })
        }
    }
}

/// Lifecycle operations, to name the one that was called in the wrong state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Operation {
    /// [`MotorBus::configure`].
    Configure,
    /// [`MotorBus::activate`].
    Activate,
    /// [`MotorBus::deactivate`].
    Deactivate,
}

impl Operation {
    /// The operation in words.
    pub fn name(self) -> &'static str {
        match self {
            Operation::Configure => "configure",
            Operation::Activate => "activate",
            Operation::Deactivate => "deactivate",
        }
    }
}

/// Everything that can go wrong on a motor bus. `Copy`, no heap: safe on the hot path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum BusError {
    /// A lifecycle operation was called in a state that does not allow it.
    #[error("{} is not allowed while the bus is {}", .operation.name(), .state.name())]
    WrongState {
        /// What was called.
        operation: Operation,
        /// State at the time.
        state: Lifecycle,
    },
    /// `exchange` was called while the bus is not active.
    #[error("exchange on a bus that is not active (it is {})", .state.name())]
    NotActive {
        /// State at the time.
        state: Lifecycle,
    },
    /// More motors than [`MAX_MOTORS`], or none.
    #[error("{count} motors configured; 1..={MAX_MOTORS} allowed")]
    BadMotorCount {
        /// Requested count.
        count: usize,
    },
    /// The same motor id appears twice (in a configuration or in one exchange).
    #[error("{motor} appears twice")]
    DuplicateMotor {
        /// Repeated motor.
        motor: MotorId,
    },
    /// A motor is placed on a bus the backend does not have.
    #[error("{motor} is placed on bus {bus}, but the backend has {bus_count} buses")]
    NoSuchBus {
        /// Motor.
        motor: MotorId,
        /// Requested bus index.
        bus: usize,
        /// Buses available.
        bus_count: usize,
    },
    /// A command addresses a motor that is not configured.
    #[error("command for {motor}, which is not configured")]
    UnknownMotor {
        /// Addressed motor.
        motor: MotorId,
    },
    /// `replies` is shorter than `commands`.
    #[error("{commands} commands but room for {replies} replies")]
    ReplyBufferTooSmall {
        /// `commands.len()`.
        commands: usize,
        /// `replies.len()`.
        replies: usize,
    },
    /// A command could not be encoded (nothing was sent).
    #[error("cannot encode command: {0}")]
    Encode(#[from] EncodeError),
    /// No reply from this motor before the deadline.
    #[error("no reply from {motor} on bus {bus} before the deadline")]
    MissingReply {
        /// Silent motor.
        motor: MotorId,
        /// Its bus.
        bus: usize,
    },
    /// A frame with this motor's reply id could not be decoded.
    #[error("malformed reply from {motor}: {error}")]
    BadReply {
        /// Replying motor.
        motor: MotorId,
        /// What was wrong.
        error: DecodeError,
    },
    /// A motor refused to enable (it replied disabled, with these fault flags).
    #[error("{motor} did not enable (motor faults: {errors})")]
    EnableRefused {
        /// Motor.
        motor: MotorId,
        /// Its fault flags.
        errors: ErrorFlags,
    },
    /// The frames of this exchange could not be carried within the budget.
    #[error(
        "exchange needs {:.0} µs of bus time, budget {:.0} µs",
        .needed.as_secs_f64() * 1e6,
        .budget.as_secs_f64() * 1e6
    )]
    DeadlineExceeded {
        /// Bus time needed (or spent before giving up).
        needed: Duration,
        /// Budget given to `exchange`.
        budget: Duration,
    },
    /// The CAN controller of this bus is bus-off.
    #[error("bus {bus} is bus-off")]
    BusOff {
        /// Bus index.
        bus: usize,
    },
    /// The CAN controller reported an error frame (class bits as in `linux/can/error.h`).
    #[error("error frame on bus {bus} (class {class:#x})")]
    ErrorFrame {
        /// Bus index.
        bus: usize,
        /// Error class bits of the CAN id.
        class: u32,
    },
    /// The operating system refused a read or write.
    #[error("I/O error on bus {bus}: {kind}")]
    Io {
        /// Bus index.
        bus: usize,
        /// What kind of error.
        kind: std::io::ErrorKind,
    },
}

/// Result alias for bus operations.
pub type Result<T> = core::result::Result<T, BusError>;

/// What one exchange did besides filling the replies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExchangeReport {
    /// Per command (same index as `commands`), which fields were clamped when encoding.
    pub saturation: [Saturation; MAX_MOTORS],
    /// Bus time the exchange took: modelled (simulation) or measured (hardware).
    pub bus_time: Duration,
}

impl ExchangeReport {
    /// Whether any command had a clamped field.
    pub fn any_saturated(&self) -> bool {
        self.saturation.iter().any(|s| s.any())
    }
}

/// A set of A1 motors behind one or more CAN buses, with a safe lifecycle.
///
/// Implementations: [`crate::sim::bus::SimBus`] (simulated firmware behind the real codec),
/// [`crate::socketcan_bus::SocketCanBus`] (Linux SocketCAN) and [`crate::udp::UdpBus`] (CAN over
/// UDP, cannelloni's format), the last two one [`crate::frame_bus::FrameBus`] over their
/// transports. All pass [`crate::conformance`]. A wrapper of another bus (a fault injector, a
/// recorder) implements [`BusWrapper`] instead and gets this trait by forwarding.
pub trait MotorBus {
    /// Current lifecycle state.
    fn state(&self) -> Lifecycle;

    /// Number of buses (interfaces) this backend drives; `MotorSpec::bus` indexes them.
    fn bus_count(&self) -> usize;

    /// Record the motors to drive. Allowed when `Unconfigured` or `Configured`.
    fn configure(&mut self, motors: &[MotorSpec]) -> Result<()>;

    /// Enable every configured motor. Allowed when `Configured`.
    fn activate(&mut self) -> Result<()>;

    /// Send `commands`, and write the reply of `commands[i].motor` to `replies[i]`, all
    /// within `budget` from the call. Allowed when `Active`; allocates nothing.
    ///
    /// On `MissingReply` the other replies are still written.
    fn exchange(
        &mut self,
        commands: &[Command],
        replies: &mut [Reply],
        budget: Duration,
    ) -> Result<ExchangeReport>;

    /// Put every configured motor in damping (special frame *disable*) and go back to
    /// `Configured`. Allowed when `Configured` or `Active`; the state becomes `Configured`
    /// even if some motor did not acknowledge (that motor is named in the error).
    fn deactivate(&mut self) -> Result<()>;

    /// The CAN frames the last `activate`, `exchange` or `deactivate` sent and received, in
    /// wire order ([`crate::frame_log`]); empty for a backend that does not record. Allocates
    /// nothing: the runtime logs them every tick.
    fn frames(&self) -> &[crate::frame_log::LoggedFrame] {
        &[]
    }
}

/// A [`MotorBus`] that wraps another and forwards to it (a fault injector, a recorder, a bus
/// paired with an IMU): implement this and the blanket impl makes the wrapper a `MotorBus` that
/// forwards every method to [`BusWrapper::inner`]. Its exchange calls
/// [`BusWrapper::before_exchange`], then the inner bus's exchange, then
/// [`BusWrapper::after_exchange`] (whatever the inner exchange returned), and returns the inner
/// bus's result: a wrapper overrides only the hook it needs. Static dispatch: the wrapper adds
/// nothing to the exchange that its hooks do not do.
///
/// The hooks see the wrapper, not the exchange's slices: no wrapper needs more (the fault
/// injector applies the faults due at the inner simulator's time; the probes record the
/// simulator's state after it; a test counts exchanges). A wrapper that must change what is
/// sent or returned implements [`MotorBus`] itself.
pub trait BusWrapper {
    /// The wrapped bus.
    type Inner: MotorBus;

    /// The wrapped bus.
    fn inner(&self) -> &Self::Inner;

    /// The wrapped bus, mutable.
    fn inner_mut(&mut self) -> &mut Self::Inner;

    /// Runs before each exchange is handed to the inner bus; by default nothing. Runs in the
    /// control tick: allocates nothing, never blocks (outside tests and tools).
    fn before_exchange(&mut self) {}

    /// Runs after each exchange of the inner bus, whether it succeeded or not; by default
    /// nothing. Runs in the control tick: allocates nothing, never blocks (outside tests and
    /// tools).
    fn after_exchange(&mut self) {}
}

impl<W: BusWrapper> MotorBus for W {
    fn state(&self) -> Lifecycle {
        self.inner().state()
    }
    fn bus_count(&self) -> usize {
        self.inner().bus_count()
    }
    fn configure(&mut self, motors: &[MotorSpec]) -> Result<()> {
        self.inner_mut().configure(motors)
    }
    fn activate(&mut self) -> Result<()> {
        self.inner_mut().activate()
    }
    fn exchange(
        &mut self,
        commands: &[Command],
        replies: &mut [Reply],
        budget: Duration,
    ) -> Result<ExchangeReport> {
        self.before_exchange();
        let result = self.inner_mut().exchange(commands, replies, budget);
        self.after_exchange();
        result
    }
    fn deactivate(&mut self) -> Result<()> {
        self.inner_mut().deactivate()
    }
    fn frames(&self) -> &[crate::frame_log::LoggedFrame] {
        self.inner().frames()
    }
}

/// The configured motor set, in fixed storage (no allocation).
#[derive(Debug, Clone, Copy)]
pub struct MotorTable {
    specs: [Option<MotorSpec>; MAX_MOTORS],
    len: usize,
}

impl Default for MotorTable {
    fn default() -> Self {
        Self {
            specs: [None; MAX_MOTORS],
            len: 0,
        }
    }
}

impl MotorTable {
    /// Validate and store a motor set for a backend with `bus_count` buses.
    pub fn new(motors: &[MotorSpec], bus_count: usize) -> Result<Self> {
        if motors.is_empty() || motors.len() > MAX_MOTORS {
            return Err(BusError::BadMotorCount {
                count: motors.len(),
            });
        }
        let mut table = Self::default();
        for (i, spec) in motors.iter().enumerate() {
            if spec.bus >= bus_count {
                return Err(BusError::NoSuchBus {
                    motor: spec.id,
                    bus: spec.bus,
                    bus_count,
                });
            }
            if motors[..i].iter().any(|other| other.id == spec.id) {
                return Err(BusError::DuplicateMotor { motor: spec.id });
            }
            table.specs[i] = Some(*spec);
        }
        table.len = motors.len();
        Ok(table)
    }

    /// The configured motors.
    pub fn iter(&self) -> impl Iterator<Item = MotorSpec> + '_ {
        self.specs[..self.len].iter().flatten().copied()
    }

    /// Number of configured motors.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no motor is configured.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The spec of a configured motor.
    pub fn get(&self, motor: MotorId) -> Option<MotorSpec> {
        self.iter().find(|s| s.id == motor)
    }

    /// Check an exchange's arguments and encode its commands, before anything is sent.
    ///
    /// Returns the frames (index = command index), each command's bus, and saturation.
    pub fn prepare(
        &self,
        commands: &[Command],
        replies: &[Reply],
    ) -> Result<(
        [a1::Frame; MAX_MOTORS],
        [usize; MAX_MOTORS],
        [Saturation; MAX_MOTORS],
    )> {
        if replies.len() < commands.len() {
            return Err(BusError::ReplyBufferTooSmall {
                commands: commands.len(),
                replies: replies.len(),
            });
        }
        if commands.len() > MAX_MOTORS {
            return Err(BusError::BadMotorCount {
                count: commands.len(),
            });
        }
        let empty = a1::Frame {
            id: 0,
            data: [0; 8],
        };
        let mut frames = [empty; MAX_MOTORS];
        let mut buses = [0; MAX_MOTORS];
        let mut saturation = [Saturation::NONE; MAX_MOTORS];
        for (i, command) in commands.iter().enumerate() {
            let spec = self.get(command.motor).ok_or(BusError::UnknownMotor {
                motor: command.motor,
            })?;
            if commands[..i].iter().any(|c| c.motor == command.motor) {
                return Err(BusError::DuplicateMotor {
                    motor: command.motor,
                });
            }
            let encoded = a1::encode_command(command)?;
            frames[i] = encoded.frame;
            buses[i] = spec.bus;
            saturation[i] = encoded.saturated;
        }
        Ok((frames, buses, saturation))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn spec(bus: usize, id: u8) -> MotorSpec {
        MotorSpec {
            bus,
            id: MotorId::new(id).unwrap(),
        }
    }

    #[test]
    fn the_frame_log_holds_a_failed_activation_of_every_motor() {
        // enable + reply, then disable + reply, per motor
        assert_eq!(crate::frame_log::FRAME_LOG_CAPACITY, 4 * MAX_MOTORS);
    }

    #[test]
    fn motor_table_rejects_bad_sets_with_the_culprit() {
        assert_eq!(
            MotorTable::new(&[], 2).unwrap_err(),
            BusError::BadMotorCount { count: 0 }
        );
        assert_eq!(
            MotorTable::new(&[spec(0, 1), spec(1, 1)], 2).unwrap_err(),
            BusError::DuplicateMotor {
                motor: MotorId::new(1).unwrap()
            }
        );
        assert_eq!(
            MotorTable::new(&[spec(0, 1), spec(2, 3)], 2).unwrap_err(),
            BusError::NoSuchBus {
                motor: MotorId::new(3).unwrap(),
                bus: 2,
                bus_count: 2
            }
        );
        let many: Vec<_> = (0..17).map(|i| spec(0, i)).collect();
        assert!(matches!(
            MotorTable::new(&many, 1),
            Err(BusError::BadMotorCount { count: 17 })
        ));
        let t = MotorTable::new(&[spec(1, 4), spec(0, 2)], 2).unwrap();
        assert_eq!(t.len(), 2);
        assert_eq!(t.get(MotorId::new(2).unwrap()), Some(spec(0, 2)));
    }

    #[test]
    fn prepare_checks_everything_before_sending() {
        let t = MotorTable::new(&[spec(0, 1), spec(1, 2)], 2).unwrap();
        let m1 = MotorId::new(1).unwrap();
        let m2 = MotorId::new(2).unwrap();
        let replies = [Reply::zeroed(m1); 2];
        let ok = [
            Command::damping(m2, 1.0),
            Command::pd(m1, 0.1, 0.0, 900.0, 1.0, 0.0),
        ];
        let (frames, buses, sat) = t.prepare(&ok, &replies).unwrap();
        assert_eq!(frames[0].id, m2.command_id());
        assert_eq!(buses[..2], [1, 0]);
        assert!(sat[1].contains(a1::Field::Kp));
        let dup = [Command::brake(m1), Command::brake(m1)];
        assert_eq!(
            t.prepare(&dup, &replies).unwrap_err(),
            BusError::DuplicateMotor { motor: m1 }
        );
        let unknown = [Command::brake(MotorId::new(9).unwrap())];
        assert!(matches!(
            t.prepare(&unknown, &replies),
            Err(BusError::UnknownMotor { .. })
        ));
        assert_eq!(
            t.prepare(&ok, &replies[..1]).unwrap_err(),
            BusError::ReplyBufferTooSmall {
                commands: 2,
                replies: 1
            }
        );
        let nan = [Command::pd(m1, f64::NAN, 0.0, 0.0, 0.0, 0.0)];
        assert!(matches!(
            t.prepare(&nan, &replies),
            Err(BusError::Encode(_))
        ));
    }
}
