//! Where each variable lives in x ([`Layout`]), and the scales of the acceleration and torque
//! variables.

/// q̈ = `ACC_SCALE` × its variable.
pub const ACC_SCALE: f64 = 10.0;
/// u = `TORQUE_SCALE` × its variable.
pub const TORQUE_SCALE: f64 = 10.0;

/// Where each variable lives in x.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Reduced coordinates.
    pub nq: usize,
    /// Actuators.
    pub nu: usize,
    /// Outputs.
    pub m: usize,
    /// Bézier degree.
    pub degree: usize,
    /// Intervals N.
    pub intervals: usize,
    /// Variables per point.
    pub stride: usize,
    /// Design variables (0, or 2 in a co-design: thigh and shin length, m).
    pub design: usize,
    /// Whether each point has the power slacks p, n (the cost-of-transport problem does; the
    /// feasibility problem, which has no cost on them, does not).
    pub slacks: bool,
    /// The nodes' times as fractions of the step duration T: N + 1 increasing values from 0
    /// to 1 ([`mesh_nodes`]); interval i spans `mesh[i]..mesh[i + 1]`.
    pub mesh: Vec<f64>,
}

/// The node times of N intervals, as fractions of the step duration: s(i/N) with
/// s(u) = u − g sin(2πu)/(2π) for the grading g ∈ [0, 1) (`[collocation] mesh_grading`).
/// g = 0 is the uniform mesh; with g > 0 the first and last intervals are 1 − g times the
/// uniform length and the middle ones up to 1 + g times, because Hermite–Simpson's local
/// error (∝ h⁵) on a gait is largest at the step's ends (planner/CODESIGN.md, "Plan accuracy").
pub fn mesh_nodes(intervals: usize, grading: f64) -> Vec<f64> {
    let two_pi = 2.0 * std::f64::consts::PI;
    (0..=intervals)
        .map(|i| {
            if i == intervals {
                return 1.0;
            }
            let u = i as f64 / intervals as f64;
            u - grading * (two_pi * u).sin() / two_pi
        })
        .collect()
}

impl Layout {
    /// Number of points, 2N + 1.
    pub fn points(&self) -> usize {
        2 * self.intervals + 1
    }
    /// First index of q_r at point k.
    pub fn q(&self, k: usize) -> usize {
        k * self.stride
    }
    /// First index of q̇_r at point k.
    pub fn dq(&self, k: usize) -> usize {
        k * self.stride + self.nq
    }
    /// First index of the scaled q̈_r at point k.
    pub fn ddq(&self, k: usize) -> usize {
        k * self.stride + 2 * self.nq
    }
    /// First index of the scaled u at point k.
    pub fn u(&self, k: usize) -> usize {
        k * self.stride + 3 * self.nq
    }
    /// First index of the positive power parts at point k.
    pub fn p(&self, k: usize) -> usize {
        k * self.stride + 3 * self.nq + self.nu
    }
    /// First index of the negative power parts at point k.
    pub fn n(&self, k: usize) -> usize {
        k * self.stride + 3 * self.nq + 2 * self.nu
    }
    /// Index of the phase τ at point k (followed by τ̇ and τ̈): lifted variables, so that the
    /// costly stance-leg kinematics is differentiated once per point, not once per output.
    pub fn tau(&self, k: usize) -> usize {
        k * self.stride + self.stride - 3
    }
    /// Number of variables of the same problem without power slacks (the feasibility layout).
    pub fn len_without_slacks(&self) -> usize {
        if self.slacks {
            self.len() - 2 * self.nu * self.points()
        } else {
            self.len()
        }
    }

    /// A point of the layout without power slacks (`x`, [`Self::len_without_slacks`] long)
    /// in this one, with p = n = 0 (see [`HzdProblem::centre_power_slacks`]). An `x` of
    /// another length (or a layout without slacks) is an error naming both lengths.
    ///
    /// [`HzdProblem::centre_power_slacks`]: super::HzdProblem::centre_power_slacks
    pub fn with_slacks(&self, x: &[f64]) -> crate::Result<Vec<f64>> {
        let expected = self.len_without_slacks();
        if !self.slacks || x.len() != expected {
            return Err(crate::PlannerError::Solver(format!(
                "a point without power slacks has {expected} variables here, this one {}{}",
                x.len(),
                if self.slacks {
                    ""
                } else {
                    " (and this layout has no slacks to add)"
                }
            )));
        }
        let short = self.stride - 2 * self.nu;
        let mut out = vec![0.0; self.len()];
        for k in 0..self.points() {
            let (a, b) = (k * short, k * self.stride);
            out[b..b + 3 * self.nq + self.nu].copy_from_slice(&x[a..a + 3 * self.nq + self.nu]);
            out[b + self.stride - 3..b + self.stride].copy_from_slice(&x[a + short - 3..a + short]);
        }
        let (ga, gb) = (self.points() * short, self.points() * self.stride);
        out[gb..].copy_from_slice(&x[ga..]);
        Ok(out)
    }
    fn globals(&self) -> usize {
        self.points() * self.stride
    }
    /// Index of `α[o][j]`.
    pub fn alpha(&self, o: usize, j: usize) -> usize {
        self.globals() + o * (self.degree + 1) + j
    }
    /// Index of θ⁺.
    pub fn theta_plus(&self) -> usize {
        self.globals() + self.m * (self.degree + 1)
    }
    /// Index of θ⁻.
    pub fn theta_minus(&self) -> usize {
        self.theta_plus() + 1
    }
    /// Index of the step duration T.
    pub fn duration(&self) -> usize {
        self.theta_plus() + 2
    }
    /// Index of the step length d.
    pub fn length(&self) -> usize {
        self.theta_plus() + 3
    }
    /// Index of design variable i (0: thigh length, 1: shin length, m) in a co-design.
    pub fn design_var(&self, i: usize) -> usize {
        self.theta_plus() + 4 + i
    }
    /// Number of variables.
    pub fn len(&self) -> usize {
        self.theta_plus() + 4 + self.design
    }
    /// Whether there are no variables (never).
    pub fn is_empty(&self) -> bool {
        false
    }
    /// Interval i's share of the step duration (its h is T times this).
    pub fn interval_fraction(&self, i: usize) -> f64 {
        self.mesh[i + 1] - self.mesh[i]
    }

