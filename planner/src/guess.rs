//! The starting point of the first (feasibility) solve: a hand-built walking step.
//!
//! The hip moves forward at constant height from −d/2 to +d/2 over the stance foot; the swing
//! foot travels from −d to +d on a smooth arc with a mid-step peak; both legs follow by two-link
//! inverse kinematics; the torso stays upright. Velocities and accelerations are the exact time
//! derivatives of that motion (finite differences), torques the pinned inverse dynamics of it, and α is the least-squares Bézier fit of
//! the outputs against the phase. It is not dynamically consistent: the solver makes it so.

use crate::biped::PlanarBiped;
use crate::collocation::{Layout, ACC_SCALE, TORQUE_SCALE};
use crate::Result;
use model::bezier::bernstein_weights;
use model::Side;

/// Hip and knee angles putting the foot at `rel` (world, from the hip) with the torso upright.
fn leg_ik(rel: [f64; 2], thigh_m: f64, shin_m: f64) -> (f64, f64) {
    let dist2 = (rel[0] * rel[0] + rel[1] * rel[1]).min((thigh_m + shin_m).powi(2) * 0.9999);
    let cos_k =
        ((dist2 - thigh_m * thigh_m - shin_m * shin_m) / (2.0 * thigh_m * shin_m)).clamp(-1.0, 1.0);
    let knee = cos_k.acos();
    let direction = (-rel[0]).atan2(-rel[1]);
    let hip = direction - (shin_m * knee.sin()).atan2(thigh_m + shin_m * knee.cos());
    (hip, knee)
}

/// Reduced configuration at phase s ∈ [0, 1] of the hand-built step.
fn pose(bp: &PlanarBiped, s: f64, step_m: f64, thigh_m: f64, shin_m: f64) -> Vec<f64> {
    let height = 0.94 * (thigh_m + shin_m);
    let hip_x = -0.5 * step_m + step_m * s;
    let smooth = s * s * (3.0 - 2.0 * s);
    let swing = [
        -step_m + 2.0 * step_m * smooth,
        0.07 * (std::f64::consts::PI * s).sin(),
    ];
    let (sh, sk) = leg_ik([-hip_x, -height], thigh_m, shin_m);
    let (wh, wk) = leg_ik([swing[0] - hip_x, swing[1] - height], thigh_m, shin_m);
    let mut q = vec![0.0; bp.nq()];
    let set = |q: &mut Vec<f64>, side: Side, hip: f64, knee: f64| {
        let leg = bp.legs.side(side);
        for (joint, v) in [(leg.hip, hip), (leg.knee, knee)] {
            let c = bp.model.joints[joint].coordinate;
            if let Some(i) = bp.reduced.iter().position(|&r| r == c) {
                q[i] = v;
            }
        }
    };
    set(&mut q, bp.stance, sh, sk);
    set(&mut q, bp.swing(), wh, wk);
    q
}

/// The initial point for `layout`.
pub fn initial_guess(
    bp: &PlanarBiped,
    layout: &Layout,
    step_m: f64,
    duration_s: f64,
) -> Result<Vec<f64>> {
    let q_nom = {
        let mut q = bp.model.nominal_pose()?;
        for &(c, v) in &bp.design {
            q[c] = v;
        }
        q
    };
    let (thigh_m, shin_m) = bp.model.leg_lengths(&q_nom, bp.stance)?;
    let mut x = vec![0.0; layout.len()];
    let n = layout.points();
    let ds = 1e-4;
    let mut theta = vec![0.0; n];
    for k in 0..n {
        let s = layout.time_fraction(k);
        let q = pose(bp, s, step_m, thigh_m, shin_m);
        let qp = pose(bp, (s + ds).min(1.0), step_m, thigh_m, shin_m);
        let qm = pose(bp, (s - ds).max(0.0), step_m, thigh_m, shin_m);
        let h = ((s + ds).min(1.0) - (s - ds).max(0.0)) * duration_s;
        let hs = ds * duration_s;
        let mut ddq = vec![0.0; layout.nq];
        for i in 0..layout.nq {
            x[layout.q(k) + i] = q[i];
            x[layout.dq(k) + i] = (qp[i] - qm[i]) / h;
            // Second difference where both neighbours exist, one-sided at the ends.
            ddq[i] = if k == 0 || k == n - 1 {
                0.0
            } else {
                (qp[i] - 2.0 * q[i] + qm[i]) / (hs * hs)
            };
            x[layout.ddq(k) + i] = ddq[i] / ACC_SCALE;
        }
        // Torques: the pinned-stance inverse dynamics of the guessed motion, projected on the
        // actuated rows (the torso-pitch row stays unbalanced; the solver fixes it).
        let dq_now: Vec<f64> = (0..layout.nq).map(|i| x[layout.dq(k) + i]).collect();
        let [qf, dqf, ddqf] = bp.full_state(&q, &dq_now, &ddq)?;
        let r = bp.model.inverse_dynamics(&qf, &dqf, &ddqf)?;
        let jac = bp.stance_jacobian(&qf)?;
        for (a, &i) in bp.actuators.iter().enumerate() {
            let c = bp.reduced[i];
            let u = r[c] - jac[c][0] * r[0] - jac[c][1] * r[1];
            let limit = bp
                .model
                .joints
                .iter()
                .find(|j| j.coordinate == c)
                .map_or(0.0, |j| j.effort_limit);
            let u = u.clamp(-0.9 * limit, 0.9 * limit);
            x[layout.u(k) + a] = u / TORQUE_SCALE;
            if layout.slacks {
                let power = u * dq_now[i];
                x[layout.p(k) + a] = power.max(0.0) + 0.1;
                x[layout.n(k) + a] = (-power).max(0.0) + 0.1;
            }
        }
        let d = bp
            .model
            .stance_leg_angle_derivatives(&qf, &dqf, &ddqf, &bp.legs, bp.stance)?;
        theta[k] = d.theta;
        x[layout.tau(k) + 1] = d.rate;
        x[layout.tau(k) + 2] = d.accel;
    }
    let (tp, tm) = (theta[0], theta[n - 1]);
    for k in 0..n {
        x[layout.tau(k)] = (theta[k] - tp) / (tm - tp);
        x[layout.tau(k) + 1] /= tm - tp;
        x[layout.tau(k) + 2] /= tm - tp;
    }
    x[layout.theta_plus()] = tp;
    x[layout.theta_minus()] = tm;
    x[layout.duration()] = duration_s;
    x[layout.length()] = step_m;
    // Least-squares Bézier fit of each output against τ.
    let b = layout.degree;
    let mut w = vec![0.0; b + 1];
    for o in 0..layout.m {
        let j = bp.output_coords[o];
        let mut ata = nalgebra::DMatrix::<f64>::zeros(b + 1, b + 1);
        let mut aty = nalgebra::DVector::<f64>::zeros(b + 1);
        for k in 0..n {
            let tau = (theta[k] - tp) / (tm - tp);
            bernstein_weights(b, tau.clamp(0.0, 1.0), &mut w);
            let y = x[layout.q(k) + j];
            for r in 0..=b {
                aty[r] += w[r] * y;
                for c in 0..=b {
                    ata[(r, c)] += w[r] * w[c];
                }
            }
        }
        let alpha = ata
            .lu()
            .solve(&aty)
            .unwrap_or_else(|| nalgebra::DVector::zeros(b + 1));
        for r in 0..=b {
            x[layout.alpha(o, r)] = alpha[r];
        }
    }
    Ok(x)
}
