//! The versioned JSON gait library: one robot, one design, a gait per walking speed, ordered by
//! speed, each with the result of its independent check (Poincaré eigenvalues, the verified
//! step), so that the runtime can pick or blend the gaits on either side of a commanded speed.
//!
//! ```text
//! GaitLibrary { schema_version, robot: { name, urdf, sha256 },
//!               entries: [ { speed_mps, gait: GaitFile, check: LibraryCheck }, … ] }
//! ```
//!
//! [`GaitLibrary::load`] checks the file on its own: the version, at least one entry, speeds
//! finite, positive and strictly increasing (no duplicates), every gait valid
//! ([`GaitFile::validate`]) and of the library's robot (same name and URDF hash: an entry of
//! another robot is an error naming both), every gait's speed d/T its entry's speed, every check
//! figure finite. Errors name the file, the entry index, the field and the value. Where the
//! library meets its robot, [`GaitLibrary::read_urdf`] and [`GaitLibrary::check_against`] check
//! the URDF's hash and every gait against it. `adam plan library` writes these files
//! (`configs/gaits/adam_library.json` is the shipped robot's).

use crate::gait::{sha256_hex, GaitFile, RobotReference};
use crate::robot::PlanarModel;
use crate::{ModelError, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The library schema version this build reads and writes.
pub const LIBRARY_SCHEMA_VERSION: u32 = 1;

/// How far an entry's gait speed d/T may differ from the entry's speed, m/s (the planner
/// holds d − v·T = 0 to 1e-6 m, so d/T to about 2e-6 m/s).
pub const SPEED_MATCH_TOLERANCE_MPS: f64 = 1e-4;

/// The independent check of one library gait (`planner::verify`): the closed-loop periodic
/// orbit found by Newton on the Poincaré map, and the step it walks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LibraryCheck {
    /// Eigenvalues of the Poincaré map's Jacobian at the fixed point, `[re, im]` each.
    pub eigenvalues: Vec<[f64; 2]>,
    /// Largest eigenvalue magnitude (< 1: the orbit is locally exponentially stable).
    pub spectral_radius: f64,
    /// |P(x*) − x*| at the fixed point Newton found.
    pub fixed_point_residual: f64,
    /// Step length of the closed-loop orbit, m.
    pub verified_step_length_m: f64,
    /// Step duration of the closed-loop orbit, s.
    pub verified_step_duration_s: f64,
    /// The orbit's apex margin (`planner::verify::apex_margin`): the fraction of its
    /// post-impact angular momentum about the stance foot a step may lose and still pass over
    /// that foot. Absent in libraries planned before it was recorded (2026-12-06).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub apex_margin: Option<f64>,
}

impl LibraryCheck {
    /// The verified orbit's step duration error against the plan, relative.
    pub fn duration_error(&self, gait: &GaitFile) -> f64 {
        (self.verified_step_duration_s - gait.step_duration_s).abs() / gait.step_duration_s
    }

    /// The verified orbit's step length error against the plan, relative.
    pub fn length_error(&self, gait: &GaitFile) -> f64 {
        (self.verified_step_length_m - gait.step_length_m).abs() / gait.step_length_m.abs()
    }
}

/// One gait of a library: the speed it was planned at, the gait, and its check.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LibraryEntry {
    /// The speed the gait was planned at (`gait.speed_mps` = [v, v]), m/s.
    pub speed_mps: f64,
    /// The gait (its `robot` is the library's).
    pub gait: GaitFile,
    /// Its independent check.
    pub check: LibraryCheck,
}

/// A gait library: one robot and design, a gait per speed, ordered by speed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitLibrary {
    /// Must equal [`LIBRARY_SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The robot every gait was planned for (`urdf` relative to the library file's folder).
    pub robot: RobotReference,
    /// The gaits, by strictly increasing speed.
    pub entries: Vec<LibraryEntry>,
}

