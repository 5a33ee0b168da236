//! The costs of `[cost]` (mechanical, electrical, torque squared, weighted): each one's gradient
//! and Hessian against central finite differences, their values against the formulas computed
//! here independently, and the errors of a cost the robot or the config cannot support.

#![allow(clippy::unwrap_used)]

use planner::biped::PlanarBiped;
use planner::collocation::{HzdProblem, TORQUE_SCALE};
use planner::config::{CostKind, CostMix, PlannerConfig};
use planner::guess::initial_guess;
use planner::nlp::NlpProblem;

const URDF: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../configs/robots/adam_planar_a1.urdf"
);
const CONFIG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/planner/adam.toml");

fn setup() -> (PlanarBiped, PlannerConfig) {
    let model = model::PlanarModel::from_urdf_file(URDF).expect("model");
    let config = PlannerConfig::load(CONFIG).expect("config");
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    (bp, config)
}

fn configured(mut config: PlannerConfig, kind: CostKind) -> PlannerConfig {
    config.cost.kind = kind;
    config.cost.weights = vec![1.0, 0.7, 1.3, 0.9];
    config.cost.weighted = (kind == CostKind::Weighted).then_some(CostMix {
        mechanical: 0.5,
        electrical: 2.0,
        torque_squared: 1e-4,
    });
    config
}

/// A cost-stage problem at the guess, with the power slacks set to distinct positive values.
fn problem(bp: &PlanarBiped, config: PlannerConfig) -> (HzdProblem, Vec<f64>) {
    let probe = HzdProblem::new(bp.clone(), config.clone(), Vec::new(), true).expect("problem");
    let mut x = initial_guess(bp, &probe.layout, 0.25, 0.75).expect("guess");
    let l = &probe.layout;
    for k in 0..l.points() {
        for a in 0..l.nu {
            x[l.p(k) + a] = 0.5 + 0.1 * ((k * 7 + a * 3) % 11) as f64;
            x[l.n(k) + a] = 0.2 + 0.1 * ((k * 5 + a) % 7) as f64;
            x[l.u(k) + a] += 0.05 * (a as f64 - 1.5);
        }
    }
    let p = HzdProblem::new(bp.clone(), config, x.clone(), true).expect("problem");
    (p, x)
}

/// Largest relative error of the gradient and of the objective's Hessian (multipliers zero)
/// against central differences, and the number of finite-difference non-zeros the Hessian's
/// pattern lacks.
fn check(p: &HzdProblem, x: &[f64]) -> (f64, f64, usize) {
    let n = x.len();
    let mut g = vec![0.0; n];
    p.gradient(x, &mut g).unwrap();
    let f = |x: &[f64]| p.objective(x).unwrap();
    let grad = |x: &[f64]| {
        let mut g = vec![0.0; n];
        p.gradient(x, &mut g).unwrap();
        g
    };
    let scale = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut grad_err = 0.0f64;
    let mut fd_hess = vec![Vec::new(); n];
    for j in 0..n {
        let h = 1e-6 * (1.0 + x[j].abs());
        let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
        xp[j] += h;
        xm[j] -= h;
        let fd = (f(&xp) - f(&xm)) / (2.0 * h);
        grad_err = grad_err.max((fd - g[j]).abs() / scale.max(1e-12));
        let (gp, gm) = (grad(&xp), grad(&xm));
        for i in 0..n {
            let v = (gp[i] - gm[i]) / (2.0 * h);
            if v != 0.0 {
                fd_hess[j].push((i, v));
            }
        }
    }
    let pattern = p.hessian_structure();
    let mut values = vec![0.0; pattern.len()];
    let zero = vec![0.0; p.num_constraints()];
    p.hessian_values(x, 1.0, &zero, &mut values).unwrap();
    let mut analytic = std::collections::HashMap::new();
    for ((&r, &c), v) in pattern.rows.iter().zip(&pattern.cols).zip(&values) {
        *analytic.entry((r.max(c), r.min(c))).or_insert(0.0) += v;
    }
    let hscale = analytic
        .values()
        .fold(0.0f64, |m: f64, v: &f64| m.max(v.abs()));
    let (mut hess_err, mut outside) = (0.0f64, 0usize);
    for (j, col) in fd_hess.iter().enumerate() {
        for &(i, v) in col {
            if i < j {
                continue;
            }
            match analytic.get(&(i, j)) {
                Some(a) => hess_err = hess_err.max((a - v).abs() / hscale),
                None if v.abs() > 1e-6 * hscale => outside += 1,
                None => {}
            }
        }
    }
    // Analytic entries the differences do not see are errors too.
    for (&(i, j), &a) in &analytic {
        if !fd_hess[j].iter().any(|&(r, _)| r == i) {
            hess_err = hess_err.max(a.abs() / hscale);
        }
    }
    (grad_err, hess_err, outside)
}

