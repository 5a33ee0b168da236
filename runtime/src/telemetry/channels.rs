//! The logged channels' JSON schemas and the messages of one [`StateSample`], shared by the MCAP
//! writer ([`crate::telemetry::log`]) and the live view ([`crate::live`]), so a layout made on a
//! log works live and the other way round: one function builds each, whichever sink it feeds.

use crate::slots::{OUTPUTS, SLOTS};
use crate::telemetry::sample::StateSample;
use serde_json::{json, Map, Value};

/// Names of the logged channels.
pub const CHANNELS: [&str; 10] = [
    "/joints",
    "/hzd",
    "/estimator",
    "/state",
    "/safety",
    "/transitions",
    "/input",
    "/command",
    "/speed",
    "/can",
];

/// One channel: its topic, schema name (`jsonschema`) and schema; messages are JSON.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelSchema {
    /// Topic, e.g. `/joints`.
    pub topic: &'static str,
    /// Schema name, e.g. `adam.Joints`.
    pub schema_name: &'static str,
    /// The JSON schema.
    pub schema: Value,
}

fn number() -> Value {
    json!({"type": "number"})
}

fn object_of(names: impl Iterator<Item = String>, item: Value) -> Value {
    let props: Map<String, Value> = names.map(|n| (n, item.clone())).collect();
    json!({"type": "object", "properties": props})
}

/// The schemas of [`CHANNELS`], in that order, for a run with these joints (by slot; `None`:
/// not driven) and outputs.
pub fn channel_schemas(
    joint_names: &[Option<String>; SLOTS],
    output_names: &[String; OUTPUTS],
) -> Vec<ChannelSchema> {
    let joint = json!({"type": "object", "properties": {
        "q_rad": number(), "dq_rad_s": number(), "tau_nm": number(),
        "temperature_c": number(), "q_cmd_rad": number(), "dq_cmd_rad_s": number(),
        "tau_cmd_nm": number(), "fresh": {"type": "boolean"}}});
    let mut joints = object_of(joint_names.iter().flatten().cloned(), joint);
    joints["properties"]["t_s"] = number();
    let outputs = || object_of(output_names.iter().cloned(), number());
    let hzd = json!({"type": "object", "properties": {
        "t_s": number(), "phase": number(), "phase_rate_per_s": number(),
        "stance": {"type": "string"}, "steps": {"type": "integer"},
        "recoveries": {"type": "integer"}, "catches": {"type": "integer"},
        "swing_foot_height_m": number(),
        "y_des_rad": outputs(), "dy_des_rad_s": outputs(), "y_act_rad": outputs(),
        "y_err_rad": outputs()}});
    let estimator = json!({"type": "object", "properties": {
        "t_s": number(), "pitch_rad": number(), "pitch_rate_rad_s": number(),
        "gyro_bias_rad_s": number(), "imu_gyro_rad_s": number(),
        "imu_accel_x_mps2": number(), "imu_accel_z_mps2": number()}});
    let state = json!({"type": "object", "properties": {
        "t_s": number(), "tick": {"type": "integer"}, "state": {"type": "string"},
        "state_code": {"type": "integer"}, "trip_code": {"type": "integer"},
        "overruns": {"type": "integer"}, "overrun_streak": {"type": "integer"},
        "tick_compute_us": number()}});
    let safety = json!({"type": "object", "properties": {
        "t_s": number(), "tick": {"type": "integer"}, "reason": {"type": "string"},
        "code": {"type": "integer"}}, "additionalProperties": true});
    let transitions = json!({"type": "object", "properties": {
        "t_s": number(), "from": {"type": "string"}, "to": {"type": "string"}}});
    // One `type` per field: Foxglove's JSON-schema reader takes no type lists (see the tests).
    let exact = || {
        json!({"type": "number",
            "description": "non-finite values are the strings \"NaN\", \"inf\", \"-inf\""})
    };
    let motor = json!({"type": "object", "properties": {
        "fresh": {"type": "boolean"}, "q_rad": exact(), "dq_rad_s": exact(),
        "tau_nm": exact(), "temperature_c": exact(), "errors": {"type": "integer"}}});
    let mut input = object_of(joint_names.iter().flatten().cloned(), motor);
    input["properties"]["t_s"] = exact();
    input["properties"]["tick"] = json!({"type": "integer"});
    input["properties"]["overrun_streak"] = json!({"type": "integer"});
    input["properties"]["operator"] =
        json!({"type": "string", "description": "null: no operator command this tick"});
    input["properties"]["imu"] = json!({"type": "object",
        "description": "null: no IMU sample this tick", "properties": {
        "t_s": exact(), "gyro_pitch_rad_s": exact(), "accel_x_mps2": exact(),
        "accel_z_mps2": exact()}});
    let joint_command = json!({"type": "object", "properties": {
        "mode": {"type": "string", "enum": ["pd", "damping"]}, "q_des_rad": exact(),
        "dq_des_rad_s": exact(), "kp_nm_per_rad": exact(), "kd_nm_s_per_rad": exact(),
        "tau_ff_nm": exact()}});
    let mut command = object_of(joint_names.iter().flatten().cloned(), joint_command);
    command["properties"]["t_s"] = exact();
    command["properties"]["tick"] = json!({"type": "integer"});
    command["properties"]["state"] = json!({"type": "string"});
    let names = [
        "adam.Joints",
        "adam.Hzd",
        "adam.Estimator",
        "adam.State",
        "adam.SafetyTrip",
        "adam.Transition",
        "adam.TickInput",
        "adam.TickCommand",
        "adam.Speed",
        "adam.CanFrame",
    ];
    let schemas = [
        joints,
        hzd,
        estimator,
        state,
        safety,
        transitions,
        input,
        command,
        super::speed_log::speed_schema(),
        super::frames::frame_schema(),
    ];
    CHANNELS
        .iter()
        .zip(names)
        .zip(schemas)
        .map(|((&topic, schema_name), schema)| ChannelSchema {
            topic,
            schema_name,
            schema,
        })
        .collect()
}

