//! What the verification reports ([`VerifyReport`]) and what fails it: no fixed point, an
//! unstable orbit, an orbit that is not the planned one ([`CONSISTENCY_TOLERANCE_RAD`],
//! [`STEP_DURATION_TOLERANCE`]), and the planner's promise of [`PLAN_ACCURACY`].

use std::fmt;

/// Largest joint difference between the closed-loop fixed point and the planned post-impact
/// state for the gait to count as the planned one, rad (about 3°: collocation error with N = 20
/// is near 1e-3 rad; a different orbit is off by tenths of a radian).
pub const CONSISTENCY_TOLERANCE_RAD: f64 = 0.05;

/// Largest relative difference between the step duration of the closed-loop fixed point and the
/// planned one for the gait to count as the planned one (under any feedback law, the runtime's
/// joint PD included; the planner's own promise under the paper's controller is the tighter
/// [`PLAN_ACCURACY`]). The fixed point's speed is sensitive: the plan's collocation error,
/// amplified by 1/(1 − |λ|max), moves it; on a uniform mesh of 20 intervals ADAM's plan
/// (|λ|max 0.86) stepped in 0.991 s at its fixed point against 0.900 s planned (10 %), on the
/// default graded mesh in 0.904 s (0.5 %). 20 % rejects a gait whose joints match but whose
/// pace does not (a 0.005 rad shift of the swing hip's Bézier coefficients: ~0.5 s).
pub const STEP_DURATION_TOLERANCE: f64 = 0.2;

/// What the verification found.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyReport {
    /// Residual |P(x*) − x*|∞ at the fixed point.
    pub fixed_point_residual: f64,
    /// Newton iterations used.
    pub newton_iterations: usize,
    /// Eigenvalues of DP at the fixed point, (re, im), sorted by decreasing modulus.
    pub eigenvalues: Vec<(f64, f64)>,
    /// Largest |λ|.
    pub spectral_radius: f64,
    /// Largest joint difference between the fixed point and the gait's planned x⁺, rad.
    pub max_joint_difference_rad: f64,
    /// Largest |y| (joint minus desired output) along the simulated step, rad.
    pub max_output_error_rad: f64,
    /// |P(x_plan) − x_plan|∞: how periodic the planned post-impact state is in closed loop.
    pub planned_state_residual: f64,
    /// Simulated step duration at the fixed point, s (planned in the gait file).
    pub step_duration_s: f64,
    /// Simulated step length, m.
    pub step_length_m: f64,
    /// The apex margin of the orbit ([`apex_margin`]): the fraction of its post-impact angular
    /// momentum the step can lose and still carry the robot over the stance foot.
    pub apex_margin: f64,
    /// The step the gait file plans.
    pub planned_step: StepFigures,
    /// One closed-loop step from the planned x⁺: the planned step as the closed loop walks it.
    pub step_from_plan: StepFigures,
}

/// How long and how far one step is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepFigures {
    /// Step duration, s.
    pub duration_s: f64,
    /// Step length, m.
    pub length_m: f64,
}

impl VerifyReport {
    /// Stable and consistent: the fixed point exists to `tol`, every |λ| < 1, and the orbit is
    /// the planned one (joints within [`CONSISTENCY_TOLERANCE_RAD`] of the planned x⁺, steps
    /// within [`STEP_DURATION_TOLERANCE`] of the planned duration).
    pub fn passed(&self, tol: f64) -> bool {
        self.failures(tol).is_empty()
    }

    /// What fails the check, one sentence each with the figure and its limit (empty: passed).
    pub fn failures(&self, tol: f64) -> Vec<String> {
        let mut failed = Vec::new();
        if !below(self.fixed_point_residual, tol) {
            failed.push(format!(
                "no periodic orbit: fixed-point residual {:.2e} (limit {tol:.0e})",
                self.fixed_point_residual
            ));
        }
        if !below(self.spectral_radius, 1.0) {
            failed.push(format!("unstable: |λ|max {:.4} ≥ 1", self.spectral_radius));
        }
        if !below(self.max_joint_difference_rad, CONSISTENCY_TOLERANCE_RAD) {
            failed.push(format!(
                "not the planned orbit: its joints are {:.4} rad from the planned x⁺ (limit \
                 {CONSISTENCY_TOLERANCE_RAD} rad)",
                self.max_joint_difference_rad
            ));
        }
        let planned_s = self.planned_step.duration_s;
        let off = (self.step_duration_s - planned_s).abs() / planned_s;
        if !below(off, STEP_DURATION_TOLERANCE) {
            failed.push(format!(
                "not the planned pace: the orbit steps in {:.4} s, the plan in {planned_s:.4} s \
                 ({:.0} % off, limit {:.0} %)",
                self.step_duration_s,
                100.0 * off,
                100.0 * STEP_DURATION_TOLERANCE
            ));
        }
        failed
    }
}

/// What the planner promises of a plan: the verified periodic orbit's step duration and step
/// length within this fraction of the planned ones (issue #28 item 5; planner/CODESIGN.md,
/// "Plan accuracy").
pub const PLAN_ACCURACY: f64 = 0.01;

impl VerifyReport {
    /// (orbit − plan)/plan of the step duration and of the step length at the fixed point.
    pub fn plan_mismatch(&self) -> (f64, f64) {
        let planned = self.planned_step;
        (
            self.step_duration_s / planned.duration_s - 1.0,
            self.step_length_m / planned.length_m - 1.0,
        )
    }

