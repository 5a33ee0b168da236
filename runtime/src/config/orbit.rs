//! The `[orbit]` section: the within-step orbit lever (`runtime::control::orbit`).

use crate::RuntimeError;
use serde::{Deserialize, Serialize};

/// The orbit lever: each tick of a step, the torso leans (both hips together) by
/// δ = clamp(`gain_rad_per_mps` · (σ*(τ) − σ)/(M·L), ±`max_lean_rad`), faded out from
/// `fade_from_phase` to the impact and rate-limited to `max_lean_rate_rad_s`; σ is the angular
/// momentum about the stance foot and σ* the planned orbit's at the same phase.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrbitConfig {
    /// Whether the lever acts (false: the gait's outputs alone, as before it).
    pub enabled: bool,
    /// Lean per m/s of the orbit's velocity error (σ* − σ)/(M·L), rad/(m/s) = rad·s/m.
    pub gain_rad_per_mps: f64,
    /// The lean stays within ± this, rad.
    pub max_lean_rad: f64,
    /// The lean changes by at most this much per second, rad/s.
    pub max_lean_rate_rad_s: f64,
    /// From this phase on the lean fades out (minimum jerk) to 0 at the impact, in (0, 1].
    pub fade_from_phase: f64,
    /// The measured momentum about the stance foot is low-passed at this frequency, Hz (the
    /// joint rates' noise is as large as the signal).
    pub sigma_filter_hz: f64,
    /// Whether the lever also acts while the treadmill speed control switches library gaits
    /// (default false: measured worse there, `runtime::control::orbit`).
    #[serde(default)]
    pub with_speed_control: bool,
}

impl Default for OrbitConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            gain_rad_per_mps: 0.1,
            max_lean_rad: 0.15,
            max_lean_rate_rad_s: 0.5,
            fade_from_phase: 0.8,
            sigma_filter_hz: 5.0,
            with_speed_control: false,
        }
    }
}

impl OrbitConfig {
    /// Finite, non-negative gains and limits, a fade within (0, 1]; errors name `origin`, the
    /// field and the value.
    pub fn validate(&self, origin: &str) -> crate::Result<()> {
        let bad = |field: &str, v: f64, reason: &str| RuntimeError::InvalidField {
            origin: origin.to_string(),
            field: field.into(),
            value: v.to_string(),
            reason: reason.into(),
        };
        for (field, v) in [
            ("orbit.gain_rad_per_mps", self.gain_rad_per_mps),
            ("orbit.max_lean_rad", self.max_lean_rad),
            ("orbit.max_lean_rate_rad_s", self.max_lean_rate_rad_s),
            ("orbit.sigma_filter_hz", self.sigma_filter_hz),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(field, v, "must be finite and not negative"));
            }
        }
        if self.max_lean_rad > 0.5 {
            return Err(bad(
                "orbit.max_lean_rad",
                self.max_lean_rad,
                "must be at most 0.5 rad (a larger lean takes the torso far off the gait's pose)",
            ));
        }
        if !(self.fade_from_phase > 0.0 && self.fade_from_phase <= 1.0) {
            return Err(bad(
                "orbit.fade_from_phase",
                self.fade_from_phase,
                "must be within (0, 1]",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Spoil = fn(&mut OrbitConfig);

    #[test]
    fn bad_orbit_gains_are_refused_naming_the_field_and_value() {
        let cases: [(&str, Spoil); 4] = [
            ("orbit.gain_rad_per_mps", |c| c.gain_rad_per_mps = f64::NAN),
            ("orbit.max_lean_rad", |c| c.max_lean_rad = 0.8),
            ("orbit.max_lean_rate_rad_s", |c| {
                c.max_lean_rate_rad_s = -1.0
            }),
            ("orbit.fade_from_phase", |c| c.fade_from_phase = 0.0),
        ];
        for (field, spoil) in cases {
            let mut c = OrbitConfig::default();
            spoil(&mut c);
            let e = c.validate("adam.toml").expect_err("refused").to_string();
            assert!(e.contains("adam.toml") && e.contains(field), "{e}");
        }
        assert!(OrbitConfig::default().validate("adam.toml").is_ok());
    }
}
