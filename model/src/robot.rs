//! The planar kinematic tree of a robot in its sagittal (x–z) plane.
//!
//! Coordinates: `q = [x_m, z_m, pitch_rad, q_1 … q_nj]`, the floating base (the root link: ADAM's
//! torso) followed by one coordinate per non-fixed joint, depth-first from the root with siblings
//! in file order (ADAM: left hip, right hip, then the left leg's design and knee joints, then the
//! right leg's). x points forward, z up, pitch is a rotation about +y (positive pitch turns +x
//! towards −z, the URDF convention).
//!
//! Joint roles follow the joint type: a revolute joint is an actuated joint (a column of B), a
//! prismatic joint is a *design virtual joint* (the paper's q_D: a massless link whose length the
//! co-design optimizes; fixed on the real robot, unactuated in B).
//!
//! # Biped naming convention
//! The planner, the impact relabeling and the phase variable find the legs by name:
//! joints `left_hip_pitch`, `left_knee_pitch`, `right_hip_pitch`, `right_knee_pitch`; point-foot
//! frames (links attached by a fixed joint) `left_foot`, `right_foot`; optional design joints
//! `left_thigh_design`, `left_shin_design`, `right_thigh_design`, `right_shin_design`.
//! Any planar point-foot biped whose URDF uses these names can be planned.

use crate::{ModelError, Result};
use serde::{Deserialize, Serialize};

/// Number of floating-base coordinates (x, z, pitch).
pub const BASE_DOF: usize = 3;
/// Largest number of bodies (non-fixed links) the allocation-free kinematics supports. ADAM has
/// 9 (with its design-joint bodies). Every per-body array is this long, and the planner's
/// derivative evaluations move them around: a needlessly large capacity is paid in memory traffic.
pub const MAX_BODIES: usize = 16;
/// Largest number of coordinates the allocation-free kinematics supports.
pub const MAX_DOF: usize = MAX_BODIES + BASE_DOF;

/// Mass properties of a body in the sagittal plane, in its body frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyInertia<S> {
    /// Mass in kg.
    pub mass_kg: S,
    /// Centre of mass (x, z) in the body frame, m.
    pub com_xz_m: [S; 2],
    /// Moment of inertia about the y axis through the centre of mass, kg·m².
    pub inertia_yy_kgm2: S,
}

impl BodyInertia<f64> {
    /// No mass.
    pub const ZERO: Self = Self {
        mass_kg: 0.0,
        com_xz_m: [0.0, 0.0],
        inertia_yy_kgm2: 0.0,
    };

    /// Adds another body's mass properties given in this frame (parallel-axis theorem).
    pub fn combine(&self, other: &Self) -> Self {
        let m = self.mass_kg + other.mass_kg;
        if m <= 0.0 {
            return Self::ZERO;
        }
        let com = [
            (self.mass_kg * self.com_xz_m[0] + other.mass_kg * other.com_xz_m[0]) / m,
            (self.mass_kg * self.com_xz_m[1] + other.mass_kg * other.com_xz_m[1]) / m,
        ];
        let d2 = |c: [f64; 2]| (c[0] - com[0]).powi(2) + (c[1] - com[1]).powi(2);
        Self {
            mass_kg: m,
            com_xz_m: com,
            inertia_yy_kgm2: self.inertia_yy_kgm2
                + self.mass_kg * d2(self.com_xz_m)
                + other.inertia_yy_kgm2
                + other.mass_kg * d2(other.com_xz_m),
        }
    }
}

/// What a joint does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind {
    /// Rotation about ±y; `axis_sign` is +1 for axis (0, 1, 0) and −1 for (0, −1, 0).
    Revolute {
        /// ±1.
        axis_sign: f64,
    },
    /// Translation along a unit axis (x, z) in the joint frame.
    Prismatic {
        /// Unit axis (x, z).
        axis_xz: [f64; 2],
    },
}

/// Role of a joint in the HZD problem.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointRole {
    /// Driven by a motor: a column of B.
    Actuated,
    /// A design virtual joint (massless prismatic link): fixed on hardware, optimized by co-design.
    Design,
}

