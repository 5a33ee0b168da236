//! The robot as the planner sees it: a planar point-foot biped in pinned-stance coordinates.
//!
//! The planner's coordinates are the *reduced* ones: torso pitch and the actuated joints (design
//! joints are parameters, base position follows from the stance foot sitting at the origin). Each
//! reduced state (q_r, q̇_r, q̈_r) maps to the model's full floating-base state by placing the base
//! so that the stance foot is at the world origin, at rest and unaccelerated.

use crate::{PlannerError, Result};
use model::gait::OutputDefinition;
use model::kinematics::BodyStates;
use model::robot::{JointRole, Legs, MAX_DOF};
use model::{PlanarModel, Real, Side};

/// A planar biped prepared for planning.
#[derive(Clone, Debug)]
pub struct PlanarBiped {
    /// The robot model.
    pub model: PlanarModel,
    /// Its legs.
    pub legs: Legs,
    /// The stance leg of the planned step.
    pub stance: Side,
    /// (full coordinate, value) of every design joint, m.
    pub design: Vec<(usize, f64)>,
    /// Full coordinate of each reduced coordinate: pitch, then the actuated joints in model order.
    pub reduced: Vec<usize>,
    /// Reduced index of each actuator (B's columns, model order).
    pub actuators: Vec<usize>,
    /// Relabeling in reduced coordinates: after impact, reduced coordinate i takes the value of
    /// reduced coordinate `relabel[i]`.
    pub relabel: Vec<usize>,
    /// The outputs (ADAM's: stance hip, stance knee, swing hip, swing knee).
    pub outputs: Vec<OutputDefinition>,
    /// Reduced index of each output's joint.
    pub output_coords: Vec<usize>,
}

/// Full q and q̇ of one state, and the full q̈ of each of several reduced accelerations
/// ([`PlanarBiped::full_states`]).
pub type FullStates<S> = ([Vec<S>; 2], Vec<Vec<S>>);

impl PlanarBiped {
    /// Prepares `model` with every design joint at `design_values` (in design-joint order, or all
    /// zero when empty) for a step on `stance`.
    pub fn new(model: PlanarModel, stance: Side, design_values: &[f64]) -> Result<Self> {
        let legs = model.legs()?;
        let design_joints = model.design_joints();
        if !design_values.is_empty() && design_values.len() != design_joints.len() {
            return Err(PlannerError::Robot {
                robot: model.name.clone(),
                reason: format!(
                    "{} design values for {} design joints",
                    design_values.len(),
                    design_joints.len()
                ),
            });
        }
        let design = design_joints
            .iter()
            .enumerate()
            .map(|(i, &j)| {
                (
                    model.joints[j].coordinate,
                    design_values.get(i).copied().unwrap_or(0.0),
                )
            })
            .collect();
        let mut reduced = vec![2];
        for j in &model.joints {
            if j.role == JointRole::Actuated {
                reduced.push(j.coordinate);
            }
        }
        let index_of = |coord: usize| reduced.iter().position(|&c| c == coord);
        let actuators = model
            .actuated_joints()
            .iter()
            .map(|&j| index_of(model.joints[j].coordinate).unwrap_or(0))
            .collect();
        let perm = model.relabel_permutation();
        let relabel = reduced
            .iter()
            .map(|&c| index_of(perm[c]).unwrap_or(0))
            .collect();
        let outputs = OutputDefinition::adam();
        let mut output_coords = Vec::new();
        for o in &outputs {
            let j = model.require_joint(&o.joint_name(stance))?;
            output_coords.push(index_of(model.joints[j].coordinate).unwrap_or(0));
        }
        Ok(Self {
            model,
            legs,
            stance,
            design,
            reduced,
            actuators,
            relabel,
            outputs,
            output_coords,
        })
    }

    /// Number of reduced coordinates.
    pub fn nq(&self) -> usize {
        self.reduced.len()
    }

    /// Number of actuators.
    pub fn nu(&self) -> usize {
        self.actuators.len()
    }

    /// The swing side.
    pub fn swing(&self) -> Side {
        self.stance.other()
    }

    /// Full (q, q̇, q̈) from the reduced state, with the stance foot pinned at the origin.
    pub fn full_state<S: Real>(&self, qr: &[S], dqr: &[S], ddqr: &[S]) -> Result<[Vec<S>; 3]> {
        self.full_state_design(qr, dqr, ddqr, None)
    }

    /// [`Self::full_state`] with the design joints of both legs set to `design` = [thigh, shin]
    /// design-joint values, m (the co-design's variables; left = right), instead of the fixed
    /// values this biped was built with.
    pub fn full_state_design<S: Real>(
        &self,
        qr: &[S],
        dqr: &[S],
        ddqr: &[S],
        design: Option<[S; 2]>,
    ) -> Result<[Vec<S>; 3]> {
        let ([q, dq], mut ddqs) = self.full_states_design(qr, dqr, &[ddqr], design)?;
        Ok([q, dq, ddqs.remove(0)])
    }

