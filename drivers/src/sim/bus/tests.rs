//! Tests of `SimBus` through its `MotorBus` face: PD, envelope, latency, heat, seeds, silent
//! motors, wire faults, error flags, bus time and configuration errors.

use super::*;
use crate::a1::{Mode, MotorId};
use crate::sim::plant::{InertiaDampingPlant, RigidJoint};
use crate::timing::{frame_bits, Stuffing};

const PERIOD: Duration = Duration::from_millis(1);

fn id(n: u8) -> MotorId {
    MotorId::new(n).unwrap()
}

fn joint(load: f64) -> RigidJoint {
    RigidJoint {
        inertia_kg_m2: 0.05,
        damping_nm_s_per_rad: 0.05,
        load_torque_nm: load,
    }
}

/// `n` motors with ids 1..=n, joint i on bus i % buses.
fn sim(n: usize, buses: usize, load: f64, seed: u64) -> SimBus<InertiaDampingPlant> {
    let motors = (0..n)
        .map(|j| SimMotor {
            spec: MotorSpec {
                bus: j % buses,
                id: id(j as u8 + 1),
            },
            joint: j,
        })
        .collect();
    let config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: buses,
        motors,
        model: A1Model::default(),
        seed,
    };
    let plant = InertiaDampingPlant::new(vec![joint(load); n]).unwrap();
    SimBus::new(config, plant).unwrap()
}

fn active(bus: &mut SimBus<InertiaDampingPlant>) -> Vec<MotorSpec> {
    let specs: Vec<_> = bus.config().motors.iter().map(|m| m.spec).collect();
    bus.configure(&specs).unwrap();
    bus.activate().unwrap();
    specs
}

#[test]
fn pd_settles_at_the_static_deflection() {
    // Steady state of kp(q* − q) + load = 0 is q = q* + load/kp.
    let (kp, kd, load) = (80.0, 2.0, 4.0);
    let mut bus = sim(1, 1, load, 1);
    active(&mut bus);
    let m = id(1);
    let mut r = [Reply::zeroed(m)];
    for _ in 0..1500 {
        bus.exchange(&[Command::pd(m, 0.3, 0.0, kp, kd, 0.0)], &mut r, PERIOD)
            .unwrap();
    }
    let expected = 0.3 + load / kp;
    // Reply quantum 0.38 mrad; encoder 0.02 mrad; noise-driven torque ripple ≪ 1 mrad.
    assert!(
        (r[0].q_rad - expected).abs() < 1e-3,
        "{} vs {expected}",
        r[0].q_rad
    );
    // Filtered velocity noise is ≈ 0.05 rad/s rms (0.3-count encoder noise
    // differentiated at 10 kHz, 500 Hz low-pass): allow 4σ, and kd·4σ on the torque.
    assert!((r[0].tau_nm + load).abs() < 0.4, "{}", r[0].tau_nm);
    assert!(r[0].dq_rad_s.abs() < 0.2, "{}", r[0].dq_rad_s);
    assert_eq!(r[0].mode, Mode::PositionVelocity);
    assert!(r[0].enabled);
}

#[test]
fn torque_saturates_and_speed_tops_out_at_the_envelope() {
    let mut bus = sim(1, 1, 0.0, 2);
    active(&mut bus);
    let m = id(1);
    let mut r = [Reply::zeroed(m)];
    bus.exchange(&[Command::pd(m, 0.0, 0.0, 0.0, 0.0, 60.0)], &mut r, PERIOD)
        .unwrap();
    let mut peak_tau: f64 = 0.0;
    for _ in 0..3000 {
        let rep = bus
            .exchange(&[Command::pd(m, 0.0, 0.0, 0.0, 0.0, 60.0)], &mut r, PERIOD)
            .unwrap();
        assert!(rep.saturation[0].contains(a1::Field::TauFf));
        peak_tau = peak_tau.max(r[0].tau_nm);
    }
    assert!(peak_tau <= 33.5 && peak_tau > 33.4, "{peak_tau}");
    // Top speed: envelope torque = plant friction b·ω: 33.5(21 − ω)/10.5 = 0.05 ω.
    let w = 21.0 * 33.5 / 10.5 / (33.5 / 10.5 + 0.05);
    let v = bus.plant().velocity_rad_s(0);
    assert!((v - w).abs() < 0.05, "{v} vs {w}");
}

