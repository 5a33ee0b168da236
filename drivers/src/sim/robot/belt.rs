//! The treadmill's belt: its speed (steps, and ramps toward a target at a set acceleration),
//! its travel in the world, and its ends.
//!
//! The robot is integrated in the frame that moves with the belt's surface (see the robot
//! module docs, "Treadmill"). At a constant belt speed that frame is inertial; while the belt
//! ramps it accelerates at `−a_belt` (world x, the surface moving backwards faster), and every
//! body feels the inertial force `+m·a_belt` forward. Its generalized force is
//! `a_belt · D(q)[:, x]`: the base's x coordinate translates every body alike, so the x column
//! of `D` is `Σ m_i ∂x_com,i/∂q` exactly.

/// An end of the belt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BeltEnd {
    /// Behind the robot (where the belt carries a robot that walks too slowly).
    Back,
    /// In front of the robot.
    Front,
}

/// The belt's state (world frame: x forward, the surface moving backwards at `speed_mps`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Belt {
    /// Present speed of the surface, backwards \[m/s\].
    pub(super) speed_mps: f64,
    /// Speed the belt ramps toward \[m/s\].
    pub(super) target_mps: f64,
    /// Ramp acceleration \[m/s²\].
    pub(super) ramp_mps2: f64,
    /// Belt length \[m\] (infinite: endless).
    pub(super) length_m: f64,
    /// World x of the belt's centre \[m\].
    pub(super) centre_x_m: f64,
    /// World x of the belt frame's origin at `since_t_s` \[m\].
    offset0_m: f64,
    /// Since when the speed has been constant \[s\].
    since_t_s: f64,
}

impl Belt {
    /// A belt at `speed_mps`, its frame's origin at the world's.
    pub(super) fn new(speed_mps: f64, ramp_mps2: f64, length_m: f64) -> Self {
        Self {
            speed_mps,
            target_mps: speed_mps,
            ramp_mps2,
            length_m,
            centre_x_m: 0.0,
            offset0_m: 0.0,
            since_t_s: 0.0,
        }
    }

    /// World displacement of the belt frame at `t_s`: `−∫ v_belt dt` \[m\] (exact between
    /// changes of speed, which re-anchor it).
    pub(super) fn offset_m(&self, t_s: f64) -> f64 {
        self.offset0_m - self.speed_mps * (t_s - self.since_t_s)
    }

    /// The belt's mean acceleration over the next `h` seconds toward its target \[m/s²\]: the
    /// ramp, or less on the step that reaches the target; 0 at the target.
    pub(super) fn acceleration_over(&self, h: f64) -> f64 {
        let dv = self.target_mps - self.speed_mps;
        if dv == 0.0 {
            0.0
        } else {
            (dv / h).clamp(-self.ramp_mps2, self.ramp_mps2)
        }
    }

    /// Advance from `t_s` by `tau_s` at the acceleration `a_mps2` (of
    /// [`Self::acceleration_over`]); nothing changes at zero acceleration.
    pub(super) fn advance(&mut self, t_s: f64, tau_s: f64, a_mps2: f64) {
        if a_mps2 == 0.0 {
            return;
        }
        let offset = self.offset_m(t_s) - tau_s * (self.speed_mps + 0.5 * a_mps2 * tau_s);
        self.speed_mps += a_mps2 * tau_s;
        if (self.target_mps - self.speed_mps).abs() <= 1e-12 {
            self.speed_mps = self.target_mps;
        }
        self.offset0_m = offset;
        self.since_t_s = t_s + tau_s;
    }

    /// Step the speed to `speed_mps` at `t_s` (and the target with it).
    pub(super) fn step_to(&mut self, t_s: f64, speed_mps: f64) {
        self.offset0_m = self.offset_m(t_s);
        self.since_t_s = t_s;
        self.speed_mps = speed_mps;
        self.target_mps = speed_mps;
    }

    /// The end a point at world `x_m` is beyond, if any.
    pub(super) fn beyond(&self, x_m: f64) -> Option<BeltEnd> {
        let half = 0.5 * self.length_m;
        if x_m < self.centre_x_m - half {
            Some(BeltEnd::Back)
        } else if x_m > self.centre_x_m + half {
            Some(BeltEnd::Front)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ramp_reaches_its_target_at_the_set_acceleration_and_travels_its_area() {
        let mut b = Belt::new(0.2, 0.5, 1.6);
        b.target_mps = 0.3;
        let h = 1e-4;
        let mut t = 0.0;
        while b.speed_mps != b.target_mps {
            let a = b.acceleration_over(h);
            assert!(a > 0.0 && a <= 0.5);
            b.advance(t, h, a);
            t += h;
            assert!(t < 1.0, "never reached the target");
        }
        // 0.1 m/s at 0.5 m/s² takes 0.2 s (2000 steps of 0.1 ms, the last one partial).
        assert!((t - 0.2).abs() < 1.5 * h, "{t}");
        // Travel: the trapezoid 0.2 s × 0.25 m/s mean = 0.05 m backwards.
        assert!((b.offset_m(t) + 0.05).abs() < 1e-9, "{}", b.offset_m(t));
        // Then constant: 0.3 m/s.
        assert!((b.offset_m(t + 1.0) - b.offset_m(t) + 0.3).abs() < 1e-12);
        assert_eq!(b.acceleration_over(h), 0.0);
    }

    #[test]
    fn the_ends_are_half_a_length_from_the_centre() {
        let mut b = Belt::new(0.0, 0.5, 1.6);
        b.centre_x_m = 1.0;
        assert_eq!(b.beyond(1.79), None);
        assert_eq!(b.beyond(0.21), None);
        assert_eq!(b.beyond(1.81), Some(BeltEnd::Front));
        assert_eq!(b.beyond(0.19), Some(BeltEnd::Back));
        let endless = Belt::new(0.0, 0.5, f64::INFINITY);
        assert_eq!(endless.beyond(-1e9), None);
    }
}
