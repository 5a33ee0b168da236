//! `drivers::sim::robot`: the rigid-body plant, the planar ADAM on a treadmill, with an optional
//! boom, as a [`JointPlant`].
//!
//! [`RobotSim`] simulates any [`PlanarModel`] that follows the biped naming convention (any
//! co-designed leg lengths). Put it behind [`crate::sim::bus::SimBus`] and the controller talks to
//! the whole robot through real CAN frames and simulated A1 firmware.
//!
//! # Model
//! * **Floating base** `q = [x, z, pitch, joints…]` with the model's own `D(q)`, `H(q, q̇)`. The
//!   design joints are rigid: their rows and columns are dropped (exactly the model's `q̈_D = 0`).
//! * **Actuators**: each joint's drive from the URDF ([`model::JointDrive`]) is in the model's
//!   `D` and `H` (`PlanarModel::dynamics_into`): the A1 rotors' armature N² J_rotor on the
//!   joint's diagonal of `D` (so the plastic impacts see it too) and the viscous friction b q̇ in
//!   `H`, exactly as the planner and the Poincaré check see them. A URDF without them simulates
//!   the rigid-body robot.
//! * **Treadmill.** The belt is a moving ground of a given length (`belt_length_m`, default
//!   1.6 m) under the robot, which starts at its centre; its surface moves backwards at the belt
//!   speed, stepped ([`RobotSim::set_belt_speed`]) or ramped toward a target at a set
//!   acceleration ([`RobotSim::set_belt_target_speed`], `belt_acceleration_mps2`, default
//!   0.5 m/s²). A stance foot is pinned to the belt, so it acts on the robot through the contact
//!   (friction with a moving surface: the contact's tangential velocity is relative to the
//!   belt). The equations are integrated in the frame of the belt's surface, where a stance foot
//!   is still; while the belt ramps that frame accelerates and every body feels the inertial
//!   force `m·a_belt`, applied exactly (the x column of `D`; `robot/belt.rs`). Everything
//!   reported is in the world: positions add the belt's travel, velocities subtract its speed,
//!   [`RobotSim::position_on_belt_m`] is the hip's distance forward of the belt's centre, and a
//!   stance foot beyond either end is a fall ([`FallCause::OffBelt`]).
//! * **Boom** (optional, off by default: the paper did not model it): extra mass and pitch
//!   inertia rigidly added to the torso ([`Boom`]). The boom's constraint to the sagittal plane is
//!   implicit (the model is planar).
//! * **Point feet, rigid unilateral contact, infinite friction for the dynamics.** Each foot is
//!   in the air or in stance, pinned to an anchor on the ground:
//!   - stance: `D q̈ + H = B u + Jᵀλ` with `J q̈ = −J̇ q̇` for every stance foot (one or both);
//!     a stance foot whose normal force would be negative is released (most negative first, then
//!     re-solved): a [`SimEvent::Liftoff`];
//!   - friction is *reported, not simulated*: when `|F_x| > μ F_z` a
//!     [`SimEvent::FrictionExceeded`] is recorded (edge-triggered) and the foot stays pinned;
//!   - touchdown: a free foot that crosses `z = 0` moving down within a step is located by linear
//!     interpolation of the step, the state is rolled back to that instant, a rigid **plastic**
//!     impact is applied with the touching foot (and the other foot, if in stance) pinned — an
//!     old stance foot whose impulse would pull the ground is released — and the rest of the step
//!     is integrated: a [`SimEvent::Touchdown`] with the kinetic energy before and after;
//!   - no contact of other points with the ground, and joint limits are not enforced (no hard
//!     stops). A torso or knee reaching the ground is a fall ([`SimEvent::Fall`]); the simulation
//!     continues afterwards but is no longer physical: stop it.
//! * **Disturbances** (fault injection): [`RobotSim::push`] applies an external force at the
//!   hip axis for a while (a shove on the torso); [`RobotSim::set_belt_speed`] steps the belt
//!   speed: the stance foot, pinned to the belt, is jerked with it (an impulse through the
//!   stance contact, the plastic projection in the `D` metric); [`RobotSim::set_imu_fault`]
//!   drops, spikes or freezes the IMU output ([`ImuFault`]).
//! * **Integrator**: semi-implicit (symplectic) Euler at a fixed rate `rate_hz` (10 kHz by
//!   default, the A1 firmware rate); torques are held over a step. After each step the stance
//!   feet are projected back onto their anchors (position, then velocity, in the kinetic-energy
//!   metric) so the constraint drift does not accumulate.
//!
//! # Multi-rate dynamics
//! The motors' PD runs at 10 kHz (in [`crate::sim::bus::SimBus`], [`crate::sim::firmware`]) and so does the integrator,
//! but the rigid-body quantities change on a much slower time scale: the joints move a few
//! milliradians per millisecond. So `D(q)`, `H(q, q̇)`, the factor of `D`, the contact
//! operator (stance-foot Jacobian `J`, `D⁻¹Jᵀ`, the factored `J D⁻¹ Jᵀ`) and `J̇ q̇` are
//! evaluated at the start of a step and then **held for `dynamics_refresh_substeps` steps**
//! ([`RobotSimConfig`], default 10: 1 ms at 10 kHz, one control period). A held step only
//! applies the new torques: `q̈ = D⁻¹(Bu − H)` projected by the held contact operator, semi-
//! implicit Euler, the touchdown search and the stance projection with *exact* kinematics at the
//! new `q` (positions are never held; the penetration record, the fall check and the next
//! touchdown search use the poses from before the stance projection, which moves the robot by
//! nanometres, so a held step computes its kinematics once). The hold ends early, and the step is evaluated afresh, whenever the contact set may
//! change: at a touchdown, a liftoff, a belt step or `set_state`; in flight (no foot on the
//! ground: the motion is ballistic and a held `D` would not conserve momentum to the
//! integrator's order); and when a stance foot's normal force drops below 10 % of the robot's
//! weight (liftoff is decided on fresh dynamics). The impact map is always exact.
//!
//! Why the error is small: over a hold of `T` = 1 ms, `D` and `H` change by `O(T·|q̇|)` relative
//! to their size (≈ 0.5 % at 5 rad/s), the PD torques that dominate a walking step are applied
//! exactly every step, and positions are exact. `tests/sim_fidelity.rs` runs PD-held standing
//! and marching in place with touchdowns and liftoffs both ways, same seed, through the A1
//! firmware model: standing differs by < 1e-4° in the joints and < 1 µm at the torso; marching
//! by a few hundredths of a degree and a few tenths of a millimetre, the size of the exact
//! path's own change when its step is halved (a hybrid system's event times shift with any
//! perturbation). `dynamics_refresh_substeps: 1` is the exact path: everything re-evaluated
//! every step, which is the model above without the hold.
//!
//! # Guarantees (checked by tests)
//! * ground penetration of any foot ≤ [`PENETRATION_TOLERANCE_M`] (1 µm) until a fall;
//! * kinetic energy after every impact ≤ before (plastic impact = projection in the `D` metric);
//! * same inputs, same seed → bit-identical trajectories and IMU samples.
//!
//! # Cost
//! A step allocates nothing (only the event list, past its first 64 events): kinematics, `D`,
//! `H`, the contact solve, the projections and the event search use fixed-size arrays or
//! buffers sized at construction. The solver keeps explicit inverses of `D` (`L⁻ᵀL⁻¹` from its
//! Cholesky factor: `n` divisions) and of the contact Schur complement, so a held step is a few
//! short matrix-vector products; a step computes the poses alone, and `D`, `H` rotate each body
//! once. About 130 simulated seconds per second on one core, standing or marching in place,
//! when the shared 2-core VM leaves it undisturbed: the 100 wanted, with a margin (README,
//! "Status"; `tests/sim_speed.rs`). By `perf`, the rest goes to the A1 firmware ticks (13 %,
//! their Ziggurat noise included), the step's kinematics with its sines and cosines (about 15 %),
//! `D` and `H` (8 %), the contact projections (about 13 %) and the exact CAN frame timing (6 %).
//!
//! ```no_run
//! use drivers::sim::bus::{SimBus, SimConfig};
//! use drivers::sim::firmware::A1Model;
//! use drivers::sim::robot::{RobotSim, RobotSimConfig};
//! let (robot, _urdf) = model::design::generate_model(&model::design::DesignLengths::ADAM)?;
//! let sim = RobotSim::new(&robot, RobotSimConfig::default())?; // standing on both feet
//! let motors = sim.leg_motors(0, 1); // hip id 1, knee id 2 on bus 0; hip 3, knee 4 on bus 1
//! let config = SimConfig {
//!     control_rate_hz: 1000.0,
//!     bitrate_bps: 1_000_000,
//!     bus_count: 2,
//!     motors,
//!     model: A1Model::default(),
//!     seed: 1,
//! };
//! let bus = SimBus::new(config, sim)?; // a MotorBus; bus.plant() is the ground truth
//! println!("pitch {} rad", bus.plant().torso_pitch_rad());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod belt;
mod config;
mod events;
mod solver;
mod step;

