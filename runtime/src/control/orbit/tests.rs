//! The orbit lever on the shipped robot and gait: σ*(τ) against the plan, the lean's geometry,
//! and the law in a one-step simulation of the zero dynamics.

#![allow(clippy::unwrap_used)]

use super::*;
use crate::control::double_support::GeometryParts;
use crate::Setup;
use model::PlanarModel;

struct Fixture {
    setup: Setup,
    parts: GeometryParts,
    table: GaitTable,
}

impl Fixture {
    fn shipped() -> Self {
        let setup = Setup::shipped().unwrap();
        let model: &PlanarModel = &setup.model;
        let nominal = model.nominal_pose().unwrap();
        let q = model
            .with_design(
                &nominal,
                setup.gait.design.thigh_length_m,
                setup.gait.design.shin_length_m,
            )
            .unwrap();
        let parts = GeometryParts::new(model, &q);
        let table = GaitTable::new(&setup.gait, model, &parts.legs).unwrap();
        Self {
            setup,
            parts,
            table,
        }
    }

    fn geometry(&self) -> Geometry<'_> {
        self.parts.geometry(&self.setup.model)
    }
}

/// The centre of mass ahead of the stance foot of `stance` at pose `q`, m.
fn com_ahead_m(g: &Geometry, q: &[f64; MAX_DOF], stance: Side) -> Option<f64> {
    let st = g.model.body_poses(&q[..g.dof]).ok()?;
    let foot = g.model.frame_position_in(&st, g.legs.side(stance).foot);
    let com = g.model.center_of_mass(&q[..g.dof]).ok()?;
    Some(com[0] - foot[0])
}

#[test]
fn the_planned_post_impact_state_lies_on_the_orbit_s_momentum_profile() {
    let f = Fixture::shipped();
    let g = f.geometry();
    let orbit = OrbitTable::of(&g, &f.table, &f.setup.gait).unwrap();
    // σ* at τ = 0 is built from the planned post-impact state's momentum; that state, written
    // as κ(τ)·τ̇ from its own stance-leg angle rate, must give the same momentum: the plan's
    // state is on the outputs' manifold and κ is computed from the Bézier outputs alone.
    let init = f.setup.gait.initial_state.as_ref().unwrap();
    let (theta, theta_rate) = f
        .setup
        .model
        .stance_leg_angle_rate(&init.q, &init.dq, &f.parts.legs, f.table.first_stance)
        .unwrap();
    let span = f.table.theta_minus_rad - f.table.theta_plus_rad;
    let tau0 = (theta - f.table.theta_plus_rad) / span;
    assert!(tau0.abs() < 1e-3, "post-impact phase {tau0}");
    let sigma_plan = orbit.kappa[0] * theta_rate / span;
    let sigma_state = orbit.sigma_at(0.0);
    let mut q = [0.0; MAX_DOF];
    let mut dq = [0.0; MAX_DOF];
    q[..g.dof].copy_from_slice(&init.q);
    dq[..g.dof].copy_from_slice(&init.dq);
    // angular_momentum_about directly at the planned state (the planner pins the foot too).
    let foot = f.parts.legs.side(f.table.first_stance).foot;
    let st = f.setup.model.body_poses(&init.q).unwrap();
    let p = f.setup.model.frame_position_in(&st, foot);
    let direct = f
        .setup
        .model
        .angular_momentum_about(&init.q, &init.dq, p)
        .unwrap();
    assert!(
        (direct - sigma_state).abs() < 1e-6 * direct.abs().max(1.0),
        "pinned {sigma_state} vs direct {direct}"
    );
    assert!(
        (sigma_plan - sigma_state).abs() < 0.01 * sigma_state,
        "σ from κ·τ̇ {sigma_plan} vs the state's {sigma_state}"
    );
    let _ = (q, dq);
}

#[test]
fn the_planned_orbit_takes_the_gait_s_step_duration() {
    let f = Fixture::shipped();
    let orbit = OrbitTable::of(&f.geometry(), &f.table, &f.setup.gait).unwrap();
    let t = orbit.duration_s();
    let planned = f.setup.gait.step_duration_s;
    eprintln!("orbit duration {t:.4} s, planned {planned:.4} s");
    assert!((t - planned).abs() < 0.005 * planned, "{t} vs {planned}");
    // Momentum stays positive and smooth: the robot passes over its foot.
    assert!(orbit.sigma.iter().all(|s| *s > 0.0));
}

fn lever(f: &Fixture) -> OrbitLever {
    lever_with(f, &on())
}

/// The shipped gains, the lever on (it is off as shipped).
fn on() -> OrbitConfig {
    OrbitConfig {
        enabled: true,
        ..OrbitConfig::default()
    }
}

fn lever_with(f: &Fixture, config: &OrbitConfig) -> OrbitLever {
    OrbitLever::new(config, &f.geometry(), (&f.setup.gait, &f.table), &[]).unwrap()
}

