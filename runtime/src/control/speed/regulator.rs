//! The step-to-step speed regulator, the step lever and the belt-position loop: one update per
//! impact (the law: the parent module's docs).
//!
//! # The start on the plan (`speed.start_on_plan`, measured 2026-12-06, off as shipped)
//! A walk begun in a library gait's own state (the simulator's constant-belt, belt-step and
//! push runs) walks that gait's *plan* at first and creeps to its calibrated speed c(σ) only
//! over tens of steps; with the calibration from the first impact the regulator asks at once
//! for the gait that walks the belt after the creep (σ = c⁻¹(belt): 0.185 at 0.20 m/s), too
//! slow a gait for the first steps, and the robot falls back 0.07–0.22 m. With the option the
//! integral starts at c(σ₀) − σ₀ for the gait σ₀ the walk began on, so the first steps ask
//! for σ₀ itself, and the integral (k_i per step, as always) takes the creep up only as the
//! steps' error shows it. A walk from Stand is unchanged (its launch is not on a plan).
//!
//! `adam bench treadmill --config C --seeds …`, max |position| after 10 s at 0.15 / 0.20 /
//! 0.25 / 0.30 / 0.35 m/s (C: the treadmill config with the step lean and the step length
//! after the impact, the options its comment names):
//! - seeds 1–5: 0.089 / 0.193 / 0.097 / 0.085 / 0.046 m without, 0.451 (seed 5 tripped a knee
//!   limit after a stall relaunch at 6 s) / 0.086 / 0.087 / 0.071 / 0.067 m with it; seeds
//!   6–10: 0.298 (one trip) / 0.102 / 0.088 / 0.056 / 0.043 m without, 0.343 / 0.125 / 0.102 /
//!   0.083 / 0.080 m with it;
//! - the belt step (seeds 1–10): with it no fall (without: seed 6 falls) and |position|
//!   0.068–0.324 m, but down matches in 18 steps (seed 2) and never (seed 9);
//! - with the option alone (no lean) the belts wander more, 0.334 (one fall) / 0.213 / 0.300 /
//!   0.131 / 0.114 m (seeds 1–5): the start is not the only slow transient, the lean damps the
//!   others.
//! - On the 0.15 m/s belt every seed's second step takes 1.12–1.21 s from the 0.15 m/s gait's
//!   planned state, with or without the option (whose integral there is 0.003 m/s): the slow
//!   gait's own start, which one seed in ten does not survive with the lean, with the option
//!   or without it (seeds 11–30: 20 of 20 walk 60 s both ways; the shipped treadmill config
//!   walks seeds 1–30).
//!
//! Tried with it and not kept (seeds 1–10): the slow lean down to 0.12 m/s
//! (`step_lean_from_mps`): 5 of 10 trip at 0.15 m/s; σ limited to 0.01 m/s a step: 0.447 m at
//! 0.25 m/s; the step lever at 0.2 or 0.3 s: trips at every belt below 0.30 m/s; the
//! disturbance settle from 0.07 m/s: the belt step falls (seed 9); a belt slowed by more than
//! 0.05 m/s starting the disturbance settle (the command following the robot down, a
//! prototype): down within 8 steps in 6 of 10 seeds (without it 8): seed 3 falls, seed 4
//! never matches, seeds 2 and 9 take 20 and 25 steps.

use super::super::tick::{OperatorCommand, SpeedStatus};
use crate::config::SpeedConfig;

/// The library speed σ that walks a speed, and back: the walked-speed calibration
/// (`speed.walked_mps`) or, without one, the identity.
pub(in crate::control) trait SpeedMap {
    /// The library speed σ whose gait walks `walked_mps`, m/s.
    fn sigma_for(&self, walked_mps: f64) -> f64;
    /// The speed the gait of library speed `sigma_mps` walks, m/s.
    fn walked_at(&self, sigma_mps: f64) -> f64;
}

/// No calibration: σ is the walked speed.
pub(in crate::control) struct Uncalibrated;