#[test]
fn one_tick_of_latency() {
    let mut bus = sim(1, 1, 0.0, 3);
    active(&mut bus);
    let m = id(1);
    let mut r = [Reply::zeroed(m)];
    let hold = Command::pd(m, 0.0, 0.0, 50.0, 1.0, 0.0);
    for _ in 0..200 {
        bus.exchange(&[hold], &mut r, PERIOD).unwrap();
    }
    let p_before = bus.plant().position_rad(0);
    let step = Command::pd(m, 0.5, 0.0, 50.0, 1.0, 0.0);
    bus.exchange(&[step], &mut r, PERIOD).unwrap();
    let (p0, q0) = (bus.plant().position_rad(0), r[0].q_rad);
    bus.exchange(&[step], &mut r, PERIOD).unwrap();
    let (p1, q1) = (bus.plant().position_rad(0), r[0].q_rad);
    // The period after exchange k still runs the old command (latency): the joint
    // holds (jitter ≪ 0.02 mrad). The next period runs the step: 25 N·m on
    // 0.05 kg·m² moves ½·500·(1 ms)² ≈ 0.25 mrad.
    assert!((p0 - p_before).abs() < 2e-5, "{p0} vs {p_before}");
    assert!(p1 - p0 > 1.5e-4, "{p1} vs {p0}");
    // Reply k+1 is sampled before the step acts: unchanged within a reply quantum.
    assert!((q1 - q0).abs() <= a1::codec::REPLY_Q.quantum() + 1e-12);
}

#[test]
fn temperature_follows_the_first_order_model_and_trips() {
    let mut bus = sim(1, 1, 0.0, 4);
    bus.config.model.thermal_capacitance_j_per_k = 0.6; // time constant 0.9 s
    bus.plant_mut().set_load(0, 15.0);
    active(&mut bus);
    let m = id(1);
    let mut r = [Reply::zeroed(m)];
    let model = bus.config().model;
    // Holding a 15 N·m load: loss 15²/(9.1·0.092)²·0.25 = 80 W, steady 145 °C.
    let p = model.copper_loss_w(15.0);
    let steady = model.ambient_c + p * model.thermal_resistance_k_per_w;
    let tau_th = model.thermal_resistance_k_per_w * model.thermal_capacitance_j_per_k;
    let hold = Command::pd(m, 0.0, 0.0, 200.0, 3.0, 0.0);
    for _ in 0..300 {
        bus.exchange(&[hold], &mut r, PERIOD).unwrap();
    }
    // After 0.3 s (torque settles in a few ms, so ~0.3 s of full loss).
    let t = 0.3;
    let analytic = steady + (model.ambient_c - steady) * (-t / tau_th).exp();
    let sim_t = bus.temperature_c(m).unwrap();
    assert!((sim_t - analytic).abs() < 1.0, "{sim_t} vs {analytic}");
    assert!((r[0].temperature_c - sim_t).abs() <= 0.5 + 1e-9);
    assert!(r[0].errors.is_empty());
    // Keep holding until it trips: flag set, motor brakes (no holding torque).
    let mut tripped = false;
    for _ in 0..2000 {
        bus.exchange(&[hold], &mut r, PERIOD).unwrap();
        if r[0].errors.contains(ErrorFlags::OVER_TEMPERATURE) {
            tripped = true;
            break;
        }
    }
    assert!(tripped);
    bus.exchange(&[hold], &mut r, PERIOD).unwrap();
    assert_eq!(r[0].tau_nm, 0.0, "output off while over temperature");
    // Cools below the release threshold, then obeys again.
    let mut released = false;
    for _ in 0..5000 {
        bus.exchange(&[hold], &mut r, PERIOD).unwrap();
        if r[0].errors.is_empty() {
            released = true;
            break;
        }
    }
    assert!(released);
    assert!(r[0].temperature_c < model.recover_temperature_c + 1.0);
}

