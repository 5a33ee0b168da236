//! The orbit lever: a within-step feedback on the zero dynamics' energy that pulls the walk back
//! onto the planned orbit (HZD zero-dynamics energy feedback).
//!
//! # The zero dynamics, and the planned σ*(τ)
//! With a point foot, single support has one unactuated degree of freedom. Once the outputs
//! track y^d(τ), the state is (θ, σ): θ the stance-leg angle (the phase τ = (θ − θ⁺)/(θ⁻ − θ⁺))
//! and σ the angular momentum about the stance foot (`model::dynamics`,
//! `angular_momentum_about`, + forward). Only gravity's moment changes σ:
//! σ̇ = M·g·(x_c − x_f), the centre of mass x_c ahead of the foot x_f. On the outputs' manifold
//! every velocity is q̇ = (∂q/∂τ)·τ̇, so σ = κ(τ)·τ̇ with κ a function of the pose alone, and
//! ```text
//! d(σ²/2)/dτ = σ·σ̇/τ̇ = κ(τ)·M·g·(x_c(τ) − x_f)
//! σ*(τ)²     = σ*(0)² + 2·M·g·∫₀^τ κ(s)·(x_c(s) − x_f) ds
//! ```
//! σ*(0) is the momentum of the gait's planned post-impact state (`initial_state`). The table
//! is computed once at load ([`OrbitTable::of`]) on [`ORBIT_SAMPLES`] phases, with the launch
//! table's manifold point (`orbit_table`: the momentum per unit θ̇ on the outputs' manifold,
//! exact, the stance foot pinned) times dθ/dτ, so the launch and the lever share one σ*(θ)
//! integrand; the two tables differ only in where σ* starts (here the planned post-impact
//! state, there the σ⁺ that gives the planned duration). Each library gait gets its table; at an impact the
//! table of the speed the next step walks is the two neighbours' blend, as the gait's own tables
//! ([`OrbitLever::select`]). The planned duration ∫₀¹ κ/σ* dτ equals the gait's step duration
//! to the plan's accuracy (a unit test).
//!
//! # The law
//! Each tick in Walk (single support, not the braking step of a Stop), from the estimated torso
//! pitch and rate and the measured joint angles and rates, with the stance foot pinned:
//! ```text
//! ê  += (1 − e^(−2π·f·dt))·(σ*(τ) − σ − ê)      the error low-passed at f (0 on a new stance foot)
//! e   = ê / (M·L)                               velocity error of the orbit, m/s (L = thigh + shin)
//! δ*  = clamp(k·e, ±δ_max) · w(τ)               lean, rad; w = 1 up to τ_f, then a minimum-jerk
//!                                               fade to 0 at τ = 1 (the impact pose is the gait's)
//! δ   = δ_prev + clamp(δ* − δ_prev, ±δ̇_max·dt)   rate-limited
//! y^d₀ += s·δ, y^d₂ += s·δ;  ẏ^d₀, ẏ^d₂ += s·δ̇    stance hip and swing hip together
//! ```
//! The stance hip turns the torso about the hip (the stance leg, pinned, does not move), and the
//! swing hip turns by the same angle so the swing thigh's absolute angle, and the swing foot, are
//! unchanged (a unit test: the feet's relative position does not move). s = ±1 is the sign that
//! moves the centre of mass forward, found on the model at load. A robot slower than its orbit
//! (σ < σ*) leans forward: gravity's moment grows and σ catches up within the step; a fast one
//! leans back. The lean does not move θ (the stance leg's angle), so the phase is unchanged.
//!
//! The lean's rate is not fed to ẏ^d (only the offset of y^d): it is the derivative of a filtered
//! noisy error, and through the hips' damping (3 N·m·s/rad) it chattered them at ±1.5 rad/s
//! until the accelerometer saw false impacts (measured).
//!
//! # Gains
//! The config's `[orbit]` section ([`crate::config::OrbitConfig`]): k = `gain_rad_per_mps`,
//! δ_max = `max_lean_rad`, δ̇_max = `max_lean_rate_rad_s`, τ_f = `fade_from_phase`, f =
//! `sigma_filter_hz`. Shipped: k = 0.1 rad/(m/s), δ_max = 0.15 rad, δ̇_max = 0.5 rad/s,
//! τ_f = 0.8, f = 5 Hz. M·L = 11.4 kg·m for ADAM, so k = 0.1 leans 0.009 rad per kg·m²/s of
//! momentum error (σ* runs 1.47–3.81 kg·m²/s over the shipped gait's step).
//!
//! **Off as shipped** (`enabled = false`, measured 2026-12-05 after the merge): with the lever on,
//! `tests/faults.rs`'s `delay-1` (1 % of motor replies 2 ms late, so missing for a tick, their
//! last values held) ends the walk in a step timeout after 6 steps of 0.05 m mean length, with 2
//! repeated touchdowns; without it the same run rides through. Not yet traced; the lever's
//! sensitivity to a held sample (or a false touchdown it provokes) is the first suspect.
//!
//! # What it does (measured 2026-12-05, seeds 1–5)
//! - The shipped gait from its planned state (`adam run --backend sim --seed s`, 30 s): without
//!   the lever its steps take 0.924–0.970 s (planned 0.900 s) and it drifts −0.11 … −0.35 m on
//!   the belt; with it (k = 0.1, δ̇_max = 1.5 rad/s) 0.905–0.929 s and −0.14 … +0.005 m, as
//!   shipped (δ̇_max = 0.5 rad/s) 0.901–0.928 s and −0.134 … +0.028 m; k = 0.15: 0.898–0.918 s,
//!   −0.10 … +0.04 m; k = 0.2: 0.895–0.908 s, −0.02 … +0.05 m.
//! - The re-planned gait (`runtime/tests/fixtures/adam_codesign_graded.json`) from Stand onto a
//!   belt at 0.25 m/s (`runtime/tests/restart_sim.rs`, `the_replanned_gait_walks_on_from_stand`):
//!   without the lever 2 of 5 walk on (seeds 3–5 stall on the return from the launch's fast
//!   transient); k = 0.1 and 0.15: 5 of 5; k = 0.2: 4 of 5; k = 0.3: 0 of 5; k = 0.8: 5 of 5
//!   but on another, twice as fast orbit. Its restart after a Stop (0.20 m braking step): 5 of 5
//!   up to k = 0.15, 3 of 5 at k = 0.2 and 0.3. The shipped gait's walk from Stand
//!   (`runtime/tests/stand_sim.rs`) stays on the fast transient (last step 0.58 s) at k = 0.15,
//!   converges at k = 0.1; fading from τ_f = 0.5 or 0.6 fails it at both gains. Hence k = 0.1.
//!   `runtime/tests/stop_sim.rs` (Stop at 3.0 s) then still rocked 2.2 s after Stand (kinetic
//!   energy 4.5e-4 J, limit 1e-4 J) with δ̇_max = 1.5 rad/s (1.7e-4 J with τ_f = 0.7, 1.4e-4 J with
//!   0.9); δ̇_max = 0.5 rad/s: 1.5e-5 J, and the walks above unchanged. k = 0.08 or 0.12 fail
//!   the re-plan's restart or walk from Stand. These are knife edges: the runs are chaotic.
//! - With the treadmill speed control switching library gaits (`adam bench treadmill` with the
//!   shipped library) the lever made things worse at every gain tried, so it is off there
//!   (`with_speed_control = false`). Against the lever off (the README's table: 0.15 m/s 4/5
//!   stall, 0.20 m/s 2/5, belt step 4/5 ride through, −20 N at 10/30/90 % 0/5): k = 0.2 (fade
//!   0.7, the rate fed to ẏ^d off) 0.20 m/s 4/5 stall, belt step 2/5; k = 0.1: 0.20 m/s 3/5,
//!   belt step 2/5, −20 N unchanged (0/5 at 10/30/90 %); k = 0.3: 0.25 m/s 5/5 off the front of
//!   the belt. The library gaits walk 15–20 % faster than planned (`runtime::control::speed`),
//!   so the lever pulls against the regulator's integral, which was tuned to that bias.
//! - Each library gait alone (no speed control, `cargo run --release -p runtime --example
//!   impact_probe -- CONFIG GAIT v 60 1` with `enabled = true`, mean over 30–60 s, seed 1):
//!   the lever makes every gait faster, not slower: the 0.225 m/s gait walks 133 % of its plan
//!   at k = 0.1 and 143 % at k = 0.3 (125.6 % without the lever), 0.30 m/s 117.8 / 121.8 %
//!   (115.3 %). Why the gaits walk fast at all: `runtime::control::speed`, "Where the extra
//!   energy comes from".
//! - Why the gain stays small: k = 0.4–0.8 on the shipped gait falls within 3–13 s (steps
//!   shortening to 0.01–0.1 m). Two mechanisms seen in the logs: the lean is an internal motion,
//!   so it does not change σ about the stance foot, but it moves the centre of mass and so the
//!   linear momentum at the impact, and with it σ about the *next* foot (a lean fading out
//!   before the impact pumps or drains the next step); and turning the heavy torso turns the
//!   legs the other way (σ is conserved), so a forward lean first slows θ. Carrying the lean
//!   through the impact (no fade: the lean is symmetric in the legs, so the relabeled references
//!   stay continuous) was worse (k = 0.8 falls in 4–7 s). A −20 N push for 0.2 s takes
//!   ≈ 2.4 kg·m²/s, most of σ; recovering it within the step needs a lean of ≈ 0.2 rad, twenty
//!   times what k = 0.1 gives: the pushes and the slow belts are not fixed by this lever.
//!
//! Nothing here allocates after construction: the tables are fixed arrays, the tick's kinematics
//! runs on stack arrays.

