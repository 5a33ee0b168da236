//! The Foxglove WebSocket protocol (`foxglove.websocket.v1`), sans-IO: the server's messages
//! as text or bytes, and the client's parsed into [`ClientMessage`] / [`ClientData`] with
//! errors that say what is wrong. The subset a read-only viewer with client publishing needs:
//! `serverInfo`, `advertise`, `status`, binary `messageData` from the server; `subscribe`,
//! `unsubscribe`, `advertise`, `unadvertise` and binary client message data from the client.
//! Anything else a client sends is an error.

use serde::Deserialize;
use serde_json::{json, Value};

/// The WebSocket subprotocol, i.e. the protocol version, a client must offer.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";

/// Opcode of the server's binary `messageData`.
pub const OP_MESSAGE_DATA: u8 = 0x01;
/// Opcode of the client's binary message data on a channel it advertised.
pub const OP_CLIENT_MESSAGE_DATA: u8 = 0x01;

/// Severity of a `status` message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// Information (level 0).
    Info = 0,
    /// Warning (level 1).
    Warning = 1,
    /// Error (level 2).
    Error = 2,
}

/// A channel the server advertises (messages JSON, schema `jsonschema`).
#[derive(Clone, Debug, PartialEq)]
pub struct ServerChannel {
    /// Channel id.
    pub id: u32,
    /// Topic.
    pub topic: String,
    /// Schema name.
    pub schema_name: String,
    /// The JSON schema, as text.
    pub schema: String,
}

/// `serverInfo`: the server's name, capabilities (`clientPublish` when commands are allowed)
/// and encodings it accepts from clients.
pub fn server_info(name: &str, client_publish: bool, session_id: &str) -> String {
    let (capabilities, encodings): (Vec<&str>, Vec<&str>) = if client_publish {
        (vec!["clientPublish"], vec!["json"])
    } else {
        (vec![], vec![])
    };
    json!({"op": "serverInfo", "name": name, "capabilities": capabilities,
        "supportedEncodings": encodings, "metadata": {}, "sessionId": session_id})
    .to_string()
}

/// `advertise` of `channels`.
pub fn advertise(channels: &[ServerChannel]) -> String {
    let list: Vec<Value> = channels
        .iter()
        .map(|c| {
            json!({"id": c.id, "topic": c.topic, "encoding": "json",
                "schemaName": c.schema_name, "schema": c.schema, "schemaEncoding": "jsonschema"})
        })
        .collect();
    json!({"op": "advertise", "channels": list}).to_string()
}

/// `status` with a message.
pub fn status(level: Level, message: &str) -> String {
    json!({"op": "status", "level": level as u8, "message": message}).to_string()
}

/// Binary `messageData`: opcode, subscription id (u32 LE), time (u64 LE, ns), payload.
pub fn message_data(subscription_id: u32, t_ns: u64, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(13 + payload.len());
    out.push(OP_MESSAGE_DATA);
    out.extend_from_slice(&subscription_id.to_le_bytes());
    out.extend_from_slice(&t_ns.to_le_bytes());
    out.extend_from_slice(payload);
    out
}

/// One subscription a client asks for.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct Subscription {
    /// The client's id for it (used in `messageData`).
    pub id: u32,
    /// The server channel.
    #[serde(rename = "channelId")]
    pub channel_id: u32,
}

/// A channel a client advertises to publish on.
#[derive(Clone, Debug, Deserialize, PartialEq, Eq)]
pub struct ClientChannel {
    /// The client's id for it.
    pub id: u32,
    /// Topic.
    pub topic: String,
    /// Message encoding (`json` is the only one accepted).
    pub encoding: String,
    /// Schema name.
    #[serde(rename = "schemaName", default)]
    pub schema_name: String,
}

/// A text message from a client.
#[derive(Clone, Debug, PartialEq)]
pub enum ClientMessage {
    /// Subscribe to server channels.
    Subscribe(Vec<Subscription>),
    /// End subscriptions by their ids.
    Unsubscribe(Vec<u32>),
    /// Advertise channels to publish on.
    Advertise(Vec<ClientChannel>),
    /// Withdraw advertised channels by id.
    Unadvertise(Vec<u32>),
}

#[derive(Deserialize)]
#[serde(tag = "op")]
enum Wire {
    #[serde(rename = "subscribe")]
    Subscribe { subscriptions: Vec<Subscription> },
    #[serde(rename = "unsubscribe")]
    Unsubscribe {
        #[serde(rename = "subscriptionIds")]
        subscription_ids: Vec<u32>,
    },
    #[serde(rename = "advertise")]
    Advertise { channels: Vec<ClientChannel> },
    #[serde(rename = "unadvertise")]
    Unadvertise {
        #[serde(rename = "channelIds")]
        channel_ids: Vec<u32>,
    },
}

/// Why a client message was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ProtocolError {
    /// Not JSON, or not one of the operations this server knows.
    #[error("malformed client message ({message}): {excerpt}")]
    Malformed {
        /// What the parser said.
        message: String,
        /// The message's first characters.
        excerpt: String,
    },
    /// A binary message that is not client message data.
    #[error("binary client message: {0}")]
    Binary(String),
}