pub use belt::BeltEnd;
pub use config::{
    standing_pose, Boom, RobotSimConfig, DEFAULT_BELT_ACCELERATION_MPS2, DEFAULT_BELT_LENGTH_M,
};
pub use events::{FallCause, FallRecord, SimEvent, Touchdown};

use crate::bus::MotorSpec;
use crate::imu::{Imu, ImuError, ImuFault, ImuNoise, ImuSample, NoisyImu};
use crate::sim::firmware::SimMotor;
use crate::sim::plant::JointPlant;
use belt::Belt;
use config::validate;
use model::kinematics::BodyStates;
use model::robot::{BodyInertia, Legs};
use model::{ModelError, PlanarModel, Side};
use solver::{Solver, MAX_CONTACTS};
use thiserror::Error;

/// Largest foot penetration the simulator allows itself \[m\].
pub const PENETRATION_TOLERANCE_M: f64 = 1e-6;

const SIDES: [Side; 2] = [Side::Left, Side::Right];

fn side_index(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

/// What can go wrong building or running a [`RobotSim`].
#[derive(Debug, Error)]
pub enum RobotSimError {
    /// A configuration value is out of range.
    #[error("robot sim config: {field} = {value} is invalid: {reason}")]
    Config {
        /// Field name.
        field: &'static str,
        /// Value found.
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// The model could not be evaluated (or lacks the biped names).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A vector has the wrong length.
    #[error("{what}: expected length {expected}, found {found}")]
    Dimension {
        /// Which vector.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Length found.
        found: usize,
    },
    /// A state puts a foot below the ground.
    #[error("{} foot is {depth_m} m below the ground", side.prefix())]
    Penetration {
        /// Which foot.
        side: Side,
        /// How deep \[m\].
        depth_m: f64,
    },
    /// The mass matrix was not positive definite (a massless chain or a non-finite state).
    #[error("mass matrix not positive definite at t = {t_s} s")]
    NotPositiveDefinite {
        /// Simulated time \[s\].
        t_s: f64,
    },
    /// An earlier step failed; the simulation is frozen.
    #[error("simulation faulted at t = {t_s} s and is frozen")]
    Faulted {
        /// Time of the fault \[s\].
        t_s: f64,
    },
}

/// Result alias of the simulator.
pub type Result<T, E = RobotSimError> = core::result::Result<T, E>;

/// Contact state of one foot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Contact {
    /// Not touching the ground.
    Air,
    /// Pinned to a ground point (belt frame, x and z) \[m\].
    Stance {
        /// The anchor in the belt frame \[m\].
        anchor_xz_m: [f64; 2],
    },
}

/// Which joint of a leg.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LegJoint {
    /// Hip pitch.
    Hip,
    /// Knee pitch.
    Knee,
}