impl SpeedMap for Uncalibrated {
    fn sigma_for(&self, walked_mps: f64) -> f64 {
        walked_mps
    }
    fn walked_at(&self, sigma_mps: f64) -> f64 {
        sigma_mps
    }
}

/// The regulator and the position loop: what the operator set and what the steps measured.
#[derive(Clone, Debug)]
pub(in crate::control) struct SpeedRegulator {
    /// Belt travel since the last impact, m.
    belt_travel_m: f64,
    /// Time of the last [`SpeedRegulator::advance`], s.
    last_t_s: Option<f64>,
    /// The step before the last: length, m, and duration, s (the error is measured over the
    /// last two steps, a stride: left and right steps differ).
    previous_step: Option<(f64, f64)>,
    pub(in crate::control) status: SpeedStatus,
    /// The `[speed]` section: the law's gains and the start and restart settings (cloned once,
    /// at start-up; read, never changed).
    config: SpeedConfig,
    /// The next impact sets σ without the per-step limit.
    unlimited_next: bool,
    /// The walk began from Stand (a launch), not in the gait's own state.
    from_stand: bool,
    /// Impacts since the walk began (from Stand or in the gait's own state).
    steps_walked: u32,
    /// The position loop's reference, m (0: the centre).
    reference_m: f64,
    /// Impacts left during which the reference follows the estimate (after the belt started,
    /// or after a disturbed step).
    settle_left: u32,
    /// The settle under way follows a disturbed step (`speed.disturbance_settle_mps`): the
    /// command follows the robot down and the integral rests too.
    disturbed: bool,
    /// A Stop under way with speed control: its approach and slowing steps.
    stop: Option<StopPhase>,
    /// The last step was more than `speed.disturbance_settle_mps` off the operator's speed.
    previous_off: bool,
}

/// Where a Stop with speed control is (`runtime::control::speed`, "Start and restart").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum StopPhase {
    /// Walking toward `speed.stop_ahead_m`: impacts so far.
    Approach(u32),
    /// There: the steps slow to `speed.stop_library_mps`.
    Slowing,
    /// The next step is the braking step.
    Brake,
}

/// The most the tick after an impact may correct the step's length by, m (the swing foot
/// moves a millimetre or so in the period between the encoders' sample and the impact).
const MAX_STEP_LENGTH_CORRECTION_M: f64 = 0.01;

/// How near its stop target a Stop's approach ends, m.
const STOP_TARGET_TOLERANCE_M: f64 = 0.05;

/// A Stop's approach brakes after this many impacts even short of its target.
const STOP_APPROACH_MAX_STEPS: u32 = 12;

impl SpeedRegulator {
    /// A regulator whose first library speed is `start_mps` (the gait walked before speed
    /// control begins).
    pub(in crate::control) fn new(config: &SpeedConfig, start_mps: f64) -> Self {
        let mut status = SpeedStatus::UNKNOWN;
        status.library_mps = start_mps;
        Self {
            belt_travel_m: 0.0,
            last_t_s: None,
            previous_step: None,
            status,
            config: config.clone(),
            unlimited_next: false,
            from_stand: true,
            steps_walked: 0,
            reference_m: 0.0,
            settle_left: 0,
            disturbed: false,
            stop: None,
            previous_off: false,
        }
    }

    /// The `[speed]` section it runs on.
    pub(in crate::control) fn config(&self) -> &SpeedConfig {
        &self.config
    }

    /// Start (the Ramp to Stand begins): the robot stands at the belt's centre; with
    /// `speed.position_from_start` the position counts from here.
    pub(in crate::control) fn at_start(&mut self) {
        self.belt_travel_m = 0.0;
        self.status.position_m = 0.0;
        self.reference_m = 0.0;
    }