    /// Point k's time as a fraction of the step duration (a midpoint halfway through its
    /// interval).
    pub fn time_fraction(&self, k: usize) -> f64 {
        let i = k / 2;
        if k % 2 == 0 {
            self.mesh[i]
        } else {
            0.5 * (self.mesh[i] + self.mesh[i + 1])
        }
    }

    /// Simpson weight c_k of point k in ∫ ≈ T/(6N) Σ c_k f_k: on a uniform mesh 1, 4, 2, …,
    /// 4, 1; on a graded one each interval's 1, 4, 1 scaled by N times its fraction of T.
    pub fn simpson_weight(&self, k: usize) -> f64 {
        let n = self.intervals as f64;
        let i = k / 2;
        if k % 2 == 1 {
            4.0 * n * self.interval_fraction(i)
        } else {
            let before = if i > 0 {
                self.interval_fraction(i - 1)
            } else {
                0.0
            };
            let after = if i < self.intervals {
                self.interval_fraction(i)
            } else {
                0.0
            };
            n * (before + after)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout(intervals: usize, grading: f64) -> Layout {
        Layout {
            nq: 1,
            nu: 1,
            m: 1,
            degree: 2,
            intervals,
            stride: 7,
            design: 0,
            slacks: false,
            mesh: mesh_nodes(intervals, grading),
        }
    }

    /// The graded mesh runs from 0 to 1, increasing, with end intervals 1 − g times the uniform
    /// length; grading 0 is the uniform mesh.
    #[test]
    fn the_graded_mesh_is_increasing_and_shortest_at_the_ends() {
        for g in [0.0, 0.5, 0.8, MAX_GRADING_FOR_TESTS] {
            let l = layout(20, g);
            assert_eq!((l.mesh[0], l.mesh[20]), (0.0, 1.0));
            assert!((0..20).all(|i| l.interval_fraction(i) > 0.0), "{g}");
            let end = l.interval_fraction(0) * 20.0;
            // s(1/N)·N = 1 − g·sin(2π/N)/(2π/N): 1 − g to within 1.7 % of g at N = 20.
            assert!((end - (1.0 - g)).abs() < 0.017 * g + 1e-12, "{g}: {end}");
            assert!((l.interval_fraction(19) - l.interval_fraction(0)).abs() < 1e-12);
            assert!(l.interval_fraction(10) >= l.interval_fraction(0));
        }
        let u = layout(20, 0.0);
        assert!((0..20).all(|i| (u.interval_fraction(i) - 0.05).abs() < 1e-15));
        assert_eq!(u.time_fraction(3), 0.5 * (u.mesh[1] + u.mesh[2]));
    }

    /// Simpson's weights integrate cubics exactly on any mesh: Σ c_k f(t_k) T/(6N) = ∫₀ᵀ f.
    #[test]
    fn simpson_weights_integrate_cubics_exactly_on_a_graded_mesh() {
        for g in [0.0, 0.8] {
            let l = layout(7, g);
            let t_s = 0.9;
            let f = |t: f64| 1.0 - 2.0 * t + 3.0 * t * t - 4.0 * t * t * t;
            let sum: f64 = (0..l.points())
                .map(|k| l.simpson_weight(k) * f(t_s * l.time_fraction(k)))
                .sum();
            let quad = sum * t_s / (6.0 * l.intervals as f64);
            let exact = t_s - t_s.powi(2) + t_s.powi(3) - t_s.powi(4);
            assert!((quad - exact).abs() < 1e-13, "{g}: {quad} vs {exact}");
        }
        let u = layout(3, 0.0);
        let weights: Vec<f64> = (0..u.points()).map(|k| u.simpson_weight(k)).collect();
        for (w, expected) in weights.iter().zip([1.0, 4.0, 2.0, 4.0, 2.0, 4.0, 1.0]) {
            assert!((w - expected).abs() < 1e-14, "{weights:?}");
        }
    }

    const MAX_GRADING_FOR_TESTS: f64 = crate::config::MAX_MESH_GRADING;
}
