//! URDF → [`PlanarModel`]: reads a URDF with urdf-rs, checks that it is planar and a tree, merges
//! fixed links into their parents (keeping them as named frames) and projects every inertial
//! onto the sagittal plane (mass, x–z centre of mass, I_yy about the centre of mass, with the
//! inertial's own rotation applied).
//!
//! Before urdf-rs reads the text, a pass over the XML refuses what urdf-rs lets through or
//! reports without a name: a root element other than `<robot>`, a link or joint name used twice,
//! a numeric attribute of a joint or inertial that is not the right count of finite numbers, a
//! negative moment of inertia. Those errors name the link or joint, its line, the attribute and
//! the value as written.
//!
//! # Joint drives (armature and viscous friction)
//! A revolute joint's viscous friction is the standard `<dynamics damping="b"/>` (N·m·s/rad,
//! joint side; `friction`, Coulomb friction, is refused unless zero: the model has none). Its
//! actuator is a standard ROS `<transmission>` whose `<actuator>` carries the gear ratio as
//! `<mechanicalReduction>` (the ROS element) and, as elements of the same form that ROS tools
//! ignore, the motor's constants:
//!
//! ```xml
//! <transmission name="left_knee_pitch_transmission">
//!   <type>transmission_interface/SimpleTransmission</type>
//!   <joint name="left_knee_pitch"/>
//!   <actuator name="left_knee_pitch_motor">
//!     <mechanicalReduction>9.1</mechanicalReduction>     <!-- N, motor turns per joint turn -->
//!     <rotorInertia>0.000120758</rotorInertia>           <!-- J_rotor, kg·m², motor side -->
//!     <torqueConstant>0.092</torqueConstant>             <!-- k_t, N·m/A, motor side -->
//!     <windingResistance>0.25</windingResistance>        <!-- R, Ω, in P_cu = i² R -->
//!   </actuator>
//! </transmission>
//! ```
//!
//! (Drake's `drake:gear_ratio` and `drake:rotor_inertia` are the same two numbers.) The armature
//! N² J_rotor enters the mass matrix; k_t and R only the electrical cost. Every element is
//! optional: a joint without them has zero armature and friction. A value that is not one
//! finite number, a negative one (zero gear ratio or torque constant), a transmission naming an
//! unknown or non-revolute joint, or two transmissions for one joint are errors naming the
//! transmission or joint, its line, the element and the value.

use crate::robot::{
    Body, BodyInertia, Frame, Joint, JointDrive, JointKind, JointRole, PlanarModel,
};
use crate::{ModelError, Result};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// Standard gravity, m/s².
pub const STANDARD_GRAVITY_MPS2: f64 = 9.81;

const PLANAR_TOL: f64 = 1e-9;

impl PlanarModel {
    /// Loads a planar model from a URDF file. Errors name the file and the link or joint.
    pub fn from_urdf_file(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|error| ModelError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        Self::from_urdf_str(&text, &path.display().to_string())
    }