    /// A Stop begins (speed control on, a library): with `speed.stop_ahead_m` on a moving belt
    /// the steps first walk to that far ahead; with `speed.stop_library_mps` they then slow to
    /// that gait; then the braking step ([`SpeedRegulator::brake_now`]). Neither: it brakes
    /// at once, as without speed control.
    pub(in crate::control) fn begin_stop(&mut self) {
        let st = &self.config;
        let ahead = st.stop_ahead_m > 0.0 && self.status.belt_mps > 0.0;
        self.stop = if ahead {
            self.reference_m = st.stop_ahead_m;
            self.settle_left = 0;
            self.unlimited_next |= st.first_step_unlimited;
            Some(StopPhase::Approach(0))
        } else if st.stop_library_mps > 0.0 {
            Some(StopPhase::Slowing)
        } else {
            None
        };
    }

    /// A Stop walks its approach or slowing steps (the controller runs the regulator at its
    /// impacts and brakes once [`SpeedRegulator::brake_now`]).
    pub(in crate::control) fn stopping(&self) -> bool {
        self.stop.is_some()
    }

    /// The step that starts at this impact is the braking step.
    pub(in crate::control) fn brake_now(&self) -> bool {
        self.stop == Some(StopPhase::Brake)
    }

    /// Whether a belt speed is known (speed control runs only then).
    pub(in crate::control) fn active(&self) -> bool {
        self.status.belt_mps.is_finite()
    }

