//! The `[speed]` section: the step-to-step speed regulator and the belt-position loop
//! (`runtime::control::speed`).

use crate::RuntimeError;
use serde::{Deserialize, Serialize};

/// Speed control on a treadmill: how the walking speed follows the belt and how the robot is
/// kept at the belt's centre. Active once a gait library is loaded and a belt speed is known
/// (an operator `belt` command).
///
/// At each impact k (the Poincaré section), with the last step's measured speed v_k, the
/// last stride's (two steps) v̄_k, the belt speed b set by the operator and the estimated
/// position p on the belt (+ forward):
/// ```text
/// k_p   = position_gain_per_step / T̄_k  (T̄_k: the last stride's mean step duration;
///         position_gain_per_s if position_gain_per_step = 0)
/// v_cmd = clamp(b + offset − k_p · p, c(library range))  (c: walked_mps, or the identity)
/// e_k   = v_cmd,k−1 − v̄_k          (speed error of the last stride against its command)
/// I    += integral_gain · e_k                           (|I| ≤ integral_limit_mps)
/// σ     = clamp(c⁻¹(v_cmd + speed_gain · e_k + I), library range,
///               σ_prev ± max_change_per_step_mps)          (the library gait of the next step)
/// Δℓ    = clamp(g · (v_k − v_cmd), ± max_step_offset_m)   (the next step lands Δℓ longer:
///         g = step_length_gain_s after a fast step,        the step lever)
///             slow_step_length_gain_s after a slow one
/// λ     = clamp(−h · (v_k − v_cmd), ± max_step_lean_rad)  (the next step's torso lean,
///         h = step_lean_gain_rad_per_mps after a fast step,  + forward: the step lean)
///             slow_step_lean_gain_rad_per_mps after a slow one,
///             times clamp((σ − step_lean_from_mps) / (step_lean_full_mps − step_lean_from_mps), 0, 1)
/// a step with v_k − b − offset > disturbance_settle_mps: for disturbance_settle_steps
///         impacts v_cmd = max(b + offset, v_k − max_change_per_step_mps), no lever, no I
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeedConfig {
    /// Position loop: commanded speed per metre of position on the belt, (m/s)/m = 1/s.
    pub position_gain_per_s: f64,
    /// Position loop per step (0, the default: off, `position_gain_per_s` acts): the commanded
    /// speed per metre of position is this over the last stride's mean step duration, 1/s. The
    /// loop acts once a step, so its gain per step sets its stability: the same 0.3 /s is 0.3
    /// of the error per 1 s step at 0.15 m/s and 0.17 per 0.57 s step at 0.30 m/s
    /// (`runtime::control::speed`; 0.17 in `configs/runtime/adam_treadmill.toml`).
    #[serde(default = "default_position_gain_per_step")]
    pub position_gain_per_step: f64,
    /// Proportional gain of the step-to-step speed regulator (library speed per speed error).
    pub speed_gain: f64,
    /// Integral gain of the regulator, per step.
    pub integral_gain: f64,
    /// The regulator's integral stays within ± this, m/s.
    pub integral_limit_mps: f64,
    /// The library speed changes by at most this much from one step to the next, m/s: each
    /// switch starts the new gait close to its own orbit.
    pub max_change_per_step_mps: f64,
    /// The step lever: the next step lands this much longer per m/s that the last step was
    /// faster than the command, m/(m/s) = s (0: off).
    #[serde(default = "default_step_length_gain_s")]
    pub step_length_gain_s: f64,
    /// The step lever's offset stays within ± this, m.
    #[serde(default = "default_max_step_offset_m")]
    pub max_step_offset_m: f64,
    /// The step lever's gain after a step slower than the command, m/(m/s) = s: the next step
    /// lands this much shorter per m/s too slow (default: `step_length_gain_s`'s 0.1; 0 in
    /// `configs/runtime/adam_treadmill.toml`: on the shipped library a shorter step after a
    /// slow one stalled more walks at 0.15–0.20 m/s, `runtime::control::speed`).
    #[serde(default = "default_step_length_gain_s")]
    pub slow_step_length_gain_s: f64,
    /// The step lean: the next step leans the torso (both hips offset alike, the feet's
    /// relative pose unmoved) back by this much per m/s that the last step was faster than the
    /// command, forward when slower, rad/(m/s) (0, the default: off). Speed damping on the
    /// Poincaré section: gravity's work over the step answers the lean within the step, where
    /// the library speed σ moves the walked speed by a tenth per step (`runtime::control::speed`).
    #[serde(default)]
    pub step_lean_gain_rad_per_mps: f64,
    /// The step lean's gain after a step slower than the command (the next step leans
    /// forward), rad/(m/s) (0, the default: no forward lean).
    #[serde(default)]
    pub slow_step_lean_gain_rad_per_mps: f64,
    /// The step lean's gains act in full from this library speed σ of the next step up,
    /// m/s, and scale down linearly to 0 at `step_lean_from_mps` (the slow gaits walk several
    /// times faster per mrad of lean: a lean that damps the 0.30 m/s gaits stalls the 0.15 m/s
    /// ones). 0, the default: in full at every σ.
    #[serde(default)]
    pub step_lean_full_mps: f64,
    /// Below this library speed σ, no step lean, m/s (see `step_lean_full_mps`; below it,
    /// unless both are 0).
    #[serde(default)]
    pub step_lean_from_mps: f64,
    /// Measure each step's length again at the tick after an impact felt by the IMU (both feet
    /// down), and correct the position by the difference: the encoders' sample of the impact
    /// tick predates the impact (`runtime::control::speed`, "The step's length"). Off by default.
    #[serde(default)]
    pub step_length_after_impact: bool,
    /// The step lean stays within ± this, rad (above 0 when a lean gain is, at most 0.5).
    #[serde(default)]
    pub max_step_lean_rad: f64,
    /// Where the position on the belt comes from: leg odometry (the belt speed set by the
    /// operator integrated against the measured steps).
    #[serde(default)]
    pub position_source: PositionSource,
    /// The gait library file ([`model::library::GaitLibrary`]), relative to the config file's
    /// folder (absent: no library, speed control off).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub library: Option<String>,
    /// The walked-speed calibration of the library (empty, the default: none, σ is the speed
    /// the regulator asks for): the speed each library gait walks on the simulated robot, m/s,
    /// one per library entry in its order, strictly increasing. The regulator then works in
    /// walked speeds and takes the library speed σ that walks its target from this map
    /// (piecewise linear, its inverse; `runtime::control::speed`, "The walked-speed
    /// calibration").
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walked_mps: Vec<f64>,
    /// A walk begun in its gait's own state starts with the integral at the calibration's
    /// offset there, c(σ) − σ (false, the default: at 0): its first steps ask for the gait they
    /// started on, which walks its plan at first, and the integral takes the creep to c(σ) up
    /// as the steps show it (`runtime::control::speed::regulator`, "The start on the plan").
    #[serde(default)]
    pub start_on_plan: bool,
    /// How far below the slowest library gait σ may go, m/s (0, the default: not at all): the
    /// gait there extrapolates the two slowest linearly. Room for the regulator below a belt
    /// that the slowest gait walks faster than.
    #[serde(default)]
    pub below_library_mps: f64,
    /// The step lever measures a step against the requested speed rather than the command
    /// when the request is below what the slowest gait walks (false, the default: against the
    /// command): room below a belt slower than the library walks.
    #[serde(default)]
    pub lever_below_library: bool,
    /// Walk from Stand: the launch aims at the orbit of the library gait this fraction of the
    /// way from the gait Stand stood in to the one that walks the commanded speed (0, the
    /// default: the Stand gait), and the first step walks it.
    #[serde(default)]
    pub launch_gait_fraction: f64,
    /// The first impact after a Walk from Stand (and after a Stop) sets the library speed
    /// without `max_change_per_step_mps` (false, the default: limited): the start gets up to
    /// the belt's speed at once.
    #[serde(default)]
    pub first_step_unlimited: bool,
    /// The position on the belt counts from Start (the robot at the centre), the belt's travel
    /// while standing included (false, the default: from each Walk).
    #[serde(default)]
    pub position_from_start: bool,
    /// The integral rests for this many impacts after a Walk from Stand (and during a Stop):
    /// the first steps after a launch walk off their gait's calibration.
    #[serde(default)]
    pub integral_delay_steps: u32,
    /// When the operator starts the belt (from rest) while the robot walks, for this many
    /// impacts the position loop's reference follows the estimate (the command is the belt's
    /// speed) and the step lever rests: the belt's ramp shoves the robot forward over the belt,
    /// which is not a position error to correct at once (0, the default: none).
    #[serde(default)]
    pub belt_start_settle_steps: u32,
    /// Then the reference glides back to the centre at this speed, m/s (0: it jumps back).
    #[serde(default)]
    pub reference_glide_mps: f64,
    /// The belt-change feed-forward, m/s (0, the default: off): when the operator speeds up a
    /// moving belt by more than this while the robot walks, the next impact sets the
    /// library speed for the new belt without `max_change_per_step_mps` (as
    /// `first_step_unlimited` after a Walk from Stand) and the integral starts again from 0.
    #[serde(default)]
    pub belt_change_unlimited_mps: f64,
    /// A disturbance (a forward push) seen at an impact: a step faster than the operator's
    /// speed (belt + offset) by more than this, m/s, starts a settle (0, the default: off; a
    /// slow step never does: following the robot down only means something after a fast
    /// one). For `disturbance_settle_steps` impacts after the last such step the reference
    /// follows the estimate, the step lever and the integral rest, and the command follows the
    /// robot down: the last step's speed less `max_change_per_step_mps`, never below the
    /// operator's (the first such impact sets σ without the step limit); then the reference
    /// glides back at `reference_glide_mps` (`runtime::control::speed`, "Forward pushes").
    #[serde(default)]
    pub disturbance_settle_mps: f64,
    /// ... for this many impacts.
    #[serde(default)]
    pub disturbance_settle_steps: u32,
    /// A Stop on a moving belt first walks to this far ahead of the centre, m (0, the default:
    /// it brakes at once): the robot then stands longer before the belt carries it off the back.
    #[serde(default)]
    pub stop_ahead_m: f64,
    /// ... at the belt's speed plus this, m/s.
    #[serde(default)]
    pub stop_approach_mps: f64,
    /// A Stop with speed control brakes only after a step on a library gait of at most this
    /// speed σ, m/s (0, the default: brakes from any gait): the braking step does not stop the
    /// fast gaits.
    #[serde(default)]
    pub stop_library_mps: f64,
    /// The stall relaunch, s (0, the default: off): a Walk step whose phase has made no
    /// progress for this long, the robot nearly at rest on both feet (a backward push stopped
    /// the torso short of the stance foot; on a moving belt it is then carried back), starts
    /// again from double support, as Walk from Stand launches (`runtime::control::recovery`;
    /// 1.0 in `configs/runtime/adam_treadmill.toml`). Once per step; shorter than
    /// `safety.stall_timeout_s`, which stays the last resort. Acts with or without a library.
    #[serde(default)]
    pub stall_relaunch_s: f64,
    /// The step-back catch, m (0, the default: off): a Walk step whose swing foot lands at
    /// least this far behind the stance foot while the robot moves back is caught at once in
    /// double support and launched again (`runtime::control::recovery`, "The step-back catch").
    #[serde(default)]
    pub step_back_catch_m: f64,
}

