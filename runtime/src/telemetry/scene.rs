//! The robot in 3D for Foxglove, in the log and live: per-sample `foxglove.FrameTransforms` of
//! every URDF link (`/tf`), the URDF itself (`/robot_description`, `std_msgs/String` in JSON,
//! so Foxglove's URDF layer can load it from a log or a live server), and a
//! `foxglove.SceneUpdate` (`/scene`) with the treadmill's belt and a stick figure of the links
//! (each line locked to its link's frame, so it moves with `/tf`).
//!
//! ```text
//! StateSample (motor q, estimated pitch; true pitch and belt position in simulation)
//!   ─ calibration (motor → joint) ─▶ planar forward kinematics (model::kinematics)
//!   ─▶ link poses in the plane, the lower foot on the belt (z = 0)
//!   ─▶ world → torso, then parent → child per URDF joint (y from the URDF: the hips' offsets)
//! ```
//! Two trees: the controller's (estimated pitch; the hip over the belt's centre, x = 0), and, in
//! simulation, the ground truth under the prefix [`TRUTH_PREFIX`] (true pitch; the hip at the
//! true position on the belt). The MCAP writer logs `/tf` every [`TF_LOG_PERIOD_S`] of
//! controller time and `/scene` + `/robot_description` every [`SCENE_LOG_PERIOD_S`]; the live
//! view decimates as it is told ([`crate::live`]).

use crate::slots::{SlotLayout, LEG_SLOTS, SLOTS};
use crate::telemetry::sample::StateSample;
use crate::{Result, RuntimeError};
use model::PlanarModel;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// Topic of the link transforms (`foxglove.FrameTransforms`).
pub const TF_TOPIC: &str = "/tf";
/// Topic of the belt and the stick figure (`foxglove.SceneUpdate`).
pub const SCENE_TOPIC: &str = "/scene";
/// Topic of the URDF text (`std_msgs/String`: `{"data": "<robot …>"}`).
pub const ROBOT_DESCRIPTION_TOPIC: &str = "/robot_description";
/// The three topics of this module, after the log's [`crate::telemetry::log::CHANNELS`].
pub const SCENE_TOPICS: [&str; 3] = [TF_TOPIC, SCENE_TOPIC, ROBOT_DESCRIPTION_TOPIC];
/// Frame prefix of the simulator's ground-truth tree.
pub const TRUTH_PREFIX: &str = "truth/";
/// The fixed frame: x forward along the belt from its centre, z up from its surface.
pub const WORLD_FRAME: &str = "world";
/// Period of `/tf` in the MCAP log, s of controller time (100 Hz).
pub const TF_LOG_PERIOD_S: f64 = 0.01;
/// Period of `/scene` and `/robot_description` in the MCAP log, s.
pub const SCENE_LOG_PERIOD_S: f64 = 1.0;

/// Schema names and JSON schemas of [`SCENE_TOPICS`], in that order.
pub fn scene_schemas() -> [(&'static str, Value); 3] {
    let vec3 = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}});
    let quat = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"},
        "w": {"type": "number"}}});
    let time = json!({"type": "object", "properties": {
        "sec": {"type": "integer"}, "nsec": {"type": "integer"}}});
    let tf = json!({"type": "object", "properties": {"transforms": {"type": "array", "items": {
        "type": "object", "properties": {"timestamp": time, "parent_frame_id": {"type": "string"},
        "child_frame_id": {"type": "string"}, "translation": vec3, "rotation": quat}}}}});
    let color = json!({"type": "object", "properties": {"r": {"type": "number"},
        "g": {"type": "number"}, "b": {"type": "number"}, "a": {"type": "number"}}});
    let pose = json!({"type": "object", "properties": {"position": vec3, "orientation": quat}});
    let entity = json!({"type": "object", "properties": {
        "timestamp": time, "frame_id": {"type": "string"}, "id": {"type": "string"},
        "lifetime": time, "frame_locked": {"type": "boolean"},
        "cubes": {"type": "array", "items": {"type": "object", "properties": {
            "pose": pose, "size": vec3, "color": color}}},
        "lines": {"type": "array", "items": {"type": "object", "properties": {
            "type": {"type": "integer"}, "pose": pose, "thickness": {"type": "number"},
            "scale_invariant": {"type": "boolean"}, "points": {"type": "array", "items": vec3},
            "color": color}}}}});
    let scene = json!({"type": "object", "properties": {
        "deletions": {"type": "array"}, "entities": {"type": "array", "items": entity}}});
    let string = json!({"type": "object", "properties": {"data": {"type": "string"}}});
    [
        ("foxglove.FrameTransforms", tf),
        ("foxglove.SceneUpdate", scene),
        ("std_msgs/String", string),
    ]
}

