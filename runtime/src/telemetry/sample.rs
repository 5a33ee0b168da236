//! The per-tick state sample: a fixed-size `#[repr(C)]` record built after every tick, published
//! zero-copy over iceoryx2 (feature `iceoryx2`, on by default) and queued to the MCAP logger.

use crate::control::{ControlState, JointCommand, TickInput, TickOutput};
use crate::slots::{OUTPUTS, SLOTS};
use crate::{Result, RuntimeError};
#[cfg(feature = "iceoryx2")]
use iceoryx2::prelude::ZeroCopySend;
use model::Side;

/// Everything about one tick, plain old data (no pointers), identical in every process.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "iceoryx2", derive(ZeroCopySend))]
#[repr(C)]
pub struct StateSample {
    /// Tick counter.
    pub tick: u64,
    /// Controller time, s.
    pub t_s: f64,
    /// [`ControlState`] as `u32`.
    pub state: u32,
    /// Stance leg: 0 left, 1 right.
    pub stance: u32,
    /// [`crate::safety::Trip::code`] of the latched trip, 0 if none.
    pub trip_code: u32,
    /// Motor slots with a reply this tick (bit per slot).
    pub fresh_mask: u32,
    /// Completed steps.
    pub steps: u32,
    /// Relaunches after a stalled step ([`crate::control::Status::recoveries`]).
    pub recoveries: u32,
    /// Step-back catches ([`crate::control::Status::catches`]).
    pub catches: u32,
    /// Consecutive overruns.
    pub overrun_streak: u32,
    /// Total overruns.
    pub overruns: u64,
    /// Compute time of the controller tick, ns.
    pub tick_compute_ns: u64,
    /// Phase τ.
    pub phase: f64,
    /// τ̇, 1/s.
    pub phase_rate_per_s: f64,
    /// Measured position per slot (motor side), rad.
    pub q_rad: [f64; SLOTS],
    /// Measured velocity per slot, rad/s.
    pub dq_rad_s: [f64; SLOTS],
    /// Measured torque per slot, N·m.
    pub tau_nm: [f64; SLOTS],
    /// Winding temperature per slot, °C.
    pub temperature_c: [f64; SLOTS],
    /// Commanded position per slot, rad.
    pub q_cmd_rad: [f64; SLOTS],
    /// Commanded velocity per slot, rad/s.
    pub dq_cmd_rad_s: [f64; SLOTS],
    /// Torque the command asks for at the measured state, N·m.
    pub tau_cmd_nm: [f64; SLOTS],
    /// Desired outputs y^d, rad.
    pub y_des_rad: [f64; OUTPUTS],
    /// ẏ^d, rad/s.
    pub dy_des_rad_s: [f64; OUTPUTS],
    /// Actual outputs y^a, rad.
    pub y_act_rad: [f64; OUTPUTS],
    /// Swing foot height above the stance foot, m (NaN outside Walk).
    pub swing_foot_height_m: f64,
    /// Estimated torso pitch, rad.
    pub pitch_rad: f64,
    /// Bias-corrected pitch rate, rad/s.
    pub pitch_rate_rad_s: f64,
    /// Gyro bias estimate, rad/s.
    pub gyro_bias_rad_s: f64,
    /// Raw gyro pitch rate, rad/s (NaN when no sample this tick).
    pub imu_gyro_rad_s: f64,
    /// Raw accelerometer x, m/s².
    pub imu_accel_x_mps2: f64,
    /// Raw accelerometer z, m/s².
    pub imu_accel_z_mps2: f64,
    /// The simulator's true torso pitch, rad (NaN on hardware): the live view's second tree.
    pub true_pitch_rad: f64,
    /// The simulator's true position on the belt, + forward of its centre, m (NaN on hardware).
    pub true_belt_position_m: f64,
}

impl Default for StateSample {
    fn default() -> Self {
        Self {
            tick: 0,
            t_s: 0.0,
            state: 0,
            stance: 0,
            trip_code: 0,
            fresh_mask: 0,
            steps: 0,
            recoveries: 0,
            catches: 0,
            overrun_streak: 0,
            overruns: 0,
            tick_compute_ns: 0,
            phase: 0.0,
            phase_rate_per_s: 0.0,
            q_rad: [0.0; SLOTS],
            dq_rad_s: [0.0; SLOTS],
            tau_nm: [0.0; SLOTS],
            temperature_c: [0.0; SLOTS],
            q_cmd_rad: [0.0; SLOTS],
            dq_cmd_rad_s: [0.0; SLOTS],
            tau_cmd_nm: [0.0; SLOTS],
            y_des_rad: [0.0; OUTPUTS],
            dy_des_rad_s: [0.0; OUTPUTS],
            y_act_rad: [0.0; OUTPUTS],
            swing_foot_height_m: 0.0,
            pitch_rad: 0.0,
            pitch_rate_rad_s: 0.0,
            gyro_bias_rad_s: 0.0,
            imu_gyro_rad_s: 0.0,
            imu_accel_x_mps2: 0.0,
            imu_accel_z_mps2: 0.0,
            true_pitch_rad: f64::NAN,
            true_belt_position_m: f64::NAN,
        }
    }
}

