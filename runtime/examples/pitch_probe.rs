//! Does the torso-pitch estimate drive the walked speed? A library gait alone on an endless
//! belt with the shipped estimator, or with the simulator's true pitch handed to the controller
//! (the measurements behind `runtime::estimator`, "The touchdown pitch", and
//! `runtime::control::speed`, "Why the library speed does not set the walked speed").
//!
//! ```text
//! cargo run --release -p runtime --example pitch_probe -- CONFIG GAIT BELT_MPS DURATION_S SEED MODE [OFFSET_MRAD]
//! ```
//! MODE:
//! - `est`: the shipped estimator on the simulated IMU;
//! - `truth`: the controller's pitch is the true pitch at the time of the encoder sample it
//!   is paired with (the gyro replaced by the true pitch's finite difference, the touchdown
//!   measurement switched off), plus OFFSET_MRAD (a deliberate constant error);
//! - `truth-imu`: the same with the true pitch at the IMU sample's time (one control period
//!   after the encoders' on the simulated bus).
//!
//! On stdout, one line per simulated touchdown (t, side, step length, duration, speed), then
//! one per touchdown the controller detects: what the legs measure there (the pitch that levels
//! the feet, from the true joint angles at the encoders' sample) against the true pitch at the
//! encoders' sample and at the IMU's, the true height of the landing foot above the stance foot
//! at the encoders' sample, and the sim's touchdown time against the encoders' sample. Last, the
//! walked speed over 10 s to the end against the gait's plan. With `LOG=path` in the
//! environment the run is logged (MCAP). The truth is for diagnosis only: the shipped
//! controller never sees it.

use drivers::bus::BusWrapper;
use drivers::imu::{Imu, ImuError, ImuSample};
use drivers::sim::bus::SimBus;
use drivers::sim::robot::{RobotSim, SimEvent};
use runtime::backend::WalkProgress;
use runtime::sim::inject::FaultClock;
use runtime::sim::run::{sim_backend, SimWalkOptions};
use runtime::{Backend, LoopOptions, Setup};
use std::process::ExitCode;

const USAGE: &str =
    "usage: pitch_probe CONFIG GAIT BELT_MPS DURATION_S SEED est|truth|truth-imu|exact-gyro|noiseless [OFFSET_MRAD]";

#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Estimated,
    /// The true pitch at the encoders' sample (`false`) or the IMU's (`true`).
    Truth {
        at_imu: bool,
    },
    /// The shipped estimator, its gyro the true pitch's finite difference at the IMU's sample
    /// (no noise, no bias, no integration error; the touchdown measurement on).
    ExactGyro,
    /// The shipped estimator on an IMU without noise or bias.
    Noiseless,
}

struct Probe {
    bus: SimBus<RobotSim>,
    mode: Mode,
    offset_rad: f64,
    /// The plant's state after each exchange (the encoders of the next exchange sample it).
    q_after: Vec<Vec<f64>>,
    q0: Vec<f64>,
    /// (the pitch handed out last, its stamp); `None` before the first read.
    last: Option<(f64, f64)>,
    /// Exchange index at which the controller counted each touchdown.
    detections: Vec<usize>,
    progress: WalkProgress,
}

impl Probe {
    /// True pitch at the start of exchange `k` (what its encoder replies sample), rad.
    fn pitch_at_exchange(&self, k: usize) -> f64 {
        if k == 0 {
            self.q0[2]
        } else {
            self.q_after[k - 1][2]
        }
    }
}

/// The simulator's bus, the true state after each exchange recorded.
impl BusWrapper for Probe {
    type Inner = SimBus<RobotSim>;
    fn inner(&self) -> &Self::Inner {
        &self.bus
    }
    fn inner_mut(&mut self) -> &mut Self::Inner {
        &mut self.bus
    }
    fn after_exchange(&mut self) {
        self.q_after.push(self.bus.plant().q().to_vec());
    }
}