    /// [`Self::full_state`] for several reduced accelerations at one (q_r, q̇_r): one
    /// kinematics pass, and each full q̈ bit for bit the one `full_state` gives for it.
    pub fn full_states<S: Real>(
        &self,
        qr: &[S],
        dqr: &[S],
        ddqrs: &[&[S]],
    ) -> Result<FullStates<S>> {
        self.full_states_design(qr, dqr, ddqrs, None)
    }

    fn full_states_design<S: Real>(
        &self,
        qr: &[S],
        dqr: &[S],
        ddqrs: &[&[S]],
        design: Option<[S; 2]>,
    ) -> Result<FullStates<S>> {
        let n = self.model.dof();
        let z = S::zero();
        let (mut q, mut dq) = (vec![z; n], vec![z; n]);
        self.fill_coordinates(qr, dqr, design, &mut q, &mut dq);
        let mut st = BodyStates::zeroed();
        self.model.body_states_into(&q, &dq, &mut st)?;
        let foot = self.legs.side(self.stance).foot;
        let p = self.model.frame_position_in(&st, foot);
        let v = self.model.frame_velocity_in(&st, foot);
        let bias = self.model.frame_bias_acceleration_in(&st, foot);
        let ddqs = ddqrs
            .iter()
            .map(|ddqr| {
                let mut ddq = vec![z; n];
                for (i, &c) in self.reduced.iter().enumerate() {
                    ddq[c] = ddqr[i];
                }
                let mut a = bias;
                self.model.point_jacobian_into(
                    &st,
                    self.model.frames[foot].body,
                    p,
                    |r, c, val| a[r] += val * ddq[c],
                );
                ddq[0] = -a[0];
                ddq[1] = -a[1];
                ddq
            })
            .collect();
        for k in 0..2 {
            q[k] = -p[k];
            dq[k] = -v[k];
        }
        Ok(([q, dq], ddqs))
    }

    /// The body states at the reduced state (q_r, q̇_r), with the design joints set as in
    /// [`Self::full_state_design`] but the floating base at rest at the origin (base x, z and
    /// their rates zero): one kinematics pass, no allocation. Anything that depends only on
    /// relative positions, angular rates and bias accelerations (inverse dynamics, point
    /// Jacobians, one point relative to another) is the pinned robot's, up to rounding.
    pub fn states_at_rest_base<S: Real>(
        &self,
        qr: &[S],
        dqr: &[S],
        design: Option<[S; 2]>,
        st: &mut BodyStates<S>,
    ) -> Result<()> {
        let n = self.model.dof();
        let z = S::zero();
        let (mut q, mut dq) = ([z; MAX_DOF], [z; MAX_DOF]);
        self.fill_coordinates(qr, dqr, design, &mut q[..n], &mut dq[..n]);
        self.model.body_states_into(&q[..n], &dq[..n], st)?;
        Ok(())
    }

    /// Writes the reduced coordinates and rates into full `q`, `dq` (zero elsewhere on entry),
    /// and the design joints: this biped's fixed values, or `design` = [thigh, shin] for both
    /// legs.
    fn fill_coordinates<S: Real>(
        &self,
        qr: &[S],
        dqr: &[S],
        design: Option<[S; 2]>,
        q: &mut [S],
        dq: &mut [S],
    ) {
        for (i, &c) in self.reduced.iter().enumerate() {
            q[c] = qr[i];
            dq[c] = dqr[i];
        }
        for &(c, v) in &self.design {
            q[c] = S::from(v);
        }
        if let Some([thigh, shin]) = design {
            for side in [Side::Left, Side::Right] {
                let leg = self.legs.side(side);
                if let Some(j) = leg.thigh_design {
                    q[self.model.joints[j].coordinate] = thigh;
                }
                if let Some(j) = leg.shin_design {
                    q[self.model.joints[j].coordinate] = shin;
                }
            }
        }
    }

    /// The stance-foot Jacobian's column `c` (x and z rows) at full q.
    pub fn stance_jacobian<S: Real>(&self, q: &[S]) -> Result<Vec<[S; 2]>> {
        let mut st = BodyStates::zeroed();
        self.model.body_poses_into(q, &mut st)?;
        let foot = self.legs.side(self.stance).foot;
        let p = self.model.frame_position_in(&st, foot);
        let mut cols = vec![[S::zero(); 2]; self.model.dof()];
        self.model
            .point_jacobian_into(&st, self.model.frames[foot].body, p, |r, c, v| {
                cols[c][r] = v
            });
        Ok(cols)
    }
}