/// Loop bookkeeping that goes into a sample besides the controller's input and output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoopStats {
    /// Tick counter.
    pub tick: u64,
    /// Total overruns.
    pub overruns: u64,
    /// Compute time of the tick, ns.
    pub tick_compute_ns: u64,
}

impl StateSample {
    /// Fill `self` from one tick (no allocation).
    pub fn fill(&mut self, input: &TickInput, output: &TickOutput, stats: LoopStats) {
        let s = &output.status;
        self.tick = stats.tick;
        self.t_s = input.t_s;
        self.state = s.state as u32;
        self.stance = match s.stance {
            Side::Left => 0,
            Side::Right => 1,
        };
        self.trip_code = s.trip.map_or(0, |t| t.code());
        self.steps = s.steps;
        self.recoveries = s.recoveries;
        self.catches = s.catches;
        self.overrun_streak = input.overrun_streak;
        self.overruns = stats.overruns;
        self.tick_compute_ns = stats.tick_compute_ns;
        self.phase = s.phase;
        self.phase_rate_per_s = s.phase_rate_per_s;
        self.fresh_mask = 0;
        for (slot, m) in input.motors.iter().enumerate() {
            if m.fresh {
                self.fresh_mask |= 1 << slot;
            }
            let c: &JointCommand = &output.commands[slot];
            self.q_rad[slot] = m.q_rad;
            self.dq_rad_s[slot] = m.dq_rad_s;
            self.tau_nm[slot] = m.tau_nm;
            self.temperature_c[slot] = m.temperature_c;
            self.q_cmd_rad[slot] = c.q_des_rad;
            self.dq_cmd_rad_s[slot] = c.dq_des_rad_s;
            self.tau_cmd_nm[slot] = c.torque_at(m.q_rad, m.dq_rad_s);
        }
        self.y_des_rad = s.y_des_rad;
        self.dy_des_rad_s = s.dy_des_rad_s;
        self.y_act_rad = s.y_act_rad;
        self.swing_foot_height_m = s.swing_foot_height_m;
        self.pitch_rad = s.pitch_rad;
        self.pitch_rate_rad_s = s.pitch_rate_rad_s;
        self.gyro_bias_rad_s = s.gyro_bias_rad_s;
        let (g, ax, az) = input.imu.map_or((f64::NAN, f64::NAN, f64::NAN), |i| {
            (i.gyro_pitch_rad_s, i.accel_x_mps2, i.accel_z_mps2)
        });
        self.imu_gyro_rad_s = g;
        self.imu_accel_x_mps2 = ax;
        self.imu_accel_z_mps2 = az;
    }

    /// The control state.
    pub fn control_state(&self) -> ControlState {
        match self.state {
            1 => ControlState::Ramp,
            2 => ControlState::Stand,
            3 => ControlState::Walk,
            4 => ControlState::Stop,
            5 => ControlState::Damping,
            _ => ControlState::Idle,
        }
    }
}

/// A node of this process, with iceoryx2's own logging quieted first (once).
///
/// iceoryx2 looks for its config file (`iceoryx2.toml`, see its docs) and, finding none, warns
/// on stderr at every start that it uses its defaults: that is our normal case, not something a
/// user must act on. Its log level is therefore set to `error` unless the environment variable
/// `IOX2_LOG_LEVEL` asks for another (iceoryx2's own switch); a config file, if present, is
/// still loaded.
#[cfg(feature = "iceoryx2")]
pub fn iceoryx2_node() -> std::result::Result<
    iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
    iceoryx2::node::NodeCreationFailure,
> {
    static QUIET: std::sync::Once = std::sync::Once::new();
    QUIET.call_once(|| {
        iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error)
    });
    iceoryx2::prelude::NodeBuilder::new().create::<iceoryx2::prelude::ipc::Service>()
}

/// The state service of the loop's samples (an iceoryx2 publish-subscribe port factory).
#[cfg(feature = "iceoryx2")]
pub type StateService = iceoryx2::service::port_factory::publish_subscribe::PortFactory<
    iceoryx2::prelude::ipc::Service,
    StateSample,
    (),
>;