/// The simulated planar ADAM (see the module docs).
#[derive(Debug, Clone)]
pub struct RobotSim {
    model: PlanarModel,
    config: RobotSimConfig,
    legs: Legs,
    feet: [usize; 2],
    actuated_coordinates: Vec<usize>,
    solver: Solver,
    q: Vec<f64>,
    dq: Vec<f64>,
    q_prev: Vec<f64>,
    dq_prev: Vec<f64>,
    generalized_force: Vec<f64>,
    /// D(q) and H(q, q̇) of the present step (buffers reused every step).
    mass_matrix: nalgebra::DMatrix<f64>,
    drift: nalgebra::DVector<f64>,
    /// Steps integrated with the present `D`, `H`, factor and contact operator.
    dynamics_age: u32,
    /// `D`, `H`, factor and contact operator must be re-evaluated before the next step (the
    /// state or the contact set changed).
    refresh_due: bool,
    /// `−J̇ q̇` of the stance feet at the last evaluation (the contact operator's target).
    stance_bias: [f64; 2 * MAX_CONTACTS],
    /// Foot heights at the end of the last step \[m\] (the touchdown search of a frozen step).
    foot_z_m: [f64; 2],
    /// Buffer of a step's end poses (always `Some` between steps).
    pose_scratch: Option<Box<BodyStates<f64>>>,
    /// The robot's weight \[N\].
    weight_n: f64,
    reduced_a: Vec<f64>,
    reduced_b: Vec<f64>,
    torque_nm: Vec<f64>,
    contact: [Contact; 2],
    force_n: [[f64; 2]; 2],
    friction_exceeded: [bool; 2],
    t_s: f64,
    base_accel_mps2: [f64; 2],
    events: Vec<SimEvent>,
    fallen: Option<FallRecord>,
    max_penetration_m: f64,
    imu: Option<NoisyImu>,
    /// (time, base velocity in the belt frame, belt speed) at the previous IMU read: the IMU
    /// reports the mean world acceleration since then.
    imu_last: Option<(f64, [f64; 2], f64)>,
    fault_t_s: Option<f64>,
    /// External force at the hip axis (world x, z) \[N\] and the time it ends \[s\].
    push: ([f64; 2], f64),
    /// The treadmill's belt.
    belt: Belt,
    /// The belt's acceleration over the present integration step \[m/s²\].
    belt_accel_mps2: f64,
    imu_fault: ImuFault,
    imu_held: ImuSample,
}