/// A non-fixed joint: it creates a body and a coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// URDF name.
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Actuated or design.
    pub role: JointRole,
    /// The body this joint moves.
    pub body: usize,
    /// Index of its coordinate in q.
    pub coordinate: usize,
    /// Lower position limit (rad or m).
    pub lower: f64,
    /// Upper position limit (rad or m).
    pub upper: f64,
    /// Effort limit (N·m or N); 0 when the URDF gives none.
    pub effort_limit: f64,
    /// Velocity limit (rad/s or m/s), as the URDF gives it (0 for the rigid design joints).
    pub velocity_limit: f64,
    /// The joint's drive: viscous friction and the actuator behind it (all zero when the URDF
    /// gives none). Only revolute joints carry one.
    pub drive: JointDrive,
}

/// Viscous friction of a joint and the actuator that drives it, read from the URDF
/// (`<dynamics damping=…>` and a `<transmission>`, see [`crate::urdf`]).
///
/// The dynamics use two numbers: the **armature** `N² J_rotor` (the rotor's inertia reflected
/// through the gear, added to the joint's diagonal entry of the mass matrix D, so it also
/// enters the impact map) and the **viscous friction** `b q̇` (added to the drift H: a torque
/// `−b q̇` on the joint). The torque constant and the winding resistance are for the electrical
/// cost only. A model without the data has zero armature and friction: the rigid-body model.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointDrive {
    /// Viscous friction coefficient b (joint side), N·m·s/rad.
    pub damping_nms_per_rad: f64,
    /// Gear ratio N (motor turns per joint turn), when given.
    pub gear_ratio: Option<f64>,
    /// Rotor inertia about its axis (motor side), kg·m², when given.
    pub rotor_inertia_kgm2: Option<f64>,
    /// Motor torque constant k_t (motor side), N·m/A, when given.
    pub torque_constant_nm_per_a: Option<f64>,
    /// Winding resistance R in the copper loss i² R (i the torque-producing current), Ω, when
    /// given.
    pub winding_resistance_ohm: Option<f64>,
}

impl JointDrive {
    /// The reflected rotor inertia N² J_rotor (joint side), kg·m²; zero unless both the gear
    /// ratio and the rotor inertia are given.
    pub fn armature_kgm2(&self) -> f64 {
        match (self.gear_ratio, self.rotor_inertia_kgm2) {
            (Some(n), Some(j)) => n * n * j,
            _ => 0.0,
        }
    }

    /// The copper-loss coefficient R / (N k_t)², W/(N·m)²: the winding's Joule heat per squared
    /// joint torque. `Err(field)` names the first constant that is missing.
    pub fn copper_loss_w_per_nm2(&self) -> std::result::Result<f64, &'static str> {
        let n = self.gear_ratio.ok_or("mechanicalReduction")?;
        let kt = self.torque_constant_nm_per_a.ok_or("torqueConstant")?;
        let r = self.winding_resistance_ohm.ok_or("windingResistance")?;
        Ok(r / (n * kt * n * kt))
    }
}

/// A rigid body: one non-fixed link with the fixed links merged into it.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Name of its URDF link.
    pub name: String,
    /// Parent body (None for the floating base).
    pub parent: Option<usize>,
    /// The joint that moves it (None for the base).
    pub joint: Option<usize>,
    /// Joint origin (x, z) in the parent body frame, m.
    pub origin_xz_m: [f64; 2],
    /// Joint origin pitch in the parent body frame, rad.
    pub origin_pitch_rad: f64,
    /// Mass properties, fixed links included.
    pub inertia: BodyInertia<f64>,
    /// Indices of the joints from the root to this body (inclusive).
    pub joint_path: Vec<usize>,
}

/// A named point rigidly attached to a body (a merged fixed link, e.g. a foot).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// URDF link name.
    pub name: String,
    /// Body it is fixed to.
    pub body: usize,
    /// Position (x, z) in the body frame, m.
    pub offset_xz_m: [f64; 2],
    /// Orientation in the body frame, rad.
    pub pitch_rad: f64,
}

