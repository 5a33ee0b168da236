//! Diagnosis of the walked orbit against the planned one, from the simulator's truth (the
//! measurements behind `runtime::control::speed`, "Why the library speed does not set the
//! walked speed").
//!
//! ```text
//! cargo run --release -p runtime --example impact_probe -- CONFIG GAIT BELT_MPS DURATION_S SEED
//! ```
//! The gait alone (no speed control unless CONFIG names a library), from its planned
//! post-impact state, on an endless belt. On stdout two tables:
//! - one line per simulated touchdown: step length (m) and duration (s), the angular momentum
//!   σ (kg·m²/s) just before the impact about the old stance foot and about the new one, just
//!   after about the new one (a plastic impact of one foot conserves it), the kinetic energy
//!   lost, the old stance foot's liftoff after the impact (NaN: released at the impact), the
//!   controller's touchdown detection delay, σ mid-step, θ, θ̇, pitch and pitch rate before;
//! - one line per step: the gravity work of single support W = ∫ 2σ·M·g·(x_c − x_f) dt (the
//!   change of σ² over the step), the part of it from the outputs' position errors (the
//!   centre of mass of the measured pose against the planned pose at the same stance-leg
//!   angle, per output), the outputs' mean errors (mrad) and, after `vel`, the part from each
//!   output's rate off the outputs' manifold (ẏᵢ − y^d'ᵢ(τ)·τ̇).
//!
//! With `DUMP` set in the environment, every single-support tick goes to stderr (per output:
//! error, rate error, its momentum per unit rate; then step, t, τ, θ̇, σ, x_c − x_f, pitch
//! rate, the controller's phase). The truth is for diagnosis only: the controller never sees it.

use drivers::bus::BusWrapper;
use drivers::imu::{Imu, ImuError, ImuSample};
use drivers::sim::bus::SimBus;
use drivers::sim::robot::{RobotSim, SimEvent};
use model::Side;
use runtime::backend::WalkProgress;
use runtime::sim::inject::FaultClock;
use runtime::sim::run::{sim_backend, SimWalkOptions};
use runtime::{Backend, LoopOptions, Setup};
use std::process::ExitCode;

#[derive(Clone, Debug)]
struct Rec {
    t_s: f64,
    q: Vec<f64>,
    dq: Vec<f64>,
    stance: [bool; 2],
    steps: u32,
    phase: f64,
}

struct Recorder {
    bus: SimBus<RobotSim>,
    recs: Vec<Rec>,
    progress: WalkProgress,
}

/// The simulator's bus, each exchange recorded (with the simulator's truth).
impl BusWrapper for Recorder {
    type Inner = SimBus<RobotSim>;
    fn inner(&self) -> &Self::Inner {
        &self.bus
    }
    fn inner_mut(&mut self) -> &mut Self::Inner {
        &mut self.bus
    }
    fn after_exchange(&mut self) {
        let p = self.bus.plant();
        self.recs.push(Rec {
            t_s: p.time_s(),
            q: p.q().to_vec(),
            dq: p.dq().to_vec(),
            stance: [p.in_stance(Side::Left), p.in_stance(Side::Right)],
            steps: self.progress.steps,
            phase: self.progress.phase,
        });
    }
}

impl Imu for Recorder {
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        self.bus.read(out)
    }
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        self.bus.read_at(t_s)
    }
}

impl Backend for Recorder {
    fn true_pitch_rad(&self) -> Option<f64> {
        self.bus.true_pitch_rad()
    }
    fn observe(&mut self, progress: &WalkProgress) {
        self.progress = *progress;
    }
}

fn main() -> ExitCode {
    match probe(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!(
                "impact_probe: {e}\nusage: impact_probe CONFIG GAIT BELT_MPS DURATION_S SEED"
            );
            ExitCode::from(2)
        }
    }
}