#[test]
fn every_cost_has_an_exact_gradient_and_hessian() {
    let (bp, config) = setup();
    for kind in [
        CostKind::Mechanical,
        CostKind::Electrical,
        CostKind::TorqueSquared,
        CostKind::Weighted,
    ] {
        let (p, x) = problem(&bp, configured(config.clone(), kind));
        let (grad_err, hess_err, outside) = check(&p, &x);
        println!(
            "{:<15} cost {:.6e}: gradient error {grad_err:.1e}, Hessian error {hess_err:.1e}, {outside} entries outside the pattern",
            kind.name(),
            p.objective(&x).unwrap()
        );
        assert!(grad_err < 1e-7, "{kind:?}: gradient error {grad_err}");
        assert!(hess_err < 1e-6, "{kind:?}: Hessian error {hess_err}");
        assert_eq!(outside, 0, "{kind:?}");
    }
}

#[test]
fn each_cost_is_its_formula() {
    let (bp, config) = setup();
    let model = &bp.model;
    let mg = model.total_mass_kg() * model.gravity_mps2;
    let w = [1.0, 0.7, 1.3, 0.9];
    // R / (N k_t)² of each actuator from the URDF's transmissions, by hand.
    let rho: Vec<f64> = model
        .actuated_joints()
        .iter()
        .map(|&j| {
            let d = model.joints[j].drive;
            let (n, kt, r) = (
                d.gear_ratio.unwrap(),
                d.torque_constant_nm_per_a.unwrap(),
                d.winding_resistance_ohm.unwrap(),
            );
            r / (n * kt).powi(2)
        })
        .collect();
    let values: Vec<f64> = [
        CostKind::Mechanical,
        CostKind::Electrical,
        CostKind::TorqueSquared,
        CostKind::Weighted,
    ]
    .iter()
    .map(|&kind| {
        let (p, x) = problem(&bp, configured(config.clone(), kind));
        let l = &p.layout;
        let (t, d) = (x[l.duration()], x[l.length()]);
        let h6 = t / (6.0 * l.intervals as f64);
        let (mut mech, mut elec, mut tsq) = (0.0, 0.0, 0.0);
        // The reported costs of transport use |u q̇| and max(u q̇, 0) themselves.
        let (mut mech_reported, mut elec_reported) = (0.0, 0.0);
        for k in 0..l.points() {
            for a in 0..l.nu {
                let c = l.simpson_weight(k) * w[a];
                let u = TORQUE_SCALE * x[l.u(k) + a];
                let (pp, nn) = (x[l.p(k) + a], x[l.n(k) + a]);
                mech += h6 * c * (pp + nn);
                elec += h6 * c * (rho[a] * u * u + pp);
                tsq += h6 * c * u * u;
                let power = u * x[l.dq(k) + bp.actuators[a]];
                mech_reported += h6 * c * power.abs();
                elec_reported += h6 * c * (rho[a] * u * u + power.max(0.0));
            }
        }
        let (mech, elec, tsq) = (mech / (mg * d), elec / (mg * d), tsq / d);
        let (mech_reported, elec_reported) = (mech_reported / (mg * d), elec_reported / (mg * d));
        let expected = match kind {
            CostKind::Mechanical => mech,
            CostKind::Electrical => elec,
            CostKind::TorqueSquared => tsq,
            CostKind::Weighted => 0.5 * mech + 2.0 * elec + 1e-4 * tsq,
        };
        let got = p.objective(&x).unwrap();
        assert!(
            (got - expected).abs() <= 1e-12 * expected.abs(),
            "{kind:?}: {got} vs {expected}"
        );
        // The reported costs of transport are the mechanical and electrical ones whatever the
        // objective.
        let m = p.cost_of_transport(&x);
        assert!(
            (m - mech_reported).abs() <= 1e-12 * mech_reported,
            "{m} vs {mech_reported}"
        );
        let e = p.electrical_cost_of_transport(&x).unwrap();
        assert!(
            (e - elec_reported).abs() <= 1e-12 * elec_reported,
            "{e} vs {elec_reported}"
        );
        got
    })
    .collect();
    // Four different functions of x.
    for i in 0..4 {
        for j in 0..i {
            assert!((values[i] - values[j]).abs() > 1e-9 * values[i].abs());
        }
    }
}

