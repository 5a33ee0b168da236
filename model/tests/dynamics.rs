//! The dynamics checked against independent computations: the Lagrangian (Christoffel symbols of
//! D from dual numbers), the kinetic energy from the velocity recursion, energy conservation, and
//! finite differences.

mod common;

use common::*;
use model::num_dual::Dual64;
use model::{PlanarModel, Side};
use nalgebra::{DMatrix, DVector};

fn dual_at(q: &[f64], i: usize) -> Vec<Dual64> {
    q.iter()
        .enumerate()
        .map(|(k, &v)| {
            if k == i {
                Dual64::from(v).derivative()
            } else {
                Dual64::from(v)
            }
        })
        .collect()
}

/// ∂D/∂q_i for every i, by forward-mode dual numbers.
fn mass_matrix_derivatives(model: &PlanarModel, q: &[f64]) -> Vec<DMatrix<f64>> {
    let n = model.dof();
    (0..n)
        .map(|i| {
            let qd = dual_at(q, i);
            let zero = vec![Dual64::from(0.0); n];
            let d = model.dynamics(&qd, &zero).expect("dynamics").mass_matrix;
            d.map(|v| v.eps)
        })
        .collect()
}

/// Coriolis matrix from the Christoffel symbols of the first kind.
fn christoffel_coriolis(dd: &[DMatrix<f64>], dq: &[f64]) -> DMatrix<f64> {
    let n = dq.len();
    DMatrix::from_fn(n, n, |k, j| {
        (0..n)
            .map(|i| 0.5 * (dd[i][(k, j)] + dd[j][(k, i)] - dd[k][(i, j)]) * dq[i])
            .sum()
    })
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_over_random_configurations() {
    let model = adam();
    let mut r = rng(1);
    let mut worst_eig = f64::INFINITY;
    for _ in 0..300 {
        let q = random_q(&model, &mut r);
        let d = model
            .dynamics(&q, &vec![0.0; model.dof()])
            .expect("dynamics")
            .mass_matrix;
        let asym = (&d - d.transpose()).abs().max() / d.abs().max();
        assert!(asym < 1e-14, "D not symmetric: {asym}");
        let eig = d.symmetric_eigenvalues().min();
        worst_eig = worst_eig.min(eig);
        assert!(eig > 0.0, "D not positive definite at {q:?}: λ_min = {eig}");
    }
    // The smallest eigenvalue belongs to the foot masses moving along the shin (0.06 kg).
    assert!(worst_eig > 1e-4, "λ_min = {worst_eig}");
}

#[test]
fn kinetic_energy_from_velocities_equals_quadratic_form_of_d() {
    let model = adam();
    let mut r = rng(2);
    for _ in 0..100 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 2.0);
        let d = model.dynamics(&q, &dq).expect("dynamics").mass_matrix;
        let v = DVector::from_column_slice(&dq);
        let quad = 0.5 * (v.transpose() * &d * &v)[0];
        let t = model.kinetic_energy(&q, &dq).expect("energy");
        assert!(
            (quad - t).abs() <= 1e-12 * t.abs().max(1.0),
            "{quad} vs {t}"
        );
    }
}

#[test]
fn drift_equals_the_lagrangian_christoffel_form() {
    let model = adam();
    let mut r = rng(3);
    for _ in 0..40 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 3.0);
        let h = model.dynamics(&q, &dq).expect("dynamics").drift;
        let dd = mass_matrix_derivatives(&model, &q);
        let c = christoffel_coriolis(&dd, &dq);
        let grav: Vec<f64> = (0..model.dof())
            .map(|i| model.potential_energy(&dual_at(&q, i)).expect("V").eps)
            .collect();
        let lagrange = c * DVector::from_column_slice(&dq) + DVector::from_vec(grav);
        let err = rel_diff(h.as_slice(), lagrange.as_slice());
        assert!(err < 1e-12, "H differs from C q̇ + G by {err} (relative)");
    }
}

#[test]
fn d_dot_minus_two_c_is_skew_symmetric() {
    let model = adam();
    let mut r = rng(4);
    for _ in 0..20 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 3.0);
        let dd = mass_matrix_derivatives(&model, &q);
        let n = model.dof();
        let d_dot = (0..n).fold(DMatrix::zeros(n, n), |acc, i| acc + &dd[i] * dq[i]);
        let n_mat = d_dot.clone() - christoffel_coriolis(&dd, &dq) * 2.0;
        let sym = (&n_mat + n_mat.transpose()).abs().max() / d_dot.abs().max().max(1e-12);
        assert!(sym < 1e-12, "Ḋ − 2C is not skew-symmetric: {sym}");
    }
}

