//! The versioned JSON gait file: everything the runtime needs to execute a planned HZD gait, and
//! everything a reader needs to trust it (which robot, which design, which solver, how well).
//!
//! Outputs are joint angles named by role: `y^a = [stance hip, stance knee, swing hip, swing knee]`
//! for ADAM. With the state-based phase, `y^d_i(τ) = Bézier(α_i, τ)` with τ from
//! [`crate::phase::state_phase`]. The file describes one step with `stance_leg` in stance; the
//! next step uses the same α with the legs relabeled.
//!
//! [`GaitFile::load`] checks the file on its own (errors name the field, and the line where the
//! JSON does not parse or has the wrong shape); where the gait meets its robot,
//! [`GaitFile::read_urdf`] and [`GaitFile::check_against`] check it against the URDF it names
//! (state lengths, output joints, Bézier coefficients within the joint limits).

use crate::bezier::MAX_BEZIER_DEGREE;
use crate::design::DesignLengths;
use crate::robot::{PlanarModel, Side};
use crate::{ModelError, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::Path;

/// The schema version this build reads and writes.
pub const GAIT_SCHEMA_VERSION: u32 = 1;

/// Which leg a joint of an output belongs to, relative to the current step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LegRole {
    /// The leg on the ground.
    Stance,
    /// The leg in the air.
    Swing,
}

/// One controlled output: a joint angle, named by role.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputDefinition {
    /// Output name, e.g. `stance_knee`.
    pub name: String,
    /// Stance or swing leg.
    pub leg: LegRole,
    /// Joint name without the side prefix, e.g. `knee_pitch`; the joint is `<side>_<joint>`.
    pub joint: String,
}

impl OutputDefinition {
    /// The URDF joint name of this output when `stance` is the stance leg.
    pub fn joint_name(&self, stance: Side) -> String {
        let side = match self.leg {
            LegRole::Stance => stance,
            LegRole::Swing => stance.other(),
        };
        format!("{}_{}", side.prefix(), self.joint)
    }

    /// ADAM's four outputs: stance hip, stance knee, swing hip, swing knee.
    pub fn adam() -> Vec<Self> {
        [
            ("stance_hip", LegRole::Stance, "hip_pitch"),
            ("stance_knee", LegRole::Stance, "knee_pitch"),
            ("swing_hip", LegRole::Swing, "hip_pitch"),
            ("swing_knee", LegRole::Swing, "knee_pitch"),
        ]
        .into_iter()
        .map(|(n, l, j)| Self {
            name: n.into(),
            leg: l,
            joint: j.into(),
        })
        .collect()
    }
}

/// How τ is computed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PhaseDefinition {
    /// τ = (θ − θ⁺) / (θ⁻ − θ⁺), θ the stance-leg angle (see [`crate::phase`]).
    StateBased {
        /// θ just after impact, rad.
        theta_plus_rad: f64,
        /// θ just before impact, rad.
        theta_minus_rad: f64,
    },
    /// τ = t / T with T the gait's step duration.
    TimeBased,
}

/// The Bézier coefficients of the desired outputs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BezierSpec {
    /// Degree b.
    pub degree: usize,
    /// α, one row of b + 1 coefficients per output, rad.
    pub alpha: Vec<Vec<f64>>,
}

/// Which robot model the gait was planned for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotReference {
    /// Robot name from the URDF.
    pub name: String,
    /// Path of the URDF, relative to the gait file's folder.
    pub urdf: String,
    /// SHA-256 of the URDF text, lower-case hex.
    pub sha256: String,
}

/// A state of the robot: coordinates and velocities in the model's order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotState {
    /// q.
    pub q: Vec<f64>,
    /// q̇.
    pub dq: Vec<f64>,
}

/// How the gait was found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSummary {
    /// Solver name and version.
    pub solver: String,
    /// Final status (`optimal`, `acceptable`, ...).
    pub status: String,
    /// Interior-point iterations, all stages.
    pub iterations: usize,
    /// Wall time of the solves, s.
    pub solve_time_s: f64,
    /// Final objective.
    pub objective: f64,
    /// Largest constraint violation at the solution.
    pub constraint_violation: f64,
}

/// Largest number of samples of a [`FeedforwardTable`] (the runtime keeps them in a fixed array).
pub const MAX_FEEDFORWARD_SAMPLES: usize = 256;