fn side_name(stance: u32) -> &'static str {
    if stance == 0 {
        "left"
    } else {
        "right"
    }
}

/// The four messages of one sample: `/joints`, `/hzd`, `/estimator`, `/state` (the first four
/// of [`CHANNELS`], in that order). `/hzd` carries the tracking error `y_err_rad` = y^d − y^a
/// beside the outputs, for plots.
pub fn sample_messages(
    s: &StateSample,
    joint_names: &[Option<String>; SLOTS],
    output_names: &[String; OUTPUTS],
) -> [Value; 4] {
    let t = s.t_s;
    let mut joints = Map::new();
    joints.insert("t_s".into(), json!(t));
    for (slot, name) in joint_names.iter().enumerate() {
        let Some(name) = name else { continue };
        joints.insert(
            name.clone(),
            json!({
                "q_rad": s.q_rad[slot], "dq_rad_s": s.dq_rad_s[slot],
                "tau_nm": s.tau_nm[slot], "temperature_c": s.temperature_c[slot],
                "q_cmd_rad": s.q_cmd_rad[slot], "dq_cmd_rad_s": s.dq_cmd_rad_s[slot],
                "tau_cmd_nm": s.tau_cmd_nm[slot],
                "fresh": s.fresh_mask & (1 << slot) != 0,
            }),
        );
    }
    let outputs = |v: &[f64; OUTPUTS]| -> Value {
        let m: Map<String, Value> = output_names
            .iter()
            .zip(v)
            .map(|(n, x)| (n.clone(), json!(x)))
            .collect();
        Value::Object(m)
    };
    let hzd = json!({
        "t_s": t, "phase": s.phase, "phase_rate_per_s": s.phase_rate_per_s,
        "stance": side_name(s.stance), "steps": s.steps, "recoveries": s.recoveries,
        "catches": s.catches,
        "swing_foot_height_m": s.swing_foot_height_m,
        "y_des_rad": outputs(&s.y_des_rad), "dy_des_rad_s": outputs(&s.dy_des_rad_s),
        "y_act_rad": outputs(&s.y_act_rad),
        "y_err_rad": outputs(&std::array::from_fn(|i| s.y_des_rad[i] - s.y_act_rad[i])),
    });
    let estimator = json!({
        "t_s": t, "pitch_rad": s.pitch_rad, "pitch_rate_rad_s": s.pitch_rate_rad_s,
        "gyro_bias_rad_s": s.gyro_bias_rad_s, "imu_gyro_rad_s": s.imu_gyro_rad_s,
        "imu_accel_x_mps2": s.imu_accel_x_mps2, "imu_accel_z_mps2": s.imu_accel_z_mps2,
    });
    let state = json!({
        "t_s": t, "tick": s.tick, "state": s.control_state().name(),
        "state_code": s.state, "trip_code": s.trip_code, "overruns": s.overruns,
        "overrun_streak": s.overrun_streak,
        "tick_compute_us": s.tick_compute_ns as f64 * 1e-3,
    });
    [Value::Object(joints), hzd, estimator, state]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::telemetry::scene::scene_schemas;

    /// Whether Foxglove's JSON-schema reader (the one its MCAP and WebSocket players use to
    /// give a `jsonschema` channel its fields) takes `schema`: an object with `properties`,
    /// each of one `type` (boolean, string, number, integer, object, array; no type lists, no
    /// null), nested objects likewise, arrays with `items` of one such type. Anything else
    /// makes the viewer refuse the whole topic ("Unsupported type [...]").
    fn foxglove_reads(schema: &Value, path: &str) -> Result<(), String> {
        if schema["type"] != "object" {
            return Err(format!("{path}: type {} is not \"object\"", schema["type"]));
        }
        let props = schema["properties"]
            .as_object()
            .ok_or_else(|| format!("{path}: an object without properties"))?;
        for (name, field) in props {
            let at = format!("{path}.{name}");
            match field["type"].as_str() {
                Some("boolean" | "number" | "integer") => {}
                Some("string") if field.get("contentEncoding").is_none() => {}
                Some("object") => foxglove_reads(field, &at)?,
                Some("array") => match field["items"]["type"].as_str() {
                    Some("boolean" | "number" | "integer" | "string") => {}
                    Some("object") => foxglove_reads(&field["items"], &at)?,
                    _ => return Err(format!("{at}: array items {}", field["items"])),
                },
                _ => return Err(format!("{at}: type {}", field["type"])),
            }
        }
        Ok(())
    }

    #[test]
    fn every_schema_of_the_log_and_the_live_view_is_one_foxglove_reads() {
        let joints: [Option<String>; SLOTS] =
            std::array::from_fn(|i| (i % 2 == 0).then(|| format!("joint_{i}")));
        let outputs: [String; OUTPUTS] = std::array::from_fn(|i| format!("y{i}"));
        let schemas = channel_schemas(&joints, &outputs);
        assert_eq!(schemas.len(), CHANNELS.len());
        for c in &schemas {
            foxglove_reads(&c.schema, c.topic).unwrap_or_else(|e| panic!("{e}"));
        }
        for (name, schema) in scene_schemas() {
            foxglove_reads(&schema, name).unwrap_or_else(|e| panic!("{e}"));
        }
    }

    #[test]
    fn what_foxglove_refuses_is_refused_here() {
        let typed = |t: Value| json!({"type": "object", "properties": {"x": {"type": t}}});
        assert!(foxglove_reads(&typed(json!("number")), "ok").is_ok());
        assert!(foxglove_reads(&typed(json!(["number", "null"])), "list").is_err());
        assert!(foxglove_reads(&typed(json!("null")), "null").is_err());
        let bare_array = json!({"type": "object", "properties": {"a": {"type": "array"}}});
        assert!(foxglove_reads(&bare_array, "array").is_err());
        let no_props = json!({"type": "object", "properties": {"o": {"type": "object"}}});
        assert!(foxglove_reads(&no_props, "object").is_err());
    }
}