use super::double_support::Geometry;
use super::gait_table::{side_index, GaitTable};
use crate::config::OrbitConfig;
use crate::slots::OUTPUTS;
use crate::{Result, RuntimeError};
use model::gait::GaitFile;
use model::robot::MAX_DOF;
use model::Side;

/// After an impact the error filter holds this long, s: the impact's ticks (the motors'
/// replies lag it by a tick, the joint rates jump) measure neither foot's momentum.
const IMPACT_HOLD_S: f64 = 0.01;

/// Phases of the σ*(τ) table (τ_k = k/(N − 1)).
pub(super) const ORBIT_SAMPLES: usize = 65;

/// The planned orbit's momentum about the stance foot against the phase.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct OrbitTable {
    /// σ*(τ_k), kg·m²/s.
    pub(super) sigma: [f64; ORBIT_SAMPLES],
    /// κ(τ_k) = ∂σ/∂τ̇ on the outputs' manifold, kg·m².
    pub(super) kappa: [f64; ORBIT_SAMPLES],
}

/// The pose on the gait's outputs at phase `tau` for `stance`, the hips offset by `lean_rad`
/// (times the outputs' `lean` pattern): joints at y^d(τ), pitch such that the stance leg is at
/// θ(τ). `None` if Newton does not converge.
pub(super) fn pose_at(
    g: &Geometry,
    table: &GaitTable,
    stance: Side,
    tau: f64,
    lean_rad: f64,
) -> Option<[f64; MAX_DOF]> {
    let mut q = *g.q_template;
    q[0] = 0.0;
    q[1] = 0.0;
    let s = side_index(stance);
    for i in 0..OUTPUTS {
        q[g.leg_coord[table.out_slot[s][i]]] = table.eval(i, tau).0 + LEAN[i] * lean_rad;
    }
    let target = table.theta_plus_rad + tau * (table.theta_minus_rad - table.theta_plus_rad);
    let theta = |q: &[f64; MAX_DOF]| g.model.stance_leg_angle(&q[..g.dof], g.legs, stance).ok();
    let mut pitch = table.initial_pitch.map_or(0.0, |(p, _)| p);
    for _ in 0..6 {
        q[2] = pitch;
        let th = theta(&q)?;
        q[2] = pitch + 1e-6;
        let slope = (theta(&q)? - th) / 1e-6;
        if slope.abs().partial_cmp(&0.1) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        pitch -= (th - target) / slope;
    }
    q[2] = pitch;
    let err = theta(&q)? - target;
    (err.abs() < 1e-9).then_some(q)
}

