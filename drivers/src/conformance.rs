//! One conformance suite for every [`MotorBus`] backend.
//!
//! A backend provides a [`Harness`]: fresh buses on the same hardware, the motors that
//! are present, an id nobody answers to, and a sniffer of the frames the host sent. The
//! checks are plain functions returning [`Failure`]s; [`run_all`] runs them all and
//! [`motor_bus_conformance!`](crate::motor_bus_conformance) turns them into one `#[test]`
//! each. `SimBus` runs them in CI; on a machine with CAN, a SocketCAN harness (a second
//! socket per interface as the sniffer) runs the same checks against real motors.
//!
//! # Tolerance of the PD hold check
//! Holding `q0` with stiffness `kp` against an unknown constant load `τ_load` settles at
//! `q0 + τ_load / kp`. The harness states the largest load it expects, and the check
//! allows `|τ_load|max / kp` plus quantization: half a `q_des` step (0.19 mrad), half a
//! reply step (0.19 mrad) and one encoder count at the joint (0.02 mrad), rounded up to
//! 1 mrad in total for noise.

use crate::a1::{self, Command, Frame, FrameKind, Reply, Special};
use crate::bus::{BusError, Lifecycle, MotorBus, MotorSpec};
use core::time::Duration;
use thiserror::Error;

/// What a backend provides to the suite.
pub trait Harness {
    /// The backend under test.
    type Bus: MotorBus;
    /// A fresh, unconfigured bus on the hardware (the previous one has been dropped).
    fn new_bus(&mut self) -> Self::Bus;
    /// Motors present and answering (at least one).
    fn motors(&self) -> Vec<MotorSpec>;
    /// A motor spec on a real bus whose id no motor answers to.
    fn absent_motor(&self) -> MotorSpec;
    /// Host → motor frames seen on the wire since the last call.
    fn take_sent_frames(&mut self) -> Vec<Frame>;
    /// Budget of one exchange (the control period).
    fn budget(&self) -> Duration;
    /// Parameters of the PD hold check.
    fn hold(&self) -> HoldCheck;
}

/// How to check that PD holds a position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldCheck {
    /// Stiffness \[N·m/rad\].
    pub kp_nm_per_rad: f64,
    /// Damping \[N·m·s/rad\].
    pub kd_nm_s_per_rad: f64,
    /// Largest constant external torque on any joint \[N·m\].
    pub max_load_nm: f64,
    /// Cycles to hold (long enough to settle).
    pub cycles: usize,
}

/// A failed conformance check.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("conformance check `{check}` failed: {detail}")]
pub struct Failure {
    /// Check name.
    pub check: &'static str,
    /// What went wrong.
    pub detail: String,
}

type Check = Result<(), Failure>;

fn fail(check: &'static str, detail: impl Into<String>) -> Failure {
    Failure {
        check,
        detail: detail.into(),
    }
}

fn expect<T: core::fmt::Debug>(
    check: &'static str,
    what: &str,
    got: Result<T, BusError>,
    want: impl Fn(&Result<T, BusError>) -> bool,
) -> Check {
    if want(&got) {
        Ok(())
    } else {
        Err(fail(check, format!("{what}: got {got:?}")))
    }
}

fn damping_commands(motors: &[MotorSpec]) -> Vec<Command> {
    motors.iter().map(|m| Command::damping(m.id, 1.0)).collect()
}

fn replies_for(commands: &[Command]) -> Vec<Reply> {
    commands.iter().map(|c| Reply::zeroed(c.motor)).collect()
}

/// Calls in the wrong state are refused with typed errors; the state machine moves only
/// along configure → activate → deactivate.
pub fn lifecycle_order_is_enforced<H: Harness>(h: &mut H) -> Check {
    const C: &str = "lifecycle_order_is_enforced";
    let motors = h.motors();
    let mut bus = h.new_bus();
    if bus.state() != Lifecycle::Unconfigured {
        return Err(fail(C, format!("new bus is {:?}", bus.state())));
    }
    let wrong = |r: &Result<(), BusError>| matches!(r, Err(BusError::WrongState { .. }));
    expect(C, "activate before configure", bus.activate(), wrong)?;
    expect(C, "deactivate before configure", bus.deactivate(), wrong)?;
    expect(C, "configure", bus.configure(&motors), Result::is_ok)?;
    expect(C, "configure again", bus.configure(&motors), Result::is_ok)?;
    expect(C, "activate", bus.activate(), Result::is_ok)?;
    if bus.state() != Lifecycle::Active {
        return Err(fail(C, format!("after activate: {:?}", bus.state())));
    }
    expect(C, "activate twice", bus.activate(), wrong)?;
    expect(C, "configure while active", bus.configure(&motors), wrong)?;
    expect(C, "deactivate", bus.deactivate(), Result::is_ok)?;
    if bus.state() != Lifecycle::Configured {
        return Err(fail(C, format!("after deactivate: {:?}", bus.state())));
    }
    expect(C, "re-activate", bus.activate(), Result::is_ok)?;
    expect(C, "deactivate", bus.deactivate(), Result::is_ok)
}