/// The planned actuator torques along the step, by phase: the runtime's optional feed-forward
/// term. Linear interpolation between samples, held at the ends.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedforwardTable {
    /// Phase τ of each sample, strictly increasing (normally 0 to 1).
    pub phase: Vec<f64>,
    /// Torque of each output's joint at each sample (`torque_nm[sample][output]`), N·m.
    pub torque_nm: Vec<Vec<f64>>,
}

impl FeedforwardTable {
    /// Torque of each output at phase `tau` into `out` (one entry per output), N·m.
    pub fn eval(&self, tau: f64, out: &mut [f64]) {
        interpolate(&self.phase, &self.torque_nm, tau, out);
    }
}

/// Linear interpolation of rows `values[i]` at abscissae `knots[i]` (increasing), held at the
/// ends; `out` gets zeros for an empty table. Allocation-free.
pub fn interpolate<R: AsRef<[f64]>>(knots: &[f64], values: &[R], tau: f64, out: &mut [f64]) {
    out.iter_mut().for_each(|v| *v = 0.0);
    let n = knots.len().min(values.len());
    if n == 0 {
        return;
    }
    let i = knots[..n].partition_point(|t| *t <= tau);
    if i == 0 || i == n {
        let row = values[if i == 0 { 0 } else { n - 1 }].as_ref();
        for (v, r) in out.iter_mut().zip(row) {
            *v = *r;
        }
        return;
    }
    let (t0, t1) = (knots[i - 1], knots[i]);
    let w = if t1 > t0 { (tau - t0) / (t1 - t0) } else { 0.0 };
    let (a, b) = (values[i - 1].as_ref(), values[i].as_ref());
    for ((v, p), q) in out.iter_mut().zip(a).zip(b) {
        *v = p + w * (q - p);
    }
}

/// A planned periodic HZD gait.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitFile {
    /// Must equal [`GAIT_SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The robot model.
    pub robot: RobotReference,
    /// Thigh and shin lengths.
    pub design: DesignLengths,
    /// The controlled outputs, in the row order of α.
    pub outputs: Vec<OutputDefinition>,
    /// Bézier degree and coefficients.
    pub bezier: BezierSpec,
    /// Phase variable.
    pub phase: PhaseDefinition,
    /// The stance leg of the planned step.
    pub stance_leg: Side,
    /// Step duration, s.
    pub step_duration_s: f64,
    /// Step length, m.
    pub step_length_m: f64,
    /// Mean forward speed, m/s.
    pub speed_mps: f64,
    /// Mechanical cost of transport (dimensionless).
    pub cost_of_transport: f64,
    /// The post-impact state x⁺ at the start of the step (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_state: Option<RobotState>,
    /// The planned torques by phase, for the runtime's feed-forward term (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feedforward: Option<FeedforwardTable>,
    /// Solver summary.
    pub solver: SolverSummary,
}