/// Where a speed falls in a library: the two entries around it and the weight of the upper one
/// (`speed = (1 − weight)·lower + weight·upper`), after clamping to the library's range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedBracket {
    /// Index of the entry at or below the speed.
    pub lower: usize,
    /// Index of the entry at or above the speed (`lower` at the ends and on an entry).
    pub upper: usize,
    /// Weight of `upper`, in [0, 1].
    pub weight: f64,
    /// The speed used, m/s: the one asked for, clamped to the library's range.
    pub speed_mps: f64,
    /// Whether the speed asked for was outside the range (and clamped).
    pub clamped: bool,
}

impl GaitLibrary {
    /// Reads and validates a library file; errors name the file, the entry and the field.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|error| ModelError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        Self::from_json(&text, &path.display().to_string())
    }

    /// Parses and validates library JSON; `origin` names the source in errors.
    pub fn from_json(text: &str, origin: &str) -> Result<Self> {
        let library: Self = crate::json_path::parse_versioned(
            text,
            origin,
            "gait library",
            LIBRARY_SCHEMA_VERSION,
        )?;
        library.validate(origin)?;
        Ok(library)
    }

    /// Writes the library as pretty JSON after validating it.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.validate(&path.display().to_string())?;
        crate::json_path::write_pretty(path, self)
    }

    /// Rejects an unknown version, an empty library, speeds that are not finite, positive and
    /// strictly increasing, an invalid gait, a gait of another robot, a gait whose speed is not
    /// its entry's, and non-finite check figures, naming the entry, the field and the value.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let invalid = |field: String, value: String, reason: String| ModelError::InvalidField {
            origin: origin.to_string(),
            field,
            value,
            reason,
        };
        if self.schema_version != LIBRARY_SCHEMA_VERSION {
            return Err(invalid(
                "schema_version".into(),
                self.schema_version.to_string(),
                format!("this build reads gait library schema version {LIBRARY_SCHEMA_VERSION}"),
            ));
        }
        if self.entries.is_empty() {
            return Err(invalid(
                "entries".into(),
                "[]".into(),
                "a library needs at least one gait".into(),
            ));
        }
        let finite = |field: String, v: f64| -> Result<()> {
            if v.is_finite() {
                Ok(())
            } else {
                Err(invalid(field, v.to_string(), "must be finite".into()))
            }
        };
        for (i, e) in self.entries.iter().enumerate() {
            let at = |field: &str| format!("entries[{i}].{field}");
            if !(e.speed_mps.is_finite() && e.speed_mps > 0.0) {
                return Err(invalid(
                    at("speed_mps"),
                    e.speed_mps.to_string(),
                    "must be a positive number".into(),
                ));
            }
            if i > 0 {
                let before = self.entries[i - 1].speed_mps;
                if e.speed_mps <= before {
                    let what = if e.speed_mps == before {
                        "duplicates"
                    } else {
                        "is below"
                    };
                    return Err(invalid(
                        at("speed_mps"),
                        e.speed_mps.to_string(),
                        format!(
                            "{what} entries[{}].speed_mps = {before}: speeds must be strictly increasing",
                            i - 1
                        ),
                    ));
                }
            }
            let robot = &e.gait.robot;
            if robot.name != self.robot.name || robot.sha256 != self.robot.sha256 {
                return Err(invalid(
                    at("gait.robot"),
                    format!("'{}' (SHA-256 {})", robot.name, robot.sha256),
                    format!(
                        "the library is for robot '{}' (SHA-256 {}): every gait must be planned for it",
                        self.robot.name, self.robot.sha256
                    ),
                ));
            }
            e.gait.validate(&format!("{origin}: entries[{i}].gait"))?;
            let speed = e.gait.step_length_m / e.gait.step_duration_s;
            if (speed - e.speed_mps).abs() > SPEED_MATCH_TOLERANCE_MPS {
                return Err(invalid(
                    at("gait"),
                    format!(
                        "{} m in {} s = {speed:.6} m/s",
                        e.gait.step_length_m, e.gait.step_duration_s
                    ),
                    format!(
                        "walks another speed than its entry's speed_mps = {}",
                        e.speed_mps
                    ),
                ));
            }
            let c = &e.check;
            for (k, [re, im]) in c.eigenvalues.iter().enumerate() {
                finite(at(&format!("check.eigenvalues[{k}][0]")), *re)?;
                finite(at(&format!("check.eigenvalues[{k}][1]")), *im)?;
            }
            finite(at("check.spectral_radius"), c.spectral_radius)?;
            finite(at("check.fixed_point_residual"), c.fixed_point_residual)?;
            finite(at("check.verified_step_length_m"), c.verified_step_length_m)?;
            if !(c.verified_step_duration_s.is_finite() && c.verified_step_duration_s > 0.0) {
                return Err(invalid(
                    at("check.verified_step_duration_s"),
                    c.verified_step_duration_s.to_string(),
                    "must be a positive number".into(),
                ));
            }
        }
        if self.robot.sha256.len() != 64
            || !self.robot.sha256.bytes().all(|b| b.is_ascii_hexdigit())
        {
            return Err(invalid(
                "robot.sha256".into(),
                format!("\"{}\"", self.robot.sha256),
                "must be 64 hex digits".into(),
            ));
        }
        Ok(())
    }

    /// The slowest and fastest speed, m/s.
    pub fn speed_range_mps(&self) -> [f64; 2] {
        let first = self.entries.first().map_or(0.0, |e| e.speed_mps);
        let last = self.entries.last().map_or(0.0, |e| e.speed_mps);
        [first, last]
    }

    /// The path of the URDF this library names, relative to the library file's folder.
    pub fn urdf_path(&self, library_path: &Path) -> PathBuf {
        library_path
            .parent()
            .unwrap_or_else(|| Path::new("."))
            .join(&self.robot.urdf)
    }

    /// Reads the URDF this library names (relative to `library_path`'s folder): its path and
    /// text. An error names the library file that named it.
    pub fn read_urdf(&self, library_path: &Path) -> Result<(PathBuf, String)> {
        let path = self.urdf_path(library_path);
        match std::fs::read_to_string(&path) {
            Ok(text) => Ok((path, text)),
            Err(error) => Err(ModelError::GaitUrdf {
                gait: library_path.display().to_string(),
                urdf: self.robot.urdf.clone(),
                path,
                error,
            }),
        }
    }

    /// Checks the library against the robot it is to run on: the URDF text's hash is the
    /// library's (else an error naming both robots), and every gait passes
    /// [`GaitFile::check_against`]. `origin` names the library file, `robot_origin` the URDF.
    pub fn check_against(
        &self,
        robot: &PlanarModel,
        urdf_text: &str,
        origin: &str,
        robot_origin: &str,
    ) -> Result<()> {
        let sha = sha256_hex(urdf_text);
        if sha != self.robot.sha256 || robot.name != self.robot.name {
            return Err(ModelError::InvalidField {
                origin: origin.to_string(),
                field: "robot".into(),
                value: format!("'{}' (SHA-256 {})", self.robot.name, self.robot.sha256),
                reason: format!(
                    "{robot_origin} is robot '{}' (SHA-256 {sha}): the library was planned for another robot, or the robot changed since",
                    robot.name
                ),
            });
        }
        for (i, e) in self.entries.iter().enumerate() {
            e.gait
                .check_against(robot, &format!("{origin}: entries[{i}].gait"), robot_origin)?;
        }
        Ok(())
    }
}