/// Where the robot's position along the belt comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionSource {
    /// Leg odometry: each step adds its measured length and subtracts the belt travel.
    #[default]
    Odometry,
}

impl Default for SpeedConfig {
    fn default() -> Self {
        Self {
            position_gain_per_s: 0.3,
            position_gain_per_step: default_position_gain_per_step(),
            speed_gain: 0.5,
            integral_gain: 0.1,
            integral_limit_mps: 0.1,
            max_change_per_step_mps: 0.02,
            step_length_gain_s: default_step_length_gain_s(),
            max_step_offset_m: default_max_step_offset_m(),
            slow_step_length_gain_s: default_step_length_gain_s(),
            step_lean_gain_rad_per_mps: 0.0,
            slow_step_lean_gain_rad_per_mps: 0.0,
            step_lean_full_mps: 0.0,
            step_length_after_impact: false,
            step_lean_from_mps: 0.0,
            max_step_lean_rad: 0.0,
            position_source: PositionSource::Odometry,
            library: None,
            walked_mps: Vec::new(),
            start_on_plan: false,
            below_library_mps: 0.0,
            lever_below_library: false,
            launch_gait_fraction: 0.0,
            first_step_unlimited: false,
            position_from_start: false,
            integral_delay_steps: 0,
            belt_start_settle_steps: 0,
            reference_glide_mps: 0.0,
            belt_change_unlimited_mps: 0.0,
            disturbance_settle_mps: 0.0,
            disturbance_settle_steps: 0,
            stop_ahead_m: 0.0,
            stop_approach_mps: 0.0,
            stop_library_mps: 0.0,
            stall_relaunch_s: 0.0,
            step_back_catch_m: 0.0,
        }
    }
}

