//! The transcription's constraint blocks (which variables, which bounds) and the variable
//! bounds: joint, speed and torque limits, torso pitch, Table I.

use super::blocks::{Block, Kind};
use super::layout::TORQUE_SCALE;
use super::problem::HzdProblem;

impl HzdProblem {
    pub(super) fn add(&mut self, kind: Kind, vars: Vec<usize>, lower: &[f64], upper: &[f64]) {
        let row0 = self.lower_g.len();
        self.lower_g.extend_from_slice(lower);
        self.upper_g.extend_from_slice(upper);
        self.blocks.push(Block {
            kind,
            vars,
            row0,
            n_out: lower.len(),
            jac: Vec::new(),
            jac_vars: Vec::new(),
            seeds: Vec::new(),
            hess_slots: Vec::new(),
        });
    }

    pub(super) fn point_vars(&self, k: usize, with_ddq: bool) -> Vec<usize> {
        let l = &self.layout;
        let mut v: Vec<usize> = (l.q(k)..l.q(k) + l.nq)
            .chain(l.dq(k)..l.dq(k) + l.nq)
            .collect();
        if with_ddq {
            v.extend(l.ddq(k)..l.ddq(k) + l.nq);
        }
        v
    }

    pub(super) fn build_blocks(&mut self) {
        let l = self.layout.clone();
        let g = self.config.gait.clone();
        let (nq, nu, b) = (l.nq, l.nu, l.degree);
        let last = l.points() - 1;
        let inf = f64::INFINITY;
        for k in 0..l.points() {
            // Dynamics and contact.
            let mut vars = self.point_vars(k, true);
            vars.extend(l.u(k)..l.u(k) + nu);
            let mut lo = vec![0.0; nq];
            let mut hi = vec![0.0; nq];
            lo.extend([g.min_normal_force_n, 0.0, 0.0]);
            hi.extend([inf, inf, inf]);
            self.add(Kind::Dynamics, vars, &lo, &hi);
            // Lifted phase and output dynamics.
            let mut vars = self.point_vars(k, true);
            vars.extend([
                l.theta_plus(),
                l.theta_minus(),
                l.tau(k),
                l.tau(k) + 1,
                l.tau(k) + 2,
            ]);
            self.add(Kind::PhaseLift, vars, &[0.0; 3], &[0.0; 3]);
            for o in 0..l.m {
                let j = self.biped.output_coords[o];
                let mut vars = vec![
                    l.q(k) + j,
                    l.dq(k) + j,
                    l.ddq(k) + j,
                    l.tau(k),
                    l.tau(k) + 1,
                    l.tau(k) + 2,
                ];
                vars.extend((0..=b).map(|jj| l.alpha(o, jj)));
                self.add(Kind::OutputDynamics(o), vars, &[0.0], &[0.0]);
            }
            // Power slacks.
            for a in (0..nu).filter(|_| l.slacks) {
                let c = self.biped.actuators[a];
                let vars = vec![l.p(k) + a, l.n(k) + a, l.u(k) + a, l.dq(k) + c];
                self.add(Kind::Power(c), vars, &[0.0], &[0.0]);
            }
            // Swing foot height.
            if k > 0 {
                let vars: Vec<usize> = (l.q(k)..l.q(k) + nq).collect();
                // Interior points keep the swing foot above a parabola in time that peaks at
                // the mid-step clearance: z ≥ 0 alone let the optimum graze the ground (0.04 mm
                // below it between points near τ = 0.85) and the robot tripped in simulation.
                let s = l.time_fraction(k);
                let (lo, hi) = if k == last {
                    (0.0, 0.0)
                } else {
                    (g.swing_clearance_m * 4.0 * s * (1.0 - s), inf)
                };
                self.add(Kind::SwingHeight, vars, &[lo], &[hi]);
            }
        }
        for o in 0..l.m {
            let j = self.biped.output_coords[o];
            let mut vars = vec![
                l.q(0) + j,
                l.dq(0) + j,
                l.ddq(0) + j,
                l.tau(0),
                l.tau(0) + 1,
                l.tau(0) + 2,
            ];
            vars.extend((0..=b).map(|jj| l.alpha(o, jj)));
            self.add(Kind::OutputStart(o), vars, &[0.0, 0.0], &[0.0, 0.0]);
        }
        for i in 0..l.intervals {
            let (a, m, e) = (2 * i, 2 * i + 1, 2 * i + 2);
            for j in 0..nq {
                let vars = vec![
                    l.q(a) + j,
                    l.q(m) + j,
                    l.q(e) + j,
                    l.dq(a) + j,
                    l.dq(m) + j,
                    l.dq(e) + j,
                    l.ddq(a) + j,
                    l.ddq(m) + j,
                    l.ddq(e) + j,
                    l.duration(),
                ];
                self.add(Kind::Interval(i), vars, &[0.0; 4], &[0.0; 4]);
            }
        }
        let mut vars = self.point_vars(last, false);
        vars.push(l.length());
        self.add(
            Kind::SwingEnd,
            vars,
            &[0.0, -inf],
            &[0.0, -g.impact_velocity_mps],
        );
        self.add(
            Kind::TauEnds,
            vec![l.tau(0), l.tau(last)],
            &[0.0, 1.0],
            &[0.0, 1.0],
        );
        let mut vars = self.point_vars(last, false);
        vars.extend(self.point_vars(0, false));
        let mut lo = vec![0.0; 2 * nq];
        let mut hi = vec![0.0; 2 * nq];
        lo.extend([0.0, 0.0, 0.0, g.liftoff_velocity_mps]);
        hi.extend([inf, inf, inf, inf]);
        self.add(Kind::Impact, vars, &lo, &hi);
        // Co-design: every block that evaluates the model also sees the two lengths.
        if l.design > 0 {
            let dv = [l.design_var(0), l.design_var(1)];
            for blk in &mut self.blocks {
                if Self::uses_model(blk.kind) {
                    blk.vars.extend(dv);
                }
            }
        }
        // Cost weights of the slack variables.
        for k in 0..l.points() {
            for a in (0..nu).filter(|_| l.slacks) {
                let w = l.simpson_weight(k) * self.config.cost.weights[a];
                self.slack_weights.push((l.p(k) + a, w));
                self.slack_weights.push((l.n(k) + a, w));
            }
        }
    }