impl Imu for Probe {
    fn read(&mut self, out: &mut ImuSample) -> Result<(), ImuError> {
        self.bus.read(out)
    }
    fn read_at(&mut self, t_s: f64) -> Option<ImuSample> {
        let mut sample = self.bus.read_at(t_s)?;
        let at_imu = match self.mode {
            Mode::Truth { at_imu } => at_imu,
            Mode::ExactGyro => true,
            _ => return Some(sample),
        };
        // Exchange k just ran: its encoders sampled the state at its start, the IMU now.
        let k = self.q_after.len() - 1;
        let truth = if at_imu {
            self.q_after[k][2]
        } else {
            self.pitch_at_exchange(k)
        };
        // The estimator starts from the planned pitch (the state at t = 0) and integrates the
        // gyro from the second sample on: a finite difference of the truth integrates to it.
        sample.gyro_pitch_rad_s = match self.last {
            None => {
                self.last = Some((self.q0[2], t_s));
                0.0
            }
            Some((p0, t0)) => {
                let target = truth + self.offset_rad;
                self.last = Some((target, t_s));
                if t_s > t0 {
                    (target - p0) / (t_s - t0)
                } else {
                    0.0
                }
            }
        };
        Some(sample)
    }
}

impl Backend for Probe {
    fn true_pitch_rad(&self) -> Option<f64> {
        self.bus.true_pitch_rad()
    }
    fn true_belt_position_m(&self) -> Option<f64> {
        self.bus.true_belt_position_m()
    }
    fn observe(&mut self, progress: &WalkProgress) {
        if progress.steps != self.progress.steps {
            self.detections.push(self.q_after.len() - 1);
        }
        self.progress = *progress;
    }
}