/// Left or right.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Left leg.
    Left,
    /// Right leg.
    Right,
}

impl Side {
    /// The other side.
    pub fn other(self) -> Self {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
    /// `left` or `right`, the prefix of the biped naming convention.
    pub fn prefix(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// Indices of one leg's joints and foot frame (biped naming convention).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Leg {
    /// Index of `<side>_hip_pitch` in `joints`.
    pub hip: usize,
    /// Index of `<side>_knee_pitch` in `joints`.
    pub knee: usize,
    /// Index of `<side>_foot` in `frames`.
    pub foot: usize,
    /// Index of `<side>_thigh_design`, when present.
    pub thigh_design: Option<usize>,
    /// Index of `<side>_shin_design`, when present.
    pub shin_design: Option<usize>,
}

/// Both legs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Legs {
    /// Left leg.
    pub left: Leg,
    /// Right leg.
    pub right: Leg,
}

impl Legs {
    /// The leg on `side`.
    pub fn side(&self, side: Side) -> &Leg {
        match side {
            Side::Left => &self.left,
            Side::Right => &self.right,
        }
    }
}

/// A planar floating-base robot model.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarModel {
    /// Robot name from the URDF.
    pub name: String,
    /// Bodies in topological order (parents first); body 0 is the floating base.
    pub bodies: Vec<Body>,
    /// Non-fixed joints; joint `j` has coordinate `BASE_DOF + j`.
    pub joints: Vec<Joint>,
    /// Named frames (merged fixed links, including each body's own link at its origin).
    pub frames: Vec<Frame>,
    /// Gravitational acceleration, m/s² (positive; gravity points along −z).
    pub gravity_mps2: f64,
}

impl PlanarModel {
    /// Number of coordinates, `BASE_DOF + joints`.
    pub fn dof(&self) -> usize {
        BASE_DOF + self.joints.len()
    }

    /// Index of the joint called `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Index of the frame called `name`.
    pub fn frame_index(&self, name: &str) -> Option<usize> {
        self.frames.iter().position(|f| f.name == name)
    }

    /// Index of the joint called `name`, or an error naming it.
    pub fn require_joint(&self, name: &str) -> Result<usize> {
        self.joint_index(name)
            .ok_or_else(|| ModelError::MissingNamed {
                model: self.name.clone(),
                kind: "joint",
                name: name.to_string(),
            })
    }

    /// Index of the frame called `name`, or an error naming it.
    pub fn require_frame(&self, name: &str) -> Result<usize> {
        self.frame_index(name)
            .ok_or_else(|| ModelError::MissingNamed {
                model: self.name.clone(),
                kind: "frame",
                name: name.to_string(),
            })
    }

    /// Joint indices of the actuated joints, in coordinate order (the columns of B).
    pub fn actuated_joints(&self) -> Vec<usize> {
        (0..self.joints.len())
            .filter(|&j| self.joints[j].role == JointRole::Actuated)
            .collect()
    }

    /// Joint indices of the design virtual joints.
    pub fn design_joints(&self) -> Vec<usize> {
        (0..self.joints.len())
            .filter(|&j| self.joints[j].role == JointRole::Design)
            .collect()
    }

    /// Total mass, kg.
    pub fn total_mass_kg(&self) -> f64 {
        self.bodies.iter().map(|b| b.inertia.mass_kg).sum()
    }

    /// The actuation matrix B (dof × actuated joints): a unit entry at each actuated coordinate.
    pub fn actuation_matrix(&self) -> nalgebra::DMatrix<f64> {
        let act = self.actuated_joints();
        let mut b = nalgebra::DMatrix::zeros(self.dof(), act.len());
        for (col, &j) in act.iter().enumerate() {
            b[(self.joints[j].coordinate, col)] = 1.0;
        }
        b
    }

