//! Treadmill speed control: a library of gaits indexed by speed, a step-to-step speed
//! regulator and a belt-position loop, all acting at impacts only.
//!
//! ```text
//! operator: belt b, offset o ──┐            each tick: belt travel += b·dt
//!                              ▼
//! impact k: step length d_k (leg kinematics), duration T_k ─▶ v_k = d_k / T_k
//!           position on the belt p += d_k − belt travel over the step
//!           v_cmd = clamp(b + o − k_p·p, library range)          (belt-position loop)
//!           e_k = v_cmd − v_k;  I = clamp(I + k_i·e_k, ±I_max)     (step-to-step PI)
//!           σ = clamp(v_cmd + k_s·e_k + I, library range)
//!           gait of the next step = library interpolated at σ ─▶ Bézier α, θ⁺, θ⁻, T,
//!                                    feed-forward table, braking step
//! ```
//!
//! # Interpolation, and the post-impact state
//! The library's gaits are sorted by their planned speed; the gait at σ blends its two
//! neighbours linearly (weight w = (σ − v_i)/(v_{i+1} − v_i)): Bézier coefficients, θ⁺ and θ⁻,
//! step duration, the feed-forward torques (the right neighbour's table is sampled at the left
//! one's phases) and the braking step's offsets. The blend is written into the controller's one
//! active [`GaitTable`] at the impact: fixed arrays, no allocation, never mid-step.
//!
//! A new gait's outputs at the start of the step are not the old gait's, so switching the
//! references at the impact would jump them. The controller keeps them continuous instead: the
//! offset between the old gait's references and the new gait's at the post-impact state is
//! carried into the new step and blended out (minimum jerk) over its first 30 % of phase (20 %
//! for the swing knee) — the same blend that takes the first step after a launch into the gait.
//! The phase itself is measured with the new gait's θ⁺ and θ⁻; the phase observer keeps its
//! rate of stance-leg angle (τ̇ rescaled by the ratio of the two gaits' θ spans).
//!
//! # The law's gains
//! One update per step, on the Poincaré section: σ moves at most `max_change_per_step_mps`
//! (0.02 m/s) per step, k_s = 0.5, k_i = 0.1 (the integral removes the planned-vs-walked
//! bias), k_p = 0.3 /s. The error is taken over a stride (the last two steps): a step's speed
//! scatters by ±0.03 m/s between left and right steps.
//!
//! # Why the ends and the belt step fail (measured in the simulator, 2026-12-05)
//! Measured on the simulated ADAM with 60 s runs, seeds 1–5 (`adam bench treadmill`), and
//! single runs read back from the `/speed` channel; the library gaits up to 0.30 m/s are the
//! same in the library shipped before and now.
//!
//! 1. **The library's speed does not set the walked speed; it nudges a slow mode.** Each
//!    library gait walked alone (no speed control, an endless belt at its speed, seed 1) walks,
//!    between 25 and 40 s: 0.15 → 0.148 m/s, 0.175 → 0.177, 0.20 → 0.200, 0.225 → 0.276,
//!    0.25 → 0.305, 0.275 → 0.326, 0.30 → 0.343 m/s (the gaits from 0.225 m/s up walk
//!    0.05 m/s faster than planned: a steady-state gain ∂v/∂σ ≈ 2.5 between 0.20 and 0.25 m/s
//!    and ≈ 1 elsewhere). It gets there slowly: the 0.25 m/s gait speeds up from 0.248 to
//!    0.316 m/s over 20 s and the 0.225 m/s gait from 0.227 to 0.276 m/s, step by step, where
//!    the planner's Poincaré map has |λ| ≈ 0.88 per step. The closed loop on the simulated
//!    A1s (PD at 150 N·m/rad, the bus latency) thus walks orbits other than the planned ones,
//!    and its speed mode is nearly neutral (tens of steps). Once on a fast orbit the robot
//!    stays there: on a 0.20 m/s belt (seed 2, a trial library whose slowest gait is 0.135 m
//!    in 0.9 s), with σ held at that slowest gait for 15 s, it walked 0.22–0.25 m/s and ran
//!    off the front of the belt, where that gait alone walks 0.136 m/s. The regulator's only lever, σ, cannot pull it back within the belt's ±0.8 m.
//!    Inverting the measured steady-state map in the regulator (aiming at a walked speed and
//!    walking the gait M⁻¹ of it) was tried and did not help (seeds 1–5: 3 of 30 acceptance
//!    runs passed against 2; on a 0.20 m/s belt one fall where there was none; three belt
//!    steps off the front against one): it is the lag and the fast orbits, not the gain.
//! 2. **The slow end stalls.** The 0.15 m/s gait (0.15 m in 1.0 s, both step bounds active)
//!    has the least kinetic energy over the stance leg; a slower step after a gait switch
//!    (0.109–0.13 m/s) is followed by one that does not get over the stance foot: the step
//!    timeout trips. With shorter, quicker slow gaits (0.135 m in 0.9 s) the stalls went away
//!    but the robot ran off the front (item 1) instead.
//! 3. **The fast end crossed a jump in the library.** Planned with Table I's steps up to
//!    0.35 m, the library jumped between 0.300 and 0.325 m/s from 0.20 m / 0.67 s steps to
//!    0.26 m / 0.79 s ones; on a 0.35 m/s belt the regulator holds σ ≈ 0.30 (the gaits walk
//!    faster than planned), right at the jump, and the interpolated gaits walked erratic steps
//!    (0.27, 0.44, 0.30, 0.57 m/s in a row) and stalled in all five seeds. The library is now
//!    planned with steps of at most 0.22 m (`configs/planner/adam_library.toml`): a continuous
//!    family, and no trip at 0.35 m/s (docs/gait-library.md, "Step bounds").
//! 4. **The belt step** shows the lag at its worst (seed 1, `docs/figures/speed-belt-step.png`):
//!    after the step up at 20 s, σ rose from 0.15 to 0.25 m/s over some 5 s while the walk
//!    *slowed* from 0.26 to 0.13 m/s (a faster gait first walks slower steps), the position
//!    loop then drove σ to the top of the library (0.40) and the walk overshot to 0.44 m/s;
//!    back at 0.20 m/s σ sat at the bottom of the library (0.15) from 52 s on while the walk
//!    sped up to 0.23–0.25 m/s on a fast orbit (item 1), 0.6 m forward of the centre at 60 s.
//!    In other seeds the same runs off the front of the belt or stalls (bench table).
//!
//! What would fix it lies outside this module: a lever on the energy of each step (the step
//! length at touchdown, as the braking step of a Stop does: a longer step loses more at the
//! impact) or a closed loop whose orbits are the planned ones (the tracking gains, the
//! feed-forward), so that the library's speed is the walked speed.
//!
//! The gains are the config's `[speed]` section ([`crate::config::SpeedConfig`]).