#[test]
fn same_seed_is_bit_identical_and_another_seed_is_not() {
    let run = |seed| {
        let mut bus = sim(2, 2, 1.0, seed);
        active(&mut bus);
        let cmds = [
            Command::pd(id(1), 0.2, 0.0, 40.0, 1.0, 0.0),
            Command::pd(id(2), -0.1, 0.0, 30.0, 0.8, 0.5),
        ];
        let mut r = [Reply::zeroed(id(1)); 2];
        let mut trace = Vec::new();
        for _ in 0..500 {
            bus.exchange(&cmds, &mut r, PERIOD).unwrap();
            trace.extend(
                r.iter()
                    .flat_map(|x| [x.q_rad.to_bits(), x.dq_rad_s.to_bits()]),
            );
        }
        trace.push(bus.plant().position_rad(0).to_bits());
        trace
    };
    assert_eq!(run(11), run(11));
    assert_ne!(run(11), run(12));
}

#[test]
fn silent_motor_mid_run_is_named_and_others_still_reply() {
    let mut bus = sim(3, 1, 0.0, 5);
    active(&mut bus);
    let cmds = [1, 2, 3].map(|n| Command::damping(id(n), 1.0));
    let mut r = [Reply::zeroed(id(9)); 3];
    bus.exchange(&cmds, &mut r, PERIOD).unwrap();
    assert!(bus.set_silent(id(2), true));
    r = [Reply::zeroed(id(9)); 3];
    assert_eq!(
        bus.exchange(&cmds, &mut r, PERIOD),
        Err(BusError::MissingReply {
            motor: id(2),
            bus: 0
        })
    );
    assert_eq!(r[0].motor, id(1));
    assert_eq!(r[2].motor, id(3));
    assert_eq!(r[1].motor, id(9), "untouched slot");
}

#[test]
fn wire_loss_matches_its_probability_and_every_lost_frame_is_a_missing_reply() {
    let mut bus = sim(2, 2, 0.0, 21);
    active(&mut bus);
    let p = 0.1;
    bus.set_wire_faults(WireFaults {
        loss_probability: p,
        corrupt_probability: p,
        ..WireFaults::NONE
    })
    .unwrap();
    let cmds = [1, 2].map(|n| Command::damping(id(n), 1.0));
    let mut r = [Reply::zeroed(id(1)); 2];
    let n = 5_000;
    let mut missing = 0u64;
    for _ in 0..n {
        r.iter_mut().for_each(|x| x.q_rad = f64::NAN);
        let result = bus.exchange(&cmds, &mut r, PERIOD);
        let gone = r.iter().filter(|x| x.q_rad.is_nan()).count() as u64;
        assert_eq!(result.is_err(), gone > 0);
        missing += gone;
    }
    let stats = bus.wire_stats();
    // Each lost or corrupted frame costs exactly one reply (a lost command has no reply).
    assert_eq!(missing, stats.lost + stats.corrupted);
    // P(reply missing) = 1 − (1 − p)⁴ (command and reply, each lost or corrupted) = 0.344;
    // over 10 000 replies the standard error is 0.005: allow 4σ.
    let rate = missing as f64 / (2 * n) as f64;
    let expected = 1.0 - (1.0 - p).powi(4);
    assert!((rate - expected).abs() < 0.02, "{rate} vs {expected}");
    // Seeded: the same seed loses the same frames.
    let run = |seed| {
        let mut bus = sim(2, 2, 0.0, seed);
        active(&mut bus);
        bus.set_wire_faults(WireFaults {
            loss_probability: 0.05,
            ..WireFaults::NONE
        })
        .unwrap();
        let mut r = [Reply::zeroed(id(1)); 2];
        (0..300)
            .map(|_| bus.exchange(&cmds, &mut r, PERIOD).is_ok())
            .collect::<Vec<_>>()
    };
    assert_eq!(run(3), run(3));
    assert_ne!(run(3), run(4));
}

