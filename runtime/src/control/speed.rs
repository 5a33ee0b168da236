//! Treadmill speed control: a library of gaits indexed by speed, a step-to-step speed
//! regulator, a per-step lever on the step length and a belt-position loop, all acting at
//! impacts only.
//!
//! ```text
//! operator: belt b, offset o ──┐            each tick: belt travel += b·dt
//!                              ▼
//! impact k: step length d_k (leg kinematics), duration T_k ─▶ v_k = d_k / T_k,
//!           stride speed v̄_k over the last two steps
//!           position on the belt p += d_k − belt travel over the step
//!           v_cmd = clamp(b + o − k_p·p, library range)          (belt-position loop)
//!           e_k = v_cmd,k−1 − v̄_k;  I = clamp(I + k_i·e_k, ±I_max)  (step-to-step integral)
//!           σ = clamp(u + c·(v_cmd − u) + k_s·e_k + I, library range),  u = b + o
//!                                                                 (the gait's speed)
//!           Δℓ = clamp(k_ℓ·(v_k − v_cmd), ±Δℓ_max)               (the step lever)
//!           next step = library interpolated at σ ─▶ Bézier α, θ⁺, θ⁻, T, feed-forward,
//!                       braking step; landing Δℓ longer than its gait's step
//! ```
//!
//! # Interpolation, and the post-impact state
//! The library's gaits are sorted by their planned speed; the gait at σ blends its two
//! neighbours linearly (weight w = (σ − v_i)/(v_{i+1} − v_i)): Bézier coefficients, θ⁺ and θ⁻,
//! step duration, the feed-forward torques (the right neighbour's table is sampled at the left
//! one's phases), the braking step's offsets and the step lever's slopes. The blend is written
//! into the controller's one active [`GaitTable`] at the impact: fixed arrays, no allocation,
//! never mid-step.
//!
//! A new gait's outputs at the start of the step are not the old gait's, so switching the
//! references at the impact would jump them. The controller keeps them continuous instead: the
//! offset between the old gait's references and the new gait's at the post-impact state
//! (including the old step's lever offset, relabeled to the new stance leg) is carried into
//! the new step and blended out (minimum jerk) over its first 30 % of phase (20 % for the
//! swing knee) — the same blend that takes the first step after a launch into the gait. The
//! phase itself is measured with the new gait's θ⁺ and θ⁻; the phase observer keeps its rate of
//! stance-leg angle (τ̇ rescaled by the ratio of the two gaits' θ spans).
//!
//! # The step lever (event-based, on the Poincaré section)
//! The library speed σ alone does not set the walked speed (below: it nudges a slow mode), so
//! each step also gets a lever on its own energy: the length of its step. A longer step loses
//! more speed in its impact (the braking step of a Stop uses the same). At each impact the
//! regulator sets Δℓ = k_ℓ·(v_k − v_cmd) (the last step's speed, not the stride's: averaged
//! over two steps the lever came a step late, overshot and stalled walks at 0.20 m/s), and the
//! next step's touchdown pose becomes the gait's y^d(1) + Δℓ·∂y/∂ℓ with its stance-leg angle at
//! θ⁻ + Δℓ·∂θ/∂ℓ; the offset blends in (minimum jerk) from 30 % of the step, as the braking
//! step's does. The slopes ∂y/∂ℓ, ∂θ/∂ℓ are central differences (±2 cm) of the braking step's
//! touchdown family ([`braking_touchdown`]: both feet down, the torso at the gait's pitch and
//! at the same fraction of the way between the feet), computed for each library gait when the
//! library is loaded and interpolated with it.
//!
//! # The law's gains
//! One update per step: σ moves at most `max_change_per_step_mps` (0.02 m/s) per step; the
//! shipped gains are k_s = 0.5, k_i = 0.1 per step (the integral removes the planned-vs-walked
//! bias of the library, up to I_max = 0.1 m/s), k_p = 0.3 /s, c = 1 (`command_share`: σ starts
//! from the position loop's command v_cmd), k_ℓ = 0.1 s (1 cm longer step per 0.1 m/s too
//! fast), Δℓ_max = 0.04 m.
//!
//! Two laws were measured (2026-12-05, seeds 1–5). **A** (shipped): c = 1, k_s = 0.5,
//! k_i = 0.1 — the law before the lever, plus the lever. **B**: c = 0, k_s = 0, k_i = 0.2 (σ
//! follows the operator's speed, the position acts through the integral and the lever only).
//! On the shipped library (`adam bench treadmill`) B is better at the slow end: 0.15 m/s 0/5
//! stalls (A: 4/5), 0.20 m/s 1/5 (A: 2/5), max |position| after 10 s 0.309 / 0.300 / 0.260 /
//! 0.129 / 0.110 m at 0.15–0.35 m/s (A: 0.477 / 0.490 / 0.208 / 0.111 / 0.105 m). But on the
//! test library (`runtime/tests/fixtures/library/`) B breaks what A (and the law before the
//! lever) holds: Walk from Stand onto a belt at 0.25 m/s trips the step timeout in 4 seeds of
//! 5 (the launch leaves the robot 0.72 m behind the centre; with σ held at the belt's speed
//! the steps after the launch, walked faster than the orbit, pull σ down through the integral
//! and the walk stalls within 2 s — also with k_ℓ = 0, so not the lever; holding the error and
//! the lever for the first 2–5 steps of a walk did not save it either), the 0.25 m/s belt
//! strays 0.188 m (A: 0.147 m), and +7.5 N pushes at 90 % of the step ride through in 3 of 5.
//! In between, c = 0.5 (k_s 0.5, k_i 0.1): 0.15 m/s 5/5 stalls on the shipped library; c = 0
//! with k_s 0.5, k_i 0.1: 4/5; c = 1 with k_s 0, k_i 0.2: 2/5 at 0.15 m/s, 1/5 at 0.20 m/s
//! (0.64 m astray), the belt step 5 of 5 without a trip but 11–26 steps to match going up. So
//! k_s > 0 with c < 1 stalls the shipped library's slowest gait, and c = 1 is what the launch
//! needs; no one set of gains was found for both libraries (the runs are chaotic: a change of
//! gains moves which seeds stall, one seed at a time).
//!
//! Tried with law B before (worst |position| after 10 s): k_ℓ 0.2 → 0.15 and 0.20 m/s stall in
//! most seeds; k_ℓ 0.05 → 0.30 m at 0.25 m/s; k_ℓ 0.15 → 3 stalls of 5 at 0.15 m/s (but the
//! belt step 5 of 5); k_i 0.3 → 0.30 m at 0.20 m/s; k_p 0.5 → 0.43 m at 0.25 m/s; an integral
//! on Δℓ (0.02–0.05 m per m/s and step) → steady long steps that stall at 0.25–0.30 m/s; a
//! lever on the position (Δℓ += 0.03–0.1 m per m of position) → stalls at 0.15–0.25 m/s; the
//! integral's excess beyond the library's slowest gait turned into Δℓ → the belt step stalled
//! going down in 5 of 5. With law A on the test library: k_ℓ 0.05 → the belt step
//! 0.20 → 0.30 → 0.20 m/s stalls in seed 2 of 3; Δℓ_max 0.02 m → seed 1 of 3.
//!
//! # Why the library speed does not set the walked speed (measured, 2026-12-05)
//! Each library gait walked alone (no speed control, an endless belt at its speed, seed 1,
//! 30 s, mean speed over 5 s windows) walks its planned step length to 1 mm and a shorter
//! step duration: the 0.25 m/s gait 0.186–0.187 m steps (0.186 planned) in 0.59–0.63 s after
//! its first 5 s (0.746 s planned), 0.29–0.32 m/s; the 0.30 m/s gait 0.200 m in 0.57 s (0.666 s), 0.33–0.35 m/s; the
//! 0.20 m/s gait speeds up from 0.19 to 0.23–0.24 m/s over 30 s. What changes it, each alone:
//! - without IMU noise: the same (0.25 m/s gait 0.28–0.32 m/s): not the pitch estimate;
//! - PD gains 300/6 instead of 150/3: 0.26–0.30 m/s, and the 0.20 m/s gait 0.22–0.25 m/s;
//! - without the plan's feed-forward: every gait stalls within 5 s (the feed-forward is
//!   needed, its weight 1 is not the cause);
//! - the reference lead (`walk.reference_lead_s`, latency compensation): 0 ms → 0.27–0.32 m/s;
//!   0.5 ms (shipped) → 0.26–0.32; 2 ms → 0.22–0.26 m/s for the 0.25 m/s gait, 0.30–0.34 for
//!   the 0.30 m/s gait, but the 0.20 m/s gait then walks 0.17–0.19 and the 0.225 m/s gait
//!   0.19–0.22 m/s.
//!
//! So the walked orbit differs from the planned one in its timing, and the lever that moves
//! it most is the tracking lag of the swing (the PD and the bus latency, which the lead
//! compensates): the planner's rigid model tracks its outputs exactly, the simulated A1s lag
//! them by milliseconds, and the lag shortens the steps' duration more the faster the gait.
//! No single lead fits the library (2 ms is right at 0.25 m/s and 8–9 % slow at
//! 0.20–0.225 m/s); the lead stays at 0.5 ms (the default gait's, and the replay fixtures'),
//! and the integral takes up the bias. Not a defect of the simulator found: step lengths are
//! as planned.
//!
//! # Where it stands (2026-12-05, seeds 1–5, `adam bench treadmill`, law A)
//! 0.25–0.35 m/s: no fall, no trip, within 0.2 % of the belt's speed, max |position| after
//! 10 s 0.208 / 0.111 / 0.105 m. 0.15 m/s: 4 of 5 stall (step timeout); 0.20 m/s: 2 of 5, the
//! robot strays up to 0.49 m (law B: see above). The belt step 0.20 → 0.30 → 0.20 m/s rides
//! through in 4 seeds of 5, matching the belt in 9–28 steps going up and 4–25 going down,
//! |position| up to 0.63 m. Backward pushes of −20 N at 10, 30 and 90 % of the step stall the
//! step under way (0 of 5; 4 of 5 at 50 %, 5 of 5 at 70 %), which no per-step lever reaches: it
//! acts at the next impact. +40 N rides through at every point but one seed at 90 %.
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
    /// Each gait's step-length lever ([`StepLever::of`]).
    pub(super) levers: Box<[StepLever]>,
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
        let mut levers = Vec::with_capacity(gaits.len());
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
            let lever = StepLever::of(geometry, &table, g.step_length_m).ok_or_else(|| {
                bad(
                    k,
                    "step_length_m",
                    g.step_length_m.to_string(),
                    format!(
                        "a touchdown {STEP_LEVER_PROBE_M} m longer or shorter is out of the legs' reach"
                    ),
                )
            })?;
            speeds.push(g.speed_mps);
            tables.push(table);
            lunges.push(lunge);
            levers.push(lever);
        }
        Ok(Some(Self {
            speeds_mps: speeds.into_boxed_slice(),
            tables: tables.into_boxed_slice(),
            lunges: lunges.into_boxed_slice(),
            levers: levers.into_boxed_slice(),
        }))
    }

    /// Slowest and fastest speed, m/s.
    pub(super) fn range_mps(&self) -> (f64, f64) {
        let n = self.speeds_mps.len();
        (self.speeds_mps[0], self.speeds_mps[n - 1])
    }

    /// Writes the gait of speed `speed_mps` (clamped to the range) into `gait`, its braking
    /// step into `lunge` and its step-length lever into `lever` (keeping `lever.offset_m`):
    /// linear interpolation between the two neighbours. Allocation-free.
    pub(super) fn blend_into(
        &self,
        speed_mps: f64,
        gait: &mut GaitTable,
        lunge: &mut Lunge,
        lever: &mut StepLever,
    ) {
        let b = model::library::bracket(&self.speeds_mps, speed_mps);
        let (i, j, w) = (b.lower, b.upper, b.weight);
        lerp_table(&self.tables[i], &self.tables[j], w, gait);
        let (la, lb) = (&self.lunges[i], &self.lunges[j]);
        for k in 0..OUTPUTS {
            lunge.dy_end[k] = lerp(la.dy_end[k], lb.dy_end[k], w);
        }
        lunge.theta_rad = lerp(la.theta_rad, lb.theta_rad, w);
        let (va, vb) = (&self.levers[i], &self.levers[j]);
        for k in 0..OUTPUTS {
            lever.dy_end_per_m[k] = lerp(va.dy_end_per_m[k], vb.dy_end_per_m[k], w);
        }
        lever.theta_per_m = lerp(va.theta_per_m, vb.theta_per_m, w);
    }
}

