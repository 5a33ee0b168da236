//! Gait tiles (the paper's Fig. 5): stick figures of the robot at evenly spaced phases of one
//! step of a logged walk, for `adam plot tiles <run.mcap>`.
//!
//! ```text
//! run.mcap ─ attachments (runtime.toml, gait.json, robot.urdf) ─▶ model with the gait's design
//!          ─ /hzd (phase, stance, steps) ┐
//!          ─ /joints (motor angles)      ├─▶ one complete step ─▶ samples nearest τ = k/(n−1)
//!          ─ /estimator (pitch)          ┘      ─▶ q (pitch, model joint angles) ─▶ forward kinematics
//! ```
//! Joint angles are converted from the motor side to the model side with each leg joint's
//! `[calibration]` (direction, zero offset, gear ratio) from the attached config; the torso pitch is the controller's
//! estimate (what the robot believed). Positions are relative to the stance foot, which stays
//! put during a step. The step drawn is the middle one of the complete steps in the log (a
//! step whose start and end are both in the log).

use crate::control::ControlState;
use crate::slots::SlotLayout;
use crate::telemetry::log::CHANNELS;
use crate::telemetry::log_read::{check_schema_version, log_err, read_bytes, TopLevel};
use crate::telemetry::salvage::Salvaged;
use crate::Result;
use model::Side;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// The robot at one instant, positions in metres relative to the stance foot (x forward,
/// z up).
#[derive(Clone, Debug, PartialEq)]
pub struct StickFigure {
    /// Phase τ of the sample.
    pub phase: f64,
    /// Controller time, s.
    pub t_s: f64,
    /// Stance leg.
    pub stance: Side,
    /// Torso pitch used (the controller's estimate), rad.
    pub pitch_rad: f64,
    /// Hip (base origin) and the top of the torso (twice the torso's centre of mass height).
    pub torso_m: [[f64; 2]; 2],
    /// Stance leg: hip, knee, foot.
    pub stance_leg_m: [[f64; 2]; 3],
    /// Swing leg: hip, knee, foot.
    pub swing_leg_m: [[f64; 2]; 3],
}

/// The tiles of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct GaitTiles {
    /// Robot name.
    pub robot: String,
    /// Thigh and shin lengths of the gait's design, m.
    pub design_m: (f64, f64),
    /// Step index (the controller's step counter) drawn.
    pub step: u32,
    /// Duration of that step, s: from its first logged tick to the next step's (each the first
    /// after an impact, so a sparsely sampled log is not biased short).
    pub step_duration_s: f64,
    /// Step length, m: the landed foot ahead of the old stance foot at the next step's first
    /// logged tick (the old stance foot has barely moved then; the swing foot at this step's
    /// last tick may be a sample interval short of its landing: 1.6 cm in the 50 Hz walk fixture).
    pub step_length_m: f64,
    /// The figures, by increasing phase.
    pub figures: Vec<StickFigure>,
    /// Where the log is cut off or damaged and what was lost (`None`: read whole); the step
    /// drawn is one of the intact part.
    pub damage: Option<String>,
}

#[derive(Clone, Debug, Default)]
struct Row {
    phase: Option<f64>,
    stance: Option<Side>,
    steps: Option<u32>,
    walking: Option<bool>,
    pitch: Option<f64>,
    motor_q: Option<[f64; 4]>,
}

/// A tick of the walk with everything the tiles need.
#[derive(Clone, Copy, Debug)]
struct Sample {
    t_s: f64,
    phase: f64,
    stance: Side,
    steps: u32,
    pitch_rad: f64,
    motor_q_rad: [f64; 4],
}

impl Row {
    /// The sample of a walking tick whose channels were all read.
    fn sample(&self, t_s: f64) -> Option<Sample> {
        (self.walking == Some(true)).then_some(())?;
        Some(Sample {
            t_s,
            phase: self.phase?,
            stance: self.stance?,
            steps: self.steps?,
            pitch_rad: self.pitch?,
            motor_q_rad: self.motor_q?,
        })
    }
}