fn default_position_gain_per_step() -> f64 {
    0.0
}

fn default_step_length_gain_s() -> f64 {
    0.1
}

fn default_max_step_offset_m() -> f64 {
    0.04
}

impl SpeedConfig {
    /// Finite, non-negative gains and limit; errors name `origin`, the field and the value.
    pub fn validate(&self, origin: &str) -> crate::Result<()> {
        for (field, v) in [
            ("speed.position_gain_per_s", self.position_gain_per_s),
            ("speed.position_gain_per_step", self.position_gain_per_step),
            ("speed.speed_gain", self.speed_gain),
            ("speed.integral_gain", self.integral_gain),
            ("speed.integral_limit_mps", self.integral_limit_mps),
            (
                "speed.max_change_per_step_mps",
                self.max_change_per_step_mps,
            ),
            ("speed.step_length_gain_s", self.step_length_gain_s),
            ("speed.max_step_offset_m", self.max_step_offset_m),
            (
                "speed.slow_step_length_gain_s",
                self.slow_step_length_gain_s,
            ),
            (
                "speed.step_lean_gain_rad_per_mps",
                self.step_lean_gain_rad_per_mps,
            ),
            (
                "speed.slow_step_lean_gain_rad_per_mps",
                self.slow_step_lean_gain_rad_per_mps,
            ),
            ("speed.max_step_lean_rad", self.max_step_lean_rad),
            ("speed.step_lean_full_mps", self.step_lean_full_mps),
            ("speed.step_lean_from_mps", self.step_lean_from_mps),
            ("speed.below_library_mps", self.below_library_mps),
            ("speed.launch_gait_fraction", self.launch_gait_fraction),
            ("speed.reference_glide_mps", self.reference_glide_mps),
            (
                "speed.belt_change_unlimited_mps",
                self.belt_change_unlimited_mps,
            ),
            ("speed.disturbance_settle_mps", self.disturbance_settle_mps),
            ("speed.stop_ahead_m", self.stop_ahead_m),
            ("speed.stop_approach_mps", self.stop_approach_mps),
            ("speed.stop_library_mps", self.stop_library_mps),
            ("speed.stall_relaunch_s", self.stall_relaunch_s),
            ("speed.step_back_catch_m", self.step_back_catch_m),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(RuntimeError::InvalidField {
                    origin: origin.to_string(),
                    field: field.into(),
                    value: v.to_string(),
                    reason: "must be finite and not negative".into(),
                });
            }
        }
        // Gains that large overshoot every step (the loop is discrete: one update per step).
        for (field, v) in [
            ("speed.speed_gain", self.speed_gain),
            ("speed.integral_gain", self.integral_gain),
        ] {
            if v >= 3.0 {
                return Err(RuntimeError::InvalidField {
                    origin: origin.to_string(),
                    field: field.into(),
                    value: v.to_string(),
                    reason: "must be below 3 (the walked speed responds to the library speed with a gain of about 0.4: a step-to-step gain of 3 or more overshoots each step)"
                        .into(),
                });
            }
        }
        // The step lean: a gain with no room to lean, or a fade that does not rise, would
        // leave it silently off or in full everywhere.
        let bad = |field: &str, v: f64, reason: String| RuntimeError::InvalidField {
            origin: origin.to_string(),
            field: field.into(),
            value: v.to_string(),
            reason,
        };
        let leans =
            self.step_lean_gain_rad_per_mps > 0.0 || self.slow_step_lean_gain_rad_per_mps > 0.0;
        if leans && self.max_step_lean_rad == 0.0 {
            return Err(bad(
                "speed.max_step_lean_rad",
                self.max_step_lean_rad,
                "must be above 0 when a step lean gain is (the lean is clamped to it)".into(),
            ));
        }
        if self.max_step_lean_rad > 0.5 {
            return Err(bad(
                "speed.max_step_lean_rad",
                self.max_step_lean_rad,
                "must be at most 0.5 rad (a larger lean takes the torso far off the gait's pose)"
                    .into(),
            ));
        }
        let (from, full) = (self.step_lean_from_mps, self.step_lean_full_mps);
        if !(from == 0.0 && full == 0.0) && from >= full {
            return Err(bad(
                "speed.step_lean_from_mps",
                from,
                format!(
                    "must be below speed.step_lean_full_mps = {full} m/s (the lean's share \
                     grows from 0 there to 1 at full; both 0: in full at every speed)"
                ),
            ));
        }
        if self.launch_gait_fraction > 1.0 {
            return Err(RuntimeError::InvalidField {
                origin: origin.to_string(),
                field: "speed.launch_gait_fraction".into(),
                value: self.launch_gait_fraction.to_string(),
                reason: "must be within [0, 1] (a fraction of the way to the command's gait)"
                    .into(),
            });
        }
        if let Some(v) = self
            .walked_mps
            .iter()
            .find(|v| !(v.is_finite() && **v > 0.0))
        {
            return Err(RuntimeError::InvalidField {
                origin: origin.to_string(),
                field: "speed.walked_mps".into(),
                value: v.to_string(),
                reason: "must be positive and finite".into(),
            });
        }
        if self.start_on_plan && self.walked_mps.is_empty() {
            return Err(RuntimeError::InvalidField {
                origin: origin.to_string(),
                field: "speed.start_on_plan".into(),
                value: "true".into(),
                reason: "needs speed.walked_mps: without a calibration the integral would start \
                         at 0, as with the option off"
                    .into(),
            });
        }
        for (k, pair) in self.walked_mps.windows(2).enumerate() {
            if pair[1] <= pair[0] {
                return Err(RuntimeError::InvalidField {
                    origin: origin.to_string(),
                    field: format!("speed.walked_mps[{}]", k + 1),
                    value: pair[1].to_string(),
                    reason: format!(
                        "must be above entry {k}'s {} m/s: the calibration must increase",
                        pair[0]
                    ),
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn negative_or_non_finite_gains_are_refused_naming_the_field_and_value() {
        for bad in [-0.1, f64::INFINITY, f64::NAN] {
            let c = SpeedConfig {
                slow_step_length_gain_s: bad,
                ..SpeedConfig::default()
            };
            let e = c.validate("adam.toml").expect_err("refused").to_string();
            assert!(e.contains("adam.toml"), "{e}");
            assert!(e.contains("speed.slow_step_length_gain_s"), "{e}");
            assert!(e.contains(&bad.to_string()), "{e}");
        }
        assert!(SpeedConfig::default().validate("adam.toml").is_ok());
    }

    /// `start_on_plan` without a calibration could not act: refused, naming the field.
    #[test]
    fn a_start_on_the_plan_without_a_calibration_is_refused() {
        let config = SpeedConfig {
            start_on_plan: true,
            ..SpeedConfig::default()
        };
        let e = config.validate("t.toml").expect_err("refused").to_string();
        assert!(
            e.contains("speed.start_on_plan") && e.contains("walked_mps"),
            "{e}"
        );
        let config = SpeedConfig {
            walked_mps: vec![0.16, 0.2],
            ..config
        };
        assert!(config.validate("t.toml").is_ok());
    }

    /// A lean gain without a limit, a limit past 0.5 rad, or a fade that does not rise is
    /// refused naming the field and the value; the treadmill config's options pass.
    #[test]
    fn a_step_lean_that_could_not_act_as_set_is_refused() {
        let options = SpeedConfig {
            step_lean_gain_rad_per_mps: 0.2,
            slow_step_lean_gain_rad_per_mps: 0.1,
            max_step_lean_rad: 0.006,
            step_lean_from_mps: 0.16,
            step_lean_full_mps: 0.22,
            ..SpeedConfig::default()
        };
        assert!(options.validate("t.toml").is_ok());
        let cases = [
            (
                "speed.max_step_lean_rad",
                "0",
                SpeedConfig {
                    max_step_lean_rad: 0.0,
                    ..options.clone()
                },
            ),
            (
                "speed.max_step_lean_rad",
                "0.6",
                SpeedConfig {
                    max_step_lean_rad: 0.6,
                    ..options.clone()
                },
            ),
            (
                "speed.step_lean_from_mps",
                "0.22",
                SpeedConfig {
                    step_lean_from_mps: 0.22,
                    ..options.clone()
                },
            ),
            (
                "speed.step_lean_from_mps",
                "0.1",
                SpeedConfig {
                    step_lean_from_mps: 0.1,
                    step_lean_full_mps: 0.0,
                    ..options.clone()
                },
            ),
        ];
        for (field, value, c) in cases {
            let e = c.validate("t.toml").expect_err("refused").to_string();
            assert!(
                e.contains("t.toml") && e.contains(field) && e.contains(value),
                "{e}"
            );
        }
        // In full at every speed (both 0), and off (no gain, no limit): accepted.
        let everywhere = SpeedConfig {
            step_lean_from_mps: 0.0,
            step_lean_full_mps: 0.0,
            ..options
        };
        assert!(everywhere.validate("t.toml").is_ok());
        assert!(SpeedConfig::default().validate("t.toml").is_ok());
    }

    #[test]
    fn a_calibration_that_does_not_increase_is_refused_naming_the_entry() {
        let c = SpeedConfig {
            walked_mps: vec![0.15, 0.2, 0.2],
            ..SpeedConfig::default()
        };
        let e = c.validate("t.toml").expect_err("refused").to_string();
        assert!(e.contains("speed.walked_mps[2]"), "{e}");
        let c = SpeedConfig {
            walked_mps: vec![f64::NAN],
            ..SpeedConfig::default()
        };
        assert!(c.validate("t.toml").is_err());
        let c = SpeedConfig {
            walked_mps: vec![0.16, 0.2, 0.3],
            below_library_mps: 0.01,
            ..SpeedConfig::default()
        };
        assert!(c.validate("t.toml").is_ok());
    }
}
