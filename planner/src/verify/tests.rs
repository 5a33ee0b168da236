//! The closed loop's reduced dynamics against the model's own constrained dynamics, and its
//! controller against the output dynamics it enforces, at states around the shipped gait's.

use super::*;

/// The shipped walking gait's closed loop, and post-impact states around its planned one.
fn closed_loop_and_states() -> (ClosedLoop, Vec<Vec<f64>>) {
    let path = std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/gaits/adam_walk.json"
    ));
    let (gait, model) = load_gait_and_robot(path).expect("shipped gait");
    let cl = ClosedLoop::new(&model, &gait, VerifyOptions::default()).expect("closed loop");
    let x0 = cl.planned_state(&gait, "test").expect("initial state");
    // Deterministic perturbations of up to 0.05 rad and 0.3 rad/s, and the states 0.1 s and
    // 0.4 s along the step.
    let mut states = vec![x0.clone()];
    for k in 1..4 {
        let x: Vec<f64> = x0
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let s = ((i * 7 + k * 13) % 11) as f64 / 10.0 - 0.5;
                v + if i < x0.len() / 2 { 0.1 * s } else { 0.6 * s }
            })
            .collect();
        states.push(x);
    }
    for t in [0.1, 0.4] {
        states.push(cl.flow(&x0, t).expect("flows"));
    }
    (cl, states)
}

/// q̈_r = a₀ + M_r⁻¹ B_r u is the reduced part of the model's KKT solution of the constrained
/// dynamics [D −Aᵀ; A 0] (stance foot pinned, design joints rigid), for several torques.
#[test]
fn reduced_dynamics_are_the_models_constrained_dynamics() {
    let (cl, states) = closed_loop_and_states();
    let bp = &cl.biped;
    let nq = bp.nq();
    let stance_foot = bp.legs.side(bp.stance).foot;
    for x in &states {
        let (qr, dqr) = (&x[..nq], &x[nq..]);
        let p = cl.pinned(qr, dqr).expect("pinned dynamics");
        let [q, dq, _] = bp.full_state(qr, dqr, &vec![0.0; nq]).expect("full state");
        for u in [
            vec![0.0; bp.nu()],
            vec![10.0, -5.0, 20.0, -15.0],
            vec![-30.0, 30.0, 1.0, 0.5],
        ] {
            let ours = cl.reduced_accelerations(&p, &u);
            let kkt = bp
                .model
                .constrained_accelerations(&q, &dq, &[&u], &[stance_foot])
                .expect("constrained dynamics");
            for (i, &c) in bp.reduced.iter().enumerate() {
                let (a, b) = (ours[i], kkt[0][c]);
                assert!(
                    (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
                    "q̈ of coordinate {c} at x = {x:?}, u = {u:?}: {a} against {b}"
                );
            }
        }
    }
}

/// The input–output linearizing torque makes the outputs obey ÿ + 2εẏ + ε²y = 0, with ẏ and
/// ÿ computed here from the full state (the model's stance-leg angle and the Bézier
/// polynomials), not from the closed loop's affine decomposition.
#[test]
fn the_controller_enforces_the_output_dynamics() {
    let (cl, states) = closed_loop_and_states();
    let bp = &cl.biped;
    let nq = bp.nq();
    let eps = cl.options.epsilon_per_s;
    let span = cl.theta_minus - cl.theta_plus;
    for x in &states {
        let field = cl.field(x).expect("field");
        let (qr, dqr, ddqr) = (&x[..nq], &x[nq..], &field.f[nq..]);
        let [q, dq, ddq] = bp.full_state(qr, dqr, ddqr).expect("full state");
        let th = bp
            .model
            .stance_leg_angle_derivatives(&q, &dq, &ddq, &bp.legs, bp.stance)
            .expect("stance angle");
        let (tau, td, tdd) = (
            (th.theta - cl.theta_plus) / span,
            th.rate / span,
            th.accel / span,
        );
        for (o, &j) in bp.output_coords.iter().enumerate() {
            let (b0, b1, b2) = bezier::eval_all(&cl.alpha[o], tau);
            let y = qr[j] - b0;
            let dy = dqr[j] - b1 * td;
            let ddy = ddqr[j] - b2 * td * td - b1 * tdd;
            assert!((y - field.y[o]).abs() < 1e-12, "y of output {o}");
            let residual = ddy + 2.0 * eps * dy + eps * eps * y;
            assert!(
                residual.abs() < 1e-8 * (1.0 + ddy.abs()),
                "output {o} at x = {x:?}: ÿ + 2εẏ + ε²y = {residual}"
            );
        }
    }
}