    /// Takes an operator's speed command; false for any other command. `walking`: the
    /// controller is in Walk (a belt started from rest under the walking robot starts the
    /// settling).
    pub(in crate::control) fn operator(&mut self, cmd: OperatorCommand, walking: bool) -> bool {
        let s = &mut self.status;
        match cmd {
            OperatorCommand::Belt { speed_mps } if speed_mps.is_finite() => {
                // The belt started (from rest) under the walking robot.
                if walking && s.belt_mps == 0.0 && speed_mps != 0.0 {
                    self.settle_left = self.config.belt_start_settle_steps;
                }
                // The belt-change feed-forward: a moving belt sped up under the walking robot;
                // the next impact goes to the new belt's gait at once (not on a slow-down: a
                // jump down to a slow gait stalled, module docs).
                let change = self.config.belt_change_unlimited_mps;
                if walking && change > 0.0 && s.belt_mps > 0.0 && speed_mps - s.belt_mps > change {
                    self.unlimited_next = true;
                    s.integral_mps = 0.0;
                }
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
    pub(in crate::control) fn advance(&mut self, t_s: f64) {
        if let (Some(t0), true) = (self.last_t_s, self.active()) {
            let dt = (t_s - t0).clamp(0.0, 0.1);
            self.belt_travel_m += self.status.belt_mps * dt;
        }
        self.last_t_s = Some(t_s);
    }

    /// Forgets the steps (a walk begins in the gait's own post-impact state): position 0, no
    /// integral, no belt travel.
    pub(in crate::control) fn restart(&mut self) {
        self.forget(false);
    }

    /// [`SpeedRegulator::restart`] on the library gait of speed `sigma_mps` under a walked-speed
    /// calibration: with `speed.start_on_plan` the integral starts at `map.walked_at(σ) − σ`
    /// (within `speed.integral_limit_mps`), so that the first steps keep the gait the walk
    /// started on (module docs, "The start on the plan").
    pub(in crate::control) fn restart_on(&mut self, sigma_mps: f64, map: &impl SpeedMap) {
        self.forget(false);
        if self.config.start_on_plan && sigma_mps.is_finite() {
            let limit = self.config.integral_limit_mps;
            self.status.integral_mps = (map.walked_at(sigma_mps) - sigma_mps).clamp(-limit, limit);
        }
    }

    /// Forgets the steps as a Walk from Stand begins: no integral (resting
    /// `speed.integral_delay_steps` impacts), the first impact's σ unlimited with
    /// `speed.first_step_unlimited`; position 0 and no belt travel, or with
    /// `speed.position_from_start` both kept (the position counts from Start).
    pub(in crate::control) fn restart_from_stand(&mut self) {
        self.forget(true);
    }

    fn forget(&mut self, from_stand: bool) {
        let st = &self.config;
        self.previous_step = None;
        self.unlimited_next = from_stand && st.first_step_unlimited;
        self.from_stand = from_stand;
        self.steps_walked = 0;
        self.reference_m = 0.0;
        self.settle_left = 0;
        self.disturbed = false;
        self.previous_off = false;
        self.stop = None;
        let s = &mut self.status;
        if !(from_stand && st.position_from_start) {
            self.belt_travel_m = 0.0;
            s.position_m = 0.0;
        }
        s.integral_mps = 0.0;
        s.step_offset_m = 0.0;
        s.step_lean_rad = 0.0;
        s.step_speed_mps = f64::NAN;
        s.commanded_mps = f64::NAN;
    }

    /// The step that just ended at an impact: `length_m` over `duration_s`. Updates the
    /// position, the commanded speed, the integral and the next step's length offset
    /// (`status.step_offset_m`), and returns the library speed σ of the next step (clamped to
    /// `range_mps`).
    pub(in crate::control) fn on_impact(
        &mut self,
        length_m: f64,
        duration_s: f64,
        range_mps: (f64, f64),
    ) -> f64 {
        self.on_impact_mapped(length_m, duration_s, range_mps, &Uncalibrated)
    }

    /// [`SpeedRegulator::on_impact`] with a walked-speed calibration: the command, the error,
    /// the integral and the lever are in walked speeds (the command within what the library
    /// walks, `map.walked_at` of `range_mps`), and the next step's σ is `map.sigma_for` of the
    /// target, then clamped to `range_mps` and the step limit.
    pub(in crate::control) fn on_impact_mapped(
        &mut self,
        length_m: f64,
        duration_s: f64,
        range_mps: (f64, f64),
        map: &impl SpeedMap,
    ) -> f64 {
        let (sigma_lo, sigma_hi) = range_mps;
        let (lo, hi) = (map.walked_at(sigma_lo), map.walked_at(sigma_hi));
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
        let (stride_mps, step_s) = match self.previous_step {
            Some((l0, t0)) if measured => {
                ((l0 + length_m) / (t0 + duration_s), 0.5 * (t0 + duration_s))
            }
            _ => (s.step_speed_mps, duration_s),
        };
        self.previous_step = measured.then_some((length_m, duration_s));
        let error = if measured && s.commanded_mps.is_finite() {
            s.commanded_mps - stride_mps
        } else {
            0.0
        };
        // The position loop's gain per second, or per step over the last stride's mean step.
        let k_p = if self.config.position_gain_per_step > 0.0 && measured {
            self.config.position_gain_per_step / step_s
        } else {
            self.config.position_gain_per_s
        };
        // A disturbed step (a forward push): faster than the operator's speed by more than
        // `speed.disturbance_settle_mps` (not in a Stop, nor in the steps after a launch). A
        // slow step is left to the position loop: following the robot down means nothing there.
        let threshold = self.config.disturbance_settle_mps;
        let operator_mps = s.belt_mps + s.offset_mps;
        let pushed = measured
            && threshold > 0.0
            && self.stop.is_none()
            && steps_since_stand(self.from_stand, self.steps_walked)
                >= self.config.integral_delay_steps
            && s.step_speed_mps - operator_mps > threshold
            && !(self.disturbed && self.settle_left > 0)
            && !self.previous_off;
        if pushed {
            // The first disturbed step: σ goes to the robot's speed at once.
            self.unlimited_next |= !self.disturbed;
            self.settle_left = self.settle_left.max(self.config.disturbance_settle_steps);
            self.disturbed = true;
        }
        // A robot that stays that far off is not pushed (a stumble's run-on, a fast gait):
        // only a step off after one on the belt's speed starts a settle.
        if measured {
            self.previous_off = s.step_speed_mps - operator_mps > threshold;
        }
        // The reference: following the estimate while the robot settles after the belt started
        // or a disturbance, then gliding back to the centre; a Stop's target ahead.
        let settling = measured && self.settle_left > 0;
        let settling_disturbed = settling && self.disturbed;
        if settling {
            self.settle_left -= 1;
            self.disturbed &= self.settle_left > 0;
            self.reference_m = s.position_m;
        } else if measured && self.stop.is_none() {
            let glide = self.config.reference_glide_mps * duration_s;
            self.reference_m -= if glide > 0.0 {
                self.reference_m.clamp(-glide, glide)
            } else {
                self.reference_m
            };
        }
        self.steps_walked = self.steps_walked.saturating_add(1);
        s.requested_mps = match self.stop {
            // A Stop's approach walks ahead at a set speed over the belt's.
            Some(StopPhase::Approach(_)) if self.config.stop_approach_mps > 0.0 => {
                s.belt_mps + s.offset_mps + self.config.stop_approach_mps
            }
            // After a disturbance: the robot's speed, less a step's change, down to the belt's.
            // Never up again within the settle: a command that followed the robot up would
            // keep it fast (measured: a stumble's 0.9 m/s step ran the robot off the belt).
            _ if settling_disturbed => {
                let follow =
                    operator_mps.max(s.step_speed_mps - self.config.max_change_per_step_mps);
                if pushed {
                    follow
                } else {
                    follow.min(s.requested_mps)
                }
            }
            _ => s.belt_mps + s.offset_mps - k_p * (s.position_m - self.reference_m),
        };
        s.commanded_mps = s.requested_mps.clamp(lo, hi);
        s.clamped = s.commanded_mps != s.requested_mps;
        let resting = steps_since_stand(self.from_stand, self.steps_walked)
            <= self.config.integral_delay_steps
            || self.stop.is_some()
            || settling_disturbed;
        let k_i = if resting {
            0.0
        } else {
            self.config.integral_gain
        };
        let integral = (s.integral_mps + k_i * error).clamp(
            -self.config.integral_limit_mps,
            self.config.integral_limit_mps,
        );
        // The library gait of the command, plus the step-to-step feedback.
        let sigma = map.sigma_for(s.commanded_mps + self.config.speed_gain * error + integral);
        // Anti-windup: the integral only grows while σ is inside the library.
        if (sigma_lo..=sigma_hi).contains(&sigma) || integral.abs() < s.integral_mps.abs() {
            s.integral_mps = integral;
        }
        let last = if s.library_mps.is_finite() {
            s.library_mps.clamp(sigma_lo, sigma_hi)
        } else {
            map.sigma_for(s.commanded_mps)
        };
        let r = if std::mem::take(&mut self.unlimited_next) {
            f64::INFINITY
        } else {
            self.config.max_change_per_step_mps
        };
        s.library_mps = sigma.clamp(sigma_lo, sigma_hi).clamp(last - r, last + r);
        // σ held back by its rate limit: the command moves (a belt change), the slow loop's to follow.
        let slewing = s.library_mps != sigma.clamp(sigma_lo, sigma_hi);
        // The step lever: a step faster than the command lands the next step longer (more
        // speed lost in its impact), a slower one shorter. The last step's speed, not the
        // stride's: averaged over two steps the lever came a step late and overshot (stalls).
        // After a slow step the gain is `slow_step_length_gain_s` (0 in the treadmill config: a
        // shorter step after a slow one stalled more walks on the shipped library; module docs).
        let m = self.config.max_step_offset_m;
        s.step_offset_m = if measured && s.commanded_mps.is_finite() {
            // Below the slowest gait the lever may measure against the request (room below).
            let reference = if self.config.lever_below_library && s.requested_mps < lo {
                s.requested_mps
            } else {
                s.commanded_mps
            };
            let fast = s.step_speed_mps - reference;
            let gain = if settling {
                0.0
            } else if fast < 0.0 {
                self.config.slow_step_length_gain_s
            } else {
                self.config.step_length_gain_s
            };
            (gain * fast).clamp(-m, m)
        } else {
            0.0
        };
        // The step lean: speed damping within the next step (a fast step leans the next back).
        let lean_max = self.config.max_step_lean_rad;
        let lean_on = self.steps_walked > self.config.integral_delay_steps && !resting;
        s.step_lean_rad =
            if measured && s.commanded_mps.is_finite() && !settling && !slewing && lean_on {
                let fast = s.step_speed_mps - s.commanded_mps;
                let (from, full) = (
                    self.config.step_lean_from_mps,
                    self.config.step_lean_full_mps,
                );
                let gain = if fast >= 0.0 {
                    self.config.step_lean_gain_rad_per_mps
                } else {
                    self.config.slow_step_lean_gain_rad_per_mps
                };
                // How fast a gait the robot walks: the library's, or faster after a fast step.
                let walks = if fast >= 0.0 {
                    s.library_mps.max(map.sigma_for(s.step_speed_mps))
                } else {
                    s.library_mps
                };
                let share = if full > from {
                    ((walks - from) / (full - from)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                (-share * gain * fast).clamp(-lean_max, lean_max)
            } else {
                0.0
            };
        let position_m = s.position_m;
        self.stop_step(position_m, last, range_mps);
        self.status.library_mps
    }

    /// The step that ended at the last impact measured again (both feet down, the tick after):
    /// its length, the position and the stride's history move by `delta_m` (the next step's
    /// gait, chosen at the impact, stays). Ignored if not finite or over
    /// [`MAX_STEP_LENGTH_CORRECTION_M`].
    pub(in crate::control) fn correct_step_length(&mut self, delta_m: f64) {
        if !delta_m.is_finite()
            || delta_m.abs() > MAX_STEP_LENGTH_CORRECTION_M
            || !self.status.step_length_m.is_finite()
        {
            return;
        }
        let s = &mut self.status;
        s.step_length_m += delta_m;
        s.position_m += delta_m;
        if s.step_duration_s > 0.0 {
            s.step_speed_mps = s.step_length_m / s.step_duration_s;
        }
        if let Some((length_m, _)) = self.previous_step.as_mut() {
            *length_m += delta_m;
        }
    }

    /// A Stop's step at an impact: the approach ends at its target (or after
    /// [`STOP_APPROACH_MAX_STEPS`]); slowing caps σ at `speed.stop_library_mps` and brakes
    /// once the step that ended walked a gait no faster (`last`, m/s).
    fn stop_step(&mut self, position_m: f64, last: f64, (sigma_lo, sigma_hi): (f64, f64)) {
        let Some(phase) = self.stop else {
            return;
        };
        let there = position_m >= self.reference_m - STOP_TARGET_TOLERANCE_M;
        self.stop = Some(match phase {
            StopPhase::Approach(n) if !there && n + 1 < STOP_APPROACH_MAX_STEPS => {
                StopPhase::Approach(n + 1)
            }
            _ => StopPhase::Slowing,
        });
        if self.stop == Some(StopPhase::Slowing) {
            let slow = if self.config.stop_library_mps > 0.0 {
                self.config.stop_library_mps.clamp(sigma_lo, sigma_hi)
            } else {
                sigma_hi
            };
            let s = &mut self.status;
            if last <= slow + 1e-9 {
                self.stop = Some(StopPhase::Brake);
            }
            s.library_mps = s.library_mps.min(slow);
        }
    }
}

/// Impacts since the last Walk from Stand, for a walk `from_stand` that has walked
/// `steps_walked` impacts (`u32::MAX` for a walk begun in the gait's own state: no launch to
/// settle from).
fn steps_since_stand(from_stand: bool, steps_walked: u32) -> u32 {
    if from_stand {
        steps_walked
    } else {
        u32::MAX
    }
}

#[cfg(test)]
#[path = "regulator/lean_tests.rs"]
mod lean_tests;

#[cfg(test)]
#[allow(clippy::unwrap_used)]
#[path = "regulator/tests.rs"]
mod tests;
