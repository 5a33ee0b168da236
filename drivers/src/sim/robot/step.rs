//! One integration step of the simulated robot: the contact set (stance dynamics, liftoff), the
//! touchdown search and the plastic impact, the stance projection, friction and fall checks; with
//! the multi-rate hold of the [robot docs](super), "Multi-rate dynamics".

use super::solver::MAX_CONTACTS;
use super::{
    Contact, FallCause, FallRecord, Result, RobotSim, RobotSimError, SimEvent, Touchdown, SIDES,
};
use model::kinematics::BodyStates;

/// A step keeps the frozen dynamics only while every stance foot carries at least this
/// fraction of the robot's weight: nearer to liftoff, the contact set is decided on fresh
/// dynamics (robot module docs, "Multi-rate dynamics").
const FROZEN_MIN_NORMAL_FORCE_FRACTION: f64 = 0.1;

/// Most events (touchdowns) handled inside one integration step.
const MAX_EVENTS_PER_STEP: usize = 4;

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

impl RobotSim {
    pub(super) fn advance(&mut self, h: f64) -> Result<()> {
        // The belt's acceleration over this step (0 unless it ramps), held over its parts.
        self.belt_accel_mps2 = self.belt.acceleration_over(h);
        let mut remaining = h;
        for _ in 0..MAX_EVENTS_PER_STEP {
            let t0 = self.t_s;
            let done = self.sub_step(remaining, true)?;
            self.belt.advance(t0, done, self.belt_accel_mps2);
            remaining -= done;
            if remaining <= h * 1e-9 {
                break;
            }
        }
        if remaining > h * 1e-9 {
            // Too many events in one step (chatter): integrate the rest without event search.
            let t0 = self.t_s;
            let done = self.sub_step(remaining, false)?;
            self.belt.advance(t0, done, self.belt_accel_mps2);
        }
        Ok(())
    }

    /// Body states, D and H at the present (q, q̇) into the step's buffers, and D factored.
    pub(super) fn factor_present(&mut self) -> Result<BodyStates<f64>> {
        let st = self.model.body_states(&self.q, &self.dq)?;
        self.model
            .dynamics_into(&st, &mut self.mass_matrix, &mut self.drift)?;
        self.solver
            .factor_mass(&self.mass_matrix)
            .map_err(|_| RobotSimError::NotPositiveDefinite { t_s: self.t_s })?;
        Ok(st)
    }

    /// Stance frames (and their side indices) in left-right order.
    pub(super) fn stance_frames(&self) -> ([usize; MAX_CONTACTS], [usize; MAX_CONTACTS], usize) {
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
    /// operator first when they are due (robot module docs, "Multi-rate dynamics").
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
        // The belt frame's inertial force while the belt ramps: m·a on every body, forward
        // (the x column of D; belt module docs).
        if self.belt_accel_mps2 != 0.0 {
            let a = self.belt_accel_mps2;
            for (c, f) in self.generalized_force.iter_mut().enumerate() {
                *f += a * self.mass_matrix[(c, 0)];
            }
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
        let position_on_belt_m = self.position_on_belt_m();
        self.events.push(SimEvent::Touchdown(Touchdown {
            t_s: self.t_s,
            side: SIDES[i],
            foot_x_m: x_world,
            step_length_m: p[0] - other[0],
            impulse_ns,
            kinetic_energy_before_j,
            kinetic_energy_after_j,
            belt_speed_mps: self.belt.speed_mps,
            position_on_belt_m,
        }));
        Ok(())
    }

    /// Pull the stance feet back onto their anchors and their velocities to zero, in the
    /// kinetic-energy metric of the last factored `D` (corrections are O(h²) small). `poses`:
    /// the body poses at the present q, if already computed; `reload`: load the contact
    /// Jacobian at these poses (otherwise project with the loaded contact operator, which must
    /// be that of the present stance feet). Whether q changed.
    pub(super) fn project(
        &mut self,
        poses: Option<&BodyStates<f64>>,
        reload: bool,
    ) -> Result<bool> {
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
            // A stance foot carried (or set down) past an end of the belt.
            let offset = self.belt_offset_m();
            self.contact.iter().find_map(|c| match *c {
                Contact::Stance { anchor_xz_m } => self
                    .belt
                    .beyond(anchor_xz_m[0] + offset)
                    .map(FallCause::OffBelt),
                Contact::Air => None,
            })
        };
        if let Some(what) = what {
            self.fallen = Some(FallRecord {
                t_s: self.t_s,
                what,
                base_x_m: self.base_position_m()[0],
                position_on_belt_m: self.position_on_belt_m(),
            });
            self.events.push(SimEvent::Fall {
                t_s: self.t_s,
                what,
            });
        }
    }
}