/// SHA-256 of a text, lower-case hex.
pub fn sha256_hex(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

impl GaitFile {
    /// Reads and validates a gait file; errors name the file and the field.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| ModelError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        Self::from_json(&text, &origin)
    }

    /// Parses and validates gait JSON; `origin` names the source in errors.
    pub fn from_json(text: &str, origin: &str) -> Result<Self> {
        let gait = Self::parse(text, origin)?;
        gait.validate(origin)?;
        Ok(gait)
    }

    /// Reads a gait file without validating its values (see [`GaitFile::check_against`]).
    pub fn load_unchecked(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|error| ModelError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses gait JSON into its schema without checking the values; errors name the line, the
    /// column and the field.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        crate::json_path::parse_versioned(text, origin, "gait", GAIT_SCHEMA_VERSION)
    }

    /// The path of the URDF this gait names, relative to the gait file's folder.
    pub fn urdf_path(&self, gait_path: &Path) -> std::path::PathBuf {
        gait_path
            .parent()
            .unwrap_or_else(|| Path::new("."))
            .join(&self.robot.urdf)
    }

    /// Reads the URDF this gait names (relative to `gait_path`'s folder): its path and text. An
    /// error names the gait file that named it.
    pub fn read_urdf(&self, gait_path: &Path) -> Result<(std::path::PathBuf, String)> {
        let path = self.urdf_path(gait_path);
        match std::fs::read_to_string(&path) {
            Ok(text) => Ok((path, text)),
            Err(error) => Err(ModelError::GaitUrdf {
                gait: gait_path.display().to_string(),
                urdf: self.robot.urdf.clone(),
                path,
                error,
            }),
        }
    }

    /// Writes the gait as pretty JSON after validating it.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.validate(&path.display().to_string())?;
        crate::json_path::write_pretty(path, self)
    }

    /// Rejects NaN/inf, wrong shapes, unknown versions and a degenerate phase (θ⁺ = θ⁻), naming
    /// the field and value.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let invalid = |field: String, value: String, reason: &str| ModelError::InvalidField {
            origin: origin.to_string(),
            field,
            value,
            reason: reason.to_string(),
        };
        if self.schema_version != GAIT_SCHEMA_VERSION {
            return Err(invalid(
                "schema_version".into(),
                self.schema_version.to_string(),
                "unknown schema version",
            ));
        }
        let finite = |field: &str, v: f64| -> Result<()> {
            if v.is_finite() {
                Ok(())
            } else {
                Err(invalid(field.into(), v.to_string(), "must be finite"))
            }
        };
        let positive = |field: &str, v: f64| -> Result<()> {
            finite(field, v)?;
            if v > 0.0 {
                Ok(())
            } else {
                Err(invalid(field.into(), v.to_string(), "must be positive"))
            }
        };
        positive("design.thigh_length_m", self.design.thigh_length_m)?;
        positive("design.shin_length_m", self.design.shin_length_m)?;
        positive("step_duration_s", self.step_duration_s)?;
        finite("step_length_m", self.step_length_m)?;
        finite("speed_mps", self.speed_mps)?;
        finite("cost_of_transport", self.cost_of_transport)?;
        finite("solver.solve_time_s", self.solver.solve_time_s)?;
        finite("solver.objective", self.solver.objective)?;
        finite(
            "solver.constraint_violation",
            self.solver.constraint_violation,
        )?;
        if self.robot.sha256.len() != 64
            || !self.robot.sha256.bytes().all(|b| b.is_ascii_hexdigit())
        {
            return Err(invalid(
                "robot.sha256".into(),
                format!("\"{}\"", self.robot.sha256),
                "must be 64 hex digits",
            ));
        }
        if self.outputs.is_empty() {
            return Err(invalid(
                "outputs".into(),
                "[]".into(),
                "at least one output is needed",
            ));
        }
        let b = self.bezier.degree;
        if !(1..=MAX_BEZIER_DEGREE).contains(&b) {
            return Err(invalid(
                "bezier.degree".into(),
                b.to_string(),
                &format!("must be in 1..={MAX_BEZIER_DEGREE}"),
            ));
        }
        if self.bezier.alpha.len() != self.outputs.len() {
            return Err(invalid(
                "bezier.alpha".into(),
                format!("{} rows", self.bezier.alpha.len()),
                &format!("needs one row per output ({})", self.outputs.len()),
            ));
        }
        for (i, row) in self.bezier.alpha.iter().enumerate() {
            if row.len() != b + 1 {
                return Err(invalid(
                    format!("bezier.alpha[{i}]"),
                    format!("{} coefficients", row.len()),
                    &format!("degree {b} needs {}", b + 1),
                ));
            }
            for (k, v) in row.iter().enumerate() {
                finite(&format!("bezier.alpha[{i}][{k}]"), *v)?;
            }
        }
        if let PhaseDefinition::StateBased {
            theta_plus_rad,
            theta_minus_rad,
        } = self.phase
        {
            finite("phase.theta_plus_rad", theta_plus_rad)?;
            finite("phase.theta_minus_rad", theta_minus_rad)?;
            if (theta_minus_rad - theta_plus_rad).abs() < 1e-6 {
                return Err(invalid(
                    "phase.theta_minus_rad".into(),
                    theta_minus_rad.to_string(),
                    &format!("must differ from theta_plus_rad = {theta_plus_rad} (τ would divide by zero)"),
                ));
            }
        }
        if let Some(state) = &self.initial_state {
            if state.q.len() != state.dq.len() {
                return Err(invalid(
                    "initial_state.q".into(),
                    format!("{} entries", state.q.len()),
                    &format!(
                        "initial_state.dq has {}: q and dq need one entry per coordinate of the robot",
                        state.dq.len()
                    ),
                ));
            }
            for (name, v) in [("q", &state.q), ("dq", &state.dq)] {
                for (k, x) in v.iter().enumerate() {
                    finite(&format!("initial_state.{name}[{k}]"), *x)?;
                }
            }
        }
        if let Some(ff) = &self.feedforward {
            let n = ff.phase.len();
            if !(2..=MAX_FEEDFORWARD_SAMPLES).contains(&n) {
                return Err(invalid(
                    "feedforward.phase".into(),
                    format!("{n} samples"),
                    &format!("needs 2..={MAX_FEEDFORWARD_SAMPLES} samples"),
                ));
            }
            if ff.torque_nm.len() != n {
                return Err(invalid(
                    "feedforward.torque_nm".into(),
                    format!("{} rows", ff.torque_nm.len()),
                    &format!("needs one row per phase sample ({n})"),
                ));
            }
            for (k, t) in ff.phase.iter().enumerate() {
                finite(&format!("feedforward.phase[{k}]"), *t)?;
                if k > 0 && *t <= ff.phase[k - 1] {
                    return Err(invalid(
                        format!("feedforward.phase[{k}]"),
                        t.to_string(),
                        &format!(
                            "must be greater than the previous sample {}",
                            ff.phase[k - 1]
                        ),
                    ));
                }
            }
            for (k, row) in ff.torque_nm.iter().enumerate() {
                if row.len() != self.outputs.len() {
                    return Err(invalid(
                        format!("feedforward.torque_nm[{k}]"),
                        format!("{} entries", row.len()),
                        &format!("needs one per output ({})", self.outputs.len()),
                    ));
                }
                for (i, v) in row.iter().enumerate() {
                    finite(&format!("feedforward.torque_nm[{k}][{i}]"), *v)?;
                }
            }
        }
        Ok(())
    }
}