/// Which outputs the lean moves: the stance hip and the swing hip, by the same angle.
pub(super) const LEAN: [f64; OUTPUTS] = [1.0, 0.0, 1.0, 0.0];

/// Leans the torso of the outputs `y` by `lean_rad`: both hips offset by `sign`·`lean_rad`
/// ([`LEAN`]; `sign` from [`lean_sign`]: + moves the centre of mass forward), the knees and
/// the feet unmoved. The orbit lever's lean and the step lean (`speed`) both lean this way.
pub(super) fn add_lean(y: &mut [f64; OUTPUTS], sign: f64, lean_rad: f64) {
    for (y, l) in y.iter_mut().zip(LEAN) {
        *y += sign * l * lean_rad;
    }
}

impl OrbitTable {
    /// The planned orbit of `gait` (its `table`): σ*(τ) from its post-impact state through the
    /// zero dynamics. Errors say why (no initial state, a pose off the legs, an orbit that does
    /// not pass over the stance foot).
    pub(super) fn of(g: &Geometry, table: &GaitTable, gait: &GaitFile) -> Result<Self> {
        let bad = |reason: String| RuntimeError::Gait {
            reason: format!("orbit lever: {reason}"),
        };
        let stance = table.first_stance;
        let init = gait
            .initial_state
            .as_ref()
            .ok_or_else(|| bad("the gait has no initial_state to start σ* from".into()))?;
        if init.q.len() != g.dof || init.dq.len() != g.dof {
            return Err(bad(format!(
                "initial_state has {} / {} coordinates, the robot {}",
                init.q.len(),
                init.dq.len(),
                g.dof
            )));
        }
        let mut q0 = [0.0; MAX_DOF];
        let mut dq0 = [0.0; MAX_DOF];
        q0[..g.dof].copy_from_slice(&init.q);
        dq0[..g.dof].copy_from_slice(&init.dq);
        let (sigma0, _) = g
            .pinned_momentum(stance, &q0, &dq0)
            .ok_or_else(|| bad("the initial state's kinematics failed".into()))?;
        let mass_g = g.model.total_mass_kg() * g.model.gravity_mps2;
        let mut kappa = [0.0; ORBIT_SAMPLES];
        let mut com = [0.0; ORBIT_SAMPLES];
        for k in 0..ORBIT_SAMPLES {
            let tau = k as f64 / (ORBIT_SAMPLES - 1) as f64;
            let (kp, x) = manifold_point(g, table, tau)
                .ok_or_else(|| bad(format!("no pose on the outputs at τ = {tau:.3}")))?;
            kappa[k] = kp;
            com[k] = x;
        }
        let mut sigma = [0.0; ORBIT_SAMPLES];
        let mut s2 = sigma0 * sigma0;
        sigma[0] = sigma0;
        let h = 1.0 / (ORBIT_SAMPLES - 1) as f64;
        for k in 1..ORBIT_SAMPLES {
            s2 += mass_g * h * (kappa[k - 1] * com[k - 1] + kappa[k] * com[k]);
            if s2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || sigma0 <= 0.0 {
                return Err(bad(format!(
                    "the planned orbit stops at τ = {:.3} (σ*² = {s2:.3e})",
                    k as f64 * h
                )));
            }
            sigma[k] = s2.sqrt();
        }
        Ok(Self { sigma, kappa })
    }