    /// Loads a planar model from URDF text; `origin` names the source in error messages.
    pub fn from_urdf_str(text: &str, origin: &str) -> Result<Self> {
        let has_inertial = scan(text, origin)?;
        let drives = scan_transmissions(text, origin)?;
        let robot = urdf_rs::read_from_string(text).map_err(|e| ModelError::UrdfSyntax {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        let mut model = build(&robot, &has_inertial, origin)?;
        for j in &robot.joints {
            if let (Some(d), Some(i)) = (&j.dynamics, model.joint_index(&j.name)) {
                model.joints[i].drive.damping_nms_per_rad = d.damping;
            }
        }
        for (joint, (drive, element)) in drives {
            let i = model
                .joint_index(&joint)
                .ok_or_else(|| ModelError::UrdfField {
                    origin: origin.to_string(),
                    element: element.clone(),
                    field: "joint name".into(),
                    value: joint.clone(),
                    reason: "no movable joint of this name".into(),
                })?;
            let JointKind::Revolute { .. } = model.joints[i].kind else {
                return Err(ModelError::UrdfField {
                    origin: origin.to_string(),
                    element,
                    field: "joint name".into(),
                    value: joint,
                    reason: "an actuator drives a revolute joint; this one is prismatic".into(),
                });
            };
            let damping = model.joints[i].drive.damping_nms_per_rad;
            model.joints[i].drive = JointDrive {
                damping_nms_per_rad: damping,
                ..drive
            };
        }
        for j in &model.joints {
            if let JointKind::Prismatic { .. } = j.kind {
                if j.drive.damping_nms_per_rad != 0.0 {
                    return Err(ModelError::UrdfField {
                        origin: origin.to_string(),
                        element: format!("joint '{}'", j.name),
                        field: "dynamics damping".into(),
                        value: j.drive.damping_nms_per_rad.to_string(),
                        reason: "a design (prismatic) joint is rigid: it takes no friction".into(),
                    });
                }
            }
        }
        Ok(model)
    }
}

/// Where an attribute sits: the element path below `<robot>` and its name in errors.
const CHECKED_ATTRIBUTES: &[(&[&str], &[&str], &str, usize)] = &[
    // (element path, attributes, field prefix, numbers per attribute)
    (&["joint", "origin"], &["xyz", "rpy"], "origin", 3),
    (&["joint", "axis"], &["xyz"], "axis", 3),
    (
        &["joint", "limit"],
        &["lower", "upper", "effort", "velocity"],
        "limit",
        1,
    ),
    (
        &["link", "inertial", "origin"],
        &["xyz", "rpy"],
        "inertial origin",
        3,
    ),
    (
        &["joint", "dynamics"],
        &["damping", "friction"],
        "dynamics",
        1,
    ),
    (&["link", "inertial", "mass"], &["value"], "mass", 1),
    (
        &["link", "inertial", "inertia"],
        &["ixx", "ixy", "ixz", "iyy", "iyz", "izz"],
        "inertia",
        1,
    ),
];

/// Reads the XML once before urdf-rs does, for what urdf-rs lets through or reports without a
/// name: the root element must be `<robot>`; link and joint names are unique; the numeric
/// attributes of joints and inertials hold the right count of finite numbers (named with their
/// link or joint and line); moments of inertia are not negative. Returns, for each `<link>`,
/// whether it has an `<inertial>` child (urdf-rs silently defaults it to zero).
fn scan(text: &str, origin: &str) -> Result<HashMap<String, bool>> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut out = HashMap::new();
    // Open elements (names) and the link or joint being read: (kind, name, line).
    let mut open: Vec<String> = Vec::new();
    let mut owner: Option<(String, String, usize)> = None;
    let mut seen: HashMap<(String, String), usize> = HashMap::new();
    let mut root_seen = false;
    let syntax = |e: String| ModelError::UrdfSyntax {
        origin: origin.to_string(),
        message: e,
    };
    let line_at = |pos: u64| line_at(text, pos);
    loop {
        let pos = reader.buffer_position();
        let event = reader.read_event().map_err(|e| syntax(e.to_string()))?;
        let (e, empty) = match &event {
            Event::Start(e) => (e.clone(), false),
            Event::Empty(e) => (e.clone(), true),
            Event::End(_) => {
                if open.len() == 2 {
                    owner = None;
                }
                open.pop();
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let line = line_at(pos);
        let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
        let attr = |key: &str| -> Option<String> {
            e.attributes()
                .flatten()
                .find(|a| a.key.as_ref() == key.as_bytes())
                .map(|a| String::from_utf8_lossy(&a.value).into_owned())
        };
        if open.is_empty() {
            if root_seen {
                return Err(syntax(format!(
                    "line {line}: a second root element <{name}> after </robot>"
                )));
            }
            if name != "robot" {
                return Err(syntax(format!(
                    "line {line}: the root element is <{name}>, expected <robot>"
                )));
            }
            root_seen = true;
        } else if open.len() == 1 && (name == "link" || name == "joint") {
            let element_name = attr("name").unwrap_or_default();
            if let Some(first) = seen.insert((name.clone(), element_name.clone()), line) {
                return Err(ModelError::UrdfField {
                    origin: origin.to_string(),
                    element: format!("{name} '{element_name}' (line {line})"),
                    field: "name".into(),
                    value: element_name,
                    reason: format!("a {name} of this name is defined already (line {first})"),
                });
            }
            if name == "link" {
                out.insert(element_name.clone(), false);
            }
            owner = Some((name.clone(), element_name, line));
        } else if let Some((kind, owner_name, _)) = &owner {
            let mut path: Vec<&str> = open[1..].iter().map(String::as_str).collect();
            path.push(&name);
            if kind == "link" && path == ["link", "inertial"] {
                out.insert(owner_name.clone(), true);
            }
            for (at, keys, prefix, count) in CHECKED_ATTRIBUTES {
                if path != *at {
                    continue;
                }
                for key in *keys {
                    let Some(value) = attr(key) else { continue };
                    let field = format!("{prefix} {key}");
                    let bad = |reason: String| ModelError::UrdfField {
                        origin: origin.to_string(),
                        element: format!("{kind} '{owner_name}' (line {line})"),
                        field: field.clone(),
                        value: value.clone(),
                        reason,
                    };
                    let numbers: Vec<&str> = value.split_whitespace().collect();
                    if numbers.len() != *count {
                        return Err(bad(if *count == 1 {
                            format!("expected one number, found {}", numbers.len())
                        } else {
                            format!("expected {count} numbers, found {}", numbers.len())
                        }));
                    }
                    for n in numbers {
                        match n.parse::<f64>() {
                            Ok(v) if v.is_finite() => {
                                if ["ixx", "iyy", "izz"].contains(key) && v < 0.0 {
                                    return Err(bad(
                                        "a moment of inertia cannot be negative".into()
                                    ));
                                }
                                if *key == "damping" && v < 0.0 {
                                    return Err(bad(
                                        "viscous friction cannot be negative (it would add energy)"
                                            .into(),
                                    ));
                                }
                                if *key == "friction" && v != 0.0 {
                                    return Err(bad(
                                        "Coulomb friction is not modelled: write 0 or leave it out (viscous friction is damping)"
                                            .into(),
                                    ));
                                }
                            }
                            Ok(_) => return Err(bad(format!("'{n}' is not a finite number"))),
                            Err(_) => return Err(bad(format!("'{n}' is not a number"))),
                        }
                    }
                }
            }
        }
        if !empty {
            open.push(name);
        } else if open.len() == 1 {
            owner = None;
        }
    }
    if !root_seen {
        return Err(syntax("no <robot> element".into()));
    }
    Ok(out)
}

/// The 1-based line of byte `pos` of `text` (what URDF errors name).
fn line_at(text: &str, pos: u64) -> usize {
    text.as_bytes()[..(pos as usize).min(text.len())]
        .iter()
        .filter(|b| **b == b'\n')
        .count()
        + 1
}

/// The `<transmission>` elements: for each joint they name, its drive (gear ratio and motor
/// constants; damping comes from `<dynamics>`) and the transmission as errors name it.
fn scan_transmissions(text: &str, origin: &str) -> Result<HashMap<String, (JointDrive, String)>> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut out: HashMap<String, (JointDrive, String)> = HashMap::new();
    let line_at = |pos: u64| line_at(text, pos);
    let syntax = |e: String| ModelError::UrdfSyntax {
        origin: origin.to_string(),
        message: e,
    };
    // Depth of the element being read (1: a child of <robot>).
    let mut depth = 0usize;
    // The transmission being read: (element for errors, its depth, joint, drive).
    let mut current: Option<(String, usize, Option<String>, JointDrive)> = None;
    // The constant whose text is being read: (element name, line).
    let mut field: Option<(String, usize)> = None;
    loop {
        let pos = reader.buffer_position();
        let event = reader.read_event().map_err(|e| syntax(e.to_string()))?;
        let (e, empty) = match &event {
            Event::Start(e) => (e.clone(), false),
            Event::Empty(e) => (e.clone(), true),
            Event::End(_) => {
                if let Some((element, d, joint, drive)) = current.take() {
                    if d == depth {
                        let Some(joint) = joint else {
                            return Err(ModelError::UrdfField {
                                origin: origin.to_string(),
                                element,
                                field: "joint".into(),
                                value: String::new(),
                                reason: "a transmission names its joint: <joint name=\"…\"/>"
                                    .into(),
                            });
                        };
                        if let Some((_, first)) = out.get(&joint) {
                            return Err(ModelError::UrdfField {
                                origin: origin.to_string(),
                                element,
                                field: "joint name".into(),
                                value: joint,
                                reason: format!("{first} drives this joint already"),
                            });
                        }
                        out.insert(joint, (drive, element));
                    } else {
                        current = Some((element, d, joint, drive));
                    }
                }
                field = None;
                depth = depth.saturating_sub(1);
                continue;
            }
            Event::Text(t) => {
                if let (Some((name, line)), Some((element, _, _, drive))) = (&field, &mut current) {
                    let value = t.decode().map(|v| v.trim().to_string()).unwrap_or_default();
                    let bad = |reason: &str| ModelError::UrdfField {
                        origin: origin.to_string(),
                        element: element.clone(),
                        field: format!("{name} (line {line})"),
                        value: value.clone(),
                        reason: reason.to_string(),
                    };
                    let v: f64 = match value.parse::<f64>() {
                        Ok(v) if v.is_finite() => v,
                        Ok(_) => return Err(bad("not a finite number")),
                        Err(_) => return Err(bad("not a number")),
                    };
                    let positive = DRIVE_FIELDS.iter().any(|(f, p)| f == name && *p);
                    if v < 0.0 || (positive && v == 0.0) {
                        return Err(bad(if positive {
                            "must be positive"
                        } else {
                            "cannot be negative"
                        }));
                    }
                    let slot = match name.as_str() {
                        "mechanicalReduction" => &mut drive.gear_ratio,
                        "rotorInertia" => &mut drive.rotor_inertia_kgm2,
                        "torqueConstant" => &mut drive.torque_constant_nm_per_a,
                        _ => &mut drive.winding_resistance_ohm,
                    };
                    *slot = Some(v);
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        depth += 1;
        let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
        let line = line_at(pos);
        if depth == 2 && name == "transmission" {
            let tname = e
                .attributes()
                .flatten()
                .find(|a| a.key.as_ref() == b"name")
                .map(|a| String::from_utf8_lossy(&a.value).into_owned())
                .unwrap_or_default();
            current = Some((
                format!("transmission '{tname}' (line {line})"),
                depth,
                None,
                JointDrive::default(),
            ));
        } else if let Some((_, _, joint, _)) = &mut current {
            if name == "joint" {
                *joint = e
                    .attributes()
                    .flatten()
                    .find(|a| a.key.as_ref() == b"name")
                    .map(|a| String::from_utf8_lossy(&a.value).into_owned());
            } else if DRIVE_FIELDS.iter().any(|(f, _)| *f == name) {
                field = Some((name, line));
            }
        }
        if empty {
            // An empty element closes at once (an empty transmission has no joint).
            if let Some((element, d, None, _)) = &current {
                if *d == depth {
                    return Err(ModelError::UrdfField {
                        origin: origin.to_string(),
                        element: element.clone(),
                        field: "joint".into(),
                        value: String::new(),
                        reason: "a transmission names its joint: <joint name=\"…\"/>".into(),
                    });
                }
            }
            field = None;
            depth -= 1;
        }
    }
    Ok(out)
}

/// The drive constants a transmission's actuator may carry, and whether each must be positive
/// (it divides something).
const DRIVE_FIELDS: [(&str, bool); 4] = [
    ("mechanicalReduction", true),
    ("rotorInertia", false),
    ("torqueConstant", true),
    ("windingResistance", false),
];

/// Planar projection of a URDF inertial: (mass, com x–z in the link frame, I_yy about the com).
fn project_inertial(link: &urdf_rs::Link, origin: &str) -> Result<BodyInertia<f64>> {
    let i = &link.inertial;
    let bad = |field: &'static str, value: f64| ModelError::BadInertial {
        origin: origin.to_string(),
        link: link.name.clone(),
        field,
        value,
    };
    let m = i.mass.value;
    if !m.is_finite() || m < 0.0 {
        return Err(bad("mass", m));
    }
    for (field, v) in [
        ("ixx", i.inertia.ixx),
        ("iyy", i.inertia.iyy),
        ("izz", i.inertia.izz),
        ("ixy", i.inertia.ixy),
        ("ixz", i.inertia.ixz),
        ("iyz", i.inertia.iyz),
    ] {
        if !v.is_finite() {
            return Err(bad(field, v));
        }
    }
    for (k, v) in i.origin.xyz.iter().chain(i.origin.rpy.iter()).enumerate() {
        if !v.is_finite() {
            return Err(bad(if k < 3 { "origin xyz" } else { "origin rpy" }, *v));
        }
    }
    let t = nalgebra::Matrix3::new(
        i.inertia.ixx,
        i.inertia.ixy,
        i.inertia.ixz,
        i.inertia.ixy,
        i.inertia.iyy,
        i.inertia.iyz,
        i.inertia.ixz,
        i.inertia.iyz,
        i.inertia.izz,
    );
    let [r, p, y] = *i.origin.rpy;
    let rotm = nalgebra::Rotation3::from_euler_angles(r, p, y);
    let iyy = (rotm.matrix() * t * rotm.matrix().transpose())[(1, 1)];
    if iyy < 0.0 {
        return Err(bad("iyy", iyy));
    }
    Ok(BodyInertia {
        mass_kg: m,
        com_xz_m: [i.origin.xyz[0], i.origin.xyz[2]],
        inertia_yy_kgm2: iyy,
    })
}

/// A planar rigid transform: translation (x, z) then pitch.
#[derive(Clone, Copy)]
struct Planar {
    xz: [f64; 2],
    pitch: f64,
}

impl Planar {
    const IDENTITY: Self = Self {
        xz: [0.0, 0.0],
        pitch: 0.0,
    };
    fn apply(&self, v: [f64; 2]) -> [f64; 2] {
        let r = crate::kinematics::rot(self.pitch, v);
        [self.xz[0] + r[0], self.xz[1] + r[1]]
    }
    fn then(&self, child: &Planar) -> Planar {
        Planar {
            xz: self.apply(child.xz),
            pitch: self.pitch + child.pitch,
        }
    }
}

fn joint_origin(j: &urdf_rs::Joint, origin: &str) -> Result<Planar> {
    let [r, p, y] = *j.origin.rpy;
    if r.abs() > PLANAR_TOL || y.abs() > PLANAR_TOL || !p.is_finite() {
        return Err(ModelError::NonPlanar {
            origin: origin.to_string(),
            joint: j.name.clone(),
            what: "origin rpy",
            value: [r, p, y],
        });
    }
    let xyz = *j.origin.xyz;
    if xyz.iter().any(|v| !v.is_finite()) {
        return Err(ModelError::NonPlanar {
            origin: origin.to_string(),
            joint: j.name.clone(),
            what: "origin xyz",
            value: xyz,
        });
    }
    Ok(Planar {
        xz: [xyz[0], xyz[2]],
        pitch: p,
    })
}

fn build(
    robot: &urdf_rs::Robot,
    has_inertial: &HashMap<String, bool>,
    origin: &str,
) -> Result<PlanarModel> {
    let err_tree = |message: String| ModelError::NotATree {
        origin: origin.to_string(),
        message,
    };
    let links: HashMap<&str, &urdf_rs::Link> =
        robot.links.iter().map(|l| (l.name.as_str(), l)).collect();
    if links.len() != robot.links.len() {
        return Err(err_tree("two links share a name".into()));
    }
    for l in &robot.links {
        if !has_inertial.get(&l.name).copied().unwrap_or(false) {
            return Err(ModelError::MissingInertial {
                origin: origin.to_string(),
                link: l.name.clone(),
            });
        }
    }
    let mut parent_of: HashMap<&str, &str> = HashMap::new();
    for j in &robot.joints {
        for (role, link) in [("parent", &j.parent.link), ("child", &j.child.link)] {
            if !links.contains_key(link.as_str()) {
                return Err(ModelError::UnknownLink {
                    origin: origin.to_string(),
                    joint: j.name.clone(),
                    role,
                    link: link.clone(),
                });
            }
        }
        if let Some(prev) = parent_of.insert(j.child.link.as_str(), j.parent.link.as_str()) {
            return Err(err_tree(format!(
                "link '{}' has two parents ('{prev}' and '{}'): a kinematic loop",
                j.child.link, j.parent.link
            )));
        }
    }
    let roots: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !parent_of.contains_key(n))
        .collect();
    if roots.len() != 1 {
        return Err(err_tree(if roots.is_empty() {
            "no root link: every link has a parent, so the joints form a loop".to_string()
        } else {
            format!(
                "{} root links ({}); expected exactly one",
                roots.len(),
                roots.join(", ")
            )
        }));
    }
    let root = roots[0];

    let mut model = PlanarModel {
        name: robot.name.clone(),
        bodies: Vec::new(),
        joints: Vec::new(),
        frames: Vec::new(),
        gravity_mps2: STANDARD_GRAVITY_MPS2,
    };
    // Depth-first from the root; each stack entry: (link, body it belongs to, link frame in body).
    let mut visited: HashSet<&str> = HashSet::new();
    let mut stack: Vec<(&str, usize, Planar)> = vec![(root, 0, Planar::IDENTITY)];
    model.bodies.push(Body {
        name: root.to_string(),
        parent: None,
        joint: None,
        origin_xz_m: [0.0, 0.0],
        origin_pitch_rad: 0.0,
        inertia: BodyInertia::ZERO,
        joint_path: Vec::new(),
    });
    while let Some((link_name, body, in_body)) = stack.pop() {
        if !visited.insert(link_name) {
            return Err(err_tree(format!("link '{link_name}' is reached twice")));
        }
        let link = links[link_name];
        let local = project_inertial(link, origin)?;
        let placed = BodyInertia {
            mass_kg: local.mass_kg,
            com_xz_m: in_body.apply(local.com_xz_m),
            inertia_yy_kgm2: local.inertia_yy_kgm2,
        };
        model.bodies[body].inertia = model.bodies[body].inertia.combine(&placed);
        model.frames.push(Frame {
            name: link_name.to_string(),
            body,
            offset_xz_m: in_body.xz,
            pitch_rad: in_body.pitch,
        });
        // Children in file order get their joints and bodies now; they are pushed so that the
        // stack pops (and numbers their own children) in file order too.
        let mut children: Vec<(&str, usize, Planar)> = Vec::new();
        for j in robot.joints.iter().filter(|j| j.parent.link == link_name) {
            let o = in_body.then(&joint_origin(j, origin)?);
            let child = j.child.link.as_str();
            let kind = match j.joint_type {
                urdf_rs::JointType::Fixed => {
                    children.push((child, body, o));
                    continue;
                }
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                    let a = *j.axis.xyz;
                    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
                    if n.is_nan()
                        || n <= 0.0
                        || a[0].abs() > PLANAR_TOL * n
                        || a[2].abs() > PLANAR_TOL * n
                    {
                        return Err(ModelError::NonPlanar {
                            origin: origin.to_string(),
                            joint: j.name.clone(),
                            what: "axis",
                            value: a,
                        });
                    }
                    JointKind::Revolute {
                        axis_sign: a[1].signum(),
                    }
                }
                urdf_rs::JointType::Prismatic => {
                    let a = *j.axis.xyz;
                    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
                    if n.is_nan() || n <= 0.0 || a[1].abs() > PLANAR_TOL * n {
                        return Err(ModelError::NonPlanar {
                            origin: origin.to_string(),
                            joint: j.name.clone(),
                            what: "axis",
                            value: a,
                        });
                    }
                    JointKind::Prismatic {
                        axis_xz: [a[0] / n, a[2] / n],
                    }
                }
                ref other => {
                    return Err(ModelError::UnsupportedJoint {
                        origin: origin.to_string(),
                        joint: j.name.clone(),
                        kind: format!("{other:?}").to_lowercase(),
                    })
                }
            };
            let (lower, upper, effort, velocity) = limits(j, origin)?;
            let body_index = model.bodies.len();
            let joint_index = model.joints.len();
            let mut joint_path = model.bodies[body].joint_path.clone();
            joint_path.push(joint_index);
            model.joints.push(Joint {
                name: j.name.clone(),
                kind,
                role: match kind {
                    JointKind::Revolute { .. } => JointRole::Actuated,
                    JointKind::Prismatic { .. } => JointRole::Design,
                },
                body: body_index,
                coordinate: crate::robot::BASE_DOF + joint_index,
                lower,
                upper,
                effort_limit: effort,
                velocity_limit: velocity,
                drive: JointDrive::default(),
            });
            model.bodies.push(Body {
                name: child.to_string(),
                parent: Some(body),
                joint: Some(joint_index),
                origin_xz_m: o.xz,
                origin_pitch_rad: o.pitch,
                inertia: BodyInertia::ZERO,
                joint_path,
            });
            children.push((child, body_index, Planar::IDENTITY));
        }
        stack.extend(children.into_iter().rev());
    }
    if visited.len() != robot.links.len() {
        let missing: Vec<&str> = robot
            .links
            .iter()
            .map(|l| l.name.as_str())
            .filter(|n| !visited.contains(n))
            .collect();
        return Err(err_tree(format!(
            "links not reachable from root '{root}' (a loop): {}",
            missing.join(", ")
        )));
    }
    // Bodies were numbered in push order, which is not depth-first when a link has several
    // movable children; parents always precede children, which is all the kinematics needs.
    model.check_capacity()?;
    Ok(model)
}

fn limits(j: &urdf_rs::Joint, origin: &str) -> Result<(f64, f64, f64, f64)> {
    let l = &j.limit;
    let bad = |field: &'static str, value: f64| ModelError::BadLimit {
        origin: origin.to_string(),
        joint: j.name.clone(),
        field,
        value,
    };
    if j.joint_type == urdf_rs::JointType::Continuous {
        return Ok((
            f64::NEG_INFINITY,
            f64::INFINITY,
            l.effort.max(0.0),
            l.velocity.abs(),
        ));
    }
    if l.lower.is_nan() {
        return Err(bad("lower", l.lower));
    }
    if l.upper.is_nan() || l.upper < l.lower {
        return Err(bad("upper", l.upper));
    }
    if l.effort.is_nan() || l.effort < 0.0 {
        return Err(bad("effort", l.effort));
    }
    if l.velocity.is_nan() || l.velocity < 0.0 {
        return Err(bad("velocity", l.velocity));
    }
    Ok((l.lower, l.upper, l.effort, l.velocity))
}
