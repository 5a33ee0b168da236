//! `adam emulate motors`: the simulated ADAM served over CAN-over-UDP to another process, so
//! that the runtime drives it through a real socket ([`crate::udp`], `adam run --backend udp`).
//!
//! ```text
//! SimBus<RobotSim> (sim_backend: the robot `adam run --backend sim` walks, same seed, belt)
//!   └─ drivers::udp::serve::MotorServer on one UDP socket per bus (listen port + k)
//!        host's command packets ─▶ A1 firmware ─▶ reply packets (+ the IMU after each period)
//! ```
//! Time is lockstep: one control period per commanded period ([`drivers::udp::serve`]), so the
//! robot walks the physics of the in-process simulator whatever the wall clock does. The
//! emulator ends when the host has disabled every motor it enabled (its run is over), unless
//! asked to keep serving, or when no packet came for [`EmulateOptions::idle_exit_s`] after
//! the first; then it reports what the simulated robot did ([`EmulatorReport`]).

use crate::sim::run::{sim_backend, SimWalkOptions};
use crate::{Result, RuntimeError, Setup};
use core::time::Duration;
use drivers::sim::robot::{FallCause, SimEvent};
use drivers::udp::serve::{MotorServer, ServerStats};
use std::net::SocketAddr;
use std::time::Instant;

/// How to emulate.
#[derive(Clone, Debug)]
pub struct EmulateOptions {
    /// The simulated robot: belt speed, start (walking or standing), seed, IMU noise
    /// (`duration_s` is not used).
    pub robot: SimWalkOptions,
    /// Bus 0's address; bus `k` listens at its port + `k`.
    pub listen: SocketAddr,
    /// Serve on after a host's run ends (until idle).
    pub keep_serving: bool,
    /// Stop when no packet came for this long after the first, s (infinite: never).
    pub idle_exit_s: f64,
}

/// What the emulated robot did.
#[derive(Clone, Debug, PartialEq)]
pub struct EmulatorReport {
    /// Control periods simulated.
    pub periods: u64,
    /// Simulated time, s.
    pub sim_time_s: f64,
    /// Steps: touchdowns of alternating feet, before any fall.
    pub steps: usize,
    /// Mean step length before any fall, m (NaN without steps).
    pub mean_step_length_m: f64,
    /// The fall, if any: time, s, and cause.
    pub fall: Option<(f64, FallCause)>,
    /// The hip's position on the belt at the end (or the fall), forward of its centre, m.
    pub position_on_belt_m: f64,
    /// What the server saw on the links.
    pub link: ServerStats,
    /// Why it stopped.
    pub ended: &'static str,
}

impl std::fmt::Display for EmulatorReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "emulated {} control periods ({:.3} s simulated); ended: {}",
            self.periods, self.sim_time_s, self.ended
        )?;
        if self.steps > 0 {
            write!(
                f,
                "steps {} (mean length {:.4} m)",
                self.steps, self.mean_step_length_m
            )?;
        } else {
            write!(f, "steps 0")?;
        }
        writeln!(
            f,
            "; position on the belt {:+.3} m",
            self.position_on_belt_m
        )?;
        match self.fall {
            Some((t, what)) => writeln!(f, "fall: {what} at {t:.3} s")?,
            None => writeln!(f, "fall: none")?,
        }
        let l = &self.link;
        write!(
            f,
            "link: {} packets in, {} out; dropped: {} from unexpected senders, {} malformed; {} foreign frames ignored",
            l.packets_received, l.packets_sent, l.foreign_sender, l.malformed, l.foreign_frames
        )
    }
}

/// Bind the sockets and serve until the host's run ends (or idle); `ready` gets bus 0's
/// address once the sockets listen.
pub fn serve(
    setup: &Setup,
    options: &EmulateOptions,
    ready: impl FnOnce(SocketAddr),
) -> Result<EmulatorReport> {
    let sim = sim_backend(setup, &options.robot)?;
    let bus_count = setup.config.loop_.bus_count;
    let sockets = MotorServer::<drivers::sim::robot::RobotSim>::bind(options.listen, bus_count)
        .map_err(|e| RuntimeError::InvalidField {
            origin: "adam emulate motors".into(),
            field: "--listen".into(),
            value: options.listen.to_string(),
            reason: format!("cannot bind {bus_count} UDP ports from it (one per bus): {e}"),
        })?;
    let mut server = MotorServer::new(sim, sockets).map_err(|e| RuntimeError::Thread {
        name: "emulator",
        message: e.to_string(),
    })?;
    ready(server.local_addr(0).unwrap_or(options.listen));
    let mut last_packet: Option<Instant> = None;
    let ended = loop {
        let handled = server
            .poll(Duration::from_micros(50))
            .map_err(|e| RuntimeError::Thread {
                name: "emulator",
                message: format!("UDP: {e}"),
            })?;
        if handled > 0 {
            last_packet = Some(Instant::now());
        }
        if !options.keep_serving && server.session_over() {
            break "the host disabled every motor";
        }
        if let Some(at) = last_packet {
            if at.elapsed().as_secs_f64() > options.idle_exit_s {
                break "no packet for the idle time";
            }
        }
    };
    let bus = server.sim();
    let plant = bus.plant();
    let fall = plant.fall_record().map(|f| (f.t_s, f.what));
    let fall_t = fall.map_or(f64::INFINITY, |(t, _)| t);
    let mut steps = 0;
    let mut length_sum_m = 0.0;
    let mut last_side = None;
    for event in plant.events() {
        if let SimEvent::Touchdown(td) = event {
            if td.t_s < fall_t && last_side != Some(td.side) {
                steps += 1;
                length_sum_m += td.step_length_m;
                last_side = Some(td.side);
            }
        }
    }
    Ok(EmulatorReport {
        periods: server.stats().periods,
        sim_time_s: bus.time_s(),
        steps,
        mean_step_length_m: length_sum_m / steps as f64,
        fall,
        position_on_belt_m: plant
            .fall_record()
            .map_or(plant.position_on_belt_m(), |f| f.position_on_belt_m),
        link: server.stats(),
        ended,
    })
}