impl RobotSim {
    /// A simulator of `model` (the boom of `config` added to its torso), standing still on both
    /// feet in the pose of [`standing_pose`].
    pub fn new(model: &PlanarModel, config: RobotSimConfig) -> Result<Self> {
        validate(&config)?;
        model.check_capacity()?;
        let mut model = model.clone();
        if let Some(boom) = config.boom {
            let torso = &mut model.bodies[0].inertia;
            *torso = torso.combine(&BodyInertia {
                mass_kg: boom.mass_kg,
                com_xz_m: boom.com_xz_m,
                inertia_yy_kgm2: boom.inertia_yy_kgm2,
            });
        }
        let legs = model.legs()?;
        let n = model.dof();
        let solver = Solver::new(&model);
        let nr = solver.len();
        let actuated_coordinates: Vec<usize> = model
            .actuated_joints()
            .iter()
            .map(|&j| model.joints[j].coordinate)
            .collect();
        let q = standing_pose(
            &model,
            config.stand_hip_height_m,
            config.stand_half_stance_m,
        )?;
        let mut sim = Self {
            feet: [legs.left.foot, legs.right.foot],
            legs,
            torque_nm: vec![0.0; actuated_coordinates.len()],
            actuated_coordinates,
            solver,
            q: vec![0.0; n],
            dq: vec![0.0; n],
            q_prev: vec![0.0; n],
            dq_prev: vec![0.0; n],
            generalized_force: vec![0.0; n],
            mass_matrix: nalgebra::DMatrix::zeros(n, n),
            drift: nalgebra::DVector::zeros(n),
            dynamics_age: 0,
            refresh_due: true,
            stance_bias: [0.0; 2 * MAX_CONTACTS],
            foot_z_m: [0.0; 2],
            pose_scratch: Some(Box::new(BodyStates::zeroed())),
            weight_n: model.total_mass_kg() * model.gravity_mps2,
            reduced_a: vec![0.0; nr],
            reduced_b: vec![0.0; nr],
            contact: [Contact::Air; 2],
            force_n: [[0.0; 2]; 2],
            friction_exceeded: [false; 2],
            t_s: 0.0,
            base_accel_mps2: [0.0; 2],
            events: Vec::with_capacity(64),
            fallen: None,
            max_penetration_m: 0.0,
            imu: None,
            imu_last: None,
            fault_t_s: None,
            push: ([0.0; 2], 0.0),
            belt: Belt::new(
                config.belt_speed_mps,
                config.belt_acceleration_mps2,
                config.belt_length_m,
            ),
            belt_accel_mps2: 0.0,
            imu_fault: ImuFault::None,
            imu_held: ImuSample::default(),
            model,
            config,
        };
        let dq = vec![0.0; n];
        sim.set_state(&q, &dq)?;
        Ok(sim)
    }

