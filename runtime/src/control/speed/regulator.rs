//! The step-to-step speed regulator, the step lever and the belt-position loop: one update per
//! impact (the law: the parent module's docs).

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
    /// Impacts since the last Walk from Stand.
    steps_since_walk: u32,
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
            steps_since_walk: 0,
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
        self.steps_since_walk = if from_stand { 0 } else { u32::MAX };
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
            && self.steps_since_walk >= self.config.integral_delay_steps
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
        self.steps_since_walk = self.steps_since_walk.saturating_add(1);
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
        let resting = self.steps_since_walk <= self.config.integral_delay_steps
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

#[cfg(test)]
#[path = "regulator/lean_tests.rs"]
mod lean_tests;

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn regulator(config: &SpeedConfig) -> SpeedRegulator {
        let mut r = SpeedRegulator::new(config, 0.25);
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }, false));
        r
    }

    #[test]
    fn position_integrates_steps_against_the_belt_and_pulls_the_command_back() {
        let config = SpeedConfig {
            position_gain_per_step: 0.0,
            ..SpeedConfig::default()
        };
        let mut r = regulator(&config);
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
    fn the_position_gain_per_step_pulls_by_it_over_the_mean_step_duration() {
        let config = SpeedConfig {
            position_gain_per_step: 0.17,
            ..SpeedConfig::default()
        };
        let mut r = regulator(&config);
        // Two steps of 0.6 and 0.8 s, the robot 0.1 m behind the centre after them.
        r.belt_travel_m = 0.15;
        r.on_impact(0.15, 0.6, (0.15, 0.35));
        r.belt_travel_m = 0.3;
        r.on_impact(0.2, 0.8, (0.15, 0.35));
        assert!((r.status.position_m + 0.1).abs() < 1e-12);
        let k_p = config.position_gain_per_step / 0.7;
        assert!(
            (r.status.requested_mps - (0.25 + k_p * 0.1)).abs() < 1e-12,
            "{}",
            r.status.requested_mps
        );
        // Slower steps, a smaller gain per second: one of 1.0 s after 1.0 s.
        let mut r = regulator(&config);
        r.belt_travel_m = 0.25;
        r.on_impact(0.25, 1.0, (0.15, 0.35));
        r.belt_travel_m = 0.35;
        r.on_impact(0.25, 1.0, (0.15, 0.35));
        let k_p = config.position_gain_per_step / 1.0;
        assert!((r.status.requested_mps - (0.25 + k_p * 0.1)).abs() < 1e-12);
    }

    #[test]
    fn a_slow_stride_raises_the_next_gait_by_the_speed_gain() {
        let config = SpeedConfig {
            speed_gain: 0.5,
            integral_gain: 0.0,
            ..SpeedConfig::default()
        };
        let mut r = regulator(&config);
        // The first step sets the command; the second, 0.05 m/s slow (the stride 0.025 m/s
        // slow), with the robot put back at the centre: σ = v_cmd + k_s·0.025.
        r.belt_travel_m = 0.2;
        r.on_impact(0.2, 0.8, (0.15, 0.35));
        r.status.position_m = 0.0;
        r.belt_travel_m = 0.16;
        let sigma = r.on_impact(0.16, 0.8, (0.15, 0.35));
        assert!((sigma - (0.25 + 0.5 * 0.025)).abs() < 1e-12, "σ = {sigma}");
    }

    #[test]
    fn the_integral_removes_a_steady_bias() {
        let mut r = regulator(&SpeedConfig::default());
        r.on_impact(f64::NAN, 0.0, (0.15, 0.35));
        r.status.position_m = 0.0;
        // Each step walks 0.02 m/s slower than the gait it was given (a bias), the belt
        // travel matched to the step so the position stays put.
        let mut sigma = 0.25;
        for _ in 0..80 {
            let v = sigma - 0.02;
            r.belt_travel_m = v * 0.8;
            sigma = r.on_impact(v * 0.8, 0.8, (0.15, 0.35));
        }
        // The command settles where the robot walks the belt speed: σ = 0.27, the bias.
        assert!((sigma - 0.27).abs() < 1e-3, "σ = {sigma}");
        assert!((r.status.integral_mps - 0.02).abs() < 1e-3);
    }

    #[test]
    fn a_fast_step_lands_the_next_step_longer_within_the_limit() {
        let config = SpeedConfig::default();
        let mut r = regulator(&config);
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
        // A very fast one: at most the limit.
        r.status.position_m = 0.0;
        r.on_impact(0.4, 0.5, (0.15, 0.35));
        assert_eq!(r.status.step_offset_m, config.max_step_offset_m);
        // A restart forgets it.
        r.restart();
        assert_eq!(r.status.step_offset_m, 0.0);
    }

    /// A regulator at the centre of a 0.25 m/s belt after a first step and then a 0.16 m step
    /// in 0.8 s (0.2 m/s, slow), the belt's travel matched so the position stays put.
    fn after_a_slow_step(config: &SpeedConfig) -> SpeedRegulator {
        let mut r = regulator(config);
        r.on_impact(f64::NAN, 0.0, (0.15, 0.35));
        r.status.position_m = 0.0;
        r.belt_travel_m = 0.16;
        r.on_impact(0.16, 0.8, (0.15, 0.35));
        r
    }

    #[test]
    fn after_a_slow_step_the_lever_takes_its_slow_side_gain() {
        // None: no shorter step after a slow one.
        let config = SpeedConfig {
            slow_step_length_gain_s: 0.0,
            ..SpeedConfig::default()
        };
        let r = after_a_slow_step(&config);
        assert_eq!(r.status.commanded_mps, 0.25);
        assert_eq!(r.status.step_offset_m, 0.0);
        // With a slow-side gain: shorter by it, at most the limit.
        let config = SpeedConfig {
            slow_step_length_gain_s: 0.5,
            ..SpeedConfig::default()
        };
        let mut r = after_a_slow_step(&config);
        let expected = 0.5 * (0.2 - 0.25);
        assert!(expected < 0.0);
        assert!((r.status.step_offset_m - expected).abs() < 1e-12);
        r.status.position_m = 0.0;
        r.on_impact(0.01, 2.0, (0.15, 0.35));
        assert_eq!(r.status.step_offset_m, -config.max_step_offset_m);
    }

    /// A calibration in which every gait walks 20 % faster than its library speed.
    struct Fast;
    impl SpeedMap for Fast {
        fn sigma_for(&self, walked_mps: f64) -> f64 {
            walked_mps / 1.2
        }
        fn walked_at(&self, sigma_mps: f64) -> f64 {
            1.2 * sigma_mps
        }
    }

    #[test]
    fn with_a_calibration_the_regulator_asks_for_the_gait_that_walks_the_command() {
        let config = SpeedConfig {
            integral_gain: 0.0,
            ..SpeedConfig::default()
        };
        let mut r = regulator(&config);
        r.status.library_mps = 0.21;
        // At the centre, a step at the belt's speed: the command is the belt's 0.25 m/s and σ
        // the gait that walks it, 0.25 / 1.2.
        r.belt_travel_m = 0.2;
        let sigma = r.on_impact_mapped(0.2, 0.8, (0.15, 0.35), &Fast);
        assert_eq!(r.status.commanded_mps, 0.25);
        assert!((sigma - 0.25 / 1.2).abs() < 1e-12, "σ = {sigma}");
        // A belt faster than the fastest gait walks (0.42 m/s): the command stops there.
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.5 }, false));
        r.on_impact_mapped(0.2, 0.8, (0.15, 0.35), &Fast);
        assert!(r.status.clamped);
        assert!((r.status.commanded_mps - 0.42).abs() < 1e-12);
    }

    /// The treadmill config's start and restart settings.
    fn start_config() -> SpeedConfig {
        SpeedConfig {
            first_step_unlimited: true,
            position_from_start: true,
            integral_delay_steps: 2,
            belt_start_settle_steps: 2,
            reference_glide_mps: 0.02,
            stop_ahead_m: 0.35,
            stop_approach_mps: 0.12,
            stop_library_mps: 0.21,
            ..SpeedConfig::default()
        }
    }

    #[test]
    fn a_walk_from_stand_keeps_the_belt_travel_and_its_first_impact_jumps_to_the_command() {
        let mut r = SpeedRegulator::new(&start_config(), 0.15);
        r.at_start();
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }, false));
        // Standing 1 s on the belt: 0.25 m back, kept at Walk.
        for k in 0..=1000 {
            r.advance(f64::from(k) * 1e-3);
        }
        r.restart_from_stand();
        r.belt_travel_m += 0.25;
        // The launch and first step: 0.15 m while the belt ran 0.25 m.
        let sigma = r.on_impact(0.15, 1.0, (0.15, 0.40));
        assert!((r.status.position_m + 0.35).abs() < 1e-9, "{:?}", r.status);
        // Behind the centre: the command is above the belt's, and σ goes there at once.
        assert!(r.status.commanded_mps > 0.3);
        assert!(
            (sigma - r.status.commanded_mps).abs() < 1e-12,
            "σ = {sigma}"
        );
        // Then limited again; the integral rests for the first impacts.
        let before = r.status.library_mps;
        r.belt_travel_m = 0.1;
        let sigma = r.on_impact(0.1, 1.0, (0.15, 0.40));
        assert!((sigma - before).abs() <= 0.02 + 1e-12);
        assert_eq!(r.status.integral_mps, 0.0);
        // A walk from the gait's own state forgets the position and is limited from the start.
        r.restart();
        assert_eq!(r.status.position_m, 0.0);
        let last = r.status.library_mps;
        let sigma = r.on_impact(0.15, 1.0, (0.15, 0.40));
        assert!(
            (sigma - (last - 0.02)).abs() < 1e-12,
            "σ = {sigma} after {last}"
        );
    }

    #[test]
    fn after_a_pushed_step_the_command_follows_the_robot_down_then_the_reference_glides_back() {
        let config = SpeedConfig {
            disturbance_settle_mps: 0.13,
            disturbance_settle_steps: 2,
            speed_gain: 0.0,
            ..start_config()
        };
        let mut r = regulator(&config);
        r.belt_travel_m = 0.2;
        r.on_impact(0.2, 0.8, (0.15, 0.40));
        // A step 0.12 m/s faster than the belt: within the threshold, the lever acts.
        r.belt_travel_m = 0.1;
        r.on_impact(0.185, 0.5, (0.15, 0.40));
        assert!(r.status.step_offset_m > 0.0 && r.status.requested_mps < 0.25);
        r.status.position_m = 0.0;
        r.status.integral_mps = 0.01;
        // A pushed step at 0.65 m/s: the command is its speed less 0.02 m/s, σ goes there at
        // once (the range's top), no lever, the integral at rest.
        let sigma = r.on_impact(0.26, 0.4, (0.15, 0.40));
        assert!((r.status.requested_mps - 0.63).abs() < 1e-12);
        assert_eq!(sigma, 0.40);
        assert_eq!(r.status.step_offset_m, 0.0);
        assert_eq!(r.status.integral_mps, 0.01);
        // The next, 0.30 m/s (within the threshold), the last of the 2 settling impacts: the
        // command follows it down, σ by the step limit; then the reference glides back.
        r.on_impact(0.15, 0.5, (0.15, 0.40));
        assert!((r.status.requested_mps - 0.28).abs() < 1e-12);
        assert!((r.status.library_mps - 0.38).abs() < 1e-12);
        r.belt_travel_m = 0.125;
        r.on_impact(0.125, 0.5, (0.15, 0.40));
        assert!(r.status.requested_mps < 0.25 && r.status.requested_mps > 0.24);
        // A slow step (a backward push, 0.1 m/s: 0.15 m/s below the belt's) starts no settle:
        // the position loop asks for more than the belt's speed; off (0) nothing settles.
        r.belt_travel_m = 0.125;
        r.on_impact(0.05, 0.5, (0.15, 0.40));
        assert_eq!((r.settle_left, r.disturbed), (0, false));
        assert!(r.status.requested_mps > 0.25, "{}", r.status.requested_mps);
        let mut r = regulator(&start_config());
        r.belt_travel_m = 0.2;
        r.on_impact(0.2, 0.8, (0.15, 0.40));
        r.belt_travel_m = 0.1;
        r.on_impact(0.26, 0.4, (0.15, 0.40));
        assert!(r.status.requested_mps < 0.25 && r.status.step_offset_m > 0.0);
    }

    #[test]
    fn the_belt_started_under_the_walking_robot_is_ridden_out_then_the_reference_glides_back() {
        let mut r = SpeedRegulator::new(&start_config(), 0.15);
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.0 }, true));
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.25 }, true));
        // A shoved step 0.2 m ahead: the command stays the belt's, no longer step.
        r.on_impact(0.2, 0.5, (0.15, 0.40));
        assert_eq!(r.status.requested_mps, 0.25);
        assert_eq!(r.status.step_offset_m, 0.0);
        r.on_impact(0.125, 0.5, (0.15, 0.40));
        assert_eq!(r.status.requested_mps, 0.25);
        // Then the reference glides back (0.02 m/s over a 0.5 s step): a small pull back.
        r.belt_travel_m = 0.125;
        r.on_impact(0.125, 0.5, (0.15, 0.40));
        assert!(r.status.requested_mps < 0.25 && r.status.requested_mps > 0.24);
        // A belt that changes speed while moving does not start it again.
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.30 }, true));
        assert_eq!(r.settle_left, 0);
    }

    #[test]
    fn a_belt_change_while_walking_sets_the_next_gait_at_once_with_the_feed_forward() {
        let config = SpeedConfig {
            belt_change_unlimited_mps: 0.05,
            ..SpeedConfig::default()
        };
        let mut r = regulator(&config);
        r.status.integral_mps = 0.03;
        // A small change (0.02 m/s) and a change while not walking: limited as before.
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.27 }, true));
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.20 }, false));
        assert!(!r.unlimited_next);
        assert_eq!(r.status.integral_mps, 0.03);
        // The operator steps the belt 0.20 -> 0.30 m/s under the walking robot: the next impact
        // goes to the new belt's gait (at the centre) and the integral starts again.
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.30 }, true));
        assert_eq!(r.status.integral_mps, 0.0);
        r.status.library_mps = 0.20;
        r.belt_travel_m = 0.24;
        let sigma = r.on_impact(0.24, 0.8, (0.15, 0.40));
        assert!((sigma - 0.30).abs() < 1e-12, "σ = {sigma}");
        // Then limited again.
        r.belt_travel_m = 0.24;
        let before = r.status.library_mps;
        let sigma = r.on_impact(0.16, 0.8, (0.15, 0.40));
        assert!((sigma - before).abs() <= 0.02 + 1e-12, "σ = {sigma}");
        // A slow-down is limited (a jump down to a slow gait stalled).
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.20 }, true));
        assert!(!r.unlimited_next);
        // Off (0, the default): the same step is limited.
        let mut r = regulator(&SpeedConfig::default());
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.30 }, true));
        assert!(!r.unlimited_next);
    }

    #[test]
    fn a_stop_on_a_moving_belt_walks_ahead_then_slows_then_brakes() {
        let mut r = regulator(&start_config());
        r.status.library_mps = 0.21;
        r.begin_stop();
        assert!(r.stopping() && !r.brake_now());
        // Approach: the belt's speed plus the approach speed, whatever the position loop says.
        r.belt_travel_m = 0.2;
        r.on_impact(0.2, 0.8, (0.15, 0.40));
        assert!((r.status.requested_mps - 0.37).abs() < 1e-12);
        assert!(!r.brake_now());
        // There (within 5 cm of 0.35 m ahead), on a fast gait: one slowing step at 0.21 ...
        r.status.library_mps = 0.33;
        r.status.position_m = 0.3;
        r.belt_travel_m = 0.2;
        let sigma = r.on_impact(0.2, 0.8, (0.15, 0.40));
        assert!((sigma - 0.21).abs() < 1e-12, "σ = {sigma}");
        assert!(!r.brake_now());
        // ... then the braking step.
        r.belt_travel_m = 0.2;
        r.on_impact(0.2, 0.8, (0.15, 0.40));
        assert!(r.brake_now());
        // Without the settings a Stop brakes at once.
        let mut r = regulator(&SpeedConfig::default());
        r.begin_stop();
        assert!(!r.stopping());
    }

    #[test]
    fn commands_outside_the_library_are_clamped_and_flagged() {
        let config = SpeedConfig {
            position_gain_per_step: 0.0,
            ..SpeedConfig::default()
        };
        let mut r = regulator(&config);
        assert!(r.operator(OperatorCommand::Belt { speed_mps: 0.5 }, false));
        let sigma = r.on_impact(0.2, 0.8, (0.15, 0.35));
        assert!(r.status.clamped);
        let k_p = config.position_gain_per_s;
        assert_eq!(r.status.requested_mps, 0.5 - k_p * r.status.position_m);
        assert_eq!(r.status.commanded_mps, 0.35);
        // ... and the library speed moves towards it by at most the step limit.
        assert!((sigma - 0.27).abs() < 1e-12, "σ = {sigma}");
        assert!(!r.operator(OperatorCommand::Walk, false));
        assert!(r.operator(OperatorCommand::Nudge { delta_mps: 0.025 }, false));
        assert!(r.operator(OperatorCommand::Nudge { delta_mps: 0.025 }, false));
        assert!((r.status.offset_mps - 0.05).abs() < 1e-15);
    }
}