#[test]
fn the_electrical_cost_names_the_joint_and_constant_a_robot_lacks() {
    // The five-link walker's URDF has no transmissions.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/robots/five_link_walker.urdf"
    );
    let model = model::PlanarModel::from_urdf_file(path).expect("model");
    let mut config = PlannerConfig::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/planner/five_link.toml"
    ))
    .expect("config");
    let bp = PlanarBiped::new(model, config.gait.stance_leg, &[]).expect("biped");
    // The mechanical cost needs no constants.
    assert!(HzdProblem::new(bp.clone(), config.clone(), Vec::new(), true).is_ok());
    config.cost.kind = CostKind::Electrical;
    let e = HzdProblem::new(bp, config, Vec::new(), true)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("electrical")
            && e.contains("left_hip_pitch")
            && e.contains("mechanicalReduction"),
        "{e}"
    );
}

#[test]
fn a_cost_config_the_planner_cannot_use_is_refused_naming_the_field_and_value() {
    let text = std::fs::read_to_string(CONFIG).unwrap();
    let with = |cost: &str| {
        let start = text.find("[cost]").unwrap();
        let end = text[start..].find("[solver]").unwrap() + start;
        format!("{}{cost}\n\n{}", &text[..start], &text[end..])
    };
    let refused = |cost: &str| {
        PlannerConfig::from_toml(&with(cost), "x.toml")
            .expect_err("refused")
            .to_string()
    };
    let ok = |cost: &str| PlannerConfig::from_toml(&with(cost), "x.toml").expect("accepted");
    assert_eq!(
        ok("[cost]\nweights = [1, 1, 1, 1]").cost.kind,
        CostKind::Mechanical
    );
    assert_eq!(
        ok("[cost]\nkind = \"electrical\"\nweights = [1, 1, 1, 1]")
            .cost
            .kind,
        CostKind::Electrical
    );
    let e = refused("[cost]\nkind = \"joules\"\nweights = [1, 1, 1, 1]");
    assert!(
        e.contains("x.toml") && e.contains("joules") && e.contains("kind"),
        "{e}"
    );
    let e = refused("[cost]\nkind = \"weighted\"\nweights = [1, 1, 1, 1]");
    assert!(
        e.contains("cost.kind") && e.contains("[cost.weighted]"),
        "{e}"
    );
    let e = refused(
        "[cost]\nkind = \"weighted\"\nweights = [1, 1, 1, 1]\n[cost.weighted]\nmechanical = 1\nelectrical = -0.5",
    );
    assert!(
        e.contains("cost.weighted.electrical") && e.contains("-0.5"),
        "{e}"
    );
    let e = refused(
        "[cost]\nkind = \"weighted\"\nweights = [1, 1, 1, 1]\n[cost.weighted]\nmechanical = 0",
    );
    assert!(e.contains("cost.weighted"), "{e}");
    let e = refused(
        "[cost]\nkind = \"electrical\"\nweights = [1, 1, 1, 1]\n[cost.weighted]\nmechanical = 1",
    );
    assert!(
        e.contains("cost.weighted") && e.contains("electrical"),
        "{e}"
    );
    let e = refused("[cost]\nweights = [1, -2, 1, 1]");
    assert!(e.contains("cost.weights[1]") && e.contains("-2"), "{e}");
}