    /// Put the robot at (q, q̇) (belt frame). Feet within [`PENETRATION_TOLERANCE_M`] of the
    /// ground become stance feet (pinned where they are, on `z = 0`); the state is then
    /// projected onto their constraints. Design coordinates keep the values given, with zero
    /// velocity. The belt's centre is placed under the hip. Clears the fall flag and the
    /// penetration record, keeps time and events.
    pub fn set_state(&mut self, q: &[f64], dq: &[f64]) -> Result<()> {
        self.set_state_with_stance(q, dq, None)
    }

    /// Like [`RobotSim::set_state`], but only the foot of `stance` may become a stance foot:
    /// the other foot starts in the air even on the ground, keeping its velocity. For a
    /// post-impact state (the old stance foot lifting off at `z = 0`), which `set_state` would
    /// pin and so project away the planned velocities.
    pub fn set_state_single_stance(&mut self, q: &[f64], dq: &[f64], stance: Side) -> Result<()> {
        self.set_state_with_stance(q, dq, Some(side_index(stance)))
    }

    fn set_state_with_stance(&mut self, q: &[f64], dq: &[f64], only: Option<usize>) -> Result<()> {
        self.imu_last = None;
        self.refresh_due = true;
        let n = self.model.dof();
        for (what, v) in [("q", q), ("dq", dq)] {
            if v.len() != n {
                return Err(RobotSimError::Dimension {
                    what,
                    expected: n,
                    found: v.len(),
                });
            }
        }
        self.q.copy_from_slice(q);
        self.dq.fill(0.0);
        for &c in self.solver.free() {
            self.dq[c] = dq[c];
        }
        let st = self.model.body_poses(&self.q)?;
        for (i, side) in SIDES.into_iter().enumerate() {
            let p = self.model.frame_position_in(&st, self.feet[i]);
            if p[1] < -PENETRATION_TOLERANCE_M {
                return Err(RobotSimError::Penetration {
                    side,
                    depth_m: -p[1],
                });
            }
            let may_stand = only.is_none_or(|k| k == i);
            self.contact[i] = if may_stand && p[1] <= PENETRATION_TOLERANCE_M {
                Contact::Stance {
                    anchor_xz_m: [p[0], 0.0],
                }
            } else {
                Contact::Air
            };
        }
        self.factor_present()?;
        self.project(None, true)?;
        self.belt.centre_x_m = self.base_position_m()[0];
        self.fallen = None;
        self.max_penetration_m = 0.0;
        self.fault_t_s = None;
        Ok(())
    }

    /// Push the torso: `force_xz_n` (world x forward, z up) at the hip axis from now for
    /// `duration_s` (replacing any push still acting). Refuses non-finite values.
    pub fn push(&mut self, force_xz_n: [f64; 2], duration_s: f64) -> Result<()> {
        for (field, value) in [
            ("push.force_x_n", force_xz_n[0]),
            ("push.force_z_n", force_xz_n[1]),
            ("push.duration_s", duration_s),
        ] {
            if !value.is_finite() || (field == "push.duration_s" && value < 0.0) {
                return Err(RobotSimError::Config {
                    field,
                    value,
                    reason: "must be finite (a duration ≥ 0)",
                });
            }
        }
        self.push = (force_xz_n, self.t_s + duration_s);
        Ok(())
    }

    /// Step the belt to `speed_mps` now (its target too). The belt frame changes speed with it:
    /// every velocity relative to the belt grows by the step, then the stance feet, pinned to
    /// the belt, are brought to its speed by the contact impulse (the plastic projection). A
    /// robot in the air keeps its world velocity.
    pub fn set_belt_speed(&mut self, speed_mps: f64) -> Result<()> {
        check_belt_speed(speed_mps)?;
        let step = speed_mps - self.belt.speed_mps;
        self.belt.step_to(self.t_s, speed_mps);
        self.dq[0] += step;
        self.refresh_due = true;
        self.factor_present()?;
        self.project(None, true).map(|_| ())
    }