/// A step of the lever follows the gait up to this phase, then blends into its longer or
/// shorter touchdown pose (as the braking step does).
pub(super) const LEVER_BLEND_FROM: f64 = 0.3;

/// Half the span of the step lengths the lever's slopes are measured over, m.
pub(super) const STEP_LEVER_PROBE_M: f64 = 0.02;

/// The step-length lever: how a step's touchdown pose changes with its length, and this step's
/// length offset. A step `offset_m` longer than the gait's ends with the outputs at
/// y^d(1) + offset·`dy_end_per_m` and the stance leg at θ⁻ + offset·`theta_per_m`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct StepLever {
    /// Touchdown offset of each output per metre of extra step length, rad/m.
    pub(super) dy_end_per_m: [f64; OUTPUTS],
    /// Stance-leg angle at touchdown per metre of extra step length, rad/m.
    pub(super) theta_per_m: f64,
    /// This step's length offset, m (0: the gait's own step).
    pub(super) offset_m: f64,
}

impl StepLever {
    /// The slopes of `gait`, whose planned step is `length_m`: central differences of the
    /// touchdown pose of [`braking_touchdown`] (both feet down, the torso at the same fraction
    /// of the way between them and as far from them) at `length_m` ± [`STEP_LEVER_PROBE_M`].
    /// `None` if either pose is out of reach.
    pub(super) fn of(geometry: &Geometry, gait: &GaitTable, length_m: f64) -> Option<Self> {
        let h = STEP_LEVER_PROBE_M;
        let long = braking_touchdown(geometry, gait, length_m + h)?;
        let short = braking_touchdown(geometry, gait, length_m - h)?;
        let mut dy_end_per_m = [0.0; OUTPUTS];
        for (k, d) in dy_end_per_m.iter_mut().enumerate() {
            *d = (long.dy_end[k] - short.dy_end[k]) / (2.0 * h);
        }
        let lever = Self {
            dy_end_per_m,
            theta_per_m: (long.theta_rad - short.theta_rad) / (2.0 * h),
            offset_m: 0.0,
        };
        let finite =
            lever.dy_end_per_m.iter().all(|d| d.is_finite()) && lever.theta_per_m.is_finite();
        finite.then_some(lever)
    }