type Rhs<'a> = dyn Fn(&[f64], &[f64]) -> Vec<f64> + 'a;

/// Integrates with classic RK4 and returns the largest |E − E0| relative to the largest kinetic
/// energy reached (the energy that actually moved between kinetic and potential form).
fn rk4_energy_drift(
    model: &PlanarModel,
    q0: &[f64],
    dq0: &[f64],
    f: &Rhs<'_>,
    dt: f64,
    t_end: f64,
) -> (f64, f64) {
    let energy = |q: &[f64], dq: &[f64]| {
        model.kinetic_energy(q, dq).expect("T") + model.potential_energy(q).expect("V")
    };
    let (mut q, mut dq) = (q0.to_vec(), dq0.to_vec());
    let e0 = energy(&q, &dq);
    let (mut worst, mut t_max) = (0.0_f64, 0.0_f64);
    let steps = (t_end / dt).round() as usize;
    let axpy = |x: &[f64], k: f64, y: &[f64]| -> Vec<f64> {
        x.iter().zip(y).map(|(a, b)| a + k * b).collect()
    };
    for _ in 0..steps {
        let k1q = dq.clone();
        let k1v = f(&q, &dq);
        let (q2, v2) = (axpy(&q, dt / 2.0, &k1q), axpy(&dq, dt / 2.0, &k1v));
        let k2v = f(&q2, &v2);
        let (q3, v3) = (axpy(&q, dt / 2.0, &v2), axpy(&dq, dt / 2.0, &k2v));
        let k3v = f(&q3, &v3);
        let (q4, v4) = (axpy(&q, dt, &v3), axpy(&dq, dt, &k3v));
        let k4v = f(&q4, &v4);
        for i in 0..q.len() {
            q[i] += dt / 6.0 * (k1q[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            dq[i] += dt / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
        }
        worst = worst.max((energy(&q, &dq) - e0).abs());
        t_max = t_max.max(model.kinetic_energy(&q, &dq).expect("T"));
    }
    (worst / t_max, t_max)
}

#[test]
fn energy_is_conserved_in_flight_with_zero_torque() {
    let model = adam();
    let mut r = rng(5);
    let q0 = random_q(&model, &mut r);
    let mut dq0 = random_dq(&model, &mut r, 1.0);
    for j in model.design_joints() {
        dq0[model.joints[j].coordinate] = 0.0;
    }
    let u = vec![0.0; model.actuated_joints().len()];
    let f = |q: &[f64], dq: &[f64]| {
        model
            .forward_dynamics(q, dq, &u)
            .expect("ddq")
            .as_slice()
            .to_vec()
    };
    let (drift, t_max) = rk4_energy_drift(&model, &q0, &dq0, &f, 5e-4, 2.0);
    println!("flight: relative energy drift {drift:.2e}, max kinetic energy {t_max:.1} J");
    assert!(
        t_max > 1.0,
        "the test must exchange energy: max kinetic energy {t_max} J"
    );
    assert!(drift < 1e-6, "relative energy drift {drift}");
}

#[test]
fn energy_is_conserved_in_pinned_stance_with_zero_torque() {
    let model = adam();
    let legs = model.legs().expect("biped");
    let stance = legs.side(Side::Right).foot;
    let mut r = rng(6);
    let q0 = random_q(&model, &mut r);
    // Project a random velocity onto the constraint J q̇ = 0 (stance foot at rest).
    let st = model.body_poses(&q0).expect("poses");
    let j = model.frame_jacobian(&st, stance);
    // Design joints stay still: zero their velocity and their Jacobian columns, then project.
    let mut v = DVector::from_vec(random_dq(&model, &mut r, 1.0));
    let mut j = j;
    for jd in model.design_joints() {
        let c = model.joints[jd].coordinate;
        v[c] = 0.0;
        j.column_mut(c).fill(0.0);
    }
    let jjt = &j * j.transpose();
    let lam = jjt.lu().solve(&(&j * &v)).expect("regular");
    let dq0: Vec<f64> = (v - j.transpose() * lam).as_slice().to_vec();
    let u = vec![0.0; model.actuated_joints().len()];
    let f = |q: &[f64], dq: &[f64]| {
        model
            .constrained_dynamics(q, dq, &u, &[stance])
            .expect("ddq")
            .ddq
            .as_slice()
            .to_vec()
    };
    // The robot falls around its pinned foot and the free leg whips (kinetic energy reaches
    // ~175 J); RK4's error shrinks as dt⁴ (measured: 3.3e-2, 3.7e-3, 2.0e-4 at dt = 1e-3, 5e-4,
    // 2.5e-4 s), so dt = 5e-5 s is the step that resolves this motion to 1e-6.
    let (drift, t_max) = rk4_energy_drift(&model, &q0, &dq0, &f, 5e-5, 2.0);
    println!("pinned stance: relative energy drift {drift:.2e}, max kinetic energy {t_max:.1} J");
    assert!(t_max > 1.0, "max kinetic energy {t_max} J");
    assert!(drift < 1e-6, "relative energy drift {drift}");
}

#[test]
fn constrained_dynamics_keeps_the_stance_foot_unaccelerated() {
    let model = adam();
    let legs = model.legs().expect("biped");
    let mut r = rng(7);
    for _ in 0..20 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 2.0);
        let u = [5.0, -3.0, 2.0, 7.0];
        let foot = legs.left.foot;
        let sol = model
            .constrained_dynamics(&q, &dq, &u, &[foot])
            .expect("ddq");
        let st = model.body_states(&q, &dq).expect("st");
        let jac = model.frame_jacobian(&st, foot);
        let bias = model.frame_bias_acceleration_in(&st, foot);
        let acc = &jac * &sol.ddq;
        assert!((acc[0] + bias[0]).abs() < 1e-9 && (acc[1] + bias[1]).abs() < 1e-9);
        // Newton for the whole robot: contact force + gravity = Σ m_b a_b, with each body's com
        // acceleration J_b q̈ + J̇_b q̇ (Jacobians and bias accelerations are checked against
        // finite differences and the Lagrangian in the tests above).
        let f = sol.forces_n[0];
        let mut m_a = [0.0, 0.0];
        for (b, body) in model.bodies.iter().enumerate() {
            let i = body.inertia;
            let com = model.point_position(&st, b, i.com_xz_m);
            let ja = model.point_jacobian(&st, b, com) * &sol.ddq;
            let bias = model.point_bias_acceleration(&st, b, i.com_xz_m);
            m_a[0] += i.mass_kg * (ja[0] + bias[0]);
            m_a[1] += i.mass_kg * (ja[1] + bias[1]);
        }
        let m = model.total_mass_kg();
        let g = model.gravity_mps2;
        assert!(
            (f[0] - m_a[0]).abs() < 1e-9 * m * g,
            "Fx {} vs Σ m a {}",
            f[0],
            m_a[0]
        );
        assert!(
            (f[1] - (m_a[1] + m * g)).abs() < 1e-9 * m * g,
            "Fz {} vs Σ m a + m g {}",
            f[1],
            m_a[1] + m * g
        );
    }
}

