//! `drivers::sim`: the planar ADAM on a treadmill, with an optional boom, as a [`JointPlant`].
//!
//! [`RobotSim`] simulates any [`PlanarModel`] that follows the biped naming convention (any
//! co-designed leg lengths). Put it behind [`crate::sim_bus::SimBus`] and the controller talks to
//! the whole robot through real CAN frames and simulated A1 firmware.
//!
//! # Model
//! * **Floating base** `q = [x, z, pitch, joints…]` with the model's own `D(q)`, `H(q, q̇)`. The
//!   design joints are rigid: their rows and columns are dropped (exactly the model's `q̈_D = 0`).
//! * **Treadmill.** The belt moves at a constant `belt_speed_mps` backwards. A constant-velocity
//!   frame is inertial, so the simulation runs in the *belt frame*, where the ground is static and
//!   a stance foot is pinned; world positions and velocities are reported by adding the belt
//!   travel (`x_world = x_belt − v_belt t`). The robot walks "in place" when it walks forward at
//!   the belt speed.
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
//! The motors' PD runs at 10 kHz (in [`crate::sim_bus::SimBus`]) and so does the integrator,
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
//! use drivers::sim::{RobotSim, RobotSimConfig};
//! use drivers::sim_bus::{A1Model, SimBus, SimConfig};
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

mod solver;

use crate::bus::MotorSpec;
use crate::imu::{Imu, ImuError, ImuFault, ImuNoise, ImuSample, NoisyImu};
use crate::sim_bus::{JointPlant, SimMotor};
use model::kinematics::BodyStates;
use model::robot::{BodyInertia, Legs};
use model::{ModelError, PlanarModel, Side};
use solver::{Solver, MAX_CONTACTS};
use thiserror::Error;

/// Largest foot penetration the simulator allows itself \[m\].
pub const PENETRATION_TOLERANCE_M: f64 = 1e-6;

/// A step keeps the frozen dynamics only while every stance foot carries at least this
/// fraction of the robot's weight: nearer to liftoff, the contact set is decided on fresh
/// dynamics (module docs, "Multi-rate dynamics").
const FROZEN_MIN_NORMAL_FORCE_FRACTION: f64 = 0.1;

/// Most events (touchdowns) handled inside one integration step.
const MAX_EVENTS_PER_STEP: usize = 4;

const SIDES: [Side; 2] = [Side::Left, Side::Right];

/// Contact-set mask keeping every stance foot.
const ALL_KEPT: u8 = 0b11;

/// Contact sets to try, as masks over the `k` stance feet: all, each single one, none.
fn candidate_masks(k: usize) -> &'static [u8] {
    match k {
        0 => &[0],
        1 => &[0b1, 0],
        _ => &[0b11, 0b01, 0b10, 0],
    }
}

fn side_index(side: Side) -> usize {
    match side {
        Side::Left => 0,
        Side::Right => 1,
    }
}

/// Mass properties the boom adds to the torso.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boom {
    /// Added mass \[kg\].
    pub mass_kg: f64,
    /// Where that mass acts, in the torso frame (x, z) \[m\].
    pub com_xz_m: [f64; 2],
    /// Added pitch inertia about that point \[kg·m²\].
    pub inertia_yy_kgm2: f64,
}

/// Configuration of a [`RobotSim`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotSimConfig {
    /// Integration rate \[Hz\]; `JointPlant::step(dt)` takes `round(dt · rate)` equal steps.
    pub rate_hz: f64,
    /// Treadmill belt speed, positive when the belt surface moves backwards \[m/s\].
    pub belt_speed_mps: f64,
    /// The boom's added mass, or `None` (default: the paper did not model it).
    pub boom: Option<Boom>,
    /// Friction coefficient μ for the friction report.
    pub friction_coefficient: f64,
    /// Torso pitch beyond which the robot has fallen \[rad\].
    pub fall_pitch_limit_rad: f64,
    /// Hip height of the initial standing pose \[m\] (`None`: 92 % of the leg length).
    pub stand_hip_height_m: Option<f64>,
    /// Horizontal distance of each foot from the hip in the initial standing pose \[m\].
    pub stand_half_stance_m: f64,
    /// Integration steps that share one evaluation of `D`, `H`, the factor of `D` and the contact
    /// operator (see the module docs, "Multi-rate dynamics"): 1 re-evaluates them every step
    /// (the exact path); the default 10 evaluates them once per millisecond at 10 kHz.
    pub dynamics_refresh_substeps: u32,
}

