//! Rigid-body dynamics of the planar model, generic over the scalar type.
//!
//! `D(q) q̈ + H(q, q̇) = B u + J_c(q)ᵀ λ`, with
//! - `D = Σ_b m_b J_bᵀ J_b + I_b J_θbᵀ J_θb` (COM Jacobians J_b, angular Jacobians J_θb),
//! - `H = Σ_b m_b J_bᵀ (J̇_b q̇ + [0, g])`, the projected Newton–Euler form: planar bodies have
//!   no gyroscopic term and the angular bias accelerations vanish, so this is the whole of
//!   Coriolis, centrifugal and gravity terms. The tests check it against the Lagrangian
//!   (Christoffel symbols of D, differentiated with dual numbers) and energy conservation.
//!
//! The joint drives ([`crate::robot::JointDrive`]) add to both: each revolute joint's armature
//! N² J_rotor to its diagonal entry of D (so the impact map sees the rotors too) and its viscous
//! friction b q̇ to its entry of H. Every function here (D and H, inverse dynamics, the
//! constrained dynamics, the impact map, the kinetic energy ½ N² J_rotor q̇²) includes them, so
//! the planner, the Poincaré check and the simulator all see the same actuators; a model without
//! drive data is the rigid-body model.
//!
//! The stance foot is a holonomic constraint `p_st(q) = const` with contact force λ = (F_x, F_z)
//! in the world; the impact with the ground is rigid and plastic (the paper's reset map Δ, with the
//! left/right relabeling in [`PlanarModel::reset_map`]).

use crate::kinematics::{rot_sin_cos, BodyStates, Coefficient};
use crate::linalg::{solve_in_place, solve_many_in_place};
use crate::robot::{BodyInertia, PlanarModel, Side, MAX_DOF};
use crate::{ModelError, Real, Result};
use nalgebra::{DMatrix, DVector};

/// Mass matrix, drift and the body states they came from.
#[derive(Clone, Debug)]
pub struct Dynamics<S: Real> {
    /// D(q), dof × dof.
    pub mass_matrix: DMatrix<S>,
    /// H(q, q̇) = C(q, q̇) q̇ + G(q).
    pub drift: DVector<S>,
}

/// Result of the constrained (stance) dynamics.
#[derive(Clone, Debug)]
pub struct ConstrainedDynamics<S: Real> {
    /// q̈, rad/s² or m/s².
    pub ddq: DVector<S>,
    /// Contact force on the robot at each constrained frame, world (F_x, F_z), N.
    pub forces_n: Vec<[S; 2]>,
}

/// Result of the impact map.
#[derive(Clone, Debug)]
pub struct Impact<S: Real> {
    /// Post-impact velocity (before relabeling).
    pub dq_plus: DVector<S>,
    /// Impulse on the robot at the impacting foot, world (Λ_x, Λ_z), N·s.
    pub impulse_ns: [S; 2],
}

/// Post-impact state after the relabeling.
#[derive(Clone, Debug)]
pub struct Reset<S: Real> {
    /// Relabeled configuration.
    pub q: Vec<S>,
    /// Relabeled velocity.
    pub dq: Vec<S>,
    /// Impulse on the robot at the impacting foot, N·s.
    pub impulse_ns: [S; 2],
}

fn lift<S: Real>(i: &BodyInertia<f64>) -> BodyInertia<S> {
    BodyInertia {
        mass_kg: S::from(i.mass_kg),
        com_xz_m: [S::from(i.com_xz_m[0]), S::from(i.com_xz_m[1])],
        inertia_yy_kgm2: S::from(i.inertia_yy_kgm2),
    }
}

impl PlanarModel {
    /// The model's mass properties, one per body, lifted to the scalar type.
    pub fn inertias<S: Real>(&self) -> Vec<BodyInertia<S>> {
        self.bodies.iter().map(|b| lift(&b.inertia)).collect()
    }

    /// The model's mass properties, one per body, as [`Constant`](crate::kinematics::Constant)s
    /// (for [`Self::inverse_dynamics_in`] when they are not being differentiated).
    pub fn constant_inertias(&self) -> Vec<BodyInertia<crate::kinematics::Constant>> {
        use crate::kinematics::{constants, Constant};
        self.bodies
            .iter()
            .map(|b| BodyInertia {
                mass_kg: Constant(b.inertia.mass_kg),
                com_xz_m: constants(b.inertia.com_xz_m),
                inertia_yy_kgm2: Constant(b.inertia.inertia_yy_kgm2),
            })
            .collect()
    }

