//! The rigid, plastic impact map and the reset map.

mod common;

use common::*;
use model::Side;

/// A pre-impact state: the left (swing) foot on the ground ahead of the right, moving down and
/// forward; the robot moving forward.
fn pre_impact(model: &model::PlanarModel, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut r = rng(seed);
    let legs = model.legs().expect("biped");
    let mut q = model.nominal_pose().expect("pose");
    let c = |j: usize| model.joints[j].coordinate;
    q[c(legs.left.hip)] = -0.35;
    q[c(legs.left.knee)] = 0.15;
    q[c(legs.right.hip)] = 0.3;
    q[c(legs.right.knee)] = 0.2;
    let lf = model.frame_position(&q, legs.left.foot).expect("foot");
    q[1] -= lf[1];
    let mut dq = random_dq(model, &mut r, 1.0);
    for j in model.design_joints() {
        dq[model.joints[j].coordinate] = 0.0;
    }
    dq[0] = 0.6;
    dq[1] = -0.2;
    (q, dq)
}

#[test]
fn impact_conserves_angular_momentum_about_the_impact_point_and_stops_the_foot() {
    let model = adam();
    let legs = model.legs().expect("biped");
    for seed in 0..20 {
        let (q, dq) = pre_impact(&model, seed);
        let foot = model.frame_position(&q, legs.left.foot).expect("foot");
        let imp = model.impact(&q, &dq, legs.left.foot).expect("impact");
        let dq_plus: Vec<f64> = imp.dq_plus.iter().copied().collect();
        // The impacting foot is at rest afterwards.
        let st = model.body_states(&q, &dq_plus).expect("st");
        let v = model.frame_velocity_in(&st, legs.left.foot);
        assert!(
            v[0].abs() < 1e-12 && v[1].abs() < 1e-12,
            "foot velocity after impact {v:?}"
        );
        // The only external impulse acts at the foot, so angular momentum about it is conserved.
        let l_minus = model.angular_momentum_about(&q, &dq, foot).expect("L-");
        let l_plus = model
            .angular_momentum_about(&q, &dq_plus, foot)
            .expect("L+");
        assert!(
            (l_minus - l_plus).abs() < 1e-12 * l_minus.abs().max(1.0),
            "{l_minus} vs {l_plus}"
        );
        // Linear momentum changes by exactly the impulse.
        let m = model.total_mass_kg();
        let com_vel = |dq: &[f64]| {
            let qd: Vec<_> = q
                .iter()
                .zip(dq)
                .map(|(&a, &b)| model::num_dual::Dual64::new(a, b))
                .collect();
            let c = model.center_of_mass(&qd).expect("com");
            [c[0].eps, c[1].eps]
        };
        let (vm, vp) = (com_vel(&dq), com_vel(&dq_plus));
        for k in 0..2 {
            let dp = m * (vp[k] - vm[k]);
            assert!(
                (dp - imp.impulse_ns[k]).abs() < 1e-10 * (1.0 + dp.abs()),
                "Δp {dp} vs Λ {}",
                imp.impulse_ns[k]
            );
        }
        // A plastic impact never adds energy.
        let t_minus = model.kinetic_energy(&q, &dq).expect("T-");
        let t_plus = model.kinetic_energy(&q, &dq_plus).expect("T+");
        assert!(
            t_plus <= t_minus + 1e-12,
            "impact gained energy: {t_minus} -> {t_plus}"
        );
    }
}

#[test]
fn reset_map_swaps_the_legs_and_keeps_base_and_design() {
    let model = adam();
    let legs = model.legs().expect("biped");
    let (q, dq) = pre_impact(&model, 3);
    let reset = model.reset_map(&q, &dq, Side::Left).expect("reset");
    let c = |j: usize| model.joints[j].coordinate;
    assert_eq!(reset.q[c(legs.right.hip)], q[c(legs.left.hip)]);
    assert_eq!(reset.q[c(legs.left.knee)], q[c(legs.right.knee)]);
    assert_eq!(&reset.q[..3], &q[..3]);
    for j in model.design_joints() {
        assert_eq!(reset.q[c(j)], q[c(j)]);
    }
    // After relabeling, the old swing foot (left) is described by the right leg's coordinates
    // and stays at rest: the new stance foot is the right foot.
    let st = model.body_states(&reset.q, &reset.dq).expect("st");
    let v = model.frame_velocity_in(&st, legs.right.foot);
    assert!(
        v[0].abs() < 1e-12 && v[1].abs() < 1e-12,
        "{v:?} {:?} {:?}",
        model.relabel_permutation(),
        reset.dq
    );
    let p_before = model.frame_position(&q, legs.left.foot).expect("p");
    let p_after = model.frame_position(&reset.q, legs.right.foot).expect("p");
    assert!((p_before[0] - p_after[0]).abs() < 1e-12 && (p_before[1] - p_after[1]).abs() < 1e-12);
    // The relabeling is an involution.
    assert_eq!(model.relabel(&model.relabel(&q)), q);
}