    /// Offset of output `i` at this step's touchdown, rad.
    pub(super) fn dy_end(&self, i: usize) -> f64 {
        self.offset_m * self.dy_end_per_m[i]
    }

    /// Offset of the stance-leg angle at this step's touchdown, rad.
    pub(super) fn theta_offset_rad(&self) -> f64 {
        self.offset_m * self.theta_per_m
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
    step_length_gain_s: f64,
    max_step_offset_m: f64,
    command_share: f64,
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
            step_length_gain_s: config.step_length_gain_s,
            max_step_offset_m: config.max_step_offset_m,
            command_share: config.command_share,
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
        s.step_offset_m = 0.0;
        s.step_speed_mps = f64::NAN;
        s.commanded_mps = f64::NAN;
    }

    /// The step that just ended at an impact: `length_m` over `duration_s`. Updates the
    /// position, the commanded speed, the integral and the next step's length offset
    /// (`status.step_offset_m`), and returns the library speed σ of the next step (clamped to
    /// `range_mps`).
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
        // The library gait starts from the operator's speed (belt + offset) and takes the
        // share `command_share` of the position loop's correction (1: the command itself; 0:
        // the position acts through the integral and the step lever only; module docs).
        let base = (s.belt_mps + s.offset_mps).clamp(lo, hi);
        let sigma = base
            + self.command_share * (s.commanded_mps - base)
            + self.speed_gain * error
            + integral;
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
        // The step lever: a step faster than the command lands the next step longer (more
        // speed lost in its impact), a slower one shorter. The last step's speed, not the
        // stride's: averaged over two steps the lever came a step late and overshot (stalls).
        let m = self.max_step_offset_m;
        s.step_offset_m = if measured && s.commanded_mps.is_finite() {
            (self.step_length_gain_s * (s.step_speed_mps - s.commanded_mps)).clamp(-m, m)
        } else {
            0.0
        };
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
        let config = SpeedConfig::default();
        let mut r = regulator();
        for k in 0..=800 {
            r.advance(k as f64 * 1e-3);
        }
        // 0.8 s of belt at 0.25 m/s is 0.2 m; a 0.24 m step puts the robot 4 cm forward.
        let sigma = r.on_impact(0.24, 0.8, (0.15, 0.35));
        assert!((r.status.position_m - 0.04).abs() < 1e-9);
        // Forward of the centre: the command is below the belt speed by k_p·p ...
        let command = 0.25 - config.position_gain_per_s * 0.04;
        assert!((r.status.commanded_mps - command).abs() < 1e-9);
        // ... the library gait follows the command (no stride measured against a command yet,
        // so no error, no integral) ...
        assert!((sigma - command).abs() < 1e-12, "σ = {sigma}");
        // ... and the step was faster than the command: the next one lands longer.
        let offset = config.step_length_gain_s * (0.3 - command);
        assert!(offset > 0.0);
        assert!((r.status.step_offset_m - offset).abs() < 1e-12);
    }

    #[test]
    fn with_no_command_share_the_library_gait_follows_the_operator_not_the_position() {
        let config = SpeedConfig {
            command_share: 0.0,
            ..SpeedConfig::default()
        };
        let mut r = SpeedRegulator::new(&config, 0.25);
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }));
        r.belt_travel_m = 0.2;
        // 4 cm forward of the centre: the command drops, the library gait stays the belt's.
        let sigma = r.on_impact(0.24, 0.8, (0.15, 0.35));
        assert!(r.status.commanded_mps < 0.25 - 0.01);
        assert!((sigma - 0.25).abs() < 1e-12, "σ = {sigma}");
        // Half the share: half-way.
        let half = SpeedConfig {
            command_share: 0.5,
            ..SpeedConfig::default()
        };
        let mut r = SpeedRegulator::new(&half, 0.25);
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }));
        r.belt_travel_m = 0.2;
        let sigma = r.on_impact(0.24, 0.8, (0.15, 0.35));
        let expected = 0.25 + 0.5 * (r.status.commanded_mps - 0.25);
        assert!((sigma - expected).abs() < 1e-12, "σ = {sigma}");
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
    fn a_fast_step_lands_the_next_step_longer_a_slow_one_shorter_within_the_limit() {
        let config = SpeedConfig::default();
        let mut r = regulator();
        // Without a step measured: the gait's own step.
        r.on_impact(f64::NAN, 0.0, (0.15, 0.35));
        assert_eq!(r.status.step_offset_m, 0.0);
        // A step at 0.28 m/s on a 0.25 m/s belt, the robot at the centre: 0.03 m/s fast.
        r.status.position_m = 0.0;
        r.belt_travel_m = 0.224;
        r.on_impact(0.224, 0.8, (0.15, 0.35));
        assert_eq!(r.status.commanded_mps, 0.25);
        let expected = config.step_length_gain_s * 0.03;
        assert!(expected > 0.0 && expected < config.max_step_offset_m);
        assert!(
            (r.status.step_offset_m - expected).abs() < 1e-9,
            "{:?}",
            r.status
        );
        // A very slow step: a shorter one, at most the limit.
        r.on_impact(0.01, 2.0, (0.15, 0.35));
        let unclamped = config.step_length_gain_s * (0.005 - r.status.commanded_mps);
        assert_eq!(
            r.status.step_offset_m,
            unclamped.max(-config.max_step_offset_m)
        );
        assert!(r.status.step_offset_m < 0.0);
        // A restart forgets it.
        r.restart();
        assert_eq!(r.status.step_offset_m, 0.0);
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
