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
    /// Simpson weight of point k in ∫ ≈ h/6 Σ c_k f_k.
    pub fn simpson_weight(&self, k: usize) -> f64 {
        if k % 2 == 1 {
            4.0
        } else if k == 0 || k == 2 * self.intervals {
            1.0
        } else {
            2.0
        }
    }
}