    /// D(q) and H(q, q̇) with the model's own mass properties.
    pub fn dynamics<S: Real>(&self, q: &[S], dq: &[S]) -> Result<Dynamics<S>> {
        self.dynamics_with(&self.inertias(), q, dq)
    }

    /// D(q) and H(q, q̇) with the given mass properties (one per body), so that the co-design can
    /// differentiate through link inertias that depend on link lengths.
    pub fn dynamics_with<S: Real>(
        &self,
        inertias: &[BodyInertia<S>],
        q: &[S],
        dq: &[S],
    ) -> Result<Dynamics<S>> {
        if inertias.len() != self.bodies.len() {
            return Err(ModelError::Dimension {
                what: "inertias",
                expected: self.bodies.len(),
                found: inertias.len(),
            });
        }
        let mut st = BodyStates::zeroed();
        self.body_states_into(q, dq, &mut st)?;
        let n = self.dof();
        let z = S::zero();
        let mut dmat = DMatrix::from_element(n, n, z);
        let mut h = DVector::from_element(n, z);
        let g = S::from(self.gravity_mps2);
        let mut jac = DMatrix::from_element(2, n, z);
        let mut cols: Vec<usize> = Vec::with_capacity(n);
        for (b, inertia) in inertias.iter().enumerate() {
            if inertia.mass_kg.re() == 0.0 && inertia.inertia_yy_kgm2.re() == 0.0 {
                continue;
            }
            let m = inertia.mass_kg;
            let com = self.point_position(&st, b, inertia.com_xz_m);
            jac.fill(z);
            cols.clear();
            cols.extend(0..crate::robot::BASE_DOF);
            cols.extend(
                self.bodies[b]
                    .joint_path
                    .iter()
                    .map(|&j| self.joints[j].coordinate),
            );
            self.point_jacobian_into(&st, b, com, |r, c, v| jac[(r, c)] = v);
            let bias = self.point_bias_acceleration(&st, b, inertia.com_xz_m);
            let f = [m * bias[0], m * (bias[1] + g)];
            for &i in &cols {
                h[i] += jac[(0, i)] * f[0] + jac[(1, i)] * f[1];
                for &k in &cols {
                    dmat[(i, k)] += m * (jac[(0, i)] * jac[(0, k)] + jac[(1, i)] * jac[(1, k)]);
                }
            }
            let ang = self.angular_jacobian(b);
            for i in 0..n {
                if ang[i] == 0.0 {
                    continue;
                }
                for k in 0..n {
                    if ang[k] != 0.0 {
                        dmat[(i, k)] += inertia.inertia_yy_kgm2 * (ang[i] * ang[k]);
                    }
                }
            }
        }
        for (c, armature, damping) in self.drives() {
            if armature != 0.0 {
                dmat[(c, c)] += S::from(armature);
            }
            if damping != 0.0 {
                h[c] += dq[c] * damping;
            }
        }
        Ok(Dynamics {
            mass_matrix: dmat,
            drift: h,
        })
    }