impl Default for RobotSimConfig {
    fn default() -> Self {
        Self {
            rate_hz: 10_000.0,
            belt_speed_mps: 0.0,
            boom: None,
            friction_coefficient: 1.0,
            fall_pitch_limit_rad: 1.0,
            stand_hip_height_m: None,
            stand_half_stance_m: 0.08,
            dynamics_refresh_substeps: 10,
        }
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
    #[error("{side:?} foot is {depth_m} m below the ground")]
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

/// What touched the ground (or tipped over) in a fall.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FallCause {
    /// The torso (its hip axis or its top) reached the ground.
    Torso,
    /// A knee joint reached the ground.
    Knee(Side),
    /// The torso pitched beyond the limit.
    Pitch,
}

/// A foot touchdown: the plastic impact and the step it ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touchdown {
    /// Time of contact \[s\].
    pub t_s: f64,
    /// Foot that touched down.
    pub side: Side,
    /// Its world x position \[m\].
    pub foot_x_m: f64,
    /// Step length: this foot's x minus the other foot's x at touchdown \[m\].
    pub step_length_m: f64,
    /// Impulse on the robot at this foot, world (x, z) \[N·s\].
    pub impulse_ns: [f64; 2],
    /// Kinetic energy just before the impact \[J\].
    pub kinetic_energy_before_j: f64,
    /// Kinetic energy just after the impact \[J\].
    pub kinetic_energy_after_j: f64,
}

