//! The one error type of the `model` crate.

use std::path::PathBuf;

/// Result alias of the `model` crate.
pub type Result<T, E = ModelError> = std::result::Result<T, E>;

/// Everything that can go wrong while loading, building or evaluating a model or a gait file.
///
/// Every variant names the file, link, joint or field and the offending value, so that a user can
/// fix the input without reading our source.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error (displayed, not chained, so that it is printed once).
        error: std::io::Error,
    },
    /// The URDF is not well-formed XML or does not follow the URDF schema.
    #[error("{origin}: not a valid URDF: {message}")]
    UrdfSyntax {
        /// File name or `<string>`.
        origin: String,
        /// What urdf-rs or the XML reader said.
        message: String,
    },
    /// A link has no `<inertial>` element. Massless frames must say so with `<mass value="0"/>`.
    #[error(
        "{origin}: link '{link}' has no <inertial> element (write mass 0 for a massless frame)"
    )]
    MissingInertial {
        /// File name or `<string>`.
        origin: String,
        /// The link.
        link: String,
    },
    /// An inertial value is negative or not finite.
    #[error("{origin}: link '{link}' has an invalid {field} = {value}")]
    BadInertial {
        /// File name or `<string>`.
        origin: String,
        /// The link.
        link: String,
        /// `mass`, `iyy`, `origin` ...
        field: &'static str,
        /// The value found.
        value: f64,
    },
    /// A joint axis or origin leaves the sagittal (x–z) plane.
    #[error("{origin}: joint '{joint}' is not planar: {what} = \"{}\" (revolute axes must be ±y, prismatic axes must lie in x–z, origins may only pitch)", triple(value))]
    NonPlanar {
        /// File name or `<string>`.
        origin: String,
        /// The joint.
        joint: String,
        /// `axis` or `origin rpy`.
        what: &'static str,
        /// The offending vector.
        value: [f64; 3],
    },
    /// A joint names a link that does not exist.
    #[error("{origin}: joint '{joint}' names unknown {role} link '{link}'")]
    UnknownLink {
        /// File name or `<string>`.
        origin: String,
        /// The joint.
        joint: String,
        /// `parent` or `child`.
        role: &'static str,
        /// The missing link.
        link: String,
    },
    /// The joints do not form a tree with a single root.
    #[error("{origin}: the links do not form a tree: {message}")]
    NotATree {
        /// File name or `<string>`.
        origin: String,
        /// What is wrong (a loop, several roots, a link with two parents).
        message: String,
    },
    /// A joint type that a planar model cannot represent.
    #[error("{origin}: joint '{joint}' has unsupported type {kind} (planar models take revolute, continuous, prismatic and fixed joints)")]
    UnsupportedJoint {
        /// File name or `<string>`.
        origin: String,
        /// The joint.
        joint: String,
        /// The URDF type.
        kind: String,
    },
    /// Joint limits that are not finite or inverted.
    #[error("{origin}: joint '{joint}' has invalid limit {field} = {value}")]
    BadLimit {
        /// File name or `<string>`.
        origin: String,
        /// The joint.
        joint: String,
        /// `lower`, `upper`, `effort`, `velocity`.
        field: &'static str,
        /// The value found.
        value: f64,
    },
    /// The model does not follow the documented biped naming (`left_hip_pitch`, ...).
    #[error("model '{model}' has no {kind} named '{name}' (see model::robot for the biped naming convention)")]
    MissingNamed {
        /// The model name.
        model: String,
        /// `joint` or `frame`.
        kind: &'static str,
        /// The name looked for.
        name: String,
    },
    /// A vector of the wrong length was passed.
    #[error("{what} has length {found}, expected {expected}")]
    Dimension {
        /// Which argument.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Length found.
        found: usize,
    },
    /// A linear system (constrained dynamics, impact) is singular.
    #[error("singular linear system in {what}")]
    Singular {
        /// Where.
        what: &'static str,
    },
    /// A model has more bodies than the allocation-free kinematics supports.
    #[error("model has {bodies} bodies; at most {max} are supported")]
    TooManyBodies {
        /// Bodies found.
        bodies: usize,
        /// The limit, `MAX_BODIES`.
        max: usize,
    },
    /// A design (link lengths) outside the range the inertia fits cover.
    #[error("design {field} = {value} m is outside [{min}, {max}] m")]
    DesignOutOfRange {
        /// `thigh_length_m` or `shin_length_m`.
        field: &'static str,
        /// Requested value.
        value: f64,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
    /// A gait file or config field has an invalid value.
    #[error("{origin}: field '{field}' = {value}: {reason}")]
    InvalidField {
        /// File name or `<gait>`.
        origin: String,
        /// Dotted field path, e.g. `bezier.alpha[2][3]`.
        field: String,
        /// The value, printed.
        value: String,
        /// Why it is rejected.
        reason: String,
    },
    /// A URDF attribute of a link or joint has a value we refuse (not a number, the wrong count
    /// of numbers, negative, a name used twice).
    #[error("{origin}: {element}: {field} = \"{value}\": {reason}")]
    UrdfField {
        /// File name or `<string>`.
        origin: String,
        /// The element, e.g. `link 'torso'`, `joint 'left_knee_pitch'`.
        element: String,
        /// The attribute, e.g. `origin xyz`, `inertia ixx`, `name`.
        field: String,
        /// The value as written (or computed).
        value: String,
        /// Why it is refused.
        reason: String,
    },
    /// The URDF that a gait file names cannot be read.
    #[error("{gait}: field 'robot.urdf' = \"{urdf}\" names {}, which cannot be read: {error}", path.display())]
    GaitUrdf {
        /// The gait file that names the URDF.
        gait: String,
        /// The path as written in the gait file.
        urdf: String,
        /// The path it resolves to (relative to the gait file's folder).
        path: PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// A JSON document does not parse or does not have the expected shape; the field is located
    /// from the parser's line and column.
    #[error(
        "{origin}: line {line}, column {column}: {}{message}",
        field_text(field)
    )]
    Json {
        /// File name.
        origin: String,
        /// Line of the error, 1-based.
        line: usize,
        /// Column of the error, 1-based.
        column: usize,
        /// Dotted path of the field at the error, e.g. `bezier.alpha[1][3]` (empty at the top).
        field: String,
        /// What the parser said, without its position.
        message: String,
    },
    /// A JSON or TOML document could not be parsed.
    #[error("{origin}: {message}")]
    Parse {
        /// File name.
        origin: String,
        /// What the parser said (it includes line and column).
        message: String,
    },
}

/// A vector as URDF writes it: `0 1 0`.
fn triple(v: &[f64; 3]) -> String {
    format!("{} {} {}", v[0], v[1], v[2])
}

fn field_text(field: &str) -> String {
    if field.is_empty() {
        String::new()
    } else {
        format!("field '{field}': ")
    }
}