/// Foxglove's time: whole seconds and nanoseconds.
pub fn stamp(t_s: f64) -> Value {
    let ns = (t_s.max(0.0) * 1e9).round() as u64;
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

/// A rotation by `pitch_rad` about +y as a quaternion.
fn pitch_quat(pitch_rad: f64) -> Value {
    let (s, c) = (0.5 * pitch_rad).sin_cos();
    json!({"x": 0.0, "y": s, "z": 0.0, "w": c})
}

/// One URDF joint between two links the model knows.
#[derive(Clone, Debug)]
struct Edge {
    parent: String,
    child: String,
    parent_frame: usize,
    child_frame: usize,
    /// The joint origin's y in the parent link, m (the plane drops it).
    y_m: f64,
}

/// Link poses from a [`StateSample`]: the robot of a run, ready to give its transforms.
#[derive(Clone, Debug)]
pub struct RobotScene {
    model: PlanarModel,
    q: Vec<f64>,
    coords: [usize; LEG_SLOTS],
    layout: SlotLayout,
    edges: Vec<Edge>,
    root: String,
    feet: [usize; 2],
    torso_top_m: f64,
    belt_length_m: f64,
    urdf_text: String,
}

impl RobotScene {
    /// The robot of `setup` (its URDF, the gait's design, the config's leg joints and
    /// calibration); errors name the URDF and what is missing.
    pub fn new(setup: &crate::Setup, layout: SlotLayout) -> Result<Self> {
        let model = setup.model.clone();
        let origin = format!("URDF of {}", model.name);
        let urdf = urdf_rs::read_from_string(&setup.urdf_text).map_err(|e| {
            RuntimeError::InvalidField {
                origin: origin.clone(),
                field: "robot".into(),
                value: String::new(),
                reason: e.to_string(),
            }
        })?;
        let mut edges = Vec::new();
        for j in &urdf.joints {
            let (Some(parent_frame), Some(child_frame)) = (
                model.frame_index(&j.parent.link),
                model.frame_index(&j.child.link),
            ) else {
                continue;
            };
            edges.push(Edge {
                parent: j.parent.link.clone(),
                child: j.child.link.clone(),
                parent_frame,
                child_frame,
                y_m: j.origin.xyz[1],
            });
        }
        let nominal = model.nominal_pose()?;
        let design = &setup.gait.design;
        let q = model.with_design(&nominal, design.thigh_length_m, design.shin_length_m)?;
        let mut coords = [0usize; LEG_SLOTS];
        for (k, c) in coords.iter_mut().enumerate() {
            let name = &setup.config.leg_motors[k].joint;
            *c = model.joints[model.require_joint(name)?].coordinate;
        }
        let legs = model.legs()?;
        let com = model.bodies[0].inertia.com_xz_m;
        Ok(Self {
            root: model.bodies[0].name.clone(),
            feet: [legs.left.foot, legs.right.foot],
            torso_top_m: 2.0 * com[1].abs(),
            belt_length_m: drivers::sim::robot::DEFAULT_BELT_LENGTH_M,
            urdf_text: setup.urdf_text.clone(),
            model,
            q,
            coords,
            layout,
            edges,
        })
    }

    /// World (x, z, pitch) of every model frame, the lower foot on the belt and the root at
    /// `x_root_m`; `None` if the kinematics fail (a non-finite angle).
    fn frame_poses(
        &self,
        pitch_rad: f64,
        motor_q_rad: &[f64; SLOTS],
        x_root_m: f64,
    ) -> Option<Vec<[f64; 3]>> {
        let mut q = self.q.clone();
        q[0] = 0.0;
        q[1] = 0.0;
        q[2] = pitch_rad;
        for (k, &c) in self.coords.iter().enumerate() {
            q[c] = self.layout.model_rad(k, motor_q_rad[k]);
        }
        if q.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let st = self.model.body_poses(&q).ok()?;
        let mut poses: Vec<[f64; 3]> = (0..self.model.frames.len())
            .map(|f| {
                let p = self.model.frame_position_in(&st, f);
                let frame = &self.model.frames[f];
                [p[0], p[1], st.pose[frame.body].pitch_rad + frame.pitch_rad]
            })
            .collect();
        let ground = self
            .feet
            .iter()
            .map(|&f| poses[f][1])
            .fold(f64::MAX, f64::min);
        for p in &mut poses {
            p[0] += x_root_m;
            p[1] -= ground;
        }
        Some(poses)
    }

    fn tree(&self, out: &mut Vec<Value>, t_s: f64, prefix: &str, poses: &[[f64; 3]]) {
        let time = stamp(t_s);
        // The root link's frame is at the base origin: body 0's pose.
        if let Some(root) = self.model.frame_index(&self.root) {
            let p = poses[root];
            out.push(json!({"timestamp": time, "parent_frame_id": WORLD_FRAME,
                "child_frame_id": format!("{prefix}{}", self.root),
                "translation": {"x": p[0], "y": 0.0, "z": p[1]}, "rotation": pitch_quat(p[2])}));
        }
        for e in &self.edges {
            let (p, c) = (poses[e.parent_frame], poses[e.child_frame]);
            let rel = model::kinematics::rot(-p[2], [c[0] - p[0], c[1] - p[1]]);
            out.push(json!({"timestamp": time,
                "parent_frame_id": format!("{prefix}{}", e.parent),
                "child_frame_id": format!("{prefix}{}", e.child),
                "translation": {"x": rel[0], "y": e.y_m, "z": rel[1]},
                "rotation": pitch_quat(c[2] - p[2])}));
        }
    }

    /// `/tf` of one sample: the controller's tree, and the ground truth's when the sample has
    /// it (`true_pitch_rad` finite).
    pub fn transforms(&self, s: &StateSample) -> Value {
        let mut transforms = Vec::with_capacity(2 * (self.edges.len() + 1));
        if let Some(poses) = self.frame_poses(s.pitch_rad, &s.q_rad, 0.0) {
            self.tree(&mut transforms, s.t_s, "", &poses);
        }
        if s.true_pitch_rad.is_finite() {
            let x = if s.true_belt_position_m.is_finite() {
                s.true_belt_position_m
            } else {
                0.0
            };
            if let Some(poses) = self.frame_poses(s.true_pitch_rad, &s.q_rad, x) {
                self.tree(&mut transforms, s.t_s, TRUTH_PREFIX, &poses);
            }
        }
        json!({ "transforms": transforms })
    }

    /// `/scene` at `t_s`: the belt, and the links as lines in their own frames (both trees).
    pub fn scene_update(&self, t_s: f64) -> Value {
        let time = stamp(t_s);
        let forever = json!({"sec": 0, "nsec": 0});
        let identity = json!({"position": {"x": 0.0, "y": 0.0, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}});
        let belt = json!({"timestamp": time, "frame_id": WORLD_FRAME, "id": "belt",
            "lifetime": forever, "frame_locked": false,
            "cubes": [{"pose": {"position": {"x": 0.0, "y": 0.0, "z": -0.025},
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
                "size": {"x": self.belt_length_m, "y": 0.5, "z": 0.05},
                "color": {"r": 0.25, "g": 0.25, "b": 0.25, "a": 1.0}}],
            "lines": []});
        let mut entities = vec![belt];
        // Segments per link at the nominal pose: each child joint's origin in its parent.
        let zero = [0.0; SLOTS];
        let Some(poses) = self.frame_poses(0.0, &zero, 0.0) else {
            return json!({"deletions": [], "entities": entities});
        };
        let mut links: BTreeMap<&str, Vec<Value>> = BTreeMap::new();
        links.entry(self.root.as_str()).or_default().push(json!([
            {"x": 0.0, "y": 0.0, "z": 0.0}, {"x": 0.0, "y": 0.0, "z": self.torso_top_m}]));
        for e in &self.edges {
            let (p, c) = (poses[e.parent_frame], poses[e.child_frame]);
            let rel = model::kinematics::rot(-p[2], [c[0] - p[0], c[1] - p[1]]);
            if rel[0].hypot(rel[1]) + e.y_m.abs() < 1e-9 {
                continue;
            }
            links.entry(e.parent.as_str()).or_default().push(json!([
                {"x": 0.0, "y": 0.0, "z": 0.0}, {"x": rel[0], "y": e.y_m, "z": rel[1]}]));
        }
        for (prefix, color) in [
            ("", json!({"r": 0.1, "g": 0.45, "b": 0.9, "a": 1.0})),
            (
                TRUTH_PREFIX,
                json!({"r": 0.2, "g": 0.8, "b": 0.3, "a": 0.5}),
            ),
        ] {
            for (link, segments) in &links {
                let lines: Vec<Value> = segments
                    .iter()
                    .map(|points| {
                        json!({"type": 2, "pose": identity, "thickness": 0.03,
                            "scale_invariant": false, "points": points, "color": color})
                    })
                    .collect();
                entities.push(
                    json!({"timestamp": time, "frame_id": format!("{prefix}{link}"),
                    "id": format!("{prefix}link/{link}"), "lifetime": forever,
                    "frame_locked": true, "cubes": [], "lines": lines}),
                );
            }
        }
        json!({"deletions": [], "entities": entities})
    }

    /// `/robot_description`: the URDF text.
    pub fn robot_description(&self) -> Value {
        json!({ "data": self.urdf_text })
    }
}

/// The MCAP channel ids of [`SCENE_TOPICS`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct SceneChannels {
    ids: [u16; 3],
}

/// Adds the schemas and channels of [`SCENE_TOPICS`] to an MCAP writer.
pub(crate) fn add_scene_channels<W: std::io::Write + std::io::Seek>(
    w: &mut mcap::Writer<W>,
    meta: &BTreeMap<String, String>,
) -> mcap::McapResult<SceneChannels> {
    let mut ids = [0u16; 3];
    for (id, (topic, (name, schema))) in
        ids.iter_mut().zip(SCENE_TOPICS.iter().zip(scene_schemas()))
    {
        let text = serde_json::to_vec(&schema).unwrap_or_default();
        let sid = w.add_schema(name, "jsonschema", &text)?;
        *id = w.add_channel(sid, topic, "json", meta)?;
    }
    Ok(SceneChannels { ids })
}

/// The writer thread's side: when to write `/tf`, `/scene` and `/robot_description`.
#[derive(Clone, Debug, Default)]
pub(crate) struct SceneLog {
    next_tf_s: Option<f64>,
    next_scene_s: Option<f64>,
}

/// Half a microsecond: sample times are sums of periods, a hair off the due time.
const DUE_SLACK_S: f64 = 5e-7;

/// The next due time after one at `t_s`: on the grid of `period_s` from the first, or a period
/// after `t_s` when the samples skipped more than a period.
fn next_due(previous: Option<f64>, t_s: f64, period_s: f64) -> f64 {
    let next = previous.unwrap_or(t_s) + period_s;
    if next > t_s + DUE_SLACK_S {
        next
    } else {
        t_s + period_s
    }
}

impl SceneLog {
    /// Writes what is due at sample `s`; returns the number of messages written.
    pub(crate) fn write<W: std::io::Write + std::io::Seek>(
        &mut self,
        w: &mut mcap::Writer<W>,
        scene: Option<&RobotScene>,
        ids: &SceneChannels,
        s: &StateSample,
        seq: &mut u32,
    ) -> mcap::McapResult<u64> {
        let Some(scene) = scene else {
            return Ok(0);
        };
        let mut put = |channel: u16, v: &Value| {
            let data = serde_json::to_vec(v).unwrap_or_default();
            *seq = seq.wrapping_add(1);
            let t_ns = (s.t_s.max(0.0) * 1e9).round() as u64;
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: channel,
                    sequence: *seq,
                    log_time: t_ns,
                    publish_time: t_ns,
                },
                &data,
            )
        };
        let mut n = 0;
        let due = |next: Option<f64>| next.is_none_or(|t| s.t_s >= t - DUE_SLACK_S);
        if due(self.next_scene_s) {
            self.next_scene_s = Some(next_due(self.next_scene_s, s.t_s, SCENE_LOG_PERIOD_S));
            put(ids.ids[2], &scene.robot_description())?;
            put(ids.ids[1], &scene.scene_update(s.t_s))?;
            n += 2;
        }
        if due(self.next_tf_s) {
            self.next_tf_s = Some(next_due(self.next_tf_s, s.t_s, TF_LOG_PERIOD_S));
            put(ids.ids[0], &scene.transforms(s))?;
            n += 1;
        }
        Ok(n)
    }
}
