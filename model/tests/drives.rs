//! The joint drives (armature N² J_rotor and viscous friction b q̇) checked against independent
//! computations: the mass matrix against a hand computation, the energy balance of a damped
//! motion (the energy lost is ∫ b q̇² dt, the work put in ∫ u·q̇ dt), inverse against forward
//! dynamics, and the URDF elements that carry them.

#![allow(clippy::unwrap_used)]

mod common;

use common::*;
use model::{JointDrive, JointKind, ModelError, PlanarModel};

/// A1 constants: gear ratio 9.1, rotor inertia 0.01 / 9.1² kg·m² (armature 0.01 kg·m²).
const GEAR: f64 = 9.1;
const ROTOR_KGM2: f64 = 0.01 / (9.1 * 9.1);

/// `model` with the same drive (armature, `damping`) on every revolute joint, and no other.
fn with_drives(mut model: PlanarModel, damping: f64) -> PlanarModel {
    for j in &mut model.joints {
        j.drive = match j.kind {
            JointKind::Revolute { .. } => JointDrive {
                damping_nms_per_rad: damping,
                gear_ratio: Some(GEAR),
                rotor_inertia_kgm2: Some(ROTOR_KGM2),
                torque_constant_nm_per_a: Some(0.092),
                winding_resistance_ohm: Some(0.25),
            },
            JointKind::Prismatic { .. } => JointDrive::default(),
        };
    }
    model
}

fn rigid(mut model: PlanarModel) -> PlanarModel {
    for j in &mut model.joints {
        j.drive = JointDrive::default();
    }
    model
}

#[test]
fn armature_adds_n_squared_j_rotor_to_each_actuated_diagonal_entry_and_nothing_else() {
    let base = rigid(adam());
    let driven = with_drives(base.clone(), 0.0);
    // Hand computation: 9.1² × (0.01 / 9.1²) = 0.01 kg·m².
    let hand = 9.1 * 9.1 * ROTOR_KGM2;
    assert!((hand - 0.01).abs() < 1e-15);
    let mut r = rng(7);
    for _ in 0..20 {
        let q = random_q(&base, &mut r);
        let dq = random_dq(&base, &mut r, 2.0);
        let d0 = base.dynamics(&q, &dq).unwrap().mass_matrix;
        let d1 = driven.dynamics(&q, &dq).unwrap().mass_matrix;
        let diff = &d1 - &d0;
        for i in 0..base.dof() {
            for k in 0..base.dof() {
                let revolute = i == k
                    && i >= 3
                    && matches!(base.joints[i - 3].kind, JointKind::Revolute { .. });
                let expected = if revolute { hand } else { 0.0 };
                assert!(
                    (diff[(i, k)] - expected).abs() < 1e-12,
                    "D[{i},{k}] changed by {} (expected {expected})",
                    diff[(i, k)]
                );
            }
        }
        // The allocation-free D of the simulator agrees with it.
        let st = driven.body_states(&q, &dq).unwrap();
        let n = driven.dof();
        let mut dm = nalgebra::DMatrix::zeros(n, n);
        let mut h = nalgebra::DVector::zeros(n);
        driven.dynamics_into(&st, &mut dm, &mut h).unwrap();
        let reference = driven.dynamics(&q, &dq).unwrap();
        assert!((&dm - &reference.mass_matrix).abs().max() < 1e-12);
        assert!((&h - &reference.drift).abs().max() < 1e-10);
    }
}

#[test]
fn a_model_without_drive_data_is_the_rigid_body_model() {
    // The five-link walker's URDF has no <dynamics> or <transmission>: zero drives.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/robots/five_link_walker.urdf"
    );
    let m = PlanarModel::from_urdf_file(path).unwrap();
    assert!(m.joints.iter().all(|j| j.drive == JointDrive::default()));
    assert_eq!(m.drives().count(), 0);
}

