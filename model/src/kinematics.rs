//! Planar forward kinematics, Jacobians, velocities and bias accelerations, generic over the
//! scalar type (f64 or any num-dual number) so that the planner differentiates them exactly.
//!
//! Conventions: a world vector is `[x, z]`; `rot(θ, v)` rotates a body-frame vector into the
//! world for a body at pitch θ about +y; `perp(r) = ω̂ × r = [r_z, −r_x]` is the velocity of the
//! point r of a body spinning at unit rate about +y. The pose and bias-acceleration routines work
//! on fixed-size arrays and never allocate, so the runtime may call them inside its control tick.

use crate::robot::{JointKind, PlanarModel, MAX_BODIES, MAX_DOF};
use crate::{ModelError, Real, Result};
use nalgebra::DMatrix;

/// Position and orientation of a body frame in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose<S> {
    /// Origin (x, z), m.
    pub xz_m: [S; 2],
    /// Pitch about +y, rad.
    pub pitch_rad: S,
}

/// Rotates a body-frame vector into the world for a frame at pitch θ.
#[inline]
pub fn rot<S: Real>(pitch: S, v: [S; 2]) -> [S; 2] {
    rot_sin_cos(pitch.sin_cos(), v)
}

/// [`rot`] with `(sin θ, cos θ)` given, for a vector of scalars or of [`Constant`]s.
#[inline]
pub(crate) fn rot_sin_cos<S: Real, V: Coefficient<S>>((s, c): (S, S), v: [V; 2]) -> [S; 2] {
    [v[0].times(c) + v[1].times(s), v[1].times(c) - v[0].times(s)]
}

/// A factor of a product with a scalar `S`: `S` itself, or a [`Constant`].
///
/// With a dual-number `S`, a product by a constant lifted to `S` applies the full product rule
/// to a factor whose derivative parts are zero. A [`Constant`] scales the parts instead: the
/// same value (the dropped terms are exact zeros; only the sign of a zero can differ), at a
/// fraction of the operations. Body offsets, joint axes and (for a fixed design) mass
/// properties are such constants in the planner's derivative sweeps.
pub trait Coefficient<S>: Copy {
    /// `s * self`.
    fn times(self, s: S) -> S;
    /// `self * s` (the same value; for `S` itself, the same operations in the same order as
    /// the product written that way).
    fn times_left(self, s: S) -> S;
    /// The real part.
    fn value(self) -> f64;
}

/// An `f64` that multiplies a scalar part by part (see [`Coefficient`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constant(pub f64);

impl<S: Real> Coefficient<S> for S {
    #[inline]
    fn times(self, s: S) -> S {
        s * self
    }
    #[inline]
    fn times_left(self, s: S) -> S {
        self * s
    }
    #[inline]
    fn value(self) -> f64 {
        self.re()
    }
}

impl<S: Real> Coefficient<S> for Constant {
    #[inline]
    fn times(self, s: S) -> S {
        s * self.0
    }
    #[inline]
    fn times_left(self, s: S) -> S {
        s * self.0
    }
    #[inline]
    fn value(self) -> f64 {
        self.0
    }
}

/// `v` as [`Constant`]s.
#[inline]
pub fn constants(v: [f64; 2]) -> [Constant; 2] {
    [Constant(v[0]), Constant(v[1])]
}

/// `ω̂ × r` for a unit angular velocity about +y.
#[inline]
pub fn perp<S: Real>(r: [S; 2]) -> [S; 2] {
    [r[1], -r[0]]
}