use super::double_support::Geometry;
use super::gait_table::GaitTable;
use super::tick::{OperatorCommand, SpeedStatus};
use super::transitions::{braking_touchdown, Lunge};
use crate::config::SpeedConfig;
use crate::slots::OUTPUTS;
use crate::{Result, RuntimeError};
use model::gait::GaitFile;
use model::robot::Legs;
use model::PlanarModel;

/// The gait library as the controller holds it: one table and braking step per speed,
/// sorted by speed (at least two).
#[derive(Clone, Debug)]
pub(super) struct SpeedLibrary {
    pub(super) speeds_mps: Box<[f64]>,
    pub(super) tables: Box<[GaitTable]>,
    pub(super) lunges: Box<[Lunge]>,
}

impl SpeedLibrary {
    /// The library of `gaits` (sorted by `speed_mps`, at least two; none: `None`), each checked
    /// to be walkable by the controller of `base` (the same robot and design, the same outputs
    /// and Bézier degree, a state-based phase) with its braking step of `stop_step_m`. Errors
    /// name the entry, the field and the value.
    pub(super) fn new(
        gaits: &[GaitFile],
        base: (&GaitFile, &GaitTable),
        model: &PlanarModel,
        legs: &Legs,
        geometry: &Geometry,
        stop_step_m: f64,
    ) -> Result<Option<Self>> {
        if gaits.is_empty() {
            return Ok(None);
        }
        let bad =
            |k: usize, field: &str, value: String, reason: String| RuntimeError::InvalidField {
                origin: "gait library".into(),
                field: format!("entries[{k}].{field}"),
                value,
                reason,
            };
        if gaits.len() < 2 {
            return Err(bad(
                0,
                "speed_mps",
                gaits[0].speed_mps.to_string(),
                "a library needs at least two gaits to interpolate between".into(),
            ));
        }
        let (base_gait, base_table) = base;
        let mut speeds = Vec::with_capacity(gaits.len());
        let mut tables = Vec::with_capacity(gaits.len());
        let mut lunges = Vec::with_capacity(gaits.len());
        for (k, g) in gaits.iter().enumerate() {
            if !(g.speed_mps.is_finite() && g.speed_mps > 0.0) {
                return Err(bad(
                    k,
                    "speed_mps",
                    g.speed_mps.to_string(),
                    "must be positive and finite".into(),
                ));
            }
            if let Some(&prev) = speeds.last() {
                if g.speed_mps <= prev {
                    return Err(bad(
                        k,
                        "speed_mps",
                        g.speed_mps.to_string(),
                        format!("not above entry {}'s {prev} m/s: the library must be sorted by speed without duplicates", k - 1),
                    ));
                }
            }
            if g.robot.sha256 != base_gait.robot.sha256 {
                return Err(bad(
                    k,
                    "robot",
                    format!("{} (URDF SHA-256 {})", g.robot.name, g.robot.sha256),
                    format!(
                        "the gait walks robot {} (URDF SHA-256 {})",
                        base_gait.robot.name, base_gait.robot.sha256
                    ),
                ));
            }
            let same_design = (g.design.thigh_length_m - base_gait.design.thigh_length_m).abs()
                < 1e-9
                && (g.design.shin_length_m - base_gait.design.shin_length_m).abs() < 1e-9;
            if !same_design {
                return Err(bad(
                    k,
                    "design",
                    format!(
                        "thigh {} m, shin {} m",
                        g.design.thigh_length_m, g.design.shin_length_m
                    ),
                    format!(
                        "the gait's design is thigh {} m, shin {} m",
                        base_gait.design.thigh_length_m, base_gait.design.shin_length_m
                    ),
                ));
            }
            let table = GaitTable::new(g, model, legs)?;
            if table.alpha_len != base_table.alpha_len || table.out_slot != base_table.out_slot {
                return Err(bad(
                    k,
                    "bezier",
                    format!("degree {}", table.alpha_len.saturating_sub(1)),
                    format!(
                        "must have the gait's outputs and Bézier degree {}",
                        base_table.alpha_len.saturating_sub(1)
                    ),
                ));
            }
            if !(table.theta_plus_rad.is_finite() && table.theta_minus_rad.is_finite()) {
                return Err(bad(
                    k,
                    "phase",
                    "time_based".into(),
                    "speed control needs state-based gaits (θ⁺, θ⁻)".into(),
                ));
            }
            let lunge = braking_touchdown(geometry, &table, stop_step_m).ok_or_else(|| {
                bad(
                    k,
                    "speed_mps",
                    g.speed_mps.to_string(),
                    format!("its braking step of walk.stop_step_length_m = {stop_step_m} m is out of the legs' reach"),
                )
            })?;
            speeds.push(g.speed_mps);
            tables.push(table);
            lunges.push(lunge);
        }
        Ok(Some(Self {
            speeds_mps: speeds.into_boxed_slice(),
            tables: tables.into_boxed_slice(),
            lunges: lunges.into_boxed_slice(),
        }))
    }

