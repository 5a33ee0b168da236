//! The step-back catch's pendulum (`runtime::control::recovery`, "The step-back catch"): in
//! double support the centre of mass follows an inverted pendulum about a pivot between the
//! feet, which stops a robot moving back and carries it forward again.

use super::double_support::quintic;
use crate::estimator::GRAVITY_MPS2;

/// The catch's pivot sits this fraction of the way from the rear foot to the front foot ...
pub(super) const CATCH_PIVOT_FRACTION: f64 = 0.5;
/// ... or further back, so that the centre of mass's divergent component `x + v/ω` starts at
/// least this far ahead of it, m (else the pendulum would carry it back past the pivot) ...
pub(super) const CATCH_MIN_LEAD_M: f64 = 0.02;
/// ... but no closer than this to the rear foot, m (else no catch).
pub(super) const CATCH_REAR_MARGIN_M: f64 = 0.01;
/// The torso lowers, if the rear foot needs it, over this long, s.
pub(super) const CATCH_LOWER_S: f64 = 0.25;

/// The catch proper, in double support: the centre of mass follows an inverted pendulum about
/// a pivot between the feet, `x'' = ω²(x − p)` (the centre of pressure held at `p`), which
/// stops its backward motion and carries it forward.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Pendulum {
    /// The pivot, relative to the stance (front) foot, m.
    pub(super) pivot_x_m: f64,
    /// √(g/z) of the centre of mass's height at the start, 1/s.
    pub(super) omega_per_s: f64,
    /// The centre of mass's x and forward rate at the start, m and m/s.
    pub(super) x0_m: f64,
    pub(super) v0_mps: f64,
    /// The centre of mass ahead of the torso origin, m (held from the start).
    pub(super) com_ahead_m: f64,
}

impl Pendulum {
    /// The pendulum of a centre of mass at `x0_m` moving at `v0_mps`, `height_m` above the
    /// feet, the rear foot at `rear_x_m` (the front foot at 0), `com_ahead_m` ahead of the
    /// torso origin. `None` if no pivot at least [`CATCH_REAR_MARGIN_M`] ahead of the rear
    /// foot stops it.
    pub(super) fn new(
        (x0_m, v0_mps): (f64, f64),
        height_m: f64,
        rear_x_m: f64,
        com_ahead_m: f64,
    ) -> Option<Self> {
        if !(height_m > 0.0 && rear_x_m < 0.0 && x0_m.is_finite() && v0_mps.is_finite()) {
            return None;
        }
        let omega_per_s = (GRAVITY_MPS2 / height_m).sqrt();
        let divergent = x0_m + v0_mps / omega_per_s;
        let pivot_x_m = (rear_x_m * (1.0 - CATCH_PIVOT_FRACTION)).min(divergent - CATCH_MIN_LEAD_M);
        (pivot_x_m >= rear_x_m + CATCH_REAR_MARGIN_M).then_some(Self {
            pivot_x_m,
            omega_per_s,
            x0_m,
            v0_mps,
            com_ahead_m,
        })
    }

    /// The torso's x (the centre of mass's less its offset) and forward rate `t_s` into the
    /// catch, m and m/s.
    pub(super) fn at(&self, t_s: f64) -> (f64, f64) {
        let w = self.omega_per_s;
        let (s, c) = ((w * t_s).sinh(), (w * t_s).cosh());
        let d = self.x0_m - self.pivot_x_m;
        (
            self.pivot_x_m + d * c + self.v0_mps / w * s - self.com_ahead_m,
            d * w * s + self.v0_mps * c,
        )
    }
}

/// The torso's motion in the catch proper: its x on the [`Pendulum`], its height lowered (if
/// the rear foot needs it) from `z0_m` to `z1_m` on a minimum-jerk ramp over
/// [`CATCH_LOWER_S`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Catch {
    pub(super) pendulum: Pendulum,
    /// The torso's height at the start and once lowered, m.
    pub(super) z0_m: f64,
    pub(super) z1_m: f64,
}

impl Catch {
    /// The torso's x and forward rate `t_s` into the catch, m and m/s.
    pub(super) fn at(&self, t_s: f64) -> (f64, f64) {
        self.pendulum.at(t_s)
    }