/// A telemetry error of the service `name`.
pub fn telemetry_error(name: &str, message: String) -> RuntimeError {
    RuntimeError::Telemetry {
        service: name.to_string(),
        message,
    }
}

/// Opens the state service `name`, or creates it if neither the loop nor a viewer has yet
/// (both ask for [`SUBSCRIBER_BUFFER`]): the node that owns it, and the service. Keep the node
/// alive as long as the service, and both longer than their ports.
#[cfg(feature = "iceoryx2")]
pub fn open_state_service(
    name: &str,
) -> Result<(
    iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
    StateService,
)> {
    use iceoryx2::prelude::*;
    let node =
        iceoryx2_node().map_err(|e| telemetry_error(name, format!("cannot create a node: {e}")))?;
    let service_name: ServiceName = name
        .try_into()
        .map_err(|e| telemetry_error(name, format!("not a valid service name: {e}")))?;
    let service = node
        .service_builder(&service_name)
        .publish_subscribe::<StateSample>()
        .subscriber_max_buffer_size(SUBSCRIBER_BUFFER)
        .open_or_create()
        .map_err(|e| telemetry_error(name, format!("cannot open the service: {e}")))?;
    Ok((node, service))
}

/// Samples a subscriber of the state service may hold before the oldest is overwritten (the
/// publisher never waits): 0.5 s at 1 kHz. Publisher and subscribers ask for the same, so
/// whichever starts first creates a service the other can open.
pub const SUBSCRIBER_BUFFER: usize = 512;

/// Publishes a [`StateSample`] every tick over iceoryx2 (zero-copy shared memory).
///
/// iceoryx2 ports are not `Send`: create the publisher on the thread that uses it (the loop
/// does so on its control thread).
#[cfg(feature = "iceoryx2")]
pub struct Publisher {
    // Field order = drop order: the port before its service before its node.
    publisher:
        iceoryx2::port::publisher::Publisher<iceoryx2::prelude::ipc::Service, StateSample, ()>,
    _service: StateService,
    _node: iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
    failures: u64,
}

#[cfg(feature = "iceoryx2")]
impl Publisher {
    /// Open or create the service `name` and a publisher on it.
    pub fn new(name: &str) -> Result<Self> {
        let (node, service) = open_state_service(name)?;
        let publisher = service
            .publisher_builder()
            .create()
            .map_err(|e| telemetry_error(name, format!("cannot create a publisher: {e}")))?;
        Ok(Self {
            publisher,
            _service: service,
            _node: node,
            failures: 0,
        })
    }

    /// Publish one sample; a failure is counted, never propagated (telemetry must not stop
    /// the robot).
    pub fn publish(&mut self, sample: &StateSample) {
        let sent = self
            .publisher
            .loan_uninit()
            .map(|s| s.write_payload(*sample))
            .map(|s| s.send().is_ok());
        if !matches!(sent, Ok(true)) {
            self.failures += 1;
        }
    }

    /// Samples that could not be published.
    pub fn failures(&self) -> u64 {
        self.failures
    }
}

#[cfg(test)]
#[cfg(feature = "iceoryx2")]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use iceoryx2::prelude::*;

    #[test]
    fn a_sample_published_is_received_bit_identical() {
        // Unique name per run and process, so parallel or stale runs never meet.
        let name = format!(
            "adam/runtime/test/{}/{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos()
        );
        let mut publisher = Publisher::new(&name).unwrap();
        let node = NodeBuilder::new().create::<ipc::Service>().unwrap();
        let service_name: ServiceName = name.as_str().try_into().unwrap();
        let service = node
            .service_builder(&service_name)
            .publish_subscribe::<StateSample>()
            .open_or_create()
            .unwrap();
        let subscriber = service.subscriber_builder().create().unwrap();
        let mut sample = StateSample {
            tick: 42,
            t_s: 0.042,
            state: ControlState::Walk as u32,
            phase: 0.37,
            true_pitch_rad: 0.01,
            true_belt_position_m: -0.1,
            ..StateSample::default()
        };
        sample.q_rad[3] = 1.25;
        sample.y_des_rad[2] = -0.5;
        publisher.publish(&sample);
        let got = subscriber.receive().unwrap().unwrap();
        assert_eq!(*got.payload(), sample);
        assert_eq!(publisher.failures(), 0);
        drop(got);
        drop(subscriber);
        drop(service);
        drop(node);
        drop(publisher);
        // Clean up: the service is gone once the last port and node are dropped.
        let exists = ipc::Service::does_exist(
            &service_name,
            Config::global_config(),
            MessagingPattern::PublishSubscribe,
        )
        .unwrap();
        assert!(!exists, "service {name} left behind");
    }
}