#[test]
fn a_delayed_reply_is_missing_only_past_the_budget() {
    let cmds = [Command::damping(id(1), 1.0)];
    // 1e300 s does not fit a Duration: late, not a panic.
    for (delay_s, late) in [(0.5e-3, false), (1.5e-3, true), (1e300, true)] {
        let mut bus = sim(1, 1, 0.0, 22);
        active(&mut bus);
        bus.set_wire_faults(WireFaults {
            delay_probability: 1.0,
            delay_s,
            ..WireFaults::NONE
        })
        .unwrap();
        let mut r = [Reply::zeroed(id(1))];
        // One exchange is ≈ 0.22 ms of bus time: 0.22 + 0.5 < 1 ms, 0.22 + 1.5 > 1 ms.
        let result = bus.exchange(&cmds, &mut r, PERIOD);
        assert_eq!(result.is_err(), late, "delay {delay_s}");
        let stats = bus.wire_stats();
        assert_eq!(stats.delayed, 1);
        assert_eq!(stats.delayed_late, u64::from(late));
    }
    let mut bus = sim(1, 1, 0.0, 22);
    let bad = WireFaults {
        loss_probability: 1.5,
        ..WireFaults::NONE
    };
    assert_eq!(bus.set_wire_faults(bad), Err(("loss_probability", 1.5)));
}

#[test]
fn injected_error_flags_and_temperature_show_in_the_replies() {
    let mut bus = sim(2, 1, 0.0, 23);
    active(&mut bus);
    let cmds = [1, 2].map(|n| Command::damping(id(n), 1.0));
    let mut r = [Reply::zeroed(id(1)); 2];
    assert!(bus.set_error_flags(id(2), ErrorFlags::ENCODER));
    assert!(bus.set_temperature_c(id(1), 87.0));
    assert!(!bus.set_temperature_c(id(9), 87.0));
    bus.exchange(&cmds, &mut r, PERIOD).unwrap();
    assert_eq!(r[1].errors, ErrorFlags::ENCODER);
    assert!(r[0].errors.is_empty());
    // Reply quantum of the temperature is 1 °C; the winding cools a little in 1 ms.
    assert!(
        (r[0].temperature_c - 87.0).abs() <= 1.0,
        "{}",
        r[0].temperature_c
    );
    bus.set_error_flags(id(2), ErrorFlags::NONE);
    bus.exchange(&cmds, &mut r, PERIOD).unwrap();
    assert!(r[1].errors.is_empty());
}

#[test]
fn bus_time_is_modelled_and_overload_misses_the_deadline() {
    // 2 motors per bus on 2 buses: busiest bus carries 4 frames.
    let mut bus = sim(4, 2, 0.0, 6);
    active(&mut bus);
    let cmds = [1, 2, 3, 4].map(|n| Command::pd(id(n), 0.1, 0.0, 20.0, 0.5, 0.0));
    let mut r = [Reply::zeroed(id(1)); 4];
    let rep = bus.exchange(&cmds, &mut r, PERIOD).unwrap();
    let lo = Duration::from_micros(4 * u64::from(frame_bits(8, Stuffing::None)));
    let hi = Duration::from_micros(4 * u64::from(frame_bits(8, Stuffing::WorstCase)));
    assert!(
        rep.bus_time >= lo && rep.bus_time <= hi,
        "{:?}",
        rep.bus_time
    );
    // 5 motors on one bus need ≥ 5 × 222 µs > 1 ms.
    let mut bus = sim(5, 1, 0.0, 6);
    active(&mut bus);
    let cmds = [1, 2, 3, 4, 5].map(|n| Command::damping(id(n), 1.0));
    let mut r = [Reply::zeroed(id(1)); 5];
    match bus.exchange(&cmds, &mut r, PERIOD) {
        Err(BusError::DeadlineExceeded { needed, budget }) => {
            assert!(needed >= Duration::from_micros(5 * 222));
            assert_eq!(budget, PERIOD);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn config_errors_name_the_culprit() {
    let plant = InertiaDampingPlant::new(vec![joint(0.0)]).unwrap();
    let mut config = SimConfig {
        control_rate_hz: 1000.0,
        bitrate_bps: 1_000_000,
        bus_count: 1,
        motors: vec![SimMotor {
            spec: MotorSpec { bus: 0, id: id(1) },
            joint: 3,
        }],
        model: A1Model::default(),
        seed: 0,
    };
    let e = SimBus::new(config.clone(), plant.clone()).err().unwrap();
    assert!(e.to_string().contains("no such joint"), "{e}");
    config.motors[0].joint = 0;
    config.control_rate_hz = 3000.0;
    assert!(matches!(
        SimBus::new(config, plant),
        Err(SimError::Rates { .. })
    ));
}