impl ClientMessage {
    /// Parses a text message.
    pub fn parse(text: &str) -> Result<Self, ProtocolError> {
        let wire: Wire = serde_json::from_str(text).map_err(|e| ProtocolError::Malformed {
            message: e.to_string(),
            excerpt: text.chars().take(80).collect(),
        })?;
        Ok(match wire {
            Wire::Subscribe { subscriptions } => Self::Subscribe(subscriptions),
            Wire::Unsubscribe { subscription_ids } => Self::Unsubscribe(subscription_ids),
            Wire::Advertise { channels } => Self::Advertise(channels),
            Wire::Unadvertise { channel_ids } => Self::Unadvertise(channel_ids),
        })
    }
}

/// A binary message from a client: data on a channel it advertised.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ClientData<'a> {
    /// The client's channel id.
    pub channel_id: u32,
    /// The message.
    pub payload: &'a [u8],
}

impl<'a> ClientData<'a> {
    /// Parses a binary message: opcode 0x01, channel id (u32 LE), payload.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ProtocolError> {
        match bytes {
            [OP_CLIENT_MESSAGE_DATA, a, b, c, d, payload @ ..] => Ok(Self {
                channel_id: u32::from_le_bytes([*a, *b, *c, *d]),
                payload,
            }),
            [op, ..] if *op != OP_CLIENT_MESSAGE_DATA => {
                Err(ProtocolError::Binary(format!("unknown opcode 0x{op:02x}")))
            }
            _ => Err(ProtocolError::Binary(format!(
                "{} bytes, want at least 5 (opcode and channel id)",
                bytes.len()
            ))),
        }
    }

    /// Client message data as bytes (what a client sends; for tests and tools).
    pub fn encode(channel_id: u32, payload: &[u8]) -> Vec<u8> {
        let mut out = vec![OP_CLIENT_MESSAGE_DATA];
        out.extend_from_slice(&channel_id.to_le_bytes());
        out.extend_from_slice(payload);
        out
    }
}

/// A server `messageData` parsed back: subscription id, time (ns), payload (for clients and
/// tests).
pub fn parse_message_data(bytes: &[u8]) -> Option<(u32, u64, &[u8])> {
    match bytes {
        [OP_MESSAGE_DATA, rest @ ..] if rest.len() >= 12 => {
            let sub = u32::from_le_bytes(rest[0..4].try_into().ok()?);
            let t = u64::from_le_bytes(rest[4..12].try_into().ok()?);
            Some((sub, t, &rest[12..]))
        }
        _ => None,
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_subscribe_parses_and_garbage_is_malformed_with_an_excerpt() {
        let m = ClientMessage::parse(
            r#"{"op":"subscribe","subscriptions":[{"id":7,"channelId":2},{"id":8,"channelId":3}]}"#,
        )
        .unwrap();
        assert_eq!(
            m,
            ClientMessage::Subscribe(vec![
                Subscription {
                    id: 7,
                    channel_id: 2
                },
                Subscription {
                    id: 8,
                    channel_id: 3
                }
            ])
        );
        let e = ClientMessage::parse("{not json").unwrap_err();
        assert!(e.to_string().contains("{not json"), "{e}");
        let e = ClientMessage::parse(r#"{"op":"getParameters","parameterNames":[]}"#).unwrap_err();
        assert!(matches!(e, ProtocolError::Malformed { .. }));
    }

    #[test]
    fn advertise_carries_every_channel_with_its_schema() {
        let text = advertise(&[ServerChannel {
            id: 3,
            topic: "/tf".into(),
            schema_name: "foxglove.FrameTransforms".into(),
            schema: "{}".into(),
        }]);
        let v: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["op"], "advertise");
        assert_eq!(v["channels"][0]["id"], 3);
        assert_eq!(v["channels"][0]["schemaEncoding"], "jsonschema");
        assert_eq!(v["channels"][0]["encoding"], "json");
    }

    proptest! {
        #[test]
        fn message_data_round_trips(sub in any::<u32>(), t in any::<u64>(),
                                    payload in proptest::collection::vec(any::<u8>(), 0..64)) {
            let bytes = message_data(sub, t, &payload);
            prop_assert_eq!(parse_message_data(&bytes), Some((sub, t, &payload[..])));
        }

        #[test]
        fn client_data_round_trips(id in any::<u32>(),
                                   payload in proptest::collection::vec(any::<u8>(), 0..64)) {
            let bytes = ClientData::encode(id, &payload);
            let d = ClientData::parse(&bytes).unwrap();
            prop_assert_eq!(d.channel_id, id);
            prop_assert_eq!(d.payload, &payload[..]);
        }

        #[test]
        fn arbitrary_bytes_and_text_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..32),
                                                text in ".{0,64}") {
            let _ = ClientData::parse(&bytes);
            let _ = parse_message_data(&bytes);
            prop_assert!(ClientMessage::parse(&text).is_err() || text.contains("op"));
        }
    }
}