    /// σ*(τ), kg·m²/s (τ clamped to [0, 1]; linear between samples).
    pub(super) fn sigma_at(&self, tau: f64) -> f64 {
        let x = tau.clamp(0.0, 1.0) * (ORBIT_SAMPLES - 1) as f64;
        let k = (x.floor() as usize).min(ORBIT_SAMPLES - 2);
        let w = x - k as f64;
        self.sigma[k] + w * (self.sigma[k + 1] - self.sigma[k])
    }

    /// The step's duration on the planned orbit, ∫₀¹ κ/σ* dτ, s (trapezoid).
    #[cfg(test)]
    pub(super) fn duration_s(&self) -> f64 {
        let h = 1.0 / (ORBIT_SAMPLES - 1) as f64;
        (1..ORBIT_SAMPLES)
            .map(|k| {
                0.5 * h * (self.kappa[k - 1] / self.sigma[k - 1] + self.kappa[k] / self.sigma[k])
            })
            .sum()
    }

    fn lerp(a: &Self, b: &Self, w: f64, out: &mut Self) {
        for k in 0..ORBIT_SAMPLES {
            out.sigma[k] = a.sigma[k] + w * (b.sigma[k] - a.sigma[k]);
            out.kappa[k] = a.kappa[k] + w * (b.kappa[k] - a.kappa[k]);
        }
    }
}