#[test]
fn dual_number_derivatives_equal_central_differences() {
    let model = adam();
    let legs = model.legs().expect("biped");
    let mut r = rng(8);
    let q = random_q(&model, &mut r);
    let dq = random_dq(&model, &mut r, 2.0);
    let u = [3.0, -2.0, 1.5, 4.0];
    let h = 1e-6;
    // Quantities as flat vectors: D, H, stance ddq and force, swing-foot position, stance angle.
    let eval = |q: &[Dual64]| -> Vec<Dual64> {
        let dqd: Vec<Dual64> = dq.iter().map(|&v| Dual64::from(v)).collect();
        let ud: Vec<Dual64> = u.iter().map(|&v| Dual64::from(v)).collect();
        let dy = model.dynamics(q, &dqd).expect("dyn");
        let cd = model
            .constrained_dynamics(q, &dqd, &ud, &[legs.right.foot])
            .expect("cd");
        let st = model.body_poses(q).expect("st");
        let mut out: Vec<Dual64> = dy.mass_matrix.iter().copied().collect();
        out.extend(dy.drift.iter().copied());
        out.extend(cd.ddq.iter().copied());
        out.extend(cd.forces_n[0]);
        out.extend(model.frame_position_in(&st, legs.left.foot));
        out.push(model.stance_leg_angle_in(&st, &legs, Side::Right));
        out
    };
    for i in 0..model.dof() {
        let exact: Vec<f64> = eval(&dual_at(&q, i)).iter().map(|v| v.eps).collect();
        let shift = |s: f64| -> Vec<f64> {
            let mut qs = q.clone();
            qs[i] += s;
            let qd: Vec<Dual64> = qs.iter().map(|&v| Dual64::from(v)).collect();
            eval(&qd).iter().map(|v| v.re).collect()
        };
        let (p, m) = (shift(h), shift(-h));
        let fd: Vec<f64> = p.iter().zip(&m).map(|(a, b)| (a - b) / (2.0 * h)).collect();
        // Central differences: truncation O(h²) ≈ 1e-12 and rounding ≈ 1e-16·|f|/h ≈ 1e-10·|f|.
        let err = rel_diff(&exact, &fd);
        assert!(
            err < 1e-6,
            "∂/∂q_{i}: dual vs finite differences differ by {err} (relative)"
        );
    }
}