    /// Slowest and fastest speed, m/s.
    pub(super) fn range_mps(&self) -> (f64, f64) {
        let n = self.speeds_mps.len();
        (self.speeds_mps[0], self.speeds_mps[n - 1])
    }

    /// Writes the gait of speed `speed_mps` (clamped to the range) into `gait` and its braking
    /// step into `lunge`: linear interpolation between the two neighbours. Allocation-free.
    pub(super) fn blend_into(&self, speed_mps: f64, gait: &mut GaitTable, lunge: &mut Lunge) {
        let b = model::library::bracket(&self.speeds_mps, speed_mps);
        let (i, j, w) = (b.lower, b.upper, b.weight);
        lerp_table(&self.tables[i], &self.tables[j], w, gait);
        let (la, lb) = (&self.lunges[i], &self.lunges[j]);
        for k in 0..OUTPUTS {
            lunge.dy_end[k] = lerp(la.dy_end[k], lb.dy_end[k], w);
        }
        lunge.theta_rad = lerp(la.theta_rad, lb.theta_rad, w);
    }
}

fn lerp(a: f64, b: f64, w: f64) -> f64 {
    a + w * (b - a)
}

/// `out` = (1 − w)·a + w·b, field by field (a and b share degree and output slots: checked when
/// the library is built); the feed-forward table on a's phases.
fn lerp_table(a: &GaitTable, b: &GaitTable, w: f64, out: &mut GaitTable) {
    out.alpha_len = a.alpha_len;
    for i in 0..OUTPUTS {
        for k in 0..a.alpha_len {
            out.alpha[i][k] = lerp(a.alpha[i][k], b.alpha[i][k], w);
        }
    }
    out.out_slot = a.out_slot;
    out.theta_plus_rad = lerp(a.theta_plus_rad, b.theta_plus_rad, w);
    out.theta_minus_rad = lerp(a.theta_minus_rad, b.theta_minus_rad, w);
    out.step_duration_s = lerp(a.step_duration_s, b.step_duration_s, w);
    out.initial_pitch = match (a.initial_pitch, b.initial_pitch) {
        (Some(pa), Some(pb)) => Some((lerp(pa.0, pb.0, w), lerp(pa.1, pb.1, w))),
        (p, _) => p,
    };
    out.ff_len = a.ff_len;
    for k in 0..a.ff_len {
        let phase = a.ff_phase[k];
        out.ff_phase[k] = phase;
        let tb = b.feedforward(phase);
        for (i, t) in tb.iter().enumerate() {
            out.ff_torque_nm[k][i] = lerp(a.ff_torque_nm[k][i], *t, w);
        }
    }
}