    /// The legs, found by the biped naming convention.
    pub fn legs(&self) -> Result<Legs> {
        let leg = |side: Side| -> Result<Leg> {
            let p = side.prefix();
            Ok(Leg {
                hip: self.require_joint(&format!("{p}_hip_pitch"))?,
                knee: self.require_joint(&format!("{p}_knee_pitch"))?,
                foot: self.require_frame(&format!("{p}_foot"))?,
                thigh_design: self.joint_index(&format!("{p}_thigh_design")),
                shin_design: self.joint_index(&format!("{p}_shin_design")),
            })
        };
        Ok(Legs {
            left: leg(Side::Left)?,
            right: leg(Side::Right)?,
        })
    }

    /// The relabeling permutation of the reset map: `perm[i]` is the coordinate whose value
    /// becomes coordinate `i` after swapping the roles of the legs. Actuated joints named
    /// `left_*` and `right_*` swap; the base and the design joints keep their values (the paper's
    /// Δ_q̃, exact under the symmetric-design constraint q_LT = q_RT, q_LS = q_RS).
    pub fn relabel_permutation(&self) -> Vec<usize> {
        let mut perm: Vec<usize> = (0..self.dof()).collect();
        for (j, joint) in self.joints.iter().enumerate() {
            if joint.role != JointRole::Actuated {
                continue;
            }
            let mirror = if let Some(rest) = joint.name.strip_prefix("left_") {
                format!("right_{rest}")
            } else if let Some(rest) = joint.name.strip_prefix("right_") {
                format!("left_{rest}")
            } else {
                continue;
            };
            if let Some(m) = self.joint_index(&mirror) {
                perm[BASE_DOF + j] = BASE_DOF + m;
            }
        }
        perm
    }

    /// Applies the relabeling permutation to a coordinate (or velocity) vector.
    pub fn relabel<S: Copy>(&self, v: &[S]) -> Vec<S> {
        self.relabel_permutation().iter().map(|&i| v[i]).collect()
    }

    /// Sets every design joint so that each leg's thigh and shin have the given total lengths;
    /// the lengths at design coordinate zero are measured from the model. Returns q.
    pub fn with_design(
        &self,
        q: &[f64],
        thigh_length_m: f64,
        shin_length_m: f64,
    ) -> Result<Vec<f64>> {
        let legs = self.legs()?;
        let mut q = q.to_vec();
        for side in [Side::Left, Side::Right] {
            let leg = legs.side(side);
            let (Some(td), Some(sd)) = (leg.thigh_design, leg.shin_design) else {
                return Err(ModelError::MissingNamed {
                    model: self.name.clone(),
                    kind: "joint",
                    name: format!(
                        "{}_thigh_design / {}_shin_design",
                        side.prefix(),
                        side.prefix()
                    ),
                });
            };
            let mut zero = q.clone();
            zero[self.joints[td].coordinate] = 0.0;
            zero[self.joints[sd].coordinate] = 0.0;
            let (thigh0, shin0) = self.leg_lengths(&zero, side)?;
            q[self.joints[td].coordinate] = thigh_length_m - thigh0;
            q[self.joints[sd].coordinate] = shin_length_m - shin0;
        }
        Ok(q)
    }

    /// Thigh (hip axis to knee axis) and shin (knee axis to foot point) lengths of one leg at q, m.
    pub fn leg_lengths(&self, q: &[f64], side: Side) -> Result<(f64, f64)> {
        let legs = self.legs()?;
        let leg = legs.side(side);
        let hip = self.joint_position(q, leg.hip)?;
        let knee = self.joint_position(q, leg.knee)?;
        let foot = self.frame_position(q, leg.foot)?;
        let d = |a: [f64; 2], b: [f64; 2]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        Ok((d(hip, knee), d(knee, foot)))
    }

    /// A standing pose: base upright, every joint at zero (clamped into its limits), the lowest
    /// foot on the ground (z = 0).
    pub fn nominal_pose(&self) -> Result<Vec<f64>> {
        let mut q = vec![0.0; self.dof()];
        for j in &self.joints {
            q[j.coordinate] = 0.0_f64.clamp(j.lower, j.upper);
        }
        let legs = self.legs()?;
        let lf = self.frame_position(&q, legs.left.foot)?;
        let rf = self.frame_position(&q, legs.right.foot)?;
        q[1] = -lf[1].min(rf[1]);
        Ok(q)
    }
}