#[test]
fn stance_leg_angle_rate_matches_dual_numbers() {
    let model = adam();
    let legs = model.legs().expect("biped");
    let mut r = rng(9);
    for _ in 0..20 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 2.0);
        let qd: Vec<Dual64> = q
            .iter()
            .zip(&dq)
            .map(|(&a, &b)| Dual64::new(a, b))
            .collect();
        let theta = model.stance_leg_angle(&qd, &legs, Side::Left).expect("θ");
        let (t, rate) = model
            .stance_leg_angle_rate(&q, &dq, &legs, Side::Left)
            .expect("θ̇");
        assert!((theta.re - t).abs() < 1e-15);
        assert!((theta.eps - rate).abs() < 1e-12 * rate.abs().max(1.0));
    }
}

#[test]
fn inverse_dynamics_equals_mass_matrix_times_acceleration_plus_drift() {
    let model = adam();
    let mut r = rng(10);
    for _ in 0..50 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 3.0);
        let ddq = random_dq(&model, &mut r, 20.0);
        let dy = model.dynamics(&q, &dq).expect("dyn");
        let expected = &dy.mass_matrix * DVector::from_column_slice(&ddq) + &dy.drift;
        let id = model.inverse_dynamics(&q, &dq, &ddq).expect("id");
        let err = rel_diff(id.as_slice(), expected.as_slice());
        assert!(
            err < 1e-13,
            "inverse dynamics differs from D q̈ + H by {err} (relative)"
        );
    }
}

#[test]
fn stance_leg_angle_acceleration_matches_second_order_dual_numbers() {
    use model::num_dual::Dual2_64;
    let model = adam();
    let legs = model.legs().expect("biped");
    let mut r = rng(11);
    for _ in 0..20 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 2.0);
        let ddq = random_dq(&model, &mut r, 10.0);
        // θ(q + s q̇ + ½ s² q̈): first and second derivative at s = 0 are θ̇ and θ̈.
        let qs: Vec<Dual2_64> = (0..q.len())
            .map(|i| Dual2_64::new(q[i], dq[i], ddq[i]))
            .collect();
        let th = model.stance_leg_angle(&qs, &legs, Side::Right).expect("θ");
        let d = model
            .stance_leg_angle_derivatives(&q, &dq, &ddq, &legs, Side::Right)
            .expect("derivatives");
        assert!((d.theta - th.re).abs() < 1e-14);
        assert!(
            (d.rate - th.v1).abs() < 1e-12 * th.v1.abs().max(1.0),
            "{} vs {}",
            d.rate,
            th.v1
        );
        assert!(
            (d.accel - th.v2).abs() < 1e-11 * th.v2.abs().max(1.0),
            "{} vs {}",
            d.accel,
            th.v2
        );
    }
}