/// Something that happened in the simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SimEvent {
    /// A foot touched down.
    Touchdown(Touchdown),
    /// A stance foot left the ground (its normal force or impulse would have pulled).
    Liftoff {
        /// Time \[s\].
        t_s: f64,
        /// Which foot.
        side: Side,
    },
    /// The tangential force of a stance foot exceeds μ × its normal force (foot kept pinned).
    FrictionExceeded {
        /// Time \[s\].
        t_s: f64,
        /// Which foot.
        side: Side,
        /// |F_x| / F_z.
        ratio: f64,
    },
    /// The robot fell (reported once).
    Fall {
        /// Time \[s\].
        t_s: f64,
        /// What touched the ground or tipped.
        what: FallCause,
    },
    /// A step failed; the simulation is frozen (see [`RobotSim::step`]).
    Fault {
        /// Time \[s\].
        t_s: f64,
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
    fallen: Option<FallCause>,
    max_penetration_m: f64,
    imu: Option<NoisyImu>,
    /// (time, base velocity) at the previous IMU read: the IMU reports the mean acceleration
    /// since then.
    imu_last: Option<(f64, [f64; 2])>,
    fault_t_s: Option<f64>,
    /// External force at the hip axis (world x, z) \[N\] and the time it ends \[s\].
    push: ([f64; 2], f64),
    /// Belt travel up to `belt_since_t_s` \[m\] (world x of the belt frame's origin then).
    belt_offset0_m: f64,
    belt_since_t_s: f64,
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
            belt_offset0_m: 0.0,
            belt_since_t_s: 0.0,
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
    /// velocity. Clears the fall flag and the penetration record, keeps time and events.
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

    /// Step the belt to `speed_mps` now. The belt frame changes speed with it: every velocity
    /// relative to the belt grows by the step, then the stance feet, pinned to the belt, are
    /// brought to its speed by the contact impulse (the plastic projection). A robot in the air
    /// keeps its world velocity.
    pub fn set_belt_speed(&mut self, speed_mps: f64) -> Result<()> {
        if !speed_mps.is_finite() {
            return Err(RobotSimError::Config {
                field: "belt_speed_mps",
                value: speed_mps,
                reason: "must be finite",
            });
        }
        let step = speed_mps - self.config.belt_speed_mps;
        self.belt_offset0_m = self.belt_offset_m();
        self.belt_since_t_s = self.t_s;
        self.config.belt_speed_mps = speed_mps;
        self.dq[0] += step;
        self.refresh_due = true;
        // The IMU differentiates the belt-frame velocity: shift its reference too, so it sees
        // only the world acceleration (the impulse), not the change of frame.
        if let Some((_, v)) = self.imu_last.as_mut() {
            v[0] += step;
        }
        self.factor_present()?;
        self.project(None, true).map(|_| ())
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
        for _ in 0..substeps {
            if let Err(e) = self.advance(h) {
                self.fault_t_s = Some(self.t_s);
                self.events.push(SimEvent::Fault { t_s: self.t_s });
                return Err(e);
            }
        }
        self.base_accel_mps2 = [(self.dq[0] - v0[0]) / dt_s, (self.dq[1] - v0[1]) / dt_s];
        Ok(())
    }

    fn advance(&mut self, h: f64) -> Result<()> {
        let mut remaining = h;
        for _ in 0..MAX_EVENTS_PER_STEP {
            remaining -= self.sub_step(remaining, true)?;
            if remaining <= h * 1e-9 {
                break;
            }
        }
        if remaining > h * 1e-9 {
            // Too many events in one step (chatter): integrate the rest without event search.
            self.sub_step(remaining, false)?;
        }
        Ok(())
    }

    /// Body states, D and H at the present (q, q̇) into the step's buffers, and D factored.
    fn factor_present(&mut self) -> Result<BodyStates<f64>> {
        let st = self.model.body_states(&self.q, &self.dq)?;
        self.model
            .dynamics_into(&st, &mut self.mass_matrix, &mut self.drift)?;
        self.solver
            .factor_mass(&self.mass_matrix)
            .map_err(|_| RobotSimError::NotPositiveDefinite { t_s: self.t_s })?;
        Ok(st)
    }

    /// Stance frames (and their side indices) in left-right order.
    fn stance_frames(&self) -> ([usize; MAX_CONTACTS], [usize; MAX_CONTACTS], usize) {
        let mut frames = [0; MAX_CONTACTS];
        let mut sides = [0; MAX_CONTACTS];
        let mut k = 0;
        for i in 0..2 {
            if matches!(self.contact[i], Contact::Stance { .. }) {
                frames[k] = self.feet[i];
                sides[k] = i;
                k += 1;
            }
        }
        (frames, sides, k)
    }

    /// Integrate up to `h`; returns the time integrated (less than `h` if a touchdown
    /// interrupted the step at that instant). Re-evaluates `D`, `H`, the factor and the contact
    /// operator first when they are due (module docs, "Multi-rate dynamics").
    fn sub_step(&mut self, h: f64, detect_touchdown: bool) -> Result<f64> {
        let frozen = !self.refresh_due && self.dynamics_age < self.config.dynamics_refresh_substeps;
        let st = if frozen {
            None
        } else {
            let st = self.factor_present()?;
            self.refresh_due = false;
            self.dynamics_age = 0;
            Some(st)
        };
        self.dynamics_age += 1;
        for (f, hv) in self.generalized_force.iter_mut().zip(self.drift.iter()) {
            *f = -hv;
        }
        for (&c, &u) in self.actuated_coordinates.iter().zip(&self.torque_nm) {
            self.generalized_force[c] += u;
        }
        // A push at the hip axis (the base origin): its Jacobian is the identity on (x, z).
        if self.t_s < self.push.1 {
            self.generalized_force[0] += self.push.0[0];
            self.generalized_force[1] += self.push.0[1];
        }
        self.solver
            .gather(&self.generalized_force, &mut self.reduced_a);
        self.solver.solve_mass(&mut self.reduced_a);

        let (frames, sides, k) = self.stance_frames();
        if let Some(st) = &st {
            // Stance dynamics: the first consistent contact set (stance feet push, released
            // feet accelerate away from the ground), from keeping every stance foot to none.
            let mut chosen = None;
            for &mask in candidate_masks(k) {
                let accepted = self.solve_stance(st, &frames, &sides, k, mask)?;
                if accepted {
                    chosen = Some(mask);
                    break;
                }
            }
            // No consistent set (rigid pinning can demand pull): keep every stance foot.
            let mask = chosen.unwrap_or(ALL_KEPT);
            if chosen.is_none() {
                self.solve_stance(st, &frames, &sides, k, ALL_KEPT)?;
            } else if mask != ALL_KEPT {
                // The accepted solve is in `reduced_b`; release the dropped feet.
                for r in (0..k).filter(|&r| mask & (1 << r) == 0) {
                    self.release(sides[r]);
                }
            }
        } else if !self.solve_frozen_stance(&sides, k) {
            // In flight, or a stance foot near liftoff: this step is integrated exactly.
            self.refresh_due = true;
            return self.sub_step(h, detect_touchdown);
        }
        self.report_friction();

        // Semi-implicit Euler on the moving coordinates.
        self.q_prev.copy_from_slice(&self.q);
        self.dq_prev.copy_from_slice(&self.dq);
        self.solver.scatter_add(&self.reduced_b, h, &mut self.dq);
        for &c in self.solver.free() {
            self.q[c] += h * self.dq[c];
        }

        // The end-of-step poses go into a buffer kept between steps (1 kB: no copy, no zeroing).
        let mut poses = self
            .pose_scratch
            .take()
            .unwrap_or_else(|| Box::new(BodyStates::zeroed()));
        let integrated = self.end_step(h, st.as_ref(), detect_touchdown, &mut poses);
        self.pose_scratch = Some(poses);
        integrated
    }

    /// The rest of a step integrated over `h` from the body states `st` (if evaluated afresh):
    /// the touchdown search, the stance projection and the end-state checks, with `st1` as
    /// the buffer of the end poses. Returns the time integrated (see [`Self::sub_step`]).
    fn end_step(
        &mut self,
        h: f64,
        st: Option<&BodyStates<f64>>,
        detect_touchdown: bool,
        st1: &mut BodyStates<f64>,
    ) -> Result<f64> {
        // Touchdown of a free foot within the step: the earliest one.
        self.model.body_poses_into(&self.q, st1)?;
        let mut first: Option<(usize, f64)> = None;
        for i in 0..2 {
            if !detect_touchdown || self.contact[i] != Contact::Air {
                continue;
            }
            let z0 = match st {
                Some(st) => self.model.frame_position_in(st, self.feet[i])[1],
                None => self.foot_z_m[i],
            };
            let z1 = self.model.frame_position_in(st1, self.feet[i])[1];
            if z1 < 0.0 && z1 < z0 {
                let s = if z0 > 0.0 { z0 / (z0 - z1) } else { 0.0 };
                if first.is_none_or(|(_, s0)| s < s0) {
                    first = Some((i, s));
                }
            }
        }
        if let Some((i, s)) = first {
            for c in 0..self.q.len() {
                self.q[c] = self.q_prev[c] + s * (self.q[c] - self.q_prev[c]);
                self.dq[c] = self.dq_prev[c] + s * (self.dq[c] - self.dq_prev[c]);
            }
            self.t_s += s * h;
            self.touchdown(i)?;
            self.model.body_poses_into(&self.q, st1)?;
            self.check_end_state(st1);
            return Ok(s * h);
        }
        // The multi-rate path projects with the contact operator it integrates with, and keeps
        // the poses from before the projection (which moves the robot by nanometres) for the
        // penetration record, the fall check and the next touchdown search.
        let exact = self.config.dynamics_refresh_substeps == 1;
        if self.project(Some(st1), exact)? && exact {
            self.model.body_poses_into(&self.q, st1)?;
        }
        self.t_s += h;
        self.check_end_state(st1);
        Ok(h)
    }

    /// The stance dynamics with the contact operator and `−J̇ q̇` of the last evaluation, every
    /// stance foot kept; leaves q̈ (reduced) in `reduced_b` and the forces in `force_n`.
    /// Whether the step may keep them: some foot is in stance and every stance foot pushes
    /// with at least [`FROZEN_MIN_NORMAL_FORCE_FRACTION`] of the robot's weight (otherwise the
    /// step must be integrated, and the contact set chosen, on fresh dynamics).
    fn solve_frozen_stance(&mut self, sides: &[usize; MAX_CONTACTS], k: usize) -> bool {
        if k == 0 {
            return false;
        }
        self.reduced_b.copy_from_slice(&self.reduced_a);
        let mut lambda = [0.0; 2 * MAX_CONTACTS];
        self.solver
            .constrain(&mut self.reduced_b, &self.stance_bias, &mut lambda);
        self.force_n = [[0.0; 2]; 2];
        for r in 0..k {
            self.force_n[sides[r]] = [lambda[2 * r], lambda[2 * r + 1]];
        }
        let min_normal_n = FROZEN_MIN_NORMAL_FORCE_FRACTION * self.weight_n;
        (0..k).all(|r| lambda[2 * r + 1] >= min_normal_n)
    }

    /// Solve the stance dynamics keeping the stance feet `r` with bit `r` of `mask` set;
    /// leaves q̈ (reduced) in `reduced_b` and the forces in `force_n`. Whether the set is
    /// consistent: kept feet push (F_z ≥ 0), dropped feet accelerate upwards.
    fn solve_stance(
        &mut self,
        st: &BodyStates<f64>,
        frames: &[usize; MAX_CONTACTS],
        sides: &[usize; MAX_CONTACTS],
        k: usize,
        mask: u8,
    ) -> Result<bool> {
        let mut kept = [0; MAX_CONTACTS];
        let mut kept_sides = [0; MAX_CONTACTS];
        let mut nk = 0;
        for r in (0..k).filter(|&r| mask & (1 << r) != 0) {
            kept[nk] = frames[r];
            kept_sides[nk] = sides[r];
            nk += 1;
        }
        self.solver.set_contacts(&self.model, st, &kept[..nk]);
        let mut c = [0.0; 2 * MAX_CONTACTS];
        for r in 0..nk {
            let b = self.model.frame_bias_acceleration_in(st, kept[r]);
            c[2 * r] = -b[0];
            c[2 * r + 1] = -b[1];
        }
        self.stance_bias = c;
        self.reduced_b.copy_from_slice(&self.reduced_a);
        let mut lambda = [0.0; 2 * MAX_CONTACTS];
        self.solver.constrain(&mut self.reduced_b, &c, &mut lambda);
        self.force_n = [[0.0; 2]; 2];
        for r in 0..nk {
            self.force_n[kept_sides[r]] = [lambda[2 * r], lambda[2 * r + 1]];
        }
        if (0..nk).any(|r| lambda[2 * r + 1] < 0.0) {
            return Ok(false);
        }
        // Normal acceleration of each dropped foot: J_z q̈ + J̇_z q̇ must not point down.
        self.q_prev.fill(0.0);
        self.solver
            .scatter_add(&self.reduced_b, 1.0, &mut self.q_prev);
        for r in (0..k).filter(|&r| mask & (1 << r) == 0) {
            let frame = frames[r];
            let p = self.model.frame_position_in(st, frame);
            let mut az = self.model.frame_bias_acceleration_in(st, frame)[1];
            let ddq = &self.q_prev;
            self.model
                .point_jacobian_into(st, self.model.frames[frame].body, p, |row, col, v| {
                    if row == 1 {
                        az += v * ddq[col];
                    }
                });
            if az < 0.0 {
                return Ok(false);
            }
        }
        Ok(true)
    }

    fn release(&mut self, i: usize) {
        self.refresh_due = true;
        self.contact[i] = Contact::Air;
        self.friction_exceeded[i] = false;
        self.events.push(SimEvent::Liftoff {
            t_s: self.t_s,
            side: SIDES[i],
        });
    }

    fn report_friction(&mut self) {
        for (i, side) in SIDES.into_iter().enumerate() {
            if self.contact[i] == Contact::Air {
                continue;
            }
            let [fx, fz] = self.force_n[i];
            let ratio = if fz > 0.0 {
                fx.abs() / fz
            } else {
                f64::INFINITY
            };
            let exceeded = ratio > self.config.friction_coefficient;
            if exceeded && !self.friction_exceeded[i] {
                self.events.push(SimEvent::FrictionExceeded {
                    t_s: self.t_s,
                    side,
                    ratio,
                });
            }
            self.friction_exceeded[i] = exceeded;
        }
    }

    /// Plastic impact of foot `i` at the present state (the foot is on the ground).
    fn touchdown(&mut self, i: usize) -> Result<()> {
        let kinetic_energy_before_j = self.model.kinetic_energy(&self.q, &self.dq)?;
        self.refresh_due = true;
        let st = self.factor_present()?;
        let p = self.model.frame_position_in(&st, self.feet[i]);
        self.contact[i] = Contact::Stance {
            anchor_xz_m: [p[0], 0.0],
        };
        // Contact sets to try: with the other foot pinned too (if in stance), then alone. A set
        // is consistent when every pinned foot's normal impulse pushes and a released foot
        // leaves with an upward velocity; none consistent (rigid pinning can demand pull at a
        // grazing touchdown): keep both.
        let other = 1 - i;
        let other_in_stance = self.contact[other] != Contact::Air;
        let mut impulse_ns = [0.0; 2];
        let mut release_other = false;
        for attempt in 0..3 {
            let drop_other = attempt == 1;
            if drop_other && !other_in_stance {
                continue;
            }
            let anchor = self.contact[other];
            if drop_other {
                self.contact[other] = Contact::Air;
            }
            let (frames, sides, k) = self.stance_frames();
            self.contact[other] = anchor;
            self.solver.set_contacts(&self.model, &st, &frames[..k]);
            self.solver.gather(&self.dq, &mut self.reduced_b);
            let mut lambda = [0.0; 2 * MAX_CONTACTS];
            self.solver
                .constrain(&mut self.reduced_b, &[0.0; 2 * MAX_CONTACTS], &mut lambda);
            if let Some(r) = (0..k).find(|&r| sides[r] == i) {
                impulse_ns = [lambda[2 * r], lambda[2 * r + 1]];
            }
            if attempt == 2 {
                // Fallback: the first set, solved again above.
                break;
            }
            let pushes = (0..k).all(|r| lambda[2 * r + 1] >= 0.0);
            let leaves = !drop_other || {
                self.q_prev.fill(0.0);
                self.solver
                    .scatter_add(&self.reduced_b, 1.0, &mut self.q_prev);
                let v = self.model.body_states(&self.q, &self.q_prev)?;
                self.model.frame_velocity_in(&v, self.feet[other])[1] >= 0.0
            };
            if pushes && leaves {
                release_other = drop_other;
                break;
            }
        }
        if release_other {
            self.release(other);
        }
        for (&c, &v) in self.solver.free().iter().zip(&self.reduced_b) {
            self.dq[c] = v;
        }
        self.project(None, true)?;
        let kinetic_energy_after_j = self.model.kinetic_energy(&self.q, &self.dq)?;
        let st = self.model.body_poses(&self.q)?;
        let other = self.model.frame_position_in(&st, self.feet[1 - i]);
        let x_world = p[0] + self.belt_offset_m();
        self.events.push(SimEvent::Touchdown(Touchdown {
            t_s: self.t_s,
            side: SIDES[i],
            foot_x_m: x_world,
            step_length_m: p[0] - other[0],
            impulse_ns,
            kinetic_energy_before_j,
            kinetic_energy_after_j,
        }));
        Ok(())
    }

    /// Pull the stance feet back onto their anchors and their velocities to zero, in the
    /// kinetic-energy metric of the last factored `D` (corrections are O(h²) small). `poses`:
    /// the body poses at the present q, if already computed; `reload`: load the contact
    /// Jacobian at these poses (otherwise project with the loaded contact operator, which must
    /// be that of the present stance feet). Whether q changed.
    fn project(&mut self, poses: Option<&BodyStates<f64>>, reload: bool) -> Result<bool> {
        let (frames, sides, k) = self.stance_frames();
        if k == 0 {
            return Ok(false);
        }
        let computed;
        let st = match poses {
            Some(st) => st,
            None => {
                computed = self.model.body_poses(&self.q)?;
                &computed
            }
        };
        if reload {
            self.solver.set_contacts(&self.model, st, &frames[..k]);
        }
        let mut c = [0.0; 2 * MAX_CONTACTS];
        for r in 0..k {
            let p = self.model.frame_position_in(st, frames[r]);
            if let Contact::Stance { anchor_xz_m } = self.contact[sides[r]] {
                c[2 * r] = anchor_xz_m[0] - p[0];
                c[2 * r + 1] = anchor_xz_m[1] - p[1];
            }
        }
        self.solver.correction(&c, &mut self.reduced_b);
        self.solver.scatter_add(&self.reduced_b, 1.0, &mut self.q);
        let mut lambda = [0.0; 2 * MAX_CONTACTS];
        self.solver.gather(&self.dq, &mut self.reduced_b);
        self.solver
            .constrain(&mut self.reduced_b, &[0.0; 2 * MAX_CONTACTS], &mut lambda);
        for (&c, &v) in self.solver.free().iter().zip(&self.reduced_b) {
            self.dq[c] = v;
        }
        Ok(true)
    }

    /// At the end of a step, from the poses `st` of its final q: record the foot heights (for
    /// the next touchdown search) and the deepest penetration, and check for a fall.
    fn check_end_state(&mut self, st: &BodyStates<f64>) {
        for (i, &f) in self.feet.iter().enumerate() {
            let z = self.model.frame_position_in(st, f)[1];
            self.foot_z_m[i] = z;
            self.max_penetration_m = self.max_penetration_m.max(-z);
        }
        if self.fallen.is_some() {
            return;
        }
        let torso_com = self.model.bodies[0].inertia.com_xz_m;
        let top_local = [2.0 * torso_com[0], 2.0 * torso_com[1]];
        let hip_z = st.pose[0].xz_m[1];
        // The top is within |top_local| of the hip axis: while the hip is higher than that
        // (1 % margin for rounding), the top is up and its rotation (a sine and cosine every
        // step) is skipped.
        let top_reach_sq = top_local[0] * top_local[0] + top_local[1] * top_local[1];
        let top_down = hip_z * hip_z <= 1.01 * top_reach_sq
            && self.model.point_position(st, 0, top_local)[1] <= 0.0;
        let what = if hip_z <= 0.0 || top_down {
            Some(FallCause::Torso)
        } else if let Some(side) = SIDES.into_iter().find(|&s| {
            let knee = self.model.joints[self.legs.side(s).knee].body;
            st.pose[knee].xz_m[1] <= 0.0
        }) {
            Some(FallCause::Knee(side))
        } else if self.q[2].abs() > self.config.fall_pitch_limit_rad {
            Some(FallCause::Pitch)
        } else {
            None
        };
        if let Some(what) = what {
            self.fallen = Some(what);
            self.events.push(SimEvent::Fall {
                t_s: self.t_s,
                what,
            });
        }
    }

    /// World displacement of the belt frame: `−v_belt · t` (piecewise, over belt steps) \[m\].
    fn belt_offset_m(&self) -> f64 {
        self.belt_offset0_m - self.config.belt_speed_mps * (self.t_s - self.belt_since_t_s)
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
        [self.dq[0] - self.config.belt_speed_mps, self.dq[1]]
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

    /// The four leg motors for a [`crate::sim_bus::SimConfig`]: ADAM's numbering, hip id 1
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
        if let Some((t0, v0)) = self.imu_last {
            let dt = self.t_s - t0;
            if dt > 0.0 {
                let g = self.model.gravity_mps2;
                let f = [(v[0] - v0[0]) / dt, (v[1] - v0[1]) / dt + g];
                let (s, c) = self.q[2].sin_cos();
                truth.accel_x_mps2 = c * f[0] - s * f[1];
                truth.accel_z_mps2 = s * f[0] + c * f[1];
            }
        }
        self.imu_last = Some((self.t_s, v));
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

fn validate(c: &RobotSimConfig) -> Result<()> {
    let bad = |field, value, reason| {
        Err(RobotSimError::Config {
            field,
            value,
            reason,
        })
    };
    if !(c.rate_hz.is_finite() && c.rate_hz > 0.0) {
        return bad("rate_hz", c.rate_hz, "must be positive and finite");
    }
    if !c.belt_speed_mps.is_finite() {
        return bad("belt_speed_mps", c.belt_speed_mps, "must be finite");
    }
    if c.friction_coefficient.is_nan() || c.friction_coefficient < 0.0 {
        return bad(
            "friction_coefficient",
            c.friction_coefficient,
            "must be ≥ 0",
        );
    }
    if c.fall_pitch_limit_rad.is_nan() || c.fall_pitch_limit_rad <= 0.0 {
        return bad(
            "fall_pitch_limit_rad",
            c.fall_pitch_limit_rad,
            "must be positive",
        );
    }
    if c.dynamics_refresh_substeps == 0 {
        return bad(
            "dynamics_refresh_substeps",
            f64::from(c.dynamics_refresh_substeps),
            "must be ≥ 1",
        );
    }
    if !(c.stand_half_stance_m.is_finite() && c.stand_half_stance_m >= 0.0) {
        return bad(
            "stand_half_stance_m",
            c.stand_half_stance_m,
            "must be ≥ 0 and finite",
        );
    }
    if let Some(h) = c.stand_hip_height_m {
        if !(h.is_finite() && h > 0.0) {
            return bad("stand_hip_height_m", h, "must be positive and finite");
        }
    }
    if let Some(b) = c.boom {
        for (field, value) in [
            ("boom.mass_kg", b.mass_kg),
            ("boom.inertia_yy_kgm2", b.inertia_yy_kgm2),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return bad(field, value, "must be ≥ 0 and finite");
            }
        }
        for value in b.com_xz_m {
            if !value.is_finite() {
                return bad("boom.com_xz_m", value, "must be finite");
            }
        }
    }
    Ok(())
}

/// A standing pose: torso upright, hip axis at `hip_height_m` above the ground (`None`: 92 % of
/// the leg length), the left foot `half_stance_m` ahead of the hip and the right foot as far
/// behind, both on the ground, knees flexed. Solved by Newton's method on the model's own
/// kinematics, so it holds for any design.
pub fn standing_pose(
    model: &PlanarModel,
    hip_height_m: Option<f64>,
    half_stance_m: f64,
) -> Result<Vec<f64>> {
    let legs = model.legs()?;
    let mut q = model.nominal_pose()?;
    q[0] = 0.0;
    q[1] = 0.0;
    q[2] = 0.0;
    let (thigh, shin) = model.leg_lengths(&q, Side::Left)?;
    let height = hip_height_m.unwrap_or(0.92 * (thigh + shin));
    q[1] = height;
    for (side, dx) in [(Side::Left, half_stance_m), (Side::Right, -half_stance_m)] {
        let leg = legs.side(side);
        let (ch, ck) = (
            model.joints[leg.hip].coordinate,
            model.joints[leg.knee].coordinate,
        );
        q[ch] = -0.4;
        q[ck] = 0.8;
        let target = [dx, 0.0];
        for _ in 0..50 {
            let p = model.frame_position(&q, leg.foot)?;
            let e = [p[0] - target[0], p[1] - target[1]];
            if e[0].abs().max(e[1].abs()) < 1e-12 {
                break;
            }
            let eps = 1e-7;
            let mut jac = [[0.0; 2]; 2];
            for (col, &c) in [ch, ck].iter().enumerate() {
                let mut qp = q.clone();
                qp[c] += eps;
                let pp = model.frame_position(&qp, leg.foot)?;
                jac[0][col] = (pp[0] - p[0]) / eps;
                jac[1][col] = (pp[1] - p[1]) / eps;
            }
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            if det.abs() < 1e-12 {
                return Err(ModelError::Singular {
                    what: "standing pose inverse kinematics",
                }
                .into());
            }
            q[ch] -= (jac[1][1] * e[0] - jac[0][1] * e[1]) / det;
            q[ck] -= (-jac[1][0] * e[0] + jac[0][0] * e[1]) / det;
        }
        let p = model.frame_position(&q, leg.foot)?;
        if (p[0] - target[0]).abs() > 1e-9 || p[1].abs() > 1e-9 {
            return Err(RobotSimError::Config {
                field: "stand_hip_height_m",
                value: height,
                reason: "the feet cannot reach the ground at this height and stance",
            });
        }
    }
    Ok(q)
}