    /// The torso's height and its rate `t_s` into the catch, m and m/s.
    pub(super) fn height(&self, t_s: f64) -> (f64, f64) {
        quintic(self.z0_m, 0.0, self.z1_m, 0.0, CATCH_LOWER_S, t_s)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The pendulum of a robot 0.05 m ahead of its rear foot moving back at 0.1 m/s.
    fn moving_back() -> Catch {
        Catch {
            pendulum: Pendulum::new((-0.05, -0.1), 0.78, -0.17, -0.004).unwrap(),
            z0_m: 0.69,
            z1_m: 0.68,
        }
    }

    #[test]
    fn the_catch_starts_at_the_measured_state_and_follows_its_pendulum() {
        let c = moving_back();
        // At its start: the measured centre of mass less its offset, at the measured rate.
        let (x, v) = c.at(0.0);
        assert!((x - (-0.05 + 0.004)).abs() < 1e-12 && (v + 0.1).abs() < 1e-12);
        // x'' = ω²(x − p) at every time (central second difference, 1e-4 s: truncation
        // error ~ h²·ω⁴·|x|/12, far below 1e-6 m/s²); ẋ is the derivative of x.
        let h = 1e-4;
        for k in 0..8 {
            let t = 0.1 * f64::from(k);
            let x = |t: f64| c.at(t).0 + c.pendulum.com_ahead_m;
            let xdd = (x(t + h) - 2.0 * x(t) + x(t - h)) / (h * h);
            let want = c.pendulum.omega_per_s.powi(2) * (x(t) - c.pendulum.pivot_x_m);
            assert!((xdd - want).abs() < 1e-4, "t {t}: {xdd} vs {want}");
            let xd = (x(t + h) - x(t - h)) / (2.0 * h);
            assert!((xd - c.at(t).1).abs() < 1e-8, "t {t}");
        }
    }

    #[test]
    fn the_catch_stops_the_backward_motion_ahead_of_its_pivot_and_carries_the_robot_forward() {
        let c = moving_back();
        // The pivot halfway to the rear foot, or further back so the divergent component
        // leads it by CATCH_MIN_LEAD_M: here −0.085 m and x + v/ω = −0.0782 m.
        let divergent = c.pendulum.x0_m + c.pendulum.v0_mps / c.pendulum.omega_per_s;
        assert!(
            c.pendulum.pivot_x_m <= -0.085 + 1e-12
                && c.pendulum.pivot_x_m <= divergent - CATCH_MIN_LEAD_M
        );
        assert!(c.pendulum.pivot_x_m >= -0.17 + CATCH_REAR_MARGIN_M);
        // The rate crosses zero once, with the centre of mass still ahead of the pivot, and
        // grows forward after.
        let samples: Vec<(f64, f64)> = (0..=800).map(|k| c.at(f64::from(k) * 1e-3)).collect();
        let turn = samples.iter().position(|&(_, v)| v > 0.0).unwrap();
        assert!(turn > 0 && samples[turn..].windows(2).all(|w| w[1].1 > w[0].1));
        let lowest = samples
            .iter()
            .map(|&(x, _)| x + c.pendulum.com_ahead_m)
            .fold(f64::MAX, f64::min);
        assert!(
            lowest > c.pendulum.pivot_x_m,
            "{lowest} vs {}",
            c.pendulum.pivot_x_m
        );
        assert!(samples[800].1 > 0.2, "{:?}", samples[800]);
        // The torso lowers from z0 to z1 on a minimum-jerk ramp and stays.
        assert_eq!(c.height(0.0), (0.69, 0.0));
        assert!((c.height(CATCH_LOWER_S).0 - 0.68).abs() < 1e-12);
        assert_eq!(c.height(1.0), (0.68, 0.0));
    }

    #[test]
    fn no_catch_when_no_pivot_ahead_of_the_rear_foot_stops_the_robot() {
        // 0.05 m ahead of the rear foot, the pivot at most 0.04 m behind the centre of mass
        // (CATCH_REAR_MARGIN_M), which its divergent component must lead by
        // CATCH_MIN_LEAD_M: caught if moving back slower than (0.04 − 0.02)·ω ≈ 0.071 m/s
        // (ω = √(g/0.78 m) ≈ 3.55/s).
        assert!(Pendulum::new((-0.12, -0.065), 0.78, -0.17, 0.0).is_some());
        assert!(Pendulum::new((-0.12, -0.075), 0.78, -0.17, 0.0).is_none());
        // Nonsense in, no catch out.
        assert!(Pendulum::new((-0.05, f64::NAN), 0.78, -0.17, 0.0).is_none());
        assert!(Pendulum::new((-0.05, -0.1), 0.78, 0.1, 0.0).is_none());
    }
}