#[test]
fn the_lean_moves_the_centre_of_mass_but_not_the_swing_foot_nor_the_phase() {
    let f = Fixture::shipped();
    let g = f.geometry();
    let l = lever(&f);
    let stance = f.table.first_stance;
    for tau in [0.2, 0.5, 0.8] {
        let base = pose_at(&g, &f.table, stance, tau, 0.0).unwrap();
        let lean = pose_at(&g, &f.table, stance, tau, l.sign * 0.1).unwrap();
        let feet = |q: &[f64; MAX_DOF]| {
            let st = f.setup.model.body_poses(&q[..g.dof]).unwrap();
            let a = f
                .setup
                .model
                .frame_position_in(&st, f.parts.legs.side(stance.other()).foot);
            let b = f
                .setup
                .model
                .frame_position_in(&st, f.parts.legs.side(stance).foot);
            [a[0] - b[0], a[1] - b[1]]
        };
        let (fa, fb) = (feet(&base), feet(&lean));
        assert!(
            (fa[0] - fb[0]).abs() < 1e-9 && (fa[1] - fb[1]).abs() < 1e-9,
            "swing foot moved at τ {tau}: {fa:?} → {fb:?}"
        );
        // The torso turns by the lean (the stance leg, pinned, stays).
        assert!(((lean[2] - base[2]).abs() - 0.1).abs() < 1e-9);
        let com = |q: &[f64; MAX_DOF]| com_ahead_m(&g, q, stance).unwrap();
        let forward_m = com(&lean) - com(&base);
        assert!(
            forward_m > 1e-3,
            "a 0.1 rad lean moves the COM {forward_m} m"
        );
    }
}

#[test]
fn the_law_leans_forward_when_slow_back_when_fast_and_fades_out_at_the_impact() {
    let f = Fixture::shipped();
    let config = on();
    let mut l = lever(&f);
    let stance = f.table.first_stance;
    let table = l.table.unwrap();
    let star = table.sigma_at(0.4);
    let dt = 1e-3;
    // Slow (σ 20 % below the orbit's): forward (positive), from 0, never faster than the limit.
    let mut last = 0.0;
    for k in 0..2000 {
        let (lean, _) = l.update(k as f64 * dt, 0.4, 0.8 * star, stance, true);
        assert!((lean - last).abs() <= config.max_lean_rate_rad_s * dt + 1e-12);
        last = lean;
    }
    let expected =
        (config.gain_rad_per_mps * 0.2 * star / l.momentum_per_mps).min(config.max_lean_rad);
    assert!(expected > 0.0);
    assert!(
        (l.lean_rad - expected).abs() < 1e-6 * expected,
        "{} vs {expected}",
        l.lean_rad
    );
    // Fast: back.
    for k in 2000..4000 {
        l.update(k as f64 * dt, 0.4, 1.2 * star, stance, true);
    }
    assert!(l.lean_rad < 0.0);
    // At the impact the lean is gone whatever the error.
    for k in 4000..4500 {
        l.update(k as f64 * dt, 1.0, 0.5 * star, stance, true);
    }
    assert_eq!(l.lean_rad, 0.0);
    // Off (a Stop): back to zero too.
    for k in 4500..6000 {
        l.update(k as f64 * dt, 0.4, 0.5 * star, stance, k < 5000);
    }
    assert_eq!(l.lean_rad, 0.0);
}

/// One step of the zero dynamics from `sigma0`: σ̇ = M·g·(x_c − x_f) with the centre of mass of
/// the leaned pose, τ̇ = σ/κ(τ); with the lever (`lean`) or without. Returns (σ at τ = 1, the
/// step's duration), or `None` if the robot falls back.
fn one_step(f: &Fixture, sigma0: f64, lean: bool) -> Option<(f64, f64)> {
    let g = f.geometry();
    // A stronger gain than the shipped one: the point is the sign of the law.
    let config = OrbitConfig {
        gain_rad_per_mps: 2.0,
        ..on()
    };
    let mut l = lever_with(f, &config);
    let table = l.table.unwrap();
    let stance = f.table.first_stance;
    let mass_g = f.setup.model.total_mass_kg() * f.setup.model.gravity_mps2;
    let (mut tau, mut sigma, mut t) = (0.0, sigma0, 0.0);
    let dt = 1e-3;
    while tau < 1.0 {
        if sigma <= 0.0 || t > 3.0 {
            return None;
        }
        let delta = if lean {
            l.update(t, tau, sigma, stance, true).0
        } else {
            0.0
        };
        let q = pose_at(&g, &f.table, stance, tau, l.sign * delta)?;
        let x = com_ahead_m(&g, &q, stance)?;
        let k = tau * (ORBIT_SAMPLES - 1) as f64;
        let i = (k.floor() as usize).min(ORBIT_SAMPLES - 2);
        let kappa = table.kappa[i] + (k - i as f64) * (table.kappa[i + 1] - table.kappa[i]);
        sigma += mass_g * x * dt;
        tau += sigma / kappa * dt;
        t += dt;
    }
    Some((sigma, t))
}

#[test]
fn leaning_by_the_law_brings_a_slow_or_fast_step_back_toward_the_orbit() {
    let f = Fixture::shipped();
    let l = lever(&f);
    let table = l.table.unwrap();
    let (end, planned) = (table.sigma_at(1.0), f.setup.gait.step_duration_s);
    // On the orbit, the simulation walks the plan (its accuracy, for the comparisons below).
    let (s, t) = one_step(&f, table.sigma_at(0.0), false).unwrap();
    assert!((s - end).abs() < 0.01 * end && (t - planned).abs() < 0.01 * planned);
    for start in [0.85, 1.15] {
        let sigma0 = start * table.sigma_at(0.0);
        let without = one_step(&f, sigma0, false);
        let (s1, t1) = one_step(&f, sigma0, true).expect("with the lever the step ends");
        let e1 = (s1 - end).abs();
        eprintln!("start {start}: without {without:?}, with ({s1:.4}, {t1:.3} s); σ*(1) {end:.4}");
        if let Some((s0, _)) = without {
            let e0 = (s0 - end).abs();
            assert!(
                e1 < 0.6 * e0,
                "σ error at the impact {e1} with, {e0} without"
            );
        }
    }
}