/// The regulator and the position loop: what the operator set and what the steps measured.
#[derive(Clone, Copy, Debug)]
pub(super) struct SpeedRegulator {
    position_gain_per_s: f64,
    speed_gain: f64,
    integral_gain: f64,
    integral_limit_mps: f64,
    max_change_per_step_mps: f64,
    /// Belt travel since the last impact, m.
    belt_travel_m: f64,
    /// Time of the last [`SpeedRegulator::advance`], s.
    last_t_s: Option<f64>,
    /// The step before the last: length, m, and duration, s (the error is measured over the
    /// last two steps, a stride: left and right steps differ).
    previous_step: Option<(f64, f64)>,
    pub(super) status: SpeedStatus,
}

impl SpeedRegulator {
    /// A regulator whose first library speed is `start_mps` (the gait walked before speed
    /// control begins).
    pub(super) fn new(config: &SpeedConfig, start_mps: f64) -> Self {
        let mut status = SpeedStatus::UNKNOWN;
        status.library_mps = start_mps;
        Self {
            position_gain_per_s: config.position_gain_per_s,
            speed_gain: config.speed_gain,
            integral_gain: config.integral_gain,
            integral_limit_mps: config.integral_limit_mps,
            max_change_per_step_mps: config.max_change_per_step_mps,
            belt_travel_m: 0.0,
            last_t_s: None,
            previous_step: None,
            status,
        }
    }

    /// Whether a belt speed is known (speed control runs only then).
    pub(super) fn active(&self) -> bool {
        self.status.belt_mps.is_finite()
    }

    /// Takes an operator's speed command; false for any other command.
    pub(super) fn operator(&mut self, cmd: OperatorCommand) -> bool {
        let s = &mut self.status;
        match cmd {
            OperatorCommand::Belt { speed_mps } if speed_mps.is_finite() => {
                s.belt_mps = speed_mps;
            }
            OperatorCommand::Offset { speed_mps } if speed_mps.is_finite() => {
                s.offset_mps = speed_mps;
            }
            OperatorCommand::Nudge { delta_mps } if delta_mps.is_finite() => {
                s.offset_mps += delta_mps;
            }
            _ => return false,
        }
        true
    }

    /// Integrates the belt's travel up to `t_s` (every tick).
    pub(super) fn advance(&mut self, t_s: f64) {
        if let (Some(t0), true) = (self.last_t_s, self.active()) {
            let dt = (t_s - t0).clamp(0.0, 0.1);
            self.belt_travel_m += self.status.belt_mps * dt;
        }
        self.last_t_s = Some(t_s);
    }

    /// Forgets the steps (a walk begins): position 0, no integral, no belt travel.
    pub(super) fn restart(&mut self) {
        self.belt_travel_m = 0.0;
        self.previous_step = None;
        let s = &mut self.status;
        s.position_m = 0.0;
        s.integral_mps = 0.0;
        s.step_speed_mps = f64::NAN;
        s.commanded_mps = f64::NAN;
    }