#[test]
fn body_poses_equal_the_poses_of_body_states_bit_for_bit() {
    // `body_poses_into` is the simulator's every-step kinematics, the pose half of
    // `body_states_into`: the same poses, for f64 and for dual numbers (the planner's).
    let model = adam();
    let mut r = rng(12);
    for _ in 0..50 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 2.0);
        let full = model.body_states(&q, &dq).expect("states");
        let poses = model.body_poses(&q).expect("poses");
        assert_eq!(poses.len, full.len);
        for b in 0..full.len {
            let (p, f) = (poses.pose[b], full.pose[b]);
            assert_eq!(p.pitch_rad.to_bits(), f.pitch_rad.to_bits(), "body {b}");
            for k in 0..2 {
                assert_eq!(p.xz_m[k].to_bits(), f.xz_m[k].to_bits(), "body {b}");
                assert_eq!(poses.vel_xz[b][k], 0.0);
                assert_eq!(poses.bias_acc_xz[b][k], 0.0);
            }
            assert_eq!(poses.omega[b], 0.0);
        }
        let q_dual: Vec<Dual64> = q.iter().map(|&v| Dual64::new(v, 1.0)).collect();
        let dq_dual: Vec<Dual64> = dq.iter().map(|&v| Dual64::from(v)).collect();
        let full = model.body_states(&q_dual, &dq_dual).expect("states");
        let poses = model.body_poses(&q_dual).expect("poses");
        for b in 0..full.len {
            let (p, f) = (poses.pose[b], full.pose[b]);
            for (x, y) in [
                (p.xz_m[0], f.xz_m[0]),
                (p.xz_m[1], f.xz_m[1]),
                (p.pitch_rad, f.pitch_rad),
            ] {
                assert_eq!(x.re.to_bits(), y.re.to_bits(), "body {b}");
                assert_eq!(x.eps.to_bits(), y.eps.to_bits(), "body {b}");
            }
        }
    }
}

#[test]
fn allocation_free_dynamics_equals_dynamics_bit_for_bit() {
    // `dynamics_into` is the simulator's 10 kHz path; it must be the same computation.
    for model in [
        adam(),
        PlanarModel::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../configs/robots/adam_codesign.urdf"
        ))
        .expect("co-designed ADAM"),
    ] {
        let n = model.dof();
        let mut r = rng(11);
        let mut d = DMatrix::from_element(n, n, f64::NAN);
        let mut h = DVector::from_element(n, f64::NAN);
        for _ in 0..50 {
            let q = random_q(&model, &mut r);
            let dq = random_dq(&model, &mut r, 2.0);
            let reference = model.dynamics(&q, &dq).expect("dynamics");
            let st = model.body_states(&q, &dq).expect("states");
            model.dynamics_into(&st, &mut d, &mut h).expect("into");
            for (a, b) in d.iter().zip(reference.mass_matrix.iter()) {
                assert_eq!(a.to_bits(), b.to_bits(), "D");
            }
            for (a, b) in h.iter().zip(reference.drift.iter()) {
                assert_eq!(a.to_bits(), b.to_bits(), "H");
            }
        }
        let mut wrong = DVector::zeros(n + 1);
        let st = model
            .body_states(&vec![0.0; n], &vec![0.0; n])
            .expect("states");
        assert!(model.dynamics_into(&st, &mut d, &mut wrong).is_err());
    }
}