#[inline]
fn add<S: Real>(a: [S; 2], b: [S; 2]) -> [S; 2] {
    [a[0] + b[0], a[1] + b[1]]
}
#[inline]
fn sub<S: Real>(a: [S; 2], b: [S; 2]) -> [S; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
#[inline]
fn scale<S: Real>(k: S, a: [S; 2]) -> [S; 2] {
    [k * a[0], k * a[1]]
}

/// Fixed-capacity, allocation-free per-body state: poses, and optionally velocities.
#[derive(Clone, Copy, Debug)]
pub struct BodyStates<S> {
    /// Number of valid entries.
    pub len: usize,
    /// Pose of each body.
    pub pose: [Pose<S>; MAX_BODIES],
    /// Origin velocity of each body, m/s.
    pub vel_xz: [[S; 2]; MAX_BODIES],
    /// Angular velocity of each body about +y, rad/s.
    pub omega: [S; MAX_BODIES],
    /// Bias (velocity-product) acceleration of each body origin, m/s²: the origin acceleration
    /// when q̈ = 0. Angular bias accelerations are zero in the plane.
    pub bias_acc_xz: [[S; 2]; MAX_BODIES],
    /// (sin, cos) of each body's pitch, computed once by the kinematics pass: every point
    /// position, velocity, bias acceleration and prismatic Jacobian column rotates by them.
    pub sin_cos: [(S, S); MAX_BODIES],
}

impl<S: Real> BodyStates<S> {
    /// All-zero states of no bodies, to be filled by [`PlanarModel::body_states_into`].
    pub fn zeroed() -> Self {
        let z = S::zero();
        Self {
            len: 0,
            pose: [Pose {
                xz_m: [z, z],
                pitch_rad: z,
            }; MAX_BODIES],
            vel_xz: [[z, z]; MAX_BODIES],
            omega: [z; MAX_BODIES],
            bias_acc_xz: [[z, z]; MAX_BODIES],
            sin_cos: [(z, z); MAX_BODIES],
        }
    }
}

/// A body's pose from its parent's, and what its velocity needs of the step.
struct ChildPose<S> {
    pose: Pose<S>,
    /// World offset of the body's origin from its parent's, m.
    offset: [S; 2],
    /// The joint's motion.
    motion: ChildMotion<S>,
}

/// How a body moves on its joint.
enum ChildMotion<S> {
    /// Rotation, `axis_sign` ±1.
    Revolute { axis_sign: f64 },
    /// Translation along the world direction `axis`.
    Prismatic { axis: [S; 2] },
}

impl PlanarModel {
    fn check_len(&self, what: &'static str, v: usize) -> Result<()> {
        if v != self.dof() {
            return Err(ModelError::Dimension {
                what,
                expected: self.dof(),
                found: v,
            });
        }
        Ok(())
    }

    /// Poses of every body at q, with zero velocities. Never allocates.
    pub fn body_poses<S: Real>(&self, q: &[S]) -> Result<BodyStates<S>> {
        let mut st = BodyStates::zeroed();
        self.body_poses_into(q, &mut st)?;
        Ok(st)
    }

    /// [`Self::body_poses`] written into `st` (any previous content is overwritten): the pose
    /// half of [`Self::body_states_into`], the same operations on the poses (the simulator
    /// calls it every 0.1 ms step).
    pub fn body_poses_into<S: Real>(&self, q: &[S], st: &mut BodyStates<S>) -> Result<()> {
        self.check_len("q", q.len())?;
        self.reset_states(q, st, true);
        for (b, body) in self.bodies.iter().enumerate().skip(1) {
            let (Some(p), Some(j)) = (body.parent, body.joint) else {
                continue;
            };
            st.pose[b] = self
                .child_pose(b, p, j, q, st.pose[p], &mut st.sin_cos)
                .pose;
        }
        Ok(())
    }

    /// Zeroes `st` for this model's bodies and sets the base pose from q. With `all` false,
    /// only the bodies that a states pass does not write (the base and any body without a
    /// parent joint): [`Self::body_states_into`] overwrites every field of the others, so
    /// zeroing them first would be wasted work (kilobytes per pass for a wide dual number).
    fn reset_states<S: Real>(&self, q: &[S], st: &mut BodyStates<S>, all: bool) {
        let z = S::zero();
        let n = self.bodies.len().min(MAX_BODIES);
        st.len = self.bodies.len();
        for b in 0..n {
            let body = &self.bodies[b];
            if !all && b > 0 && body.parent.is_some() && body.joint.is_some() {
                continue;
            }
            st.pose[b] = Pose {
                xz_m: [z, z],
                pitch_rad: z,
            };
            st.vel_xz[b] = [z, z];
            st.omega[b] = z;
            st.bias_acc_xz[b] = [z, z];
            st.sin_cos[b] = (z, z);
        }
        st.pose[0] = Pose {
            xz_m: [q[0], q[1]],
            pitch_rad: q[2],
        };
        st.sin_cos[0] = q[2].sin_cos();
    }

    /// Pose of body `b` (parent `p`, joint `j`) from its parent's pose, and (sin, cos) of its
    /// pitch stored in `sin_cos[b]` (once per distinct pitch: a prismatic joint with no origin
    /// pitch keeps its parent's). Shared by [`Self::body_poses_into`] and
    /// [`Self::body_states_into`], which adds the velocities.
    fn child_pose<S: Real>(
        &self,
        b: usize,
        p: usize,
        j: usize,
        q: &[S],
        parent: Pose<S>,
        sin_cos: &mut [(S, S); MAX_BODIES],
    ) -> ChildPose<S> {
        let body = &self.bodies[b];
        let joint = &self.joints[j];
        let qj = q[joint.coordinate];
        let phi = parent.pitch_rad + S::from(body.origin_pitch_rad);
        let mut offset = rot_sin_cos(sin_cos[p], constants(body.origin_xz_m));
        let (pitch, motion) = match joint.kind {
            JointKind::Revolute { axis_sign } => {
                let pitch = phi + qj * axis_sign;
                sin_cos[b] = pitch.sin_cos();
                (pitch, ChildMotion::Revolute { axis_sign })
            }
            JointKind::Prismatic { axis_xz } => {
                sin_cos[b] = if body.origin_pitch_rad == 0.0 {
                    sin_cos[p]
                } else {
                    phi.sin_cos()
                };
                let a = rot_sin_cos(sin_cos[b], constants(axis_xz));
                offset = add(offset, scale(qj, a));
                (phi, ChildMotion::Prismatic { axis: a })
            }
        };
        ChildPose {
            pose: Pose {
                xz_m: add(parent.xz_m, offset),
                pitch_rad: pitch,
            },
            offset,
            motion,
        }
    }

    /// Poses, velocities and bias accelerations of every body at (q, q̇). Never allocates.
    pub fn body_states<S: Real>(&self, q: &[S], dq: &[S]) -> Result<BodyStates<S>> {
        let mut st = BodyStates::zeroed();
        self.body_states_into(q, dq, &mut st)?;
        Ok(st)
    }

    /// [`Self::body_states`] written into `st` (any previous content is overwritten), so that a
    /// caller evaluating with a wide dual-number type does not copy the states around.
    pub fn body_states_into<S: Real>(
        &self,
        q: &[S],
        dq: &[S],
        st: &mut BodyStates<S>,
    ) -> Result<()> {
        self.check_len("q", q.len())?;
        self.check_len("dq", dq.len())?;
        let z = S::zero();
        self.reset_states(q, st, false);
        st.vel_xz[0] = [dq[0], dq[1]];
        st.omega[0] = dq[2];
        for (b, body) in self.bodies.iter().enumerate().skip(1) {
            let (Some(p), Some(j)) = (body.parent, body.joint) else {
                continue;
            };
            let child = self.child_pose(b, p, j, q, st.pose[p], &mut st.sin_cos);
            let dqj = dq[self.joints[j].coordinate];
            let d = child.offset;
            let wp = st.omega[p];
            let v = add(st.vel_xz[p], scale(wp, perp(d)));
            let (v, omega, extra_acc) = match child.motion {
                ChildMotion::Revolute { axis_sign } => (v, wp + dqj * axis_sign, [z, z]),
                ChildMotion::Prismatic { axis: a } => {
                    (add(v, scale(dqj, a)), wp, scale(wp * dqj * 2.0, perp(a)))
                }
            };
            st.pose[b] = child.pose;
            st.vel_xz[b] = v;
            st.omega[b] = omega;
            st.bias_acc_xz[b] = add(add(st.bias_acc_xz[p], scale(-(wp * wp), d)), extra_acc);
        }
        Ok(())
    }

    /// World position of a point given in the frame of `body`.
    pub fn point_position<S: Real, V: Coefficient<S>>(
        &self,
        st: &BodyStates<S>,
        body: usize,
        local_xz: [V; 2],
    ) -> [S; 2] {
        add(st.pose[body].xz_m, rot_sin_cos(st.sin_cos[body], local_xz))
    }

    /// World velocity of a point given in the frame of `body` (needs `body_states` with q̇).
    pub fn point_velocity<S: Real, V: Coefficient<S>>(
        &self,
        st: &BodyStates<S>,
        body: usize,
        local_xz: [V; 2],
    ) -> [S; 2] {
        let r = rot_sin_cos(st.sin_cos[body], local_xz);
        add(st.vel_xz[body], scale(st.omega[body], perp(r)))
    }

    /// Bias acceleration J̇ q̇ of a point given in the frame of `body`.
    pub fn point_bias_acceleration<S: Real, V: Coefficient<S>>(
        &self,
        st: &BodyStates<S>,
        body: usize,
        local_xz: [V; 2],
    ) -> [S; 2] {
        let r = rot_sin_cos(st.sin_cos[body], local_xz);
        let w = st.omega[body];
        add(st.bias_acc_xz[body], scale(-(w * w), r))
    }

    /// Translational Jacobian (2 × dof) of the world point `p` moving with `body`.
    pub fn point_jacobian<S: Real>(
        &self,
        st: &BodyStates<S>,
        body: usize,
        p: [S; 2],
    ) -> DMatrix<S> {
        let mut jac = DMatrix::from_element(2, self.dof(), S::zero());
        self.point_jacobian_into(st, body, p, |row, col, v| jac[(row, col)] = v);
        jac
    }

    /// Writes the non-zero entries of the point Jacobian through `set(row, col, value)`.
    pub fn point_jacobian_into<S: Real>(
        &self,
        st: &BodyStates<S>,
        body: usize,
        p: [S; 2],
        set: impl FnMut(usize, usize, S),
    ) {
        self.point_jacobian_with(st, body, p, |c| st.sin_cos[c], set);
    }

    /// [`Self::point_jacobian_into`] with `sin_cos(c)` giving `(sin, cos)` of body `c`'s pitch
    /// (for a caller that has them already).
    pub(crate) fn point_jacobian_with<S: Real>(
        &self,
        st: &BodyStates<S>,
        body: usize,
        p: [S; 2],
        sin_cos: impl FnMut(usize) -> (S, S),
        mut set: impl FnMut(usize, usize, S),
    ) {
        set(0, 0, S::one());
        set(1, 1, S::one());
        self.pitch_and_joint_columns(st, body, p, sin_cos, |c, col| {
            set(0, c, col[0]);
            set(1, c, col[1]);
        });
    }

    /// The point Jacobian's columns other than the base's x and z (which are the unit
    /// vectors): `column(coordinate, [∂x/∂q_c, ∂z/∂q_c])` for the base pitch, then for every
    /// joint on the path to `body`, in path order.
    pub(crate) fn pitch_and_joint_columns<S: Real>(
        &self,
        st: &BodyStates<S>,
        body: usize,
        p: [S; 2],
        mut sin_cos: impl FnMut(usize) -> (S, S),
        mut column: impl FnMut(usize, [S; 2]),
    ) {
        column(2, perp(sub(p, st.pose[0].xz_m)));
        for &j in &self.bodies[body].joint_path {
            let joint = &self.joints[j];
            let c = joint.body;
            let col = match joint.kind {
                JointKind::Revolute { axis_sign } => {
                    let r = perp(sub(p, st.pose[c].xz_m));
                    [r[0] * axis_sign, r[1] * axis_sign]
                }
                JointKind::Prismatic { axis_xz } => rot_sin_cos(sin_cos(c), constants(axis_xz)),
            };
            column(joint.coordinate, col);
        }
    }

    /// Angular Jacobian (1 × dof, as a vector) of `body`: ∂pitch/∂q.
    pub fn angular_jacobian(&self, body: usize) -> Vec<f64> {
        let mut jac = vec![0.0; self.dof()];
        jac[2] = 1.0;
        for &j in &self.bodies[body].joint_path {
            if let JointKind::Revolute { axis_sign } = self.joints[j].kind {
                jac[self.joints[j].coordinate] = axis_sign;
            }
        }
        jac
    }

    /// World position of frame `frame` at q (f64 convenience).
    pub fn frame_position(&self, q: &[f64], frame: usize) -> Result<[f64; 2]> {
        let st = self.body_poses(q)?;
        Ok(self.frame_position_in(&st, frame))
    }

    /// World position of frame `frame` from computed body states.
    pub fn frame_position_in<S: Real>(&self, st: &BodyStates<S>, frame: usize) -> [S; 2] {
        let f = &self.frames[frame];
        if f.offset_xz_m == [0.0, 0.0] {
            // At its body's origin (a point foot): nothing to rotate.
            return st.pose[f.body].xz_m;
        }
        self.point_position(st, f.body, constants(f.offset_xz_m))
    }

    /// World velocity of frame `frame` from computed body states.
    pub fn frame_velocity_in<S: Real>(&self, st: &BodyStates<S>, frame: usize) -> [S; 2] {
        let f = &self.frames[frame];
        self.point_velocity(st, f.body, constants(f.offset_xz_m))
    }

    /// Bias acceleration J̇q̇ of frame `frame` from computed body states.
    pub fn frame_bias_acceleration_in<S: Real>(&self, st: &BodyStates<S>, frame: usize) -> [S; 2] {
        let f = &self.frames[frame];
        self.point_bias_acceleration(st, f.body, constants(f.offset_xz_m))
    }

    /// Jacobian (2 × dof) of frame `frame`.
    pub fn frame_jacobian<S: Real>(&self, st: &BodyStates<S>, frame: usize) -> DMatrix<S> {
        let p = self.frame_position_in(st, frame);
        self.point_jacobian(st, self.frames[frame].body, p)
    }

    /// World position of a joint's axis (the origin of the body it moves) at q, m.
    pub fn joint_position(&self, q: &[f64], joint: usize) -> Result<[f64; 2]> {
        let st = self.body_poses(q)?;
        Ok(st.pose[self.joints[joint].body].xz_m)
    }

    /// World position of the centre of mass of `body`.
    pub fn body_com_in<S: Real>(&self, st: &BodyStates<S>, body: usize) -> [S; 2] {
        self.point_position(st, body, constants(self.bodies[body].inertia.com_xz_m))
    }

    /// Whole-body centre of mass at q, m.
    pub fn center_of_mass<S: Real>(&self, q: &[S]) -> Result<[S; 2]> {
        let st = self.body_poses(q)?;
        let mut acc = [S::zero(), S::zero()];
        let mut m = 0.0;
        for (b, body) in self.bodies.iter().enumerate() {
            let mb = body.inertia.mass_kg;
            if mb == 0.0 {
                continue;
            }
            acc = add(acc, scale(S::from(mb), self.body_com_in(&st, b)));
            m += mb;
        }
        Ok(scale(S::from(1.0 / m), acc))
    }

    /// Checks that the allocation-free kinematics can hold this model.
    pub fn check_capacity(&self) -> Result<()> {
        if self.bodies.len() > MAX_BODIES || self.dof() > MAX_DOF {
            return Err(ModelError::TooManyBodies {
                bodies: self.bodies.len(),
                max: MAX_BODIES,
            });
        }
        Ok(())
    }
}