    /// What breaks [`PLAN_ACCURACY`], one sentence each with the figure (empty: the orbit is
    /// the plan within it).
    pub fn accuracy_failures(&self) -> Vec<String> {
        let (duration, length) = self.plan_mismatch();
        let mut failed = Vec::new();
        for (what, off, orbit, plan, unit) in [
            (
                "step duration",
                duration,
                self.step_duration_s,
                self.planned_step.duration_s,
                "s",
            ),
            (
                "step length",
                length,
                self.step_length_m,
                self.planned_step.length_m,
                "m",
            ),
        ] {
            if !below(off.abs(), PLAN_ACCURACY) {
                failed.push(format!(
                    "the orbit's {what} is {orbit:.4} {unit}, the plan's {plan:.4} {unit} \
                     ({:+.2} %, limit ±{:.0} %)",
                    100.0 * off,
                    100.0 * PLAN_ACCURACY
                ));
            }
        }
        failed
    }
}

/// The apex margin of a step from the angular momentum about the stance foot at its start,
/// σ⁺, and its smallest value over the top, σ_min (kg·m²/s, same sign): the fraction of σ⁺ an
/// impact may take away and the robot still pass over the stance foot, 1 − √(1 − (σ_min/σ⁺)²).
///
/// Why: on the gait's zero dynamics σ̇ = m·g·x_c and θ̇ = σ/I(θ), so d(σ²)/dθ depends on θ
/// alone and σ² − σ*²(θ) stays constant along a step. A step that starts with k·σ⁺ reaches
/// σ² = σ_min² − (1 − k²)·σ⁺² at the top, which is positive only while k > √(1 − (σ_min/σ⁺)²).
/// NaN if σ⁺ is zero or the two have opposite signs (the orbit stops or runs back).
pub fn apex_margin(start_momentum: f64, min_momentum: f64) -> f64 {
    let ratio = min_momentum / start_momentum;
    if ratio.is_finite() && (0.0..=1.0).contains(&ratio) {
        1.0 - (1.0 - ratio * ratio).sqrt()
    } else {
        f64::NAN
    }
}

/// Largest difference of the joint angles (reduced coordinates 1..nq: the torso pitch, 0, is
/// left out) between two reduced states, rad; NaN if either has a NaN there, so that the checks
/// made with [`below`] fail on it (`f64::max` would drop the NaN).
pub(super) fn joint_distance(x: &[f64], planned: &[f64], nq: usize) -> f64 {
    (1..nq)
        .map(|i| (x[i] - planned[i]).abs())
        .fold(
            0.0,
            |worst, d| if d.is_nan() || d > worst { d } else { worst },
        )
}

/// `value < limit`, false for NaN: a check that cannot be computed fails.
pub(super) fn below(value: f64, limit: f64) -> bool {
    value < limit
}

impl fmt::Display for VerifyReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "fixed-point residual      {:.3e} ({} Newton iterations)",
            self.fixed_point_residual, self.newton_iterations
        )?;
        writeln!(f, "spectral radius |λ|max    {:.6}", self.spectral_radius)?;
        let eig: Vec<String> = self
            .eigenvalues
            .iter()
            .map(|(re, im)| {
                if im.abs() > 1e-12 {
                    format!("{re:.4}{im:+.4}i")
                } else {
                    format!("{re:.4}")
                }
            })
            .collect();
        writeln!(f, "eigenvalues of DP         {}", eig.join(", "))?;
        writeln!(
            f,
            "max joint diff vs plan    {:.3e} rad",
            self.max_joint_difference_rad
        )?;
        writeln!(
            f,
            "max output error |y|      {:.3e} rad",
            self.max_output_error_rad
        )?;
        writeln!(
            f,
            "simulated step            {:.4} m in {:.4} s",
            self.step_length_m, self.step_duration_s
        )?;
        writeln!(
            f,
            "apex margin               {:.1} % of the post-impact momentum (lost at an impact, the step stops short of the stance foot)",
            100.0 * self.apex_margin
        )?;
        writeln!(
            f,
            "step from the planned x⁺  {:.4} m in {:.4} s (planned {:.4} m in {:.4} s), |P(x⁺) − x⁺| {:.3e}",
            self.step_from_plan.length_m,
            self.step_from_plan.duration_s,
            self.planned_step.length_m,
            self.planned_step.duration_s,
            self.planned_state_residual
        )
    }
}

#[cfg(test)]
mod tests {
    use super::{below, joint_distance};

    /// The joint distance leaves the torso pitch out, takes the worst joint, and carries a NaN
    /// through (where `fold(0.0, f64::max)` would return the other joints' worst), so that a
    /// check on it fails.
    #[test]
    fn the_joint_distance_is_the_worst_joint_and_keeps_a_nan() {
        let planned = [0.0, 0.1, 0.2, 0.3];
        assert_eq!(
            joint_distance(&[5.0, 0.1, 0.25, 0.3], &planned, 4),
            0.25 - 0.2
        );
        let nan_first = joint_distance(&[0.0, f64::NAN, 0.9, 0.3], &planned, 4);
        let nan_last = joint_distance(&[0.0, 0.1, 0.9, f64::NAN], &planned, 4);
        assert!(nan_first.is_nan() && nan_last.is_nan());
        assert!(!below(nan_first, 0.5) && !below(nan_last, 0.5));
    }
}