/// `exchange` before `activate` (and after `deactivate`) is `NotActive` and sends nothing.
pub fn exchange_requires_active<H: Harness>(h: &mut H) -> Check {
    const C: &str = "exchange_requires_active";
    let motors = h.motors();
    let budget = h.budget();
    let commands = damping_commands(&motors);
    let mut replies = replies_for(&commands);
    let mut bus = h.new_bus();
    let not_active = |r: &Result<_, BusError>| matches!(r, Err(BusError::NotActive { .. }));
    let _ = h.take_sent_frames();
    expect(
        C,
        "unconfigured",
        bus.exchange(&commands, &mut replies, budget),
        not_active,
    )?;
    expect(C, "configure", bus.configure(&motors), Result::is_ok)?;
    expect(
        C,
        "configured",
        bus.exchange(&commands, &mut replies, budget),
        not_active,
    )?;
    let sent = h.take_sent_frames();
    if !sent.is_empty() {
        return Err(fail(C, format!("frames sent while not active: {sent:?}")));
    }
    expect(C, "activate", bus.activate(), Result::is_ok)?;
    expect(C, "deactivate", bus.deactivate(), Result::is_ok)?;
    expect(
        C,
        "after deactivate",
        bus.exchange(&commands, &mut replies, budget),
        not_active,
    )
}

fn check_disabled_after(check: &'static str, motors: &[MotorSpec], frames: &[Frame]) -> Check {
    for m in motors {
        let last = frames.iter().rev().find(
            |f| matches!(a1::classify(f.id), Some((k, id)) if id == m.id && k != FrameKind::Reply),
        );
        let disabled = last.is_some_and(|f| {
            matches!(a1::decode_special(f.id, &f.data), Ok((_, Special::Disable)))
                || matches!(a1::decode_command(f.id, &f.data), Ok(c) if c.mode == a1::Mode::Damping)
        });
        if !disabled {
            return Err(fail(
                check,
                format!("last frame to {} is {last:?}, not disable/damping", m.id),
            ));
        }
    }
    Ok(())
}

fn run_pd_cycles<B: MotorBus>(
    bus: &mut B,
    motors: &[MotorSpec],
    budget: Duration,
) -> Result<(), BusError> {
    let commands: Vec<_> = motors
        .iter()
        .map(|m| Command::pd(m.id, 0.0, 0.0, 5.0, 0.5, 0.0))
        .collect();
    let mut replies = replies_for(&commands);
    for _ in 0..5 {
        bus.exchange(&commands, &mut replies, budget)?;
    }
    Ok(())
}

/// `deactivate` leaves every configured motor in damping: the last frame each motor
/// received is *disable* (or a damping command).
pub fn deactivate_sends_damping<H: Harness>(h: &mut H) -> Check {
    const C: &str = "deactivate_sends_damping";
    let motors = h.motors();
    let budget = h.budget();
    let mut bus = h.new_bus();
    expect(C, "configure", bus.configure(&motors), Result::is_ok)?;
    expect(C, "activate", bus.activate(), Result::is_ok)?;
    expect(
        C,
        "PD cycles",
        run_pd_cycles(&mut bus, &motors, budget),
        Result::is_ok,
    )?;
    expect(C, "deactivate", bus.deactivate(), Result::is_ok)?;
    check_disabled_after(C, &motors, &h.take_sent_frames())
}

/// Dropping an active bus leaves every motor in damping.
pub fn drop_sends_damping<H: Harness>(h: &mut H) -> Check {
    const C: &str = "drop_sends_damping";
    let motors = h.motors();
    let budget = h.budget();
    let mut bus = h.new_bus();
    expect(C, "configure", bus.configure(&motors), Result::is_ok)?;
    expect(C, "activate", bus.activate(), Result::is_ok)?;
    expect(
        C,
        "PD cycles",
        run_pd_cycles(&mut bus, &motors, budget),
        Result::is_ok,
    )?;
    drop(bus);
    check_disabled_after(C, &motors, &h.take_sent_frames())
}