fn probe(args: Vec<String>) -> Result<(), String> {
    let [config, gait, belt, duration, seed] = args.as_slice() else {
        return Err(format!("5 arguments expected, {} given", args.len()));
    };
    let num = |v: &str| v.parse::<f64>().map_err(|e| format!("{v}: {e}"));
    let (belt_mps, duration_s) = (num(belt)?, num(duration)?);
    let seed: u64 = seed.parse().map_err(|e| format!("{seed}: {e}"))?;
    let setup = Setup::load(config, gait).map_err(|e| e.to_string())?;
    let mut o = SimWalkOptions::new(duration_s);
    o.belt_speed_mps = Some(belt_mps);
    o.belt_length_m = f64::INFINITY;
    o.seed = seed;
    let bus = sim_backend(&setup, &o).map_err(|e| e.to_string())?;
    let model = setup.model.clone();
    let legs = model.legs().map_err(|e| e.to_string())?;
    let feet = [legs.left.foot, legs.right.foot];
    let sigma_about = |q: &[f64], dq: &[f64], foot: usize| -> f64 {
        let st = model.body_poses(q).expect("poses");
        let p = model.frame_position_in(&st, foot);
        model
            .angular_momentum_about(q, dq, [p[0], p[1]])
            .expect("momentum")
    };
    // The plan: σ⁺ about the stance foot in the gait's post-impact state.
    let s0 = setup
        .gait
        .initial_state
        .as_ref()
        .ok_or("no initial_state")?;
    let stance0 = setup.gait.stance_leg;
    let planned_sigma_plus = sigma_about(&s0.q, &s0.dq, feet[stance0 as usize]);
    let theta_plus = model
        .stance_leg_angle(&s0.q, &legs, stance0)
        .map_err(|e| e.to_string())?;
    eprintln!(
        "gait {}: planned σ⁺ {planned_sigma_plus:.4} kg·m²/s, θ⁺ {theta_plus:.4} rad, step {:.4} m in {:.4} s",
        gait, setup.gait.step_length_m, setup.gait.step_duration_s
    );
    let recorder = Recorder {
        bus,
        recs: Vec::with_capacity((duration_s * 1000.0) as usize + 10),
        progress: WalkProgress::default(),
    };
    let mut lo = LoopOptions::simulation(duration_s);
    lo.start_walking = true;
    let (_summary, rec) = runtime::run(&setup, recorder, FaultClock::new(&[]), lo, None)
        .map_err(|e| e.to_string())?;
    let events: Vec<SimEvent> = rec.bus.plant().events().to_vec();
    let recs = &rec.recs;
    println!("# k t_s side len_m dur_s v_mps sig_old_pre sig_new_pre sig_new_post post/pre KE_loss_% liftoff_ms detect_ms sig_mid theta_pre dtheta_pre pitch_pre dpitch_pre");
    let mut last_t = f64::NAN;
    let mut k = 0;
    for (n, e) in events.iter().enumerate() {
        let SimEvent::Touchdown(td) = e else { continue };
        let i = td.side as usize;
        let other = 1 - i;
        // The records around the impact.
        let Some(post) = recs.iter().position(|r| r.t_s >= td.t_s) else {
            break;
        };
        if post == 0 {
            continue;
        }
        let pre = &recs[post - 1];
        let post_r = &recs[post];
        let sig_old_pre = sigma_about(&pre.q, &pre.dq, feet[other]);
        let sig_new_pre = sigma_about(&pre.q, &pre.dq, feet[i]);
        let sig_new_post = sigma_about(&post_r.q, &post_r.dq, feet[i]);
        let liftoff_ms = events[n + 1..]
            .iter()
            .find_map(|e| match e {
                SimEvent::Liftoff { t_s, side } if *side as usize == other => Some(*t_s),
                SimEvent::Touchdown(_) => Some(f64::NAN),
                _ => None,
            })
            .map_or(f64::NAN, |t| (t - td.t_s) * 1e3);
        let steps_pre = pre.steps;
        let detect_ms = recs[post..]
            .iter()
            .find(|r| r.steps != steps_pre)
            .map_or(f64::NAN, |r| (r.t_s - td.t_s) * 1e3);
        // σ about the stance foot of the step that ended, mid-step (at its half time).
        let t_mid = if last_t.is_finite() {
            0.5 * (last_t + td.t_s)
        } else {
            f64::NAN
        };
        let sig_mid = recs
            .iter()
            .find(|r| r.t_s >= t_mid)
            .map_or(f64::NAN, |r| sigma_about(&r.q, &r.dq, feet[other]));
        let (theta_pre, dtheta_pre) = model
            .stance_leg_angle_rate(
                &pre.q,
                &pre.dq,
                &legs,
                if other == 0 { Side::Left } else { Side::Right },
            )
            .unwrap_or((f64::NAN, f64::NAN));
        let dur = td.t_s - last_t;
        println!(
            "{k} {:.4} {} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.2} {:.1} {:.1} {:.4} {:.4} {:.4} {:.4} {:.4}",
            td.t_s,
            if i == 0 { "L" } else { "R" },
            td.step_length_m,
            dur,
            td.step_length_m / dur,
            sig_old_pre,
            sig_new_pre,
            sig_new_post,
            sig_new_post / sig_new_pre,
            100.0 * (1.0 - td.kinetic_energy_after_j / td.kinetic_energy_before_j),
            liftoff_ms,
            detect_ms,
            sig_mid,
            theta_pre,
            dtheta_pre,
            pre.q[2],
            pre.dq[2],
        );
        last_t = td.t_s;
        k += 1;
    }
    // Per step: the gravity work W = ∫ 2σ·M·g·(x_c − x_f) dt (= σ⁻² − σ⁺² in single support), and
    // the part of it due to the outputs' tracking errors: the centre of mass of the measured pose
    // against the planned pose at the same stance-leg angle.
    let (ta, tb) = match &setup.gait.phase {
        model::gait::PhaseDefinition::StateBased {
            theta_plus_rad,
            theta_minus_rad,
        } => (*theta_plus_rad, *theta_minus_rad),
        _ => return Err("time-based gait".into()),
    };
    let mass_kg = model.total_mass_kg();
    let g = 9.81;
    let coord = |name: &str| model.joints[model.require_joint(name).expect("joint")].coordinate;
    let outs: Vec<[usize; 2]> = setup
        .gait
        .outputs
        .iter()
        .map(|o| {
            [
                coord(&o.joint_name(Side::Left)),
                coord(&o.joint_name(Side::Right)),
            ]
        })
        .collect();
    let alpha = &setup.gait.bezier.alpha;
    let com_rel = |q: &[f64], s: usize| -> f64 {
        let c = model.center_of_mass(q).expect("com");
        let f = model.frame_position(q, feet[s]).expect("foot");
        c[0] - f[0]
    };
    let pinned_sigma = |q: &[f64], dq: &[f64], foot: usize| -> f64 {
        let mut v = dq.to_vec();
        v[0] = 0.0;
        v[1] = 0.0;
        let st = model.body_states(q, &v).expect("states");
        let vf = model.frame_velocity_in(&st, foot);
        v[0] = -vf[0];
        v[1] = -vf[1];
        sigma_about(q, &v, foot)
    };
    let side_of = |s: usize| if s == 0 { Side::Left } else { Side::Right };
    // The planned pose at stance-leg angle θ with outputs y: the pitch that gives θ.
    let planned_pose = |q: &[f64], s: usize, y: &[f64], theta: f64| -> Vec<f64> {
        let mut qd = q.to_vec();
        for (i, o) in outs.iter().enumerate() {
            qd[o[s]] = y[i];
        }
        for _ in 0..4 {
            let th = model.stance_leg_angle(&qd, &legs, side_of(s)).expect("θ");
            let mut qe = qd.clone();
            qe[2] += 1e-6;
            let th2 = model.stance_leg_angle(&qe, &legs, side_of(s)).expect("θ");
            qd[2] -= (th - theta) / ((th2 - th) / 1e-6);
        }
        qd
    };
    println!("# step t_s W_act dW_track dW_out0 dW_out1 dW_out2 dW_out3 e0_mrad e1_mrad e2_mrad e3_mrad dpitch_mrad (errors: mean of measured − planned over the step)");
    let mut acc = [0.0f64; 16];
    let dump = std::env::var_os("DUMP").is_some();
    let mut n_acc = 0usize;
    let mut step = 0usize;
    let mut td_times = events.iter().filter_map(|e| match e {
        SimEvent::Touchdown(td) => Some(td.t_s),
        _ => None,
    });
    let mut next_td = td_times.next().unwrap_or(f64::INFINITY);
    for w in recs.windows(2) {
        let (r, r1) = (&w[0], &w[1]);
        if r.t_s >= next_td {
            if n_acc > 0 {
                let m = n_acc as f64;
                println!(
                    "{step} {:.3} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.3} {:.3} {:.3} {:.3} {:.3} vel {:.4} {:.4} {:.4} {:.4}",
                    next_td, acc[0], acc[1], acc[2], acc[3], acc[4], acc[5],
                    acc[6] / m * 1e3, acc[7] / m * 1e3, acc[8] / m * 1e3, acc[9] / m * 1e3, acc[10] / m * 1e3, acc[12], acc[13], acc[14], acc[15]
                );
            }
            acc = [0.0; 16];
            n_acc = 0;
            step += 1;
            next_td = td_times.next().unwrap_or(f64::INFINITY);
        }
        let s = match r.stance {
            [true, false] => 0,
            [false, true] => 1,
            _ => continue,
        };
        let dt = r1.t_s - r.t_s;
        let (theta, _) = model
            .stance_leg_angle_rate(&r.q, &r.dq, &legs, side_of(s))
            .expect("θ");
        let tau = ((theta - ta) / (tb - ta)).clamp(0.0, 1.0);
        let y: Vec<f64> = alpha.iter().map(|a| model::bezier::eval(a, tau)).collect();
        let qd = planned_pose(&r.q, s, &y, theta);
        let sigma = sigma_about(&r.q, &r.dq, feet[s]);
        let k = 2.0 * sigma * mass_kg * g * dt;
        let x_act = com_rel(&r.q, s);
        let x_des = com_rel(&qd, s);
        acc[0] += k * x_act;
        acc[1] += k * (x_act - x_des);
        for (i, o) in outs.iter().enumerate() {
            let e = r.q[o[s]] - y[i];
            let mut y2 = y.clone();
            y2[i] += e;
            let q2 = planned_pose(&r.q, s, &y2, theta);
            acc[2 + i] += k * (com_rel(&q2, s) - x_des);
            acc[6 + i] += e;
        }
        acc[10] += r.q[2] - qd[2];
        // The velocity part: per output, the momentum of its rate off the manifold.
        let y_act: Vec<f64> = outs.iter().map(|o| r.q[o[s]]).collect();
        let (_, theta_rate) = model
            .stance_leg_angle_rate(&r.q, &r.dq, &legs, side_of(s))
            .expect("θ̇");
        let base = planned_pose(&r.q, s, &y_act, theta);
        for (i, o) in outs.iter().enumerate() {
            let mut y2 = y_act.clone();
            y2[i] += 1e-6;
            let q2 = planned_pose(&r.q, s, &y2, theta);
            let v: Vec<f64> = q2.iter().zip(&base).map(|(a, b)| (a - b) / 1e-6).collect();
            let k_i = pinned_sigma(&base, &v, feet[s]);
            let dy_plan = model::bezier::eval_d1(&alpha[i], tau) / (tb - ta) * theta_rate;
            acc[12 + i] += 2.0 * mass_kg * g * x_act * k_i * (r.dq[o[s]] - dy_plan) * dt;
            if dump {
                eprint!(
                    " {:.5} {:.4} {:.4}",
                    r.q[o[s]] - y[i],
                    r.dq[o[s]] - dy_plan,
                    k_i
                );
            }
        }
        if dump {
            eprintln!(
                " | {step} {:.4} {tau:.4} {theta_rate:.4} {sigma:.4} {x_act:.5} {:.5} {}",
                r.t_s, r.dq[2], r.phase
            );
        }
        n_acc += 1;
    }
    Ok(())
}