    /// The step that just ended at an impact: `length_m` over `duration_s`. Updates the
    /// position, the commanded speed and the integral, and returns the library speed σ of the
    /// next step (clamped to `range_mps`).
    pub(super) fn on_impact(
        &mut self,
        length_m: f64,
        duration_s: f64,
        range_mps: (f64, f64),
    ) -> f64 {
        let (lo, hi) = range_mps;
        let s = &mut self.status;
        let measured = length_m.is_finite() && duration_s > 0.0;
        s.step_length_m = length_m;
        s.step_duration_s = duration_s;
        if measured {
            s.step_speed_mps = length_m / duration_s;
            s.position_m += length_m - self.belt_travel_m;
        }
        self.belt_travel_m = 0.0;
        // The speed error of the last stride (the step that ended and the one before) against
        // the command it walked under.
        let stride_mps = match self.previous_step {
            Some((l0, t0)) if measured => (l0 + length_m) / (t0 + duration_s),
            _ => s.step_speed_mps,
        };
        self.previous_step = measured.then_some((length_m, duration_s));
        let error = if measured && s.commanded_mps.is_finite() {
            s.commanded_mps - stride_mps
        } else {
            0.0
        };
        s.requested_mps = s.belt_mps + s.offset_mps - self.position_gain_per_s * s.position_m;
        s.commanded_mps = s.requested_mps.clamp(lo, hi);
        s.clamped = s.commanded_mps != s.requested_mps;
        let integral = (s.integral_mps + self.integral_gain * error)
            .clamp(-self.integral_limit_mps, self.integral_limit_mps);
        let sigma = s.commanded_mps + self.speed_gain * error + integral;
        // Anti-windup: the integral only grows while σ is inside the library.
        if (lo..=hi).contains(&sigma) || integral.abs() < s.integral_mps.abs() {
            s.integral_mps = integral;
        }
        let last = if s.library_mps.is_finite() {
            s.library_mps.clamp(lo, hi)
        } else {
            s.commanded_mps
        };
        let r = self.max_change_per_step_mps;
        s.library_mps = sigma.clamp(lo, hi).clamp(last - r, last + r);
        s.library_mps
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn regulator() -> SpeedRegulator {
        let mut r = SpeedRegulator::new(&SpeedConfig::default(), 0.25);
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }));
        r
    }

    #[test]
    fn position_integrates_steps_against_the_belt_and_pulls_the_command_back() {
        let mut r = regulator();
        for k in 0..=800 {
            r.advance(k as f64 * 1e-3);
        }
        // 0.8 s of belt at 0.25 m/s is 0.2 m; a 0.24 m step puts the robot 4 cm forward.
        let sigma = r.on_impact(0.24, 0.8, (0.15, 0.35));
        assert!((r.status.position_m - 0.04).abs() < 1e-9);
        // Forward of the centre: the command is below the belt speed by k_p·p.
        let k_p = SpeedConfig::default().position_gain_per_s;
        assert!((r.status.commanded_mps - (0.25 - k_p * 0.04)).abs() < 1e-9);
        assert!(sigma < 0.25);
    }

    #[test]
    fn a_slow_step_raises_the_next_gait_and_the_integral_removes_a_steady_bias() {
        let mut r = regulator();
        r.on_impact(f64::NAN, 0.0, (0.15, 0.35));
        r.status.position_m = 0.0;
        // Each step walks 0.02 m/s slower than the gait it was given (a bias), the belt
        // travel matched to the step so the position stays put.
        let mut sigma = 0.25;
        for _ in 0..60 {
            let v = sigma - 0.02;
            r.belt_travel_m = v * 0.8;
            sigma = r.on_impact(v * 0.8, 0.8, (0.15, 0.35));
        }
        // The command settles where the robot walks the belt speed: σ = 0.27, the bias.
        assert!((sigma - 0.27).abs() < 1e-3, "σ = {sigma}");
        assert!((r.status.integral_mps - 0.02).abs() < 1e-3);
    }

    #[test]
    fn commands_outside_the_library_are_clamped_and_flagged() {
        let mut r = regulator();
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.5 }));
        let sigma = r.on_impact(0.2, 0.8, (0.15, 0.35));
        assert!(r.status.clamped);
        let k_p = SpeedConfig::default().position_gain_per_s;
        assert_eq!(r.status.requested_mps, 0.5 - k_p * r.status.position_m);
        assert_eq!(r.status.commanded_mps, 0.35);
        // ... and the library speed moves towards it by at most the step limit.
        assert!((sigma - 0.27).abs() < 1e-12, "σ = {sigma}");
        assert!(!r.operator(OperatorCommand::Walk));
        assert!(r.operator(OperatorCommand::Nudge { delta_mps: 0.025 }));
        assert!(r.operator(OperatorCommand::Nudge { delta_mps: 0.025 }));
        assert!((r.status.offset_mps - 0.05).abs() < 1e-15);
    }
}