/// `replies[i]` is the reply of `commands[i].motor`, whatever the order or subset.
pub fn replies_match_commanded_motors<H: Harness>(h: &mut H) -> Check {
    const C: &str = "replies_match_commanded_motors";
    let motors = h.motors();
    let budget = h.budget();
    let mut bus = h.new_bus();
    expect(C, "configure", bus.configure(&motors), Result::is_ok)?;
    expect(C, "activate", bus.activate(), Result::is_ok)?;
    let mut reversed = damping_commands(&motors);
    reversed.reverse();
    let subset: Vec<_> = reversed.iter().step_by(2).copied().collect();
    for commands in [reversed, subset] {
        // Poison the slots with an id nobody has so stale data cannot pass.
        let absent = h.absent_motor().id;
        let mut replies = vec![Reply::zeroed(absent); commands.len() + 1];
        expect(
            C,
            "exchange",
            bus.exchange(&commands, &mut replies, budget),
            Result::is_ok,
        )?;
        for (c, r) in commands.iter().zip(&replies) {
            if c.motor != r.motor || !r.enabled {
                return Err(fail(C, format!("command to {} got reply {r:?}", c.motor)));
            }
        }
        if replies[commands.len()].motor != absent {
            return Err(fail(C, "slot past the commands was written"));
        }
    }
    expect(C, "deactivate", bus.deactivate(), Result::is_ok)
}

/// A configured motor that does not answer is named in `MissingReply`, and a failed
/// `activate` leaves the bus configured, not active.
pub fn silent_motor_is_named<H: Harness>(h: &mut H) -> Check {
    const C: &str = "silent_motor_is_named";
    let mut motors = h.motors();
    let absent = h.absent_motor();
    motors.push(absent);
    let mut bus = h.new_bus();
    expect(C, "configure", bus.configure(&motors), Result::is_ok)?;
    let got = bus.activate();
    if got
        != Err(BusError::MissingReply {
            motor: absent.id,
            bus: absent.bus,
        })
    {
        return Err(fail(
            C,
            format!("activate: got {got:?}, want MissingReply({absent:?})"),
        ));
    }
    if bus.state() != Lifecycle::Configured {
        return Err(fail(C, format!("after failed activate: {:?}", bus.state())));
    }
    check_disabled_after(C, &h.motors(), &h.take_sent_frames())
}

/// PD at the present position holds it within `max_load / kp` + 1 mrad (module docs).
pub fn pd_holds_position<H: Harness>(h: &mut H) -> Check {
    const C: &str = "pd_holds_position";
    let motors = h.motors();
    let budget = h.budget();
    let hold = h.hold();
    let mut bus = h.new_bus();
    expect(C, "configure", bus.configure(&motors), Result::is_ok)?;
    expect(C, "activate", bus.activate(), Result::is_ok)?;
    let commands = damping_commands(&motors);
    let mut start = replies_for(&commands);
    expect(
        C,
        "read start",
        bus.exchange(&commands, &mut start, budget),
        Result::is_ok,
    )?;
    let commands: Vec<_> = start
        .iter()
        .map(|r| {
            Command::pd(
                r.motor,
                r.q_rad,
                0.0,
                hold.kp_nm_per_rad,
                hold.kd_nm_s_per_rad,
                0.0,
            )
        })
        .collect();
    let mut replies = replies_for(&commands);
    for _ in 0..hold.cycles {
        expect(
            C,
            "hold",
            bus.exchange(&commands, &mut replies, budget),
            Result::is_ok,
        )?;
    }
    let tolerance = hold.max_load_nm / hold.kp_nm_per_rad + 1e-3;
    for (s, r) in start.iter().zip(&replies) {
        let error = (r.q_rad - s.q_rad).abs();
        if error > tolerance {
            return Err(fail(
                C,
                format!("{} drifted {error:.5} rad > {tolerance:.5} rad", r.motor),
            ));
        }
    }
    expect(C, "deactivate", bus.deactivate(), Result::is_ok)
}

/// Run every check; the failures (empty = conformant).
pub fn run_all<H: Harness>(h: &mut H) -> Vec<Failure> {
    let checks: [fn(&mut H) -> Check; 7] = [
        lifecycle_order_is_enforced,
        exchange_requires_active,
        deactivate_sends_damping,
        drop_sends_damping,
        replies_match_commanded_motors,
        silent_motor_is_named,
        pd_holds_position,
    ];
    checks.iter().filter_map(|check| check(h).err()).collect()
}

/// One `#[test]` per conformance check, for a harness built by `$make`.
///
/// ```ignore
/// drivers::motor_bus_conformance!(sim_conformance, || my_harness());
/// ```
#[macro_export]
macro_rules! motor_bus_conformance {
    ($module:ident, $make:expr) => {
        mod $module {
            #[allow(unused_imports)]
            use super::*;
            $crate::motor_bus_conformance!(@tests $make;
                lifecycle_order_is_enforced, exchange_requires_active, deactivate_sends_damping,
                drop_sends_damping, replies_match_commanded_motors, silent_motor_is_named,
                pd_holds_position);
        }
    };
    (@tests $make:expr; $($check:ident),*) => {
        $(
            #[test]
            fn $check() {
                let mut harness = ($make)();
                if let Err(failure) = $crate::conformance::$check(&mut harness) {
                    panic!("{failure}");
                }
            }
        )*
    };
}
