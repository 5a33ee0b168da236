//! # model: the planar ADAM, exactly
//!
//! The ground floor of adam-hzd. Everything the planner optimizes and the runtime executes is
//! computed here, once:
//!
//! ```text
//! URDF ──(urdf)──▶ PlanarModel ──(kinematics)──▶ poses, Jacobians, J̇q̇
//!                      │                              │
//!                      └──────(dynamics)──────────────┴──▶ D(q), H(q,q̇), B, stance dynamics + λ,
//!                                                             impact map Δ + relabeling
//! DesignLengths ──(design: cubic inertia fits)──▶ URDF text + PlanarModel   (GenerateModel)
//! Bézier α, phase τ(q) ──(bezier, phase)──▶ y^d, dy^d/dτ, d²y^d/dτ²  ──(gait)──▶ gait file JSON
//! gait files by speed, each with its check ──(library)──▶ gait library JSON
//! ```
//!
//! Each revolute joint may carry a drive ([`JointDrive`], from the URDF's `<dynamics>` and
//! `<transmission>`): the A1 rotor's armature N² J_rotor in D (and so in the impact map) and
//! viscous friction b q̇ in H, seen alike by the planner, the Poincaré check and the simulator;
//! the torque constant and winding resistance are for the planner's electrical cost.
//!
//! Every kinematic and dynamic function is generic over the scalar [`Real`]: `f64` for the
//! runtime and num-dual numbers (`Dual64`, `HyperDual64`, `DualSVec64<N>`, ...) for exact
//! derivatives in the planner.
//!
//! ```no_run
//! use model::{design::DesignLengths, PlanarModel};
//! let robot = PlanarModel::from_urdf_file("configs/robots/adam_planar.urdf")?;
//! let q = robot.nominal_pose()?;
//! let dq = vec![0.0; robot.dof()];
//! let dynamics = robot.dynamics(&q, &dq)?;
//! println!("D(q) = {}", dynamics.mass_matrix);
//! let (co_designed, urdf_text) = model::design::generate_model(&DesignLengths::ADAM)?;
//! # Ok::<(), model::ModelError>(())
//! ```

pub mod bezier;
pub mod design;
pub mod dynamics;
mod error;
pub mod gait;
mod json_path;
pub mod kinematics;
pub mod library;
pub mod linalg;
pub mod phase;
mod report;
pub mod robot;
pub mod urdf;

pub use error::{ModelError, Result};
pub use num_dual;
pub use robot::{JointDrive, JointKind, PlanarModel, Side};

/// The scalar of every model computation: `f64` or a num-dual number over `f64`.
pub trait Real:
    num_dual::DualNum<Primitive = f64> + Copy + num_traits::Zero + num_traits::One
{
}
impl<T: num_dual::DualNum<Primitive = f64> + Copy> Real for T {}