#[test]
fn inverse_dynamics_and_stance_angle_from_states_of_a_shifted_base_are_the_pinned_ones() {
    // The planner evaluates inverse dynamics and the stance-leg angle from one kinematics pass
    // with the floating base at rest at the origin, and only sets the base acceleration. That
    // is sound only if they depend on relative positions alone: states computed at another base
    // position and base linear velocity must give the same result to rounding.
    let model = adam();
    let legs = model.legs().expect("biped");
    let inertias = model.inertias::<f64>();
    let mut r = rng(13);
    for _ in 0..50 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 3.0);
        let ddq = random_dq(&model, &mut r, 20.0);
        let expected = model.inverse_dynamics(&q, &dq, &ddq).expect("id");
        let angle = model
            .stance_leg_angle_derivatives(&q, &dq, &ddq, &legs, Side::Right)
            .expect("angle");
        let (mut q0, mut dq0) = (q.clone(), dq.clone());
        q0[0] = 0.0;
        q0[1] = 0.0;
        dq0[0] = 0.0;
        dq0[1] = 0.0;
        let mut st = model::kinematics::BodyStates::zeroed();
        model.body_states_into(&q0, &dq0, &mut st).expect("states");
        let mut out = vec![0.0; model.dof()];
        model
            .inverse_dynamics_in(&inertias, &st, &ddq, &mut out)
            .expect("id from states");
        let err = rel_diff(&out, expected.as_slice());
        assert!(err < 1e-13, "inverse dynamics differs by {err} (relative)");
        // The stance-leg angle also ignores the base's linear acceleration.
        let mut ddq0 = ddq.clone();
        ddq0[0] = 0.0;
        ddq0[1] = 0.0;
        let a = model
            .stance_leg_angle_derivatives_in(&st, &ddq0, &legs, Side::Right)
            .expect("angle from states");
        for (x, y) in [
            (a.theta, angle.theta),
            (a.rate, angle.rate),
            (a.accel, angle.accel),
        ] {
            assert!((x - y).abs() < 1e-12 * y.abs().max(1.0), "{x} vs {y}");
        }
        // The stored (sin, cos) are those of each body's pitch.
        for b in 0..st.len {
            let (s, c) = st.sin_cos[b];
            let (s0, c0) = st.pose[b].pitch_rad.sin_cos();
            assert_eq!(
                (s.to_bits(), c.to_bits()),
                (s0.to_bits(), c0.to_bits()),
                "body {b}"
            );
        }
    }
    // Wrong lengths are errors, not panics.
    let st = model
        .body_states(&vec![0.0; model.dof()], &vec![0.0; model.dof()])
        .expect("st");
    let mut short = vec![0.0; model.dof() - 1];
    assert!(model
        .inverse_dynamics_in(&inertias, &st, &vec![0.0; model.dof()], &mut short)
        .is_err());
}

#[test]
fn constant_mass_properties_give_the_lifted_ones_hyper_dual_parts() {
    // The planner passes a fixed design's mass properties as `Constant`s, which scale a dual
    // number part by part instead of applying the product rule to a factor with zero
    // derivatives. Every part of the result must be the lifted computation's: the dropped
    // terms are exact zeros, so the values are equal (not merely close).
    use model::kinematics::BodyStates;
    use model::num_dual::HyperDual64;
    let model = adam();
    let lifted = model.inertias::<HyperDual64>();
    let fixed = model.constant_inertias();
    let n = model.dof();
    let mut r = rng(29);
    let mut nonzero_second = 0;
    for trial in 0..20 {
        let q = random_q(&model, &mut r);
        let dq = random_dq(&model, &mut r, 3.0);
        let ddq = random_dq(&model, &mut r, 20.0);
        // Seeds: ε1 on q_a, ε2 on q̇_b or q_b (a second derivative that is not zero).
        let (a, b) = (2 + trial % (n - 2), (trial * 7) % n);
        let seed = |v: &[f64], e1: Option<usize>, e2: Option<usize>| -> Vec<HyperDual64> {
            v.iter()
                .enumerate()
                .map(|(i, &x)| {
                    let d1 = if e1 == Some(i) { 1.0 } else { 0.0 };
                    let d2 = if e2 == Some(i) { 1.0 } else { 0.0 };
                    HyperDual64::new(x, d1, d2, 0.0)
                })
                .collect()
        };
        let (qh, dqh) = if trial % 2 == 0 {
            (seed(&q, Some(a), Some(b)), seed(&dq, None, None))
        } else {
            (seed(&q, Some(a), None), seed(&dq, None, Some(b)))
        };
        let ddqh = seed(&ddq, None, None);
        let mut st = BodyStates::zeroed();
        model.body_states_into(&qh, &dqh, &mut st).expect("states");
        let zero = HyperDual64::from(0.0);
        let (mut with_lifted, mut with_constants) = (vec![zero; n], vec![zero; n]);
        model
            .inverse_dynamics_in(&lifted, &st, &ddqh, &mut with_lifted)
            .expect("lifted");
        model
            .inverse_dynamics_in(&fixed, &st, &ddqh, &mut with_constants)
            .expect("constants");
        for (x, y) in with_lifted.iter().zip(&with_constants) {
            assert_eq!(
                (x.re, x.eps1, x.eps2, x.eps1eps2),
                (y.re, y.eps1, y.eps2, y.eps1eps2),
                "trial {trial}"
            );
            nonzero_second += usize::from(x.eps1eps2 != 0.0);
        }
    }
    assert!(
        nonzero_second > 20,
        "{nonzero_second} non-zero second derivatives compared"
    );
}