/// κ(τ) = ∂σ/∂τ̇ and x_c − x_f at phase `tau` on the outputs' manifold (of `table`'s first
/// stance leg): the launch table's exact I(θ) (`orbit_table`) times dθ/dτ = θ⁻ − θ⁺.
fn manifold_point(g: &Geometry, table: &GaitTable, tau: f64) -> Option<(f64, f64)> {
    let span = table.theta_minus_rad - table.theta_plus_rad;
    let (inertia, com_ahead_m) =
        super::orbit_table::manifold_point(g, table, table.theta_plus_rad + tau * span)?;
    Some((inertia * span, com_ahead_m))
}

/// The orbit lever's state and gains: the active σ* table (a library's blended at impacts), the
/// lean and its rate.
#[derive(Clone, Debug)]
pub(super) struct OrbitLever {
    gain_rad_per_mps: f64,
    max_lean_rad: f64,
    max_lean_rate_rad_s: f64,
    fade_from_phase: f64,
    sigma_filter_hz: f64,
    /// Whether the lever acts while speed control switches library gaits.
    pub(super) with_speed_control: bool,
    /// The filtered error σ* − σ, kg·m²/s (NaN: restart at the next tick), and the stance
    /// foot it is about.
    pub(super) error_hat: f64,
    stance: Option<Side>,
    /// The filter holds its error until then, s (after an impact).
    hold_until_s: f64,
    /// Velocity scale M·L, kg·m.
    momentum_per_mps: f64,
    /// +1 or −1: the hip offset that moves the centre of mass forward.
    pub(super) sign: f64,
    /// The table of the gait walked now.
    pub(super) table: Option<OrbitTable>,
    /// The library's speeds and tables (empty: none).
    speeds_mps: Box<[f64]>,
    tables: Box<[OrbitTable]>,
    /// The lean of the last tick, rad, and its rate, rad/s.
    pub(super) lean_rad: f64,
    pub(super) lean_rate_rad_s: f64,
    last_t_s: Option<f64>,
}

impl OrbitLever {
    /// The lever of `gait` (and each of `library`, sorted by speed) with the gains of `config`.
    /// Off (`table` `None`) when `config.enabled` is false. Allocates; call at start-up.
    pub(super) fn new(
        config: &OrbitConfig,
        g: &Geometry,
        gait: (&GaitFile, &GaitTable),
        library: &[GaitFile],
    ) -> Result<Self> {
        let mut lever = Self {
            gain_rad_per_mps: config.gain_rad_per_mps,
            max_lean_rad: config.max_lean_rad,
            max_lean_rate_rad_s: config.max_lean_rate_rad_s,
            fade_from_phase: config.fade_from_phase,
            sigma_filter_hz: config.sigma_filter_hz,
            with_speed_control: config.with_speed_control,
            error_hat: f64::NAN,
            stance: None,
            hold_until_s: f64::NEG_INFINITY,
            momentum_per_mps: g.model.total_mass_kg()
                * (gait.0.design.thigh_length_m + gait.0.design.shin_length_m),
            sign: 1.0,
            table: None,
            speeds_mps: Box::new([]),
            tables: Box::new([]),
            lean_rad: 0.0,
            lean_rate_rad_s: 0.0,
            last_t_s: None,
        };
        if !config.enabled {
            return Ok(lever);
        }
        let (file, table) = gait;
        lever.table = Some(OrbitTable::of(g, table, file)?);
        lever.sign = lean_sign(g, table).ok_or_else(|| RuntimeError::Gait {
            reason: "orbit lever: the hips do not move the centre of mass at mid-step".into(),
        })?;
        let mut tables = Vec::with_capacity(library.len());
        for (k, f) in library.iter().enumerate() {
            let entry = |e: RuntimeError| RuntimeError::Gait {
                reason: format!("gait library entries[{k}]: {e}"),
            };
            let t = GaitTable::new(f, g.model, g.legs).map_err(entry)?;
            tables.push(OrbitTable::of(g, &t, f).map_err(entry)?);
        }
        lever.speeds_mps = library.iter().map(|f| f.speed_mps).collect();
        lever.tables = tables.into_boxed_slice();
        Ok(lever)
    }