fn main() -> ExitCode {
    match probe(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pitch_probe: {e}\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

fn probe(args: Vec<String>) -> Result<(), String> {
    let (config, gait, belt, duration, seed, mode, offset) = match args.as_slice() {
        [c, g, b, d, s, m] => (c, g, b, d, s, m, "0"),
        [c, g, b, d, s, m, o] => (c, g, b, d, s, m, o.as_str()),
        _ => return Err(format!("6 or 7 arguments expected, {} given", args.len())),
    };
    let num = |v: &str| {
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{v:?} is not a finite number"))
    };
    let (belt_mps, duration_s, offset_mrad) = (num(belt)?, num(duration)?, num(offset)?);
    let seed: u64 = seed.parse().map_err(|e| format!("{seed}: {e}"))?;
    let mode = match mode.as_str() {
        "est" => Mode::Estimated,
        "truth" => Mode::Truth { at_imu: false },
        "truth-imu" => Mode::Truth { at_imu: true },
        "exact-gyro" => Mode::ExactGyro,
        "noiseless" => Mode::Noiseless,
        other => return Err(format!("unknown MODE {other:?}")),
    };
    let mut setup = Setup::load(config, gait).map_err(|e| e.to_string())?;
    if let Mode::Truth { .. } = mode {
        // The truth needs no correction: the touchdown measurement's weight vanishes.
        setup.config.estimator.touchdown_pitch_sigma_rad = 1e3;
    }
    let mut o = SimWalkOptions::new(duration_s);
    o.belt_speed_mps = Some(belt_mps);
    o.belt_length_m = f64::INFINITY;
    o.seed = seed;
    if mode == Mode::Noiseless {
        o.imu_noise = drivers::imu::ImuNoise::NONE;
    }
    let bus = sim_backend(&setup, &o).map_err(|e| e.to_string())?;
    let q0 = bus.plant().q().to_vec();
    let ticks = (duration_s * setup.config.loop_.rate_hz) as usize + 10;
    let probe = Probe {
        bus,
        mode,
        offset_rad: offset_mrad * 1e-3,
        q_after: Vec::with_capacity(ticks),
        q0,
        last: None,
        detections: Vec::new(),
        progress: WalkProgress::default(),
    };
    let mut lo = LoopOptions::simulation(duration_s);
    lo.start_walking = true;
    lo.log_path = std::env::var_os("LOG").map(Into::into);
    let (summary, probe) =
        runtime::run(&setup, probe, FaultClock::new(&[]), lo, None).map_err(|e| e.to_string())?;
    let model = &setup.model;
    let legs = model.legs().map_err(|e| e.to_string())?;
    let feet = [legs.left.foot, legs.right.foot];
    let period_s = 1.0 / setup.config.loop_.rate_hz;

    println!("# touchdowns: t_s side length_m duration_s speed_mps");
    let mut last_t = f64::NAN;
    let (mut sum_len, mut sum_dur, mut first_t) = (0.0, 0.0, f64::NAN);
    let mut touchdowns = Vec::new();
    for e in probe.bus.plant().events() {
        let SimEvent::Touchdown(td) = e else { continue };
        let dur = td.t_s - last_t;
        println!(
            "{:.4} {} {:.4} {:.4} {:.4}",
            td.t_s,
            if td.side as usize == 0 { "L" } else { "R" },
            td.step_length_m,
            dur,
            td.step_length_m / dur
        );
        if last_t >= 10.0 {
            sum_len += td.step_length_m;
            sum_dur += dur;
            if first_t.is_nan() {
                first_t = last_t;
            }
        }
        touchdowns.push(td.t_s);
        last_t = td.t_s;
    }

    // What the legs measure at each detected touchdown.
    println!(
        "# detections: t_s level_minus_true_enc_mrad level_minus_true_imu_mrad \
         imu_minus_enc_mrad landing_foot_height_mm touchdown_minus_enc_ms \
         level_minus_true_one_sample_later_mrad"
    );
    let height = |q: &[f64], pitch: f64| -> [f64; 2] {
        let mut q = q.to_vec();
        q[2] = pitch;
        let l = model.frame_position(&q, feet[0]).expect("foot");
        let r = model.frame_position(&q, feet[1]).expect("foot");
        [l[1] - r[1], r[1] - l[1]]
    };
    let (mut sum_enc, mut sum_imu, mut sum_post, mut n) = (0.0, 0.0, 0.0, 0usize);
    for &k in &probe.detections {
        if k == 0 {
            continue;
        }
        let q_enc = &probe.q_after[k - 1];
        let true_enc = q_enc[2];
        let true_imu = probe.q_after[k][2];
        // The pitch that levels the feet for the true joint angles at the encoders' sample.
        let mut level = true_enc;
        for _ in 0..4 {
            let h = height(q_enc, level)[0];
            let slope = (height(q_enc, level + 1e-6)[0] - h) / 1e-6;
            level -= h / slope;
        }
        // The landing foot: the lower one a moment later is the new stance foot; its height
        // above the other at the encoders' sample.
        let t_enc = k as f64 * period_s;
        let td = touchdowns
            .iter()
            .copied()
            .min_by(|a, b| (a - t_enc).abs().total_cmp(&(b - t_enc).abs()))
            .unwrap_or(f64::NAN);
        let hl = height(q_enc, true_enc);
        let q_next = &probe.q_after[k];
        let landing = if height(q_next, q_next[2])[0] < 0.0 {
            0
        } else {
            1
        };
        // The same one sample later, after the impact (the old stance foot lifting).
        let mut level_post = q_next[2];
        for _ in 0..4 {
            let h = height(q_next, level_post)[0];
            let slope = (height(q_next, level_post + 1e-6)[0] - h) / 1e-6;
            level_post -= h / slope;
        }
        let e_post = (level_post - q_next[2]) * 1e3;
        let e_enc = (level - true_enc) * 1e3;
        let e_imu = (level - true_imu) * 1e3;
        if t_enc >= 10.0 {
            sum_enc += e_enc;
            sum_imu += e_imu;
            sum_post += e_post;
            n += 1;
        }
        println!(
            "{t_enc:.4} {e_enc:.3} {e_imu:.3} {:.3} {:.3} {:.2} {e_post:.3}",
            (true_imu - true_enc) * 1e3,
            hl[landing] * 1e3,
            (td - t_enc) * 1e3
        );
    }
    let walked = sum_len / sum_dur;
    let planned = setup.gait.step_length_m / setup.gait.step_duration_s;
    eprintln!(
        "{:?} offset {offset_mrad} mrad, seed {seed}: walked {walked:.4} m/s over {first_t:.1}-{last_t:.1} s \
         = {:.1} % of the plan ({planned:.4} m/s); level − true over {n} detections after 10 s: \
         {:.2} mrad at the encoders' sample, {:.2} at the IMU's, {:.2} one sample later (after the impact); pitch RMS {:?}; {} touchdowns",
        mode,
        100.0 * walked / planned,
        sum_enc / n.max(1) as f64,
        sum_imu / n.max(1) as f64,
        sum_post / n.max(1) as f64,
        summary.tracking.pitch_rms_rad().map(f64::to_degrees),
        touchdowns.len()
    );
    Ok(())
}