    /// Ramp the belt from its present speed to `speed_mps` at the config's
    /// `belt_acceleration_mps2` (replacing any ramp under way); the stance feet go with it.
    pub fn set_belt_target_speed(&mut self, speed_mps: f64) -> Result<()> {
        check_belt_speed(speed_mps)?;
        self.belt.target_mps = speed_mps;
        Ok(())
    }

    /// Fault of the IMU output from the next read on ([`ImuFault::None`] heals it).
    pub fn set_imu_fault(&mut self, fault: ImuFault) {
        self.imu_fault = fault;
    }

    /// Attach a seeded IMU on the torso (at the hip axis) with the given noise.
    pub fn attach_imu(&mut self, noise: ImuNoise, seed: u64) {
        self.imu = Some(NoisyImu::new(noise, seed));
        self.imu_last = None;
    }

    /// Advance by `dt_s` with `torque_nm[k]` on actuated joint `k` (the model's
    /// `actuated_joints()` order) held constant, in `round(dt_s · rate_hz)` (at least one) equal
    /// steps.
    pub fn step(&mut self, torque_nm: &[f64], dt_s: f64) -> Result<()> {
        if let Some(t_s) = self.fault_t_s {
            return Err(RobotSimError::Faulted { t_s });
        }
        if torque_nm.len() != self.torque_nm.len() {
            return Err(RobotSimError::Dimension {
                what: "torque_nm",
                expected: self.torque_nm.len(),
                found: torque_nm.len(),
            });
        }
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(RobotSimError::Config {
                field: "dt_s",
                value: dt_s,
                reason: "a step must be positive and finite",
            });
        }
        self.torque_nm.copy_from_slice(torque_nm);
        let substeps = (dt_s * self.config.rate_hz).round().max(1.0) as usize;
        let h = dt_s / substeps as f64;
        let v0 = [self.dq[0], self.dq[1]];
        let belt0_mps = self.belt.speed_mps;
        for _ in 0..substeps {
            if let Err(e) = self.advance(h) {
                self.fault_t_s = Some(self.t_s);
                self.events.push(SimEvent::Fault { t_s: self.t_s });
                return Err(e);
            }
        }
        // World acceleration: the belt frame's own change of speed taken out.
        let belt_dv = self.belt.speed_mps - belt0_mps;
        self.base_accel_mps2 = [
            (self.dq[0] - v0[0] - belt_dv) / dt_s,
            (self.dq[1] - v0[1]) / dt_s,
        ];
        Ok(())
    }

    /// World displacement of the belt frame: `−∫ v_belt dt` \[m\].
    fn belt_offset_m(&self) -> f64 {
        self.belt.offset_m(self.t_s)
    }

    /// Joint torques that hold the present pose still on the present stance feet (gravity
    /// compensation, a feed-forward for standing): the minimum-norm `(u, λ)` with
    /// `B u + Jᵀ λ = G(q)` on the moving coordinates, `actuated_joints()` order \[N·m\].
    /// Allocates (start-up use).
    pub fn static_torques_nm(&self) -> Result<Vec<f64>> {
        let zero = vec![0.0; self.model.dof()];
        let gravity = self.model.dynamics(&self.q, &zero)?.drift;
        let st = self.model.body_poses(&self.q)?;
        let (frames, _, k) = self.stance_frames();
        let free = self.solver.free();
        let nu = self.actuated_coordinates.len();
        let mut a = nalgebra::DMatrix::<f64>::zeros(free.len(), nu + 2 * k);
        let mut b = nalgebra::DVector::<f64>::zeros(free.len());
        for (i, &c) in free.iter().enumerate() {
            b[i] = gravity[c];
            if let Some(col) = self.actuated_coordinates.iter().position(|&a| a == c) {
                a[(i, col)] = 1.0;
            }
        }
        for (r, &frame) in frames[..k].iter().enumerate() {
            let jac = self.model.frame_jacobian(&st, frame);
            for (i, &c) in free.iter().enumerate() {
                a[(i, nu + 2 * r)] = jac[(0, c)];
                a[(i, nu + 2 * r + 1)] = jac[(1, c)];
            }
        }
        let x = a
            .svd(true, true)
            .solve(&b, 1e-10)
            .map_err(|_| ModelError::Singular {
                what: "static torques",
            })?;
        Ok(x.iter().take(nu).copied().collect())
    }

    // ---- ground truth -------------------------------------------------------------------

    /// Simulated time \[s\].
    pub fn time_s(&self) -> f64 {
        self.t_s
    }

    /// The simulated model (boom included).
    pub fn model(&self) -> &PlanarModel {
        &self.model
    }

    /// The configuration.
    pub fn config(&self) -> &RobotSimConfig {
        &self.config
    }

    /// Generalized coordinates in the belt frame.
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// Generalized velocities in the belt frame.
    pub fn dq(&self) -> &[f64] {
        &self.dq
    }

    /// Torso pitch \[rad\].
    pub fn torso_pitch_rad(&self) -> f64 {
        self.q[2]
    }

    /// Torso pitch rate \[rad/s\].
    pub fn torso_pitch_rate_rad_s(&self) -> f64 {
        self.dq[2]
    }

    /// Base (torso frame origin, the hip axis) position in the world (x, z) \[m\].
    pub fn base_position_m(&self) -> [f64; 2] {
        [self.q[0] + self.belt_offset_m(), self.q[1]]
    }

    /// Base velocity in the world (x, z) \[m/s\].
    pub fn base_velocity_mps(&self) -> [f64; 2] {
        [self.dq[0] - self.belt.speed_mps, self.dq[1]]
    }

    /// The hip's position on the belt: its world x forward of the belt's centre \[m\].
    pub fn position_on_belt_m(&self) -> f64 {
        self.base_position_m()[0] - self.belt.centre_x_m
    }

    /// The belt's present speed, its surface moving backwards \[m/s\].
    pub fn belt_speed_mps(&self) -> f64 {
        self.belt.speed_mps
    }

    /// The speed the belt is ramping toward (its present speed when not ramping) \[m/s\].
    pub fn belt_target_speed_mps(&self) -> f64 {
        self.belt.target_mps
    }

    /// The belt's length \[m\] (infinite: endless).
    pub fn belt_length_m(&self) -> f64 {
        self.belt.length_m
    }

    /// Base velocity relative to the belt (x, z) \[m/s\]: the walking speed.
    pub fn base_velocity_over_belt_mps(&self) -> [f64; 2] {
        [self.dq[0], self.dq[1]]
    }

    /// Foot position in the world (x, z) \[m\].
    pub fn foot_position_m(&self, side: Side) -> [f64; 2] {
        let st = self.model.body_poses(&self.q);
        let p = st.map_or([f64::NAN; 2], |st| {
            self.model
                .frame_position_in(&st, self.feet[side_index(side)])
        });
        [p[0] + self.belt_offset_m(), p[1]]
    }

    /// Contact state of a foot (anchor in the belt frame).
    pub fn contact(&self, side: Side) -> Contact {
        self.contact[side_index(side)]
    }

    /// Whether a foot is in stance.
    pub fn in_stance(&self, side: Side) -> bool {
        matches!(self.contact(side), Contact::Stance { .. })
    }

    /// Contact force on the robot at a foot in the last step, world (F_x, F_z) \[N\].
    pub fn contact_force_n(&self, side: Side) -> [f64; 2] {
        self.force_n[side_index(side)]
    }

    /// Kinetic energy \[J\].
    pub fn kinetic_energy_j(&self) -> f64 {
        self.model
            .kinetic_energy(&self.q, &self.dq)
            .unwrap_or(f64::NAN)
    }

    /// Potential energy (zero at ground level) \[J\].
    pub fn potential_energy_j(&self) -> f64 {
        self.model.potential_energy(&self.q).unwrap_or(f64::NAN)
    }

    /// Events so far, oldest first.
    pub fn events(&self) -> &[SimEvent] {
        &self.events
    }

    /// Forget the recorded events.
    pub fn clear_events(&mut self) {
        self.events.clear();
    }

    /// The fall, if the robot has fallen.
    pub fn fallen(&self) -> Option<FallCause> {
        self.fallen.map(|f| f.what)
    }

    /// The fall with where and when it happened, if the robot has fallen.
    pub fn fall_record(&self) -> Option<FallRecord> {
        self.fallen
    }

    /// Deepest foot penetration seen since the last `set_state` \[m\].
    pub fn max_penetration_m(&self) -> f64 {
        self.max_penetration_m
    }

    /// The true IMU sample at the torso origin: pitch rate and the specific force in the torso
    /// frame, the acceleration being the mean over the last `step` (impacts included).
    pub fn imu_truth(&self) -> ImuSample {
        let g = self.model.gravity_mps2;
        let f = [self.base_accel_mps2[0], self.base_accel_mps2[1] + g];
        let (s, c) = self.q[2].sin_cos();
        ImuSample {
            t_s: self.t_s,
            gyro_pitch_rad_s: self.dq[2],
            accel_x_mps2: c * f[0] - s * f[1],
            accel_z_mps2: s * f[0] + c * f[1],
        }
    }

    /// The plant joint (an index for [`JointPlant`] and the torque slice) of a leg joint.
    pub fn joint_index(&self, side: Side, which: LegJoint) -> usize {
        let leg = self.legs.side(side);
        let joint = match which {
            LegJoint::Hip => leg.hip,
            LegJoint::Knee => leg.knee,
        };
        let c = self.model.joints[joint].coordinate;
        self.actuated_coordinates
            .iter()
            .position(|&a| a == c)
            .unwrap_or(usize::MAX)
    }

    /// The four leg motors for a [`crate::sim::bus::SimConfig`]: ADAM's numbering, hip id 1
    /// and knee id 2 on `left_bus`, hip id 3 and knee id 4 on `right_bus`.
    pub fn leg_motors(&self, left_bus: usize, right_bus: usize) -> Vec<SimMotor> {
        let mut motors = Vec::with_capacity(4);
        for (side, bus, first_id) in [(Side::Left, left_bus, 1), (Side::Right, right_bus, 3)] {
            for (k, which) in [LegJoint::Hip, LegJoint::Knee].into_iter().enumerate() {
                if let Some(id) = crate::a1::MotorId::new(first_id + k as u8) {
                    motors.push(SimMotor {
                        spec: MotorSpec { bus, id },
                        joint: self.joint_index(side, which),
                    });
                }
            }
        }
        motors
    }
}