    /// At an impact that switched the library gait to `speed_mps`: the σ* table of that speed
    /// (the two neighbours' blend, as [`super::speed`] blends the gaits). No allocation.
    pub(super) fn select(&mut self, speed_mps: f64) {
        if self.tables.len() < 2 {
            return;
        }
        let b = model::library::bracket(&self.speeds_mps, speed_mps);
        if let Some(out) = self.table.as_mut() {
            OrbitTable::lerp(&self.tables[b.lower], &self.tables[b.upper], b.weight, out);
        }
    }

    /// The lean of this tick, rad, and its rate, rad/s: toward k·ê/(M·L) while `on`, toward 0
    /// otherwise, rate-limited, faded to 0 at the step's end. ê is the error σ*(τ) − σ of the
    /// measured `sigma` about the foot of `stance`, low-passed at `sigma_filter_hz` (the joint
    /// rates' noise is a third of the signal; σ* itself needs no filter, so ê has no lag on the
    /// orbit); a new stance foot restarts it at 0, and so does a tick off.
    pub(super) fn update(
        &mut self,
        t_s: f64,
        tau: f64,
        sigma: f64,
        stance: Side,
        on: bool,
    ) -> (f64, f64) {
        let dt = self.last_t_s.map_or(0.0, |t0| (t_s - t0).clamp(0.0, 0.1));
        self.last_t_s = Some(t_s);
        let target = match (&self.table, on && tau.is_finite() && sigma.is_finite()) {
            (Some(table), true) => {
                let e = table.sigma_at(tau) - sigma;
                if !self.error_hat.is_finite() {
                    self.error_hat = 0.0;
                }
                if self.stance != Some(stance) {
                    // A new stance foot: the impact's ticks measure neither foot's momentum.
                    self.hold_until_s = t_s + IMPACT_HOLD_S;
                }
                if t_s >= self.hold_until_s {
                    let a = 1.0 - (-2.0 * std::f64::consts::PI * self.sigma_filter_hz * dt).exp();
                    self.error_hat += a * (e - self.error_hat);
                }
                self.stance = Some(stance);
                let e_mps = self.error_hat / self.momentum_per_mps;
                let fade = fade(tau, self.fade_from_phase);
                (self.gain_rad_per_mps * e_mps).clamp(-self.max_lean_rad, self.max_lean_rad) * fade
            }
            _ => {
                self.error_hat = f64::NAN;
                0.0
            }
        };
        let step = self.max_lean_rate_rad_s * dt;
        let change = (target - self.lean_rad).clamp(-step, step);
        self.lean_rad += change;
        self.lean_rate_rad_s = if dt > 0.0 { change / dt } else { 0.0 };
        (self.lean_rad, self.lean_rate_rad_s)
    }

    /// Whether the lever is on (a table loaded).
    pub(super) fn enabled(&self) -> bool {
        self.table.is_some()
    }
}

/// 1 up to `from`, a minimum-jerk fade to 0 at τ = 1, 0 beyond.
fn fade(tau: f64, from: f64) -> f64 {
    if tau <= from || from >= 1.0 {
        return 1.0;
    }
    if tau >= 1.0 || from >= 1.0 {
        return 0.0;
    }
    let u = (tau - from) / (1.0 - from);
    1.0 - u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
}

/// +1 if raising both hips' outputs moves the centre of mass forward at mid-step, −1 if back.
pub(super) fn lean_sign(g: &Geometry, table: &GaitTable) -> Option<f64> {
    let stance = table.first_stance;
    let com_x = |lean: f64| {
        let q = pose_at(g, table, stance, 0.5, lean)?;
        let st = g.model.body_poses(&q[..g.dof]).ok()?;
        let p = g.model.frame_position_in(&st, g.legs.side(stance).foot);
        Some(g.model.center_of_mass(&q[..g.dof]).ok()?[0] - p[0])
    };
    let d = com_x(0.01)? - com_x(-0.01)?;
    (d.abs() > 1e-6).then_some(d.signum())
}

#[cfg(test)]
#[path = "orbit/tests.rs"]
mod tests;