impl GaitFile {
    /// Checks the gait against the robot it is to run on, then [validates](GaitFile::validate)
    /// it: the state vectors have one entry per coordinate of the robot, every output's joint
    /// exists on both legs, and every Bézier coefficient lies within its joint's limits widened
    /// by the limit range on either side (the curve may pass a limit a little between
    /// coefficients; a coefficient a whole range outside is a broken file, not a plan).
    /// `origin` names the gait file in errors, `robot_origin` the URDF.
    pub fn check_against(
        &self,
        robot: &PlanarModel,
        origin: &str,
        robot_origin: &str,
    ) -> Result<()> {
        let invalid = |field: String, value: String, reason: String| ModelError::InvalidField {
            origin: origin.to_string(),
            field,
            value,
            reason,
        };
        if let Some(state) = &self.initial_state {
            for (name, v) in [("q", &state.q), ("dq", &state.dq)] {
                if v.len() != robot.dof() {
                    return Err(invalid(
                        format!("initial_state.{name}"),
                        format!("{} entries", v.len()),
                        format!(
                            "expected {}, one per coordinate of robot '{}' in {robot_origin} ({} of the torso and {} joints)",
                            robot.dof(),
                            robot.name,
                            crate::robot::BASE_DOF,
                            robot.joints.len()
                        ),
                    ));
                }
            }
        }
        self.validate(origin)?;
        for (i, output) in self.outputs.iter().enumerate() {
            for side in [self.stance_leg, self.stance_leg.other()] {
                let name = output.joint_name(side);
                let Some(j) = robot.joint_index(&name) else {
                    return Err(invalid(
                        format!("outputs[{i}].joint"),
                        format!("\"{}\"", output.joint),
                        format!("{robot_origin} has no joint '{name}'"),
                    ));
                };
                let (lower, upper) = (robot.joints[j].lower, robot.joints[j].upper);
                if !(lower.is_finite() && upper.is_finite()) {
                    continue;
                }
                let margin = upper - lower;
                for (k, a) in self.bezier.alpha[i].iter().enumerate() {
                    if *a < lower - margin || *a > upper + margin {
                        return Err(invalid(
                            format!("bezier.alpha[{i}][{k}]"),
                            readable(*a),
                            format!(
                                "output '{}' drives joint '{name}', whose limits in {robot_origin} are [{lower}, {upper}] rad; a coefficient may lie at most one limit range ({margin} rad) outside them",
                                output.name
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// A number as a user writes it: `1e300`, not three hundred digits.
fn readable(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}