fn check_belt_speed(speed_mps: f64) -> Result<()> {
    if speed_mps.is_finite() {
        Ok(())
    } else {
        Err(RobotSimError::Config {
            field: "belt_speed_mps",
            value: speed_mps,
            reason: "must be finite",
        })
    }
}

impl JointPlant for RobotSim {
    fn joint_count(&self) -> usize {
        self.actuated_coordinates.len()
    }
    fn position_rad(&self, joint: usize) -> f64 {
        self.q[self.actuated_coordinates[joint]]
    }
    fn velocity_rad_s(&self, joint: usize) -> f64 {
        self.dq[self.actuated_coordinates[joint]]
    }
    /// Advances the robot; a failed step freezes it (a [`SimEvent::Fault`] is recorded).
    fn step(&mut self, torque_nm: &[f64], dt_s: f64) {
        let _ = RobotSim::step(self, torque_nm, dt_s);
    }
}

impl Imu for RobotSim {
    /// The IMU sample: the gyro at this instant, the accelerometer averaged since the previous
    /// read (an IMU's output filter integrates over its sample period, so a foot impact shows
    /// as a spike of the mean acceleration of that period, not only in the 0.1 ms sim step
    /// that contains it).
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        let mut truth = self.imu_truth();
        let v = [self.dq[0], self.dq[1]];
        let belt_mps = self.belt.speed_mps;
        if let Some((t0, v0, belt0_mps)) = self.imu_last {
            let dt = self.t_s - t0;
            if dt > 0.0 {
                let g = self.model.gravity_mps2;
                // World acceleration: the belt frame's change of speed taken out.
                let dvx = v[0] - v0[0] - (belt_mps - belt0_mps);
                let f = [dvx / dt, (v[1] - v0[1]) / dt + g];
                let (s, c) = self.q[2].sin_cos();
                truth.accel_x_mps2 = c * f[0] - s * f[1];
                truth.accel_z_mps2 = s * f[0] + c * f[1];
            }
        }
        self.imu_last = Some((self.t_s, v, belt_mps));
        let imu = self.imu.as_mut().ok_or(ImuError::NotAttached)?;
        let mut fresh = ImuSample::default();
        imu.measure(&truth, &mut fresh);
        self.imu_fault.apply(&fresh, &self.imu_held, out)?;
        if self.imu_fault == ImuFault::None {
            self.imu_held = fresh;
        }
        Ok(())
    }
}