/// Flight dynamics (gravity, no contact) with constant torques, integrated by RK4 with the
/// work ∫ u·q̇ dt and the dissipation ∫ b q̇² dt as two more states.
fn integrate(model: &PlanarModel, q0: &[f64], dq0: &[f64], u: &[f64], b: f64) -> [f64; 4] {
    let n = model.dof();
    let act = model.actuated_joints();
    let revolute: Vec<usize> = model.drives().map(|(c, _, _)| c).collect();
    let field = |x: &[f64]| -> Vec<f64> {
        let (q, dq) = (&x[..n], &x[n..2 * n]);
        let ddq = model.forward_dynamics(q, dq, u).unwrap();
        let mut f = Vec::with_capacity(2 * n + 2);
        f.extend_from_slice(dq);
        f.extend(ddq.iter());
        let power: f64 = act
            .iter()
            .enumerate()
            .map(|(k, &j)| u[k] * dq[model.joints[j].coordinate])
            .sum();
        let loss: f64 = revolute.iter().map(|&c| b * dq[c] * dq[c]).sum();
        f.push(power);
        f.push(loss);
        f
    };
    let mut x: Vec<f64> = q0.iter().chain(dq0).copied().chain([0.0, 0.0]).collect();
    let energy = |x: &[f64]| {
        model.kinetic_energy(&x[..n], &x[n..2 * n]).unwrap()
            + model.potential_energy(&x[..n]).unwrap()
    };
    let e0 = energy(&x);
    let h = 1e-4;
    for _ in 0..3000 {
        let k1 = field(&x);
        let x2: Vec<f64> = x.iter().zip(&k1).map(|(a, k)| a + 0.5 * h * k).collect();
        let k2 = field(&x2);
        let x3: Vec<f64> = x.iter().zip(&k2).map(|(a, k)| a + 0.5 * h * k).collect();
        let k3 = field(&x3);
        let x4: Vec<f64> = x.iter().zip(&k3).map(|(a, k)| a + h * k).collect();
        let k4 = field(&x4);
        for i in 0..x.len() {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    [e0, energy(&x), x[2 * n], x[2 * n + 1]]
}

#[test]
fn energy_balance_with_friction_the_loss_is_the_integral_of_b_qdot_squared() {
    let model = with_drives(rigid(adam()), 0.5);
    let mut r = rng(11);
    let q0 = random_q(&model, &mut r);
    let dq0 = model
        .joints
        .iter()
        .fold(random_dq(&model, &mut r, 3.0), |mut v, j| {
            if let JointKind::Prismatic { .. } = j.kind {
                v[j.coordinate] = 0.0;
            }
            v
        });
    let u = [2.0, -1.5, 3.0, -0.5];
    let [e0, e1, work, loss] = integrate(&model, &q0, &dq0, &u, 0.5);
    // ΔE = W − ∫ b q̇²: the balance holds to the integrator's accuracy.
    let residual = (e1 - e0) - (work - loss);
    println!(
        "ΔE = {:.9} J, work = {work:.9} J, friction loss = {loss:.9} J, residual {residual:.2e} J",
        e1 - e0
    );
    assert!(loss > 0.1, "the motion must dissipate measurably: {loss} J");
    assert!(
        residual.abs() < 1e-7 * (1.0 + loss),
        "residual {residual} J"
    );
    // Without friction, nothing is lost: the same balance with loss 0.
    let frictionless = with_drives(rigid(adam()), 0.0);
    let [f0, f1, fwork, floss] = integrate(&frictionless, &q0, &dq0, &u, 0.0);
    assert_eq!(floss, 0.0);
    assert!(((f1 - f0) - fwork).abs() < 1e-7 * (1.0 + fwork.abs()));
}

#[test]
fn inverse_dynamics_with_armature_and_friction_inverts_forward_dynamics() {
    let model = with_drives(rigid(adam()), 0.7);
    let mut r = rng(3);
    let act = model.actuated_joints();
    let design: Vec<usize> = model
        .design_joints()
        .iter()
        .map(|&j| model.joints[j].coordinate)
        .collect();
    for _ in 0..20 {
        let q = random_q(&model, &mut r);
        let mut dq = random_dq(&model, &mut r, 3.0);
        for &c in &design {
            dq[c] = 0.0;
        }
        let u: Vec<f64> = (0..act.len()).map(|k| 5.0 * (k as f64 - 1.5)).collect();
        let ddq = model.forward_dynamics(&q, &dq, &u).unwrap();
        let tau = model
            .inverse_dynamics(&q, &dq, ddq.as_slice())
            .expect("inverse dynamics");
        let bu = model.generalized_forces(&u).unwrap();
        for i in 0..model.dof() {
            if design.contains(&i) {
                continue; // the rigid design joints' constraint forces
            }
            assert!(
                (tau[i] - bu[i]).abs() < 1e-9 * (1.0 + bu[i].abs()),
                "coordinate {i}: inverse dynamics {} vs B u {}",
                tau[i],
                bu[i]
            );
        }
    }
}

fn urdf_with(extra: &str, dynamics: &str) -> String {
    let (_, text) =
        model::design::generate_model(&model::design::DesignLengths::ADAM).expect("ADAM");
    // Drop the generator's own drives (if any) so that only the test's are present.
    let mut text = strip_transmissions(&text).replace(
        "<joint name=\"left_knee_pitch\" type=\"revolute\">",
        &format!("<joint name=\"left_knee_pitch\" type=\"revolute\">{dynamics}"),
    );
    text = text.replace("</robot>", &format!("{extra}</robot>"));
    text
}

fn strip_transmissions(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(a) = rest.find("<transmission") {
        out.push_str(&rest[..a]);
        let b = rest[a..].find("</transmission>").unwrap() + a + "</transmission>".len();
        rest = &rest[b..];
    }
    out.push_str(rest);
    out.lines()
        .filter(|l| !l.trim_start().starts_with("<dynamics"))
        .collect::<Vec<_>>()
        .join("\n")
}

const KNEE_TRANSMISSION: &str = "<transmission name=\"knee_a1\"><type>transmission_interface/SimpleTransmission</type><joint name=\"left_knee_pitch\"/><actuator name=\"knee_motor\"><mechanicalReduction>9.1</mechanicalReduction><rotorInertia>ROTOR</rotorInertia><torqueConstant>0.092</torqueConstant><windingResistance>0.25</windingResistance></actuator></transmission>";

#[test]
fn the_urdf_transmission_and_dynamics_elements_set_the_drive() {
    let text = urdf_with(
        &KNEE_TRANSMISSION.replace("ROTOR", "0.00012076"),
        "<dynamics damping=\"0.3\"/>",
    );
    let m = PlanarModel::from_urdf_str(&text, "x.urdf").expect("parses");
    let knee = &m.joints[m.joint_index("left_knee_pitch").unwrap()];
    assert_eq!(knee.drive.gear_ratio, Some(9.1));
    assert_eq!(knee.drive.rotor_inertia_kgm2, Some(0.00012076));
    assert_eq!(knee.drive.torque_constant_nm_per_a, Some(0.092));
    assert_eq!(knee.drive.winding_resistance_ohm, Some(0.25));
    assert_eq!(knee.drive.damping_nms_per_rad, 0.3);
    assert!((knee.drive.armature_kgm2() - 9.1 * 9.1 * 0.00012076).abs() < 1e-15);
    assert!(
        (knee.drive.copper_loss_w_per_nm2().unwrap() - 0.25 / (9.1f64 * 0.092).powi(2)).abs()
            < 1e-12
    );
    let hip = &m.joints[m.joint_index("left_hip_pitch").unwrap()];
    assert_eq!(hip.drive, JointDrive::default());
    assert_eq!(
        hip.drive.copper_loss_w_per_nm2(),
        Err("mechanicalReduction")
    );
}

fn refused(text: &str) -> String {
    match PlanarModel::from_urdf_str(text, "bad.urdf") {
        Ok(_) => panic!("accepted"),
        Err(e) => {
            assert!(matches!(e, ModelError::UrdfField { .. }), "{e:?}");
            e.to_string()
        }
    }
}

#[test]
fn bad_drive_values_are_refused_naming_the_element_field_and_value() {
    let e = refused(&urdf_with("", "<dynamics damping=\"-0.1\"/>"));
    assert!(
        e.contains("bad.urdf")
            && e.contains("left_knee_pitch")
            && e.contains("damping")
            && e.contains("-0.1"),
        "{e}"
    );
    let e = refused(&urdf_with("", "<dynamics damping=\"nan\"/>"));
    assert!(e.contains("dynamics damping") && e.contains("nan"), "{e}");
    let e = refused(&urdf_with(&KNEE_TRANSMISSION.replace("ROTOR", "-1e-4"), ""));
    assert!(
        e.contains("knee_a1") && e.contains("rotorInertia") && e.contains("-1e-4"),
        "{e}"
    );
    let e = refused(&urdf_with(&KNEE_TRANSMISSION.replace("ROTOR", "inf"), ""));
    assert!(
        e.contains("rotorInertia") && e.contains("inf") && e.contains("finite"),
        "{e}"
    );
    let e = refused(&urdf_with(
        &KNEE_TRANSMISSION
            .replace("ROTOR", "1e-4")
            .replace("left_knee_pitch", "left_elbow"),
        "",
    ));
    assert!(
        e.contains("left_elbow") && e.contains("no movable joint"),
        "{e}"
    );
    let e = refused(&urdf_with(
        &KNEE_TRANSMISSION
            .replace("ROTOR", "1e-4")
            .replace("<mechanicalReduction>9.1", "<mechanicalReduction>0"),
        "",
    ));
    assert!(
        e.contains("mechanicalReduction") && e.contains("positive"),
        "{e}"
    );
    let twice = KNEE_TRANSMISSION.replace("ROTOR", "1e-4");
    let e = refused(&urdf_with(&format!("{twice}{twice}"), ""));
    assert!(e.contains("drives this joint already"), "{e}");
}