/// The entries of `speeds_mps` (sorted, not empty) around `speed_mps` (clamped to their range;
/// a non-finite speed counts as the slowest) and the weight of the upper one: what the runtime
/// interpolates a library gait from. Allocation-free.
pub fn bracket(speeds_mps: &[f64], speed_mps: f64) -> SpeedBracket {
    let n = speeds_mps.len();
    let (lo, hi) = (speeds_mps[0], speeds_mps[n - 1]);
    let v = if speed_mps.is_finite() {
        speed_mps.clamp(lo, hi)
    } else {
        lo
    };
    let clamped = v != speed_mps;
    let upper = speeds_mps.partition_point(|&s| s < v).min(n - 1);
    let lower = if upper > 0 && speeds_mps[upper] > v {
        upper - 1
    } else {
        upper
    };
    let (a, b) = (speeds_mps[lower], speeds_mps[upper]);
    let weight = if b > a { (v - a) / (b - a) } else { 0.0 };
    SpeedBracket {
        lower,
        upper,
        weight,
        speed_mps: v,
        clamped,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(gait: &GaitFile, speed: f64) -> LibraryEntry {
        let mut g = gait.clone();
        g.step_length_m = speed * g.step_duration_s;
        g.speed_mps = speed;
        LibraryEntry {
            speed_mps: speed,
            gait: g,
            check: LibraryCheck {
                eigenvalues: vec![[0.5, 0.1], [0.5, -0.1]],
                spectral_radius: 0.51,
                fixed_point_residual: 1e-10,
                verified_step_length_m: speed * gait.step_duration_s,
                verified_step_duration_s: gait.step_duration_s,
                apex_margin: None,
            },
        }
    }

    fn library(speeds: &[f64]) -> GaitLibrary {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../configs/gaits/adam_walk.json"
        );
        let gait = GaitFile::load(path).expect("shipped gait");
        GaitLibrary {
            schema_version: LIBRARY_SCHEMA_VERSION,
            robot: gait.robot.clone(),
            entries: speeds.iter().map(|&v| entry(&gait, v)).collect(),
        }
    }

    #[test]
    fn a_speed_falls_between_its_two_neighbours_with_the_right_weight() {
        let lib = library(&[0.15, 0.2, 0.25]);
        let speeds: Vec<f64> = lib.entries.iter().map(|e| e.speed_mps).collect();
        let bracket = |v| bracket(&speeds, v);
        let b = bracket(0.1625);
        assert_eq!((b.lower, b.upper, b.clamped), (0, 1, false));
        assert!((b.weight - 0.25).abs() < 1e-12, "{b:?}");
        let on = bracket(0.2);
        assert_eq!((on.lower, on.upper, on.weight), (1, 1, 0.0));
        let fast = bracket(0.4);
        assert_eq!((fast.lower, fast.upper, fast.speed_mps), (2, 2, 0.25));
        assert!(fast.clamped);
        let slow = bracket(0.01);
        assert_eq!((slow.lower, slow.upper, slow.speed_mps), (0, 0, 0.15));
        assert!(slow.clamped && bracket(f64::NAN).clamped);
        assert_eq!(lib.speed_range_mps(), [0.15, 0.25]);
    }

    #[test]
    fn unsorted_duplicate_and_foreign_entries_are_named() {
        let good = library(&[0.15, 0.2]);
        good.validate("lib.json").expect("valid");
        let e = library(&[0.2, 0.15])
            .validate("lib.json")
            .expect_err("unsorted")
            .to_string();
        assert!(
            e.contains("lib.json") && e.contains("entries[1].speed_mps") && e.contains("0.15"),
            "{e}"
        );
        let e = library(&[0.2, 0.2])
            .validate("lib.json")
            .expect_err("duplicate")
            .to_string();
        assert!(
            e.contains("entries[1].speed_mps") && e.contains("duplicates"),
            "{e}"
        );
        let mut foreign = good.clone();
        foreign.entries[1].gait.robot.name = "five_link".into();
        let e = foreign
            .validate("lib.json")
            .expect_err("foreign")
            .to_string();
        assert!(
            e.contains("entries[1].gait.robot")
                && e.contains("five_link")
                && e.contains("adam_planar"),
            "{e}"
        );
        let mut off = good.clone();
        off.entries[0].speed_mps = 0.16;
        let e = off.validate("lib.json").expect_err("speed").to_string();
        assert!(e.contains("entries[0].gait") && e.contains("0.16"), "{e}");
        let mut nan = good;
        nan.entries[1].check.spectral_radius = f64::NAN;
        let e = nan.validate("lib.json").expect_err("nan").to_string();
        assert!(
            e.contains("entries[1].check.spectral_radius") && e.contains("NaN"),
            "{e}"
        );
        let e = library(&[])
            .validate("lib.json")
            .expect_err("empty")
            .to_string();
        assert!(e.contains("entries") && e.contains("at least one"), "{e}");
    }
}