    /// The revolute joints with a drive: (coordinate, armature N² J_rotor in kg·m², viscous
    /// friction b in N·m·s/rad). Never allocates.
    pub fn drives(&self) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        self.joints.iter().filter_map(|j| {
            let crate::robot::JointKind::Revolute { .. } = j.kind else {
                return None;
            };
            let (a, b) = (j.drive.armature_kgm2(), j.drive.damping_nms_per_rad);
            (a != 0.0 || b != 0.0).then_some((j.coordinate, a, b))
        })
    }

    /// Joint rate q̇ of revolute joint `j` from body states: its body's angular velocity less its
    /// parent's, times the axis sign (so the drives need no q̇ beside the states).
    fn revolute_rate<S: Real>(&self, st: &BodyStates<S>, j: usize) -> S {
        let joint = &self.joints[j];
        let body = joint.body;
        let parent = self.bodies[body].parent.unwrap_or(0);
        match joint.kind {
            crate::robot::JointKind::Revolute { axis_sign } => {
                (st.omega[body] - st.omega[parent]) * axis_sign
            }
            crate::robot::JointKind::Prismatic { .. } => S::zero(),
        }
    }

    /// Each drive's (joint index, armature, damping), for the rate from body states.
    fn drive_joints(&self) -> impl Iterator<Item = (usize, usize, f64, f64)> + '_ {
        self.joints.iter().enumerate().filter_map(|(i, j)| {
            let crate::robot::JointKind::Revolute { .. } = j.kind else {
                return None;
            };
            let (a, b) = (j.drive.armature_kgm2(), j.drive.damping_nms_per_rad);
            (a != 0.0 || b != 0.0).then_some((i, j.coordinate, a, b))
        })
    }

    /// D(q) and H(q, q̇) with the model's own mass properties from body states already computed
    /// at (q, q̇) ([`PlanarModel::body_states`]), written into `mass_matrix` (dof × dof) and
    /// `drift` (dof). Never allocates: the simulator calls it at 10 kHz. Same sums as
    /// [`PlanarModel::dynamics`], in the same order.
    pub fn dynamics_into(
        &self,
        st: &BodyStates<f64>,
        mass_matrix: &mut DMatrix<f64>,
        drift: &mut DVector<f64>,
    ) -> Result<()> {
        let n = self.dof();
        if mass_matrix.shape() != (n, n) || drift.len() != n {
            return Err(ModelError::Dimension {
                what: "dynamics_into buffers",
                expected: n,
                found: drift.len(),
            });
        }
        mass_matrix.fill(0.0);
        drift.fill(0.0);
        let g = self.gravity_mps2;
        // Columns of a body's Jacobian: the base, then the joints on its path (≤ MAX_DOF).
        let mut cols = [0usize; MAX_DOF];
        let mut jac = [[0.0f64; MAX_DOF]; 2];
        // (sin, cos) of each body's pitch, from the kinematics pass: the centre of mass, its bias
        // acceleration and the prismatic columns of the Jacobians all rotate by them.
        let sin_cos = |c: usize| st.sin_cos[c];
        for (b, body) in self.bodies.iter().enumerate() {
            let inertia = &body.inertia;
            if inertia.mass_kg == 0.0 && inertia.inertia_yy_kgm2 == 0.0 {
                continue;
            }
            let m = inertia.mass_kg;
            // `point_position` and `point_bias_acceleration`, sharing the rotation.
            let com_offset = rot_sin_cos(sin_cos(b), inertia.com_xz_m);
            let com = [
                st.pose[b].xz_m[0] + com_offset[0],
                st.pose[b].xz_m[1] + com_offset[1],
            ];
            let mut nc = 0;
            for c in 0..crate::robot::BASE_DOF {
                cols[nc] = c;
                nc += 1;
            }
            for &j in &body.joint_path {
                cols[nc] = self.joints[j].coordinate;
                nc += 1;
            }
            for &c in &cols[..nc] {
                jac[0][c] = 0.0;
                jac[1][c] = 0.0;
            }
            self.point_jacobian_with(st, b, com, sin_cos, |r, c, v| jac[r][c] = v);
            let w2 = st.omega[b] * st.omega[b];
            let bias = [
                st.bias_acc_xz[b][0] + -w2 * com_offset[0],
                st.bias_acc_xz[b][1] + -w2 * com_offset[1],
            ];
            let f = [m * bias[0], m * (bias[1] + g)];
            for (a, &i) in cols[..nc].iter().enumerate() {
                drift[i] += jac[0][i] * f[0] + jac[1][i] * f[1];
                // D is symmetric: each pair once (the products commute, so both entries get
                // the same bits as `dynamics` gives them).
                for &k in &cols[a..nc] {
                    let v = m * (jac[0][i] * jac[0][k] + jac[1][i] * jac[1][k]);
                    mass_matrix[(i, k)] += v;
                    if k != i {
                        mass_matrix[(k, i)] += v;
                    }
                }
            }
            // Angular Jacobian: 1 on the base pitch, the axis sign on each revolute joint.
            let mut ang = [(0usize, 0.0f64); MAX_DOF];
            let mut na = 0;
            ang[na] = (2, 1.0);
            na += 1;
            for &j in &body.joint_path {
                if let crate::robot::JointKind::Revolute { axis_sign } = self.joints[j].kind {
                    ang[na] = (self.joints[j].coordinate, axis_sign);
                    na += 1;
                }
            }
            // Coordinate order, as `dynamics` visits them.
            ang[..na].sort_unstable_by_key(|&(c, _)| c);
            for &(i, ai) in &ang[..na] {
                for &(k, ak) in &ang[..na] {
                    mass_matrix[(i, k)] += inertia.inertia_yy_kgm2 * (ai * ak);
                }
            }
        }
        for (j, c, armature, damping) in self.drive_joints() {
            if armature != 0.0 {
                mass_matrix[(c, c)] += armature;
            }
            if damping != 0.0 {
                drift[c] += self.revolute_rate(st, j) * damping;
            }
        }
        Ok(())
    }

    /// Inverse dynamics `D(q) q̈ + H(q, q̇)` by one forward recursion of body accelerations and a
    /// projection of each body's Newton–Euler force through its Jacobian: O(bodies × depth) and
    /// no mass matrix, which is what the planner differentiates at every collocation point.
    pub fn inverse_dynamics<S: Real>(&self, q: &[S], dq: &[S], ddq: &[S]) -> Result<DVector<S>> {
        self.inverse_dynamics_with(&self.inertias(), q, dq, ddq)
    }

    /// [`Self::inverse_dynamics`] with the given mass properties (one per body).
    pub fn inverse_dynamics_with<S: Real>(
        &self,
        inertias: &[BodyInertia<S>],
        q: &[S],
        dq: &[S],
        ddq: &[S],
    ) -> Result<DVector<S>> {
        let mut st = BodyStates::zeroed();
        self.body_states_into(q, dq, &mut st)?;
        let mut out = DVector::from_element(self.dof(), S::zero());
        self.inverse_dynamics_in(inertias, &st, ddq, out.as_mut_slice())?;
        Ok(out)
    }

    /// [`Self::inverse_dynamics_with`] from body states already computed at (q, q̇) by
    /// [`Self::body_states_into`], written into `out` (length dof). Never allocates.
    ///
    /// The result depends on the states only through relative positions, angular velocities
    /// and bias accelerations, so it is the same (up to rounding) for states computed with any
    /// base position and base linear velocity: a caller that needs the base shifted (a pinned
    /// stance foot at the origin) may pass states computed before the shift.
    ///
    /// The mass properties are scalars of the states' type, or
    /// [`Constant`](crate::kinematics::Constant)s when they do not depend on the variables
    /// being differentiated (a fixed design): the same values with fewer dual-number
    /// operations.
    pub fn inverse_dynamics_in<S: Real, I: Coefficient<S>>(
        &self,
        inertias: &[BodyInertia<I>],
        st: &BodyStates<S>,
        ddq: &[S],
        out: &mut [S],
    ) -> Result<()> {
        let n = self.dof();
        for (what, len) in [("ddq", ddq.len()), ("inverse dynamics output", out.len())] {
            if len != n {
                return Err(ModelError::Dimension {
                    what,
                    expected: n,
                    found: len,
                });
            }
        }
        let z = S::zero();
        let g = S::from(self.gravity_mps2);
        // Angular accelerations are linear in q̈ (no planar bias).
        let mut alpha = [z; crate::robot::MAX_BODIES];
        alpha[0] = ddq[2];
        for (b, body) in self.bodies.iter().enumerate().skip(1) {
            let (Some(p), Some(j)) = (body.parent, body.joint) else {
                continue;
            };
            alpha[b] = alpha[p];
            if let crate::robot::JointKind::Revolute { axis_sign } = self.joints[j].kind {
                alpha[b] += ddq[self.joints[j].coordinate] * axis_sign;
            }
        }
        out.fill(z);
        // Reused by every body (only the first nc entries are read): initialising it once
        // matters when S is a wide dual number.
        let mut cols = [(0usize, z, z); crate::robot::MAX_DOF];
        for (b, inertia) in inertias.iter().enumerate() {
            if inertia.mass_kg.value() == 0.0 && inertia.inertia_yy_kgm2.value() == 0.0 {
                continue;
            }
            let com = self.point_position(st, b, inertia.com_xz_m);
            let bias = self.point_bias_acceleration(st, b, inertia.com_xz_m);
            // a = J q̈ + J̇ q̇, then f = m (a + g ẑ); generalized force Jᵀ f + J_θᵀ I θ̈. The
            // base's x and z columns of J are the unit vectors: their products with q̈ and f
            // are the entries themselves (the products by 1 and 0 they replace add nothing but
            // the sign of a zero).
            let mut nc = 0;
            self.pitch_and_joint_columns(
                st,
                b,
                com,
                |c| st.sin_cos[c],
                |c, col| {
                    cols[nc] = (c, col[0], col[1]);
                    nc += 1;
                },
            );
            let mut a = bias;
            a[0] += ddq[0];
            a[1] += ddq[1];
            for &(c, jx, jz) in &cols[..nc] {
                a[0] += jx * ddq[c];
                a[1] += jz * ddq[c];
            }
            let f = [
                inertia.mass_kg.times_left(a[0]),
                inertia.mass_kg.times_left(a[1] + g),
            ];
            out[0] += f[0];
            out[1] += f[1];
            for &(c, jx, jz) in &cols[..nc] {
                out[c] += jx * f[0] + jz * f[1];
            }
            let torque = inertia.inertia_yy_kgm2.times_left(alpha[b]);
            out[2] += torque;
            for &j in &self.bodies[b].joint_path {
                if let crate::robot::JointKind::Revolute { axis_sign } = self.joints[j].kind {
                    out[self.joints[j].coordinate] += torque * axis_sign;
                }
            }
        }
        for (j, c, armature, damping) in self.drive_joints() {
            if armature != 0.0 {
                out[c] += ddq[c] * armature;
            }
            if damping != 0.0 {
                out[c] += self.revolute_rate(st, j) * damping;
            }
        }
        Ok(())
    }

    /// Kinetic energy ½ Σ (m |v_com|² + I ω²) from the velocity recursion (independent of D), plus
    /// each rotor's ½ N² J_rotor q̇², J.
    pub fn kinetic_energy<S: Real>(&self, q: &[S], dq: &[S]) -> Result<S> {
        let mut st = BodyStates::zeroed();
        self.body_states_into(q, dq, &mut st)?;
        let mut t = S::zero();
        for (b, body) in self.bodies.iter().enumerate() {
            let i = lift::<S>(&body.inertia);
            let v = self.point_velocity(&st, b, i.com_xz_m);
            let w = st.omega[b];
            t += (i.mass_kg * (v[0] * v[0] + v[1] * v[1]) + i.inertia_yy_kgm2 * w * w) * 0.5;
        }
        for (c, armature, _) in self.drives() {
            t += dq[c] * dq[c] * (0.5 * armature);
        }
        Ok(t)
    }

    /// Potential energy Σ m g z_com (zero at z = 0), J.
    pub fn potential_energy<S: Real>(&self, q: &[S]) -> Result<S> {
        let mut st = BodyStates::zeroed();
        self.body_poses_into(q, &mut st)?;
        let mut v = S::zero();
        for (b, body) in self.bodies.iter().enumerate() {
            let com = self.body_com_in(&st, b);
            v += com[1] * (body.inertia.mass_kg * self.gravity_mps2);
        }
        Ok(v)
    }

    /// Angular momentum about the world point `p` (about +y), kg·m²/s.
    pub fn angular_momentum_about<S: Real>(&self, q: &[S], dq: &[S], p: [S; 2]) -> Result<S> {
        let mut st = BodyStates::zeroed();
        self.body_states_into(q, dq, &mut st)?;
        Ok(self.angular_momentum_in(&st, p))
    }

    /// [`Self::angular_momentum_about`] from body states already computed with q̇.
    pub fn angular_momentum_in<S: Real>(&self, st: &BodyStates<S>, p: [S; 2]) -> S {
        let mut l = S::zero();
        for (b, body) in self.bodies.iter().enumerate() {
            l += self.body_angular_momentum_in(st, b, &lift::<S>(&body.inertia), p);
        }
        l
    }

    /// Angular momentum of body `b` with mass properties `i` about the world point `p` (about
    /// +y), kg·m²/s, from body states with q̇ (the caller's inertias: a design's, or the
    /// model's; [`Self::angular_momentum_about`] sums it over the model's bodies).
    pub fn body_angular_momentum_in<S: Real>(
        &self,
        st: &BodyStates<S>,
        b: usize,
        i: &BodyInertia<S>,
        p: [S; 2],
    ) -> S {
        let c = self.point_position(st, b, i.com_xz_m);
        let v = self.point_velocity(st, b, i.com_xz_m);
        let r = [c[0] - p[0], c[1] - p[1]];
        i.mass_kg * (r[1] * v[0] - r[0] * v[1]) + i.inertia_yy_kgm2 * st.omega[b]
    }

    /// Maps actuator torques (one per actuated joint, N·m) to generalized forces B u.
    pub fn generalized_forces<S: Real>(&self, u: &[S]) -> Result<DVector<S>> {
        let act = self.actuated_joints();
        if u.len() != act.len() {
            return Err(ModelError::Dimension {
                what: "u",
                expected: act.len(),
                found: u.len(),
            });
        }
        let mut f = DVector::from_element(self.dof(), S::zero());
        for (k, &j) in act.iter().enumerate() {
            f[self.joints[j].coordinate] = u[k];
        }
        Ok(f)
    }

    /// Flight dynamics (no contact, design joints rigid).
    pub fn forward_dynamics<S: Real>(&self, q: &[S], dq: &[S], u: &[S]) -> Result<DVector<S>> {
        Ok(self.constrained_dynamics(q, dq, u, &[])?.ddq)
    }

    /// Dynamics with the frames in `contacts` held fixed in the world (pinned point feet) and the
    /// design joints rigid: solves `[D −Aᵀ; A 0] [q̈; λ] = [B u − H; −J̇ q̇]`, where A stacks the
    /// contact Jacobians and a unit row per design joint (q̈_D = 0: the design is fixed on the
    /// robot, the paper's q̇_D = 0).
    pub fn constrained_dynamics<S: Real>(
        &self,
        q: &[S],
        dq: &[S],
        u: &[S],
        contacts: &[usize],
    ) -> Result<ConstrainedDynamics<S>> {
        let n = self.dof();
        let bu = self.generalized_forces(u)?;
        let (mut a, mut rhs) = self.constrained_system(q, dq, contacts)?;
        for i in 0..n {
            rhs[i] = bu[i] + rhs[i];
        }
        solve_in_place(&mut a, &mut rhs, "constrained dynamics")?;
        let ddq = DVector::from_iterator(n, rhs.iter().take(n).copied());
        let forces_n = (0..contacts.len())
            .map(|k| [rhs[n + 2 * k], rhs[n + 2 * k + 1]])
            .collect();
        Ok(ConstrainedDynamics { ddq, forces_n })
    }

    /// q̈ of [`Self::constrained_dynamics`] for each of several inputs `inputs` at one state,
    /// with one dynamics pass and one elimination: each result is bit for bit
    /// `constrained_dynamics(q, dq, u, contacts).ddq` for its `u` (a closed-loop law that
    /// needs the accelerations for several torques, e.g. to build a decoupling matrix).
    pub fn constrained_accelerations<S: Real>(
        &self,
        q: &[S],
        dq: &[S],
        inputs: &[&[S]],
        contacts: &[usize],
    ) -> Result<Vec<DVector<S>>> {
        let n = self.dof();
        let (mut a, drift) = self.constrained_system(q, dq, contacts)?;
        let mut rhs = DMatrix::from_element(drift.len(), inputs.len(), S::zero());
        for (k, u) in inputs.iter().enumerate() {
            let bu = self.generalized_forces(u)?;
            for i in 0..drift.len() {
                rhs[(i, k)] = if i < n { bu[i] + drift[i] } else { drift[i] };
            }
        }
        solve_many_in_place(&mut a, &mut rhs, "constrained dynamics")?;
        Ok((0..inputs.len())
            .map(|k| DVector::from_iterator(n, rhs.column(k).iter().take(n).copied()))
            .collect())
    }

    /// The constrained-dynamics system `[D −Aᵀ; A 0]` and its right-hand side without the
    /// input, `[−H; −J̇ q̇; 0]` (see [`Self::constrained_dynamics`]).
    fn constrained_system<S: Real>(
        &self,
        q: &[S],
        dq: &[S],
        contacts: &[usize],
    ) -> Result<(DMatrix<S>, DVector<S>)> {
        let n = self.dof();
        let nc = 2 * contacts.len();
        let design = self.design_joints();
        let m = nc + design.len();
        let dy = self.dynamics(q, dq)?;
        let mut st = BodyStates::zeroed();
        self.body_states_into(q, dq, &mut st)?;
        let mut a = DMatrix::from_element(n + m, n + m, S::zero());
        let mut rhs = DVector::from_element(n + m, S::zero());
        a.view_mut((0, 0), (n, n)).copy_from(&dy.mass_matrix);
        for i in 0..n {
            rhs[i] = -dy.drift[i];
        }
        for (k, &frame) in contacts.iter().enumerate() {
            let jac = self.frame_jacobian(&st, frame);
            let bias = self.frame_bias_acceleration_in(&st, frame);
            for r in 0..2 {
                for c in 0..n {
                    a[(n + 2 * k + r, c)] = jac[(r, c)];
                    a[(c, n + 2 * k + r)] = -jac[(r, c)];
                }
                rhs[n + 2 * k + r] = -bias[r];
            }
        }
        for (k, &j) in design.iter().enumerate() {
            let c = self.joints[j].coordinate;
            a[(n + nc + k, c)] = S::one();
            a[(c, n + nc + k)] = -S::one();
        }
        Ok((a, rhs))
    }

    /// Rigid, plastic impact of frame `impact_frame` with the ground: the frame comes to rest,
    /// the design joints stay rigid, every other point is free (the old stance foot may lift off;
    /// the planner checks that it does). Solves `[D −Aᵀ; A 0] [q̇⁺; Λ] = [D q̇⁻; A_D q̇⁻]` with A the
    /// foot Jacobian and the design-joint rows.
    pub fn impact<S: Real>(
        &self,
        q: &[S],
        dq_minus: &[S],
        impact_frame: usize,
    ) -> Result<Impact<S>> {
        self.impact_with(&self.inertias(), q, dq_minus, impact_frame)
    }

    /// [`Self::impact`] with the given mass properties (one per body), for the co-design.
    pub fn impact_with<S: Real>(
        &self,
        inertias: &[BodyInertia<S>],
        q: &[S],
        dq_minus: &[S],
        impact_frame: usize,
    ) -> Result<Impact<S>> {
        let n = self.dof();
        let design = self.design_joints();
        let m = 2 + design.len();
        let dy = self.dynamics_with(inertias, q, dq_minus)?;
        let mut st = BodyStates::zeroed();
        self.body_poses_into(q, &mut st)?;
        let jac = self.frame_jacobian(&st, impact_frame);
        let mut a = DMatrix::from_element(n + m, n + m, S::zero());
        let mut rhs = DVector::from_element(n + m, S::zero());
        a.view_mut((0, 0), (n, n)).copy_from(&dy.mass_matrix);
        for i in 0..n {
            rhs[i] = (0..n).fold(S::zero(), |acc, k| {
                acc + dy.mass_matrix[(i, k)] * dq_minus[k]
            });
        }
        for r in 0..2 {
            for c in 0..n {
                a[(n + r, c)] = jac[(r, c)];
                a[(c, n + r)] = -jac[(r, c)];
            }
        }
        for (k, &j) in design.iter().enumerate() {
            let c = self.joints[j].coordinate;
            a[(n + 2 + k, c)] = S::one();
            a[(c, n + 2 + k)] = -S::one();
            rhs[n + 2 + k] = dq_minus[c];
        }
        solve_in_place(&mut a, &mut rhs, "impact map")?;
        Ok(Impact {
            dq_plus: DVector::from_iterator(n, rhs.iter().take(n).copied()),
            impulse_ns: [rhs[n], rhs[n + 1]],
        })
    }

    /// The paper's reset map Δ: impact of the `swing` leg's foot, then the left/right relabeling,
    /// so that the post-impact state is again a state with the *other* leg (the old stance leg's
    /// side) in the swing role.
    pub fn reset_map<S: Real>(&self, q: &[S], dq_minus: &[S], swing: Side) -> Result<Reset<S>> {
        let legs = self.legs()?;
        let imp = self.impact(q, dq_minus, legs.side(swing).foot)?;
        let dq_plus: Vec<S> = imp.dq_plus.iter().copied().collect();
        Ok(Reset {
            q: self.relabel(q),
            dq: self.relabel(&dq_plus),
            impulse_ns: imp.impulse_ns,
        })
    }
}