/// Stick figures of `count` (≥ 2) evenly spaced phases of one complete step of the walk logged
/// in `path`.
pub fn gait_tiles(path: impl AsRef<Path>, count: usize) -> Result<GaitTiles> {
    let path = path.as_ref();
    if count < 2 {
        return Err(log_err(
            path,
            format!("tiles: count is {count}, want at least 2"),
        ));
    }
    let bytes = read_bytes(path)?;
    let log = Salvaged::read(path, &bytes)?;
    let setup = TopLevel::of(&log).setup(path)?;
    let names: Vec<&str> = setup
        .config
        .leg_motors
        .iter()
        .map(|m| m.joint.as_str())
        .collect();
    if names.len() != 4 {
        return Err(log_err(
            path,
            format!("tiles: the config has {} leg motors, want 4", names.len()),
        ));
    }

    // Rows by log time (every channel of a tick shares it).
    let mut rows: BTreeMap<u64, Row> = BTreeMap::new();
    let mut checked = Vec::new();
    // A cut-off or damaged log: every message of its intact chunks.
    for m in log.messages() {
        let topic = m.channel.topic.as_str();
        if ![CHANNELS[0], CHANNELS[1], CHANNELS[2], CHANNELS[3]].contains(&topic) {
            continue;
        }
        if !checked.contains(&topic.to_string()) {
            check_schema_version(path, &m.channel)?;
            checked.push(topic.to_string());
        }
        let v: Value = serde_json::from_slice(&m.data)
            .map_err(|e| log_err(path, format!("{topic} message is not JSON: {e}")))?;
        let row = rows.entry(m.log_time).or_default();
        match topic {
            "/joints" => {
                let mut q = [0.0; 4];
                for (k, name) in names.iter().enumerate() {
                    q[k] = v[*name]["q_rad"].as_f64().ok_or_else(|| {
                        log_err(path, format!("/joints message without {name}.q_rad"))
                    })?;
                }
                row.motor_q = Some(q);
            }
            "/hzd" => {
                row.phase = v["phase"].as_f64();
                row.steps = v["steps"].as_u64().and_then(|s| u32::try_from(s).ok());
                row.stance = match v["stance"].as_str() {
                    Some("left") => Some(Side::Left),
                    Some("right") => Some(Side::Right),
                    _ => None,
                };
            }
            "/estimator" => row.pitch = v["pitch_rad"].as_f64(),
            _ => {
                let state = v["state"].as_str();
                row.walking = Some(
                    state == Some(ControlState::Walk.name())
                        || state == Some(ControlState::Stop.name()),
                );
            }
        }
    }
    let rows: Vec<Sample> = rows
        .into_iter()
        .filter_map(|(t, r)| r.sample(t as f64 * 1e-9))
        .collect();
    // Runs of equal step counters; a complete step has a different one before and after it.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for i in 0..rows.len() {
        if i == 0 || rows[i].steps != rows[i - 1].steps {
            runs.push((i, i + 1));
        } else if let Some(last) = runs.last_mut() {
            last.1 = i + 1;
        }
    }
    if runs.len() < 3 {
        return Err(log_err(
            path,
            format!(
                "tiles: no complete step while walking ({} step counter value(s) in the log; \
                 log a walk of at least two steps)",
                runs.len()
            ),
        ));
    }
    let (a, b) = runs[runs.len() / 2];
    let step_rows = &rows[a..b];
    let step = step_rows[0].steps;

    let model = &setup.model;
    let legs = model.legs()?;
    let nominal = model.nominal_pose()?;
    let mut q = model.with_design(
        &nominal,
        setup.gait.design.thigh_length_m,
        setup.gait.design.shin_length_m,
    )?;
    q[0] = 0.0;
    q[1] = 0.0;
    let mut coords = [0usize; 4];
    for (k, name) in names.iter().enumerate() {
        coords[k] = model.joints[model.require_joint(name)?].coordinate;
    }
    let layout = SlotLayout::new(&setup.config, false);
    let mut figure_at = |r: &Sample| -> Result<StickFigure> {
        q[2] = r.pitch_rad;
        for (k, &c) in coords.iter().enumerate() {
            q[c] = layout.model_rad(k, r.motor_q_rad[k]);
        }
        let st = model.body_poses(&q)?;
        let hip = st.pose[0].xz_m;
        let com = model.body_com_in(&st, 0);
        let foot_stance = model.frame_position_in(&st, legs.side(r.stance).foot);
        let shift = |p: [f64; 2]| [p[0] - foot_stance[0], p[1] - foot_stance[1]];
        let leg = |side: Side| -> Result<[[f64; 2]; 3]> {
            let l = legs.side(side);
            let joint = |j: usize| shift(st.pose[model.joints[j].body].xz_m);
            Ok([
                joint(l.hip),
                joint(l.knee),
                shift(model.frame_position_in(&st, l.foot)),
            ])
        };
        Ok(StickFigure {
            phase: r.phase,
            t_s: r.t_s,
            stance: r.stance,
            pitch_rad: r.pitch_rad,
            torso_m: [
                shift(hip),
                shift([2.0 * com[0] - hip[0], 2.0 * com[1] - hip[1]]),
            ],
            stance_leg_m: leg(r.stance)?,
            swing_leg_m: leg(r.stance.other())?,
        })
    };
    let mut figures = Vec::with_capacity(count);
    for k in 0..count {
        let target = k as f64 / (count - 1) as f64;
        let nearest = step_rows
            .iter()
            .min_by(|x, y| {
                (x.phase - target)
                    .abs()
                    .total_cmp(&(y.phase - target).abs())
            })
            .ok_or_else(|| log_err(path, "tiles: empty step"))?;
        figures.push(figure_at(nearest)?);
    }
    // The middle run is never the last (at least three runs), so the next step has a tick.
    let next = &rows[b];
    let landed = figure_at(next)?;
    Ok(GaitTiles {
        robot: model.name.clone(),
        design_m: (
            setup.gait.design.thigh_length_m,
            setup.gait.design.shin_length_m,
        ),
        step,
        step_duration_s: next.t_s - step_rows[0].t_s,
        step_length_m: -landed.swing_leg_m[2][0],
        figures,
        damage: log.loss.summary(),
    })
}