    /// Variable bounds.
    pub fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        let l = &self.layout;
        let bp = &self.biped;
        let g = &self.config.gait;
        let inf = f64::INFINITY;
        let mut lo = vec![-inf; l.len()];
        let mut hi = vec![inf; l.len()];
        let joint_of = |c: usize| bp.model.joints.iter().find(|j| j.coordinate == c);
        let p_max = bp
            .model
            .joints
            .iter()
            .filter(|j| j.role == model::robot::JointRole::Actuated)
            .map(|j| j.effort_limit * j.velocity_limit)
            .fold(0.0, f64::max);
        for k in 0..l.points() {
            for (i, &c) in bp.reduced.iter().enumerate() {
                match joint_of(c) {
                    Some(j) => {
                        lo[l.q(k) + i] = j.lower;
                        hi[l.q(k) + i] = j.upper;
                        lo[l.dq(k) + i] = -j.velocity_limit;
                        hi[l.dq(k) + i] = j.velocity_limit;
                    }
                    None => {
                        lo[l.q(k) + i] = g.pitch_limits_rad[0];
                        hi[l.q(k) + i] = g.pitch_limits_rad[1];
                        lo[l.dq(k) + i] = -10.0;
                        hi[l.dq(k) + i] = 10.0;
                    }
                }
            }
            for a in 0..l.nu {
                let c = bp.reduced[bp.actuators[a]];
                let effort = joint_of(c).map(|j| j.effort_limit).unwrap_or(0.0);
                lo[l.u(k) + a] = -effort / TORQUE_SCALE;
                hi[l.u(k) + a] = effort / TORQUE_SCALE;
                if l.slacks {
                    lo[l.p(k) + a] = 0.0;
                    hi[l.p(k) + a] = p_max;
                    lo[l.n(k) + a] = 0.0;
                    hi[l.n(k) + a] = p_max;
                }
            }
        }
        for o in 0..l.m {
            let c = bp.reduced[bp.output_coords[o]];
            if let Some(j) = joint_of(c) {
                for jj in 0..=l.degree {
                    lo[l.alpha(o, jj)] = j.lower;
                    hi[l.alpha(o, jj)] = j.upper;
                }
            }
        }
        for i in [l.theta_plus(), l.theta_minus()] {
            lo[i] = -1.0;
            hi[i] = 1.0;
        }
        lo[l.duration()] = g.step_duration_s[0];
        hi[l.duration()] = g.step_duration_s[1];
        lo[l.length()] = g.step_length_m[0];
        hi[l.length()] = g.step_length_m[1];
        if let Some(d) = &self.design {
            for i in 0..2 {
                lo[l.design_var(i)] = d.spec.bounds_m[i][0];
                hi[l.design_var(i)] = d.spec.bounds_m[i][1];
            }
        }
        (lo, hi)
    }
}
