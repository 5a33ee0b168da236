//! `adam logs recover`: a damaged or cut-off log rewritten whole, with an honest account of what
//! the damage took.
//!
//! ```text
//! damaged.mcap ─▶ salvage (every chunk and attachment whose CRC holds, schemas and channels
//!                  from wherever they survive) ─▶ recovered.mcap: zstd chunks, summary and
//!                  indexes rebuilt, a `recovery` metadata record with the account
//!              └─▶ RecoverStats: counts, and the Loss (damaged bytes, lost chunks with their
//!                  time ranges and message counts, lost attachments; "unknown" where the file
//!                  cannot tell)
//! ```
//! Damage outside the data (header, metadata, summary, footer) loses no message: the summary is
//! rebuilt from the chunks. A chunk whose CRC fails is lost whole; its time range comes from its
//! own header or the summary's chunk index, its message count from its message indexes.
//!
//! ```no_run
//! let stats = runtime::telemetry::recover::recover("run.mcap", "run.recovered.mcap").unwrap();
//! print!("{stats}");
//! ```

use crate::telemetry::loss::Loss;
use crate::telemetry::salvage::{check_schema_version, log_err, read_bytes, Salvaged};
use crate::{Result, RuntimeError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What [`recover`] rewrote, and what the input had lost.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecoverStats {
    /// The input.
    pub input: PathBuf,
    /// The output.
    pub output: PathBuf,
    /// Messages copied.
    pub messages: u64,
    /// Attachments copied.
    pub attachments: u64,
    /// Metadata records copied (plus the added `recovery` record).
    pub metadata: u64,
    /// What the input had lost (intact: nothing).
    pub loss: Loss,
}

impl RecoverStats {
    /// The input was read whole: footer read, nothing damaged.
    pub fn input_intact(&self) -> bool {
        self.loss.is_intact()
    }
}

impl std::fmt::Display for RecoverStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} -> {}: {} messages, {} attachments, {} metadata records",
            self.input.display(),
            self.output.display(),
            self.messages,
            self.attachments,
            self.metadata
        )?;
        if self.input_intact() {
            return writeln!(f, "the input was intact: nothing lost, nothing repaired");
        }
        write!(f, "{}", self.loss)
    }
}

/// Rewrite every readable record of `input` into `output` (zstd chunks, summary and indexes),
/// adding a `recovery` metadata record that says what was recovered and what was lost.
pub fn recover(input: impl AsRef<Path>, output: impl AsRef<Path>) -> Result<RecoverStats> {
    let (input, output) = (input.as_ref(), output.as_ref());
    let bytes = read_bytes(input)?;
    let log = Salvaged::read(input, &bytes)?;
    let file = std::fs::File::create(output).map_err(|error| RuntimeError::Io {
        path: output.to_path_buf(),
        error,
    })?;
    let mut writer = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .profile("")
        .library(concat!(
            "adam-hzd runtime ",
            env!("CARGO_PKG_VERSION"),
            " (recovered)"
        ))
        .create(std::io::BufWriter::new(file))
        .map_err(|e| log_err(output, e))?;
    let mut stats = RecoverStats {
        input: input.to_path_buf(),
        output: output.to_path_buf(),
        messages: 0,
        attachments: 0,
        metadata: 0,
        loss: log.loss.clone(),
    };
    for (header, data) in &log.attachments {
        writer
            .attach(&mcap::Attachment {
                log_time: header.log_time,
                create_time: header.create_time,
                name: header.name.clone(),
                media_type: header.media_type.clone(),
                data: std::borrow::Cow::Borrowed(data),
            })
            .map_err(|e| log_err(output, e))?;
        stats.attachments += 1;
    }
    for m in &log.metadata {
        // An earlier recovery's account is kept beside this one, under its own name.
        writer.write_metadata(m).map_err(|e| log_err(output, e))?;
        stats.metadata += 1;
    }
    let mut ids: BTreeMap<u16, u16> = BTreeMap::new();
    for m in log.messages() {
        let id = match ids.get(&m.channel.id) {
            Some(id) => *id,
            None => {
                check_schema_version(input, &m.channel)?;
                let schema_id = match &m.channel.schema {
                    Some(s) => writer
                        .add_schema(&s.name, &s.encoding, &s.data)
                        .map_err(|e| log_err(output, e))?,
                    None => 0,
                };
                let id = writer
                    .add_channel(
                        schema_id,
                        &m.channel.topic,
                        &m.channel.message_encoding,
                        &m.channel.metadata,
                    )
                    .map_err(|e| log_err(output, e))?;
                ids.insert(m.channel.id, id);
                id
            }
        };
        writer
            .write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: id,
                    sequence: m.sequence,
                    log_time: m.log_time,
                    publish_time: m.publish_time,
                },
                &m.data,
            )
            .map_err(|e| log_err(output, e))?;
        stats.messages += 1;
    }
    let loss = &stats.loss;
    let mut note = BTreeMap::new();
    note.insert("source".into(), input.display().to_string());
    note.insert("source_bytes".into(), bytes.len().to_string());
    note.insert("messages".into(), stats.messages.to_string());
    note.insert("lost_chunks".into(), loss.chunks.len().to_string());
    note.insert(
        "lost_messages".into(),
        loss.lost_messages()
            .map_or_else(|| "unknown".into(), |n| n.to_string()),
    );
    note.insert(
        "summary".into(),
        loss.summary()
            .unwrap_or_else(|| "the input was intact".into()),
    );
    note.insert("account".into(), loss.to_string());
    writer
        .write_metadata(&mcap::records::Metadata {
            name: "recovery".into(),
            metadata: note,
        })
        .map_err(|e| log_err(output, e))?;
    stats.metadata += 1;
    writer.finish().map_err(|e| log_err(output, e))?;
    Ok(stats)
}
