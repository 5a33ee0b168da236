//! Every reader of our MCAP logs goes through here: one pass over the file's records that keeps
//! every record that is whole, steps over damage and says exactly what it lost.
//!
//! ```text
//! bytes ─▶ record at pos: opcode, length, content ─┬─ whole ──────────▶ kept (chunks: CRC holds)
//!                                                   └─ bad or cut off ─▶ scan forward for the next
//!            position where a chunk or attachment whose CRC holds starts (or a run of records
//!            that leads to one, or to the footer): the bytes in between are damage
//! kept chunks ─▶ messages in file order (Salvaged::messages)
//! summary chunk indexes + message indexes + chunk headers ─▶ what the damage held (Loss)
//! data and summary CRCs ─▶ damage to records that still parse
//! ```
//! Schemas and channels are taken from wherever they survive (before the damage, inside kept
//! chunks, or in the summary), so the messages of every kept chunk decode. A damaged length
//! field never makes a reader allocate what it claims: lengths are checked against the file,
//! chunk sizes against 64 × the file (at least 256 MiB), and the records inside a chunk against
//! the chunk's own sizes. What was lost is a [`Loss`].

use crate::telemetry::log::{LOG_SCHEMA_VERSION, SCHEMA_VERSION_KEY};
use crate::telemetry::loss::{Damage, Loss, LostChunk};
use crate::{Result, RuntimeError};
use mcap::records::{self, Record};
use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

/// An error about the log `path`.
pub(crate) fn log_err(path: &Path, e: impl std::fmt::Display) -> RuntimeError {
    RuntimeError::Log {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// The file's bytes (whether they are MCAP at all is for [`Salvaged::read`] to say).
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|error| RuntimeError::Io {
        path: path.to_path_buf(),
        error,
    })
}

/// Refuse a channel of another log schema version (or an unversioned one).
pub fn check_schema_version(path: &Path, channel: &mcap::Channel<'_>) -> Result<()> {
    let found = channel.metadata.get(SCHEMA_VERSION_KEY);
    if found.map(String::as_str) == Some(LOG_SCHEMA_VERSION.to_string().as_str()) {
        return Ok(());
    }
    Err(RuntimeError::LogSchemaVersion {
        path: path.to_path_buf(),
        channel: channel.topic.clone(),
        found: found.cloned().unwrap_or_else(|| "none".into()),
        expected: LOG_SCHEMA_VERSION,
    })
}

/// MCAP's magic, at the start and at the end of a file.
pub(crate) const MAGIC: &[u8] = b"\x89MCAP0\r\n";

const OP_FOOTER: u8 = 0x02;
const OP_CHUNK: u8 = 0x06;
const OP_ATTACHMENT: u8 = 0x09;
const OP_DATA_END: u8 = 0x0F;
/// Opcode (1 byte) and length (8 bytes) in front of every record.
const PREFIX: usize = 9;
/// A run of this many whole records after damage counts as a resynchronisation even if no
/// record with a CRC is among them (the summary is a long run of index records).
const CHAIN: usize = 16;

/// The most a chunk may claim to decompress to: 64 × the file (zstd on our JSON stays far
/// below that ratio), at least 256 MiB; more is damage, never an allocation.
pub(crate) fn size_limit(file_bytes: usize) -> u64 {
    (file_bytes as u64).saturating_mul(64).max(256 << 20)
}

/// A chunk whose CRC holds.
#[derive(Clone, Debug)]
struct KeptChunk {
    header: records::ChunkHeader,
    data: Range<usize>,
}

/// What the file holds in order: chunks and messages outside chunks.
#[derive(Clone, Debug)]
enum Item {
    Chunk(KeptChunk),
    Message(records::MessageHeader, Range<usize>),
}

/// CRC-32 (IEEE), as MCAP's data and summary CRCs use it.
fn crc32(data: &[u8]) -> u32 {
    const TABLE: [u32; 256] = {
        let mut table = [0u32; 256];
        let mut i = 0;
        while i < 256 {
            let mut c = i as u32;
            let mut k = 0;
            while k < 8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
                k += 1;
            }
            table[i] = c;
            i += 1;
        }
        table
    };
    !data.iter().fold(!0u32, |c, &b| {
        TABLE[((c ^ u32::from(b)) & 0xFF) as usize] ^ (c >> 8)
    })
}

/// One record's frame: opcode and body range, if the body fits in the file.
fn frame(bytes: &[u8], pos: usize) -> std::result::Result<(u8, Range<usize>), &'static str> {
    let Some(prefix) = bytes.get(pos..pos + PREFIX) else {
        return Err("the file ends inside a record's opcode and length");
    };
    let op = prefix[0];
    if op == 0 || op > OP_DATA_END {
        return Err("not a record (opcode outside 0x01–0x0f)");
    }
    let len = u64::from_le_bytes(prefix[1..].try_into().unwrap_or_default());
    let start = pos + PREFIX;
    match usize::try_from(len).ok().and_then(|l| start.checked_add(l)) {
        Some(end) if end <= bytes.len() => Ok((op, start..end)),
        _ => Err("a record's length runs past the end of the file"),
    }
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// The records of a chunk, decompressed, if its lengths agree and its CRC holds.
fn chunk_records<'a>(
    body: &'a [u8],
    limit: u64,
) -> std::result::Result<(records::ChunkHeader, Range<usize>, Vec<Record<'a>>), String> {
    let compression_len = u32_at(body, 28).ok_or("chunk header cut short")? as usize;
    let data_at = 32 + compression_len + 8;
    let Ok(Record::Chunk { header, .. }) = mcap::parse_record(OP_CHUNK, body) else {
        return Err("chunk header unreadable".into());
    };
    if data_at as u64 + header.compressed_size != body.len() as u64 {
        return Err("chunk lengths disagree".into());
    }
    if header.uncompressed_size > limit {
        return Err(format!(
            "chunk claims {} bytes uncompressed",
            header.uncompressed_size
        ));
    }
    if !matches!(header.compression.as_str(), "" | "zstd") {
        return Err(format!(
            "chunk compression {:?} unknown",
            header.compression
        ));
    }
    let out = chunk_contents(body, header.uncompressed_size)
        .map_err(|e| format!("chunk unreadable: {e}"))?;
    Ok((header, data_at..body.len(), out))
}

/// The records inside the chunk record `body`, decompressed with every length bounded by the
/// chunk's own sizes (damaged data can decompress to a record claiming exabytes) and its CRC
/// checked.
fn chunk_contents(
    body: &[u8],
    uncompressed_size: u64,
) -> std::result::Result<Vec<Record<'static>>, String> {
    use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let limit = usize::try_from(uncompressed_size.max(body.len() as u64)).unwrap_or(usize::MAX);
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_skip_end_magic(true)
            .with_validate_chunk_crcs(true)
            .with_record_length_limit(limit.saturating_add(64)),
    );
    let mut prefix = [0u8; PREFIX];
    prefix[0] = OP_CHUNK;
    prefix[1..].copy_from_slice(&(body.len() as u64).to_le_bytes());
    let (mut prefix, mut rest) = (&prefix[..], body);
    let mut out = Vec::new();
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| e.to_string())? {
            LinearReadEvent::ReadRequest(n) => {
                let from = if prefix.is_empty() {
                    &mut rest
                } else {
                    &mut prefix
                };
                let n = n.min(from.len());
                reader.insert(n).copy_from_slice(&from[..n]);
                reader.notify_read(n);
                *from = &from[n..];
            }
            // Only schemas, channels and messages belong in a chunk (and only they parse
            // without a length check that damage could defeat).
            LinearReadEvent::Record { data, opcode } if (0x03..=0x05).contains(&opcode) => {
                out.push(
                    mcap::parse_record(opcode, data)
                        .map_err(|e| e.to_string())?
                        .into_owned(),
                );
            }
            LinearReadEvent::Record { opcode, .. } => {
                return Err(format!("record 0x{opcode:02x} inside a chunk"));
            }
        }
    }
    Ok(out)
}

/// What one record at `pos` is.
enum Read<'a> {
    /// A chunk whose lengths agree and whose records read: its header, the file range of its
    /// data, its records, and whether a CRC vouches for them.
    Chunk(records::ChunkHeader, Range<usize>, Vec<Record<'a>>, bool),
    /// An attachment whose CRC holds.
    Strong(Record<'a>),
    /// Any other record that parses.
    Weak(Record<'a>),
    /// Damage.
    Bad(String),
}

/// A chunk at `pos` whose record length is damaged: its length follows from its own header
/// (compression name and compressed size), and its CRC says whether that reading is right.
fn chunk_by_its_header(bytes: &[u8], pos: usize, limit: u64) -> Option<(Read<'_>, usize)> {
    if bytes.get(pos) != Some(&OP_CHUNK) {
        return None;
    }
    let start = pos + PREFIX;
    let compression_len = u32_at(bytes, start + 28)? as usize;
    let compressed = u64_at(bytes, start + 32 + compression_len)?;
    let end = usize::try_from(compressed)
        .ok()?
        .checked_add(start + 40 + compression_len)?;
    let (header, data, inner) = chunk_records(bytes.get(start..end)?, limit).ok()?;
    (header.uncompressed_crc != 0).then(|| {
        let data = start + data.start..start + data.end;
        (Read::Chunk(header, data, inner, true), end)
    })
}

fn read_at(bytes: &[u8], pos: usize, limit: u64) -> (Read<'_>, usize) {
    let (read, end) = read_framed(bytes, pos, limit);
    match read {
        Read::Bad(why) => chunk_by_its_header(bytes, pos, limit).unwrap_or((Read::Bad(why), end)),
        read => (read, end),
    }
}

fn read_framed(bytes: &[u8], pos: usize, limit: u64) -> (Read<'_>, usize) {
    let (op, body_range) = match frame(bytes, pos) {
        Ok(f) => f,
        Err(why) => return (Read::Bad(why.into()), pos),
    };
    let end = body_range.end;
    let body = &bytes[body_range.clone()];
    let read = match op {
        OP_CHUNK => match chunk_records(body, limit) {
            Ok((header, data, inner)) => {
                let crc = header.uncompressed_crc != 0;
                let data = body_range.start + data.start..body_range.start + data.end;
                Read::Chunk(header, data, inner, crc)
            }
            Err(why) => Read::Bad(why),
        },
        OP_ATTACHMENT => {
            // parse_record slices `body[..len - 4]` after the header: check the lengths first.
            let name = u32_at(body, 16).map(|n| 20 + n as usize);
            let media = name.and_then(|at| Some(at + 4 + u32_at(body, at)? as usize));
            let data_len = media.and_then(|at| Some((at, u64_at(body, at)?)));
            let fits = data_len.and_then(|(at, n)| (at as u64 + 12).checked_add(n));
            if fits != Some(body.len() as u64) {
                Read::Bad("attachment lengths disagree".into())
            } else {
                match mcap::parse_record(op, body) {
                    Ok(rec @ Record::Attachment { crc, .. }) if crc != 0 => Read::Strong(rec),
                    Ok(rec) => Read::Weak(rec),
                    Err(e) => Read::Bad(format!("attachment unreadable: {e}")),
                }
            }
        }
        _ => match mcap::parse_record(op, body) {
            Ok(rec) => Read::Weak(rec),
            Err(e) => Read::Bad(format!("record 0x{op:02x} unreadable: {e}")),
        },
    };
    (read, end)
}

/// Does reading resume at `pos`: a chunk or attachment whose CRC holds, or a run of whole records
/// that reaches one, the end magic, the end of the file, or [`CHAIN`] records?
fn resumes_at(bytes: &[u8], mut pos: usize, limit: u64) -> bool {
    for _ in 0..CHAIN {
        if pos == bytes.len() || (pos > 8 && &bytes[pos..] == MAGIC) {
            return true;
        }
        match read_at(bytes, pos, limit) {
            (Read::Strong(_) | Read::Chunk(.., true), _) => return true,
            (Read::Weak(_) | Read::Chunk(.., false), end) => pos = end,
            (Read::Bad(_), _) => return false,
        }
    }
    true
}

/// The first position at or after `from` where reading resumes (the file's length if none).
fn resync(bytes: &[u8], from: usize, limit: u64) -> usize {
    (from..bytes.len())
        .find(|&q| {
            (q + PREFIX <= bytes.len() && frame(bytes, q).is_ok() && resumes_at(bytes, q, limit))
                || (q > 8 && &bytes[q..] == MAGIC)
        })
        .unwrap_or(bytes.len())
}

/// A log file read past its damage.
pub(crate) struct Salvaged<'a> {
    bytes: &'a [u8],
    items: Vec<Item>,
    channels: BTreeMap<u16, Arc<mcap::Channel<'a>>>,
    /// Attachments whose CRC holds, in file order.
    pub(crate) attachments: Vec<(records::AttachmentHeader, Vec<u8>)>,
    /// Metadata records, in file order.
    pub(crate) metadata: Vec<records::Metadata>,
    /// What was lost.
    pub(crate) loss: Loss,
}

/// What one pass over the records gathers before channels are put together.
#[derive(Default)]
struct Pass<'a> {
    items: Vec<Item>,
    schemas: BTreeMap<u16, (records::SchemaHeader, Cow<'a, [u8]>)>,
    channels: BTreeMap<u16, records::Channel>,
    attachments: Vec<(usize, records::AttachmentHeader, Vec<u8>)>,
    metadata: Vec<(usize, records::Metadata)>,
    /// Messages per channel id in kept chunks and outside chunks.
    kept_per_channel: BTreeMap<u16, u64>,
    kept_chunk_offsets: BTreeSet<usize>,
    /// Chunks that did not read: offset and times from their own header, if it parsed.
    bad_chunks: BTreeMap<usize, Option<(u64, u64)>>,
    /// Message indexes by the offset of the chunk they follow, and by their own offset.
    index_after_chunk: BTreeMap<usize, BTreeMap<u16, u64>>,
    /// Chunks whose message indexes damage cut short.
    interrupted: BTreeSet<usize>,
    index_at: BTreeMap<usize, (u16, u64)>,
    chunk_indexes: Vec<records::ChunkIndex>,
    attachment_indexes: Vec<records::AttachmentIndex>,
    metadata_indexes: Vec<records::MetadataIndex>,
    statistics: Option<records::Statistics>,
    footer: bool,
    data_end: bool,
    /// Position and saved CRC of the data end record and of the footer (with its summary start).
    data_end_crc: Option<(usize, u32)>,
    footer_crc: Option<(usize, u64, u32)>,
    bad_attachments: Vec<usize>,
    damage: Vec<Damage>,
    chunks_read: u64,
}

impl<'a> Pass<'a> {
    /// Damage no record showed: the data and summary sections' CRCs (where the writer saved
    /// them) catch an altered schema, channel or metadata record, or summary.
    fn check_crcs(&mut self, bytes: &[u8]) {
        if let Some((at, saved)) = self.data_end_crc {
            let seen = self.damage.iter().any(|d| d.start < at as u64);
            if saved != 0 && !seen && crc32(&bytes[..at]) != saved {
                self.damage.push(Damage {
                    start: 0,
                    end: at as u64,
                    reason: "the data section's CRC does not hold (a record outside the chunks \
                             is altered)"
                        .into(),
                });
            }
        }
        if let Some((at, summary_start, saved)) = self.footer_crc {
            let start = usize::try_from(summary_start)
                .ok()
                .filter(|&s| s > 0 && s <= at)
                .unwrap_or(at);
            let seen = self.damage.iter().any(|d| d.end > start as u64);
            let end = at + PREFIX + 16;
            if saved != 0 && !seen && bytes.get(start..end).map(crc32) != Some(saved) {
                self.damage.push(Damage {
                    start: start as u64,
                    end: at as u64,
                    reason: "the summary's CRC does not hold (it is rebuilt from the chunks)"
                        .into(),
                });
            }
        }
        self.damage.sort_by_key(|d| d.start);
    }

    fn take(&mut self, pos: usize, record: Record<'a>, last_chunk: Option<usize>) {
        match record {
            Record::Schema { header, data } => {
                self.schemas.entry(header.id).or_insert((header, data));
            }
            Record::Channel(c) => {
                self.channels.entry(c.id).or_insert(c);
            }
            Record::Message { header, data } => {
                *self.kept_per_channel.entry(header.channel_id).or_default() += 1;
                let start = pos + PREFIX + 22;
                self.items
                    .push(Item::Message(header, start..start + data.len()));
            }
            Record::MessageIndex(index) => {
                let n = index.records.len() as u64;
                self.index_at.insert(pos, (index.channel_id, n));
                if let Some(chunk) = last_chunk {
                    *self
                        .index_after_chunk
                        .entry(chunk)
                        .or_default()
                        .entry(index.channel_id)
                        .or_default() += n;
                }
            }
            Record::ChunkIndex(i) => self.chunk_indexes.push(i),
            Record::Attachment { header, data, .. } => {
                self.attachments.push((pos, header, data.into_owned()))
            }
            Record::AttachmentIndex(i) => self.attachment_indexes.push(i),
            Record::Metadata(m) => self.metadata.push((pos, m)),
            Record::MetadataIndex(i) => self.metadata_indexes.push(i),
            Record::Statistics(s) => self.statistics = Some(s),
            Record::Footer(f) => {
                self.footer = true;
                self.footer_crc = Some((pos, f.summary_start, f.summary_crc));
            }
            Record::DataEnd(d) => {
                self.data_end = true;
                self.data_end_crc = Some((pos, d.data_section_crc));
            }
            _ => {}
        }
    }
}

impl<'a> Salvaged<'a> {
    /// Read every whole record of `bytes` (the file `path`); an error only when nothing in it
    /// reads as MCAP.
    pub(crate) fn read(path: &Path, bytes: &'a [u8]) -> Result<Self> {
        let limit = size_limit(bytes.len());
        let mut pass = Pass::default();
        let mut pos = 0;
        if !bytes.starts_with(MAGIC) {
            let next = resync(bytes, 1, limit);
            pass.damage.push(Damage {
                start: 0,
                end: next as u64,
                reason: "no leading MCAP magic".into(),
            });
            pos = next;
        } else {
            pos += MAGIC.len();
        }
        let mut last_chunk: Option<usize> = None;
        while pos < bytes.len() {
            if pos > MAGIC.len() && &bytes[pos..] == MAGIC {
                break;
            }
            let (read, end) = read_at(bytes, pos, limit);
            match read {
                Read::Chunk(header, data, inner, _) => {
                    if frame(bytes, pos).map(|(_, body)| body.end) != Ok(end) {
                        pass.damage.push(Damage {
                            start: pos as u64 + 1,
                            end: (pos + PREFIX) as u64,
                            reason: "a chunk's length field (the chunk is whole and kept)".into(),
                        });
                    }
                    pass.chunks_read += 1;
                    pass.kept_chunk_offsets.insert(pos);
                    for r in inner {
                        match r {
                            Record::Message { header, .. } => {
                                *pass.kept_per_channel.entry(header.channel_id).or_default() += 1
                            }
                            other => pass.take(pos, other, None),
                        }
                    }
                    pass.items.push(Item::Chunk(KeptChunk { header, data }));
                    last_chunk = Some(pos);
                    pos = end;
                }
                Read::Strong(record) | Read::Weak(record) => {
                    if !matches!(record, Record::MessageIndex(_)) {
                        last_chunk = None;
                    }
                    pass.take(pos, record, last_chunk);
                    pos = end;
                }
                Read::Bad(reason) => {
                    let op = bytes[pos];
                    let what = match op {
                        _ if pos == MAGIC.len() => "the header",
                        OP_CHUNK => "a chunk",
                        OP_ATTACHMENT => "an attachment",
                        OP_FOOTER => "the footer",
                        _ => "a record",
                    };
                    let mut next = None;
                    // The message indexes after a chunk were cut short by this damage (unless
                    // it is the next chunk): they no longer count the chunk's messages.
                    if let Some(chunk) = last_chunk.filter(|_| op != OP_CHUNK) {
                        pass.interrupted.insert(chunk);
                    }
                    if op == OP_CHUNK {
                        let times = u64_at(bytes, pos + PREFIX)
                            .zip(u64_at(bytes, pos + PREFIX + 8))
                            .filter(|(a, b)| a <= b);
                        pass.bad_chunks.insert(pos, times);
                        last_chunk = Some(pos);
                        // Its frame may still be right (damage inside its data): its message
                        // indexes follow it and count what it held.
                        if let Ok((_, body)) = frame(bytes, pos) {
                            if resumes_at(bytes, body.end, limit) {
                                next = Some(body.end);
                            }
                        }
                    } else {
                        if op == OP_ATTACHMENT {
                            pass.bad_attachments.push(pos);
                        }
                        last_chunk = None;
                    }
                    let next = next.unwrap_or_else(|| {
                        last_chunk = None;
                        resync(bytes, pos + 1, limit)
                    });
                    pass.damage.push(Damage {
                        start: pos as u64,
                        end: next as u64,
                        reason: format!("{what}: {reason}"),
                    });
                    pos = next;
                }
            }
        }
        pass.check_crcs(bytes);
        let nothing_read = pass.items.is_empty()
            && pass.attachments.is_empty()
            && pass.metadata.is_empty()
            && pass.channels.is_empty();
        if nothing_read && !bytes.starts_with(MAGIC) {
            return Err(RuntimeError::Log {
                path: path.to_path_buf(),
                message: "not an MCAP file (no leading MCAP magic and no readable record)".into(),
            });
        }
        Ok(Self::assemble(bytes, pass))
    }

    fn assemble(bytes: &'a [u8], pass: Pass<'a>) -> Self {
        let schemas: BTreeMap<u16, Arc<mcap::Schema<'a>>> = pass
            .schemas
            .into_iter()
            .map(|(id, (h, data))| {
                let schema = mcap::Schema {
                    id,
                    name: h.name,
                    encoding: h.encoding,
                    data,
                };
                (id, Arc::new(schema))
            })
            .collect();
        let channels: BTreeMap<u16, Arc<mcap::Channel<'a>>> = pass
            .channels
            .into_iter()
            .map(|(id, c)| {
                let channel = mcap::Channel {
                    id,
                    topic: c.topic,
                    schema: schemas.get(&c.schema_id).cloned(),
                    message_encoding: c.message_encoding,
                    metadata: c.metadata,
                };
                (id, Arc::new(channel))
            })
            .collect();
        let mut messages_read = 0;
        let mut undecodable = 0;
        for (id, n) in &pass.kept_per_channel {
            if channels.contains_key(id) {
                messages_read += n;
            } else {
                undecodable += n;
            }
        }
        // Lost chunks: every indexed chunk not kept, and every chunk whose header was seen in
        // the damage; counts from their message indexes wherever those survived.
        let mut lost: BTreeMap<usize, LostChunk> = BTreeMap::new();
        let after = |offset: usize| {
            (!pass.interrupted.contains(&offset))
                .then(|| pass.index_after_chunk.get(&offset).cloned())
                .flatten()
        };
        for ci in &pass.chunk_indexes {
            let Ok(offset) = usize::try_from(ci.chunk_start_offset) else {
                continue;
            };
            // A damaged summary can name offsets where no chunk ever was: trust an index only
            // where a chunk starts or damage hides what started there.
            let in_damage = pass
                .damage
                .iter()
                .any(|d| (d.start..d.end).contains(&(offset as u64)));
            if pass.kept_chunk_offsets.contains(&offset)
                || !(in_damage || bytes.get(offset) == Some(&OP_CHUNK))
            {
                continue;
            }
            let messages: Option<BTreeMap<u16, u64>> = ci
                .message_index_offsets
                .iter()
                .map(|(ch, at)| {
                    let at = usize::try_from(*at).ok()?;
                    pass.index_at
                        .get(&at)
                        .filter(|(c, _)| c == ch)
                        .map(|(c, n)| (*c, *n))
                })
                .collect();
            lost.insert(
                offset,
                LostChunk {
                    offset: offset as u64,
                    time_ns: Some((ci.message_start_time, ci.message_end_time)),
                    messages: messages.or_else(|| after(offset)),
                },
            );
        }
        for (offset, times) in &pass.bad_chunks {
            lost.entry(*offset).or_insert_with(|| LostChunk {
                offset: *offset as u64,
                time_ns: *times,
                messages: after(*offset),
            });
        }
        let kept_attachments: BTreeSet<usize> = pass.attachments.iter().map(|a| a.0).collect();
        let mut lost_attachments: Vec<String> = pass
            .attachment_indexes
            .iter()
            .filter(|i| !kept_attachments.contains(&(i.offset as usize)))
            .map(|i| i.name.clone())
            .collect();
        let indexed: BTreeSet<u64> = pass.attachment_indexes.iter().map(|i| i.offset).collect();
        lost_attachments.extend(
            pass.bad_attachments
                .iter()
                .filter(|at| !indexed.contains(&(**at as u64)))
                .map(|at| format!("at byte {at} (name unknown)")),
        );
        let kept_metadata: BTreeSet<usize> = pass.metadata.iter().map(|m| m.0).collect();
        let lost_metadata = pass
            .metadata_indexes
            .iter()
            .filter(|i| !kept_metadata.contains(&(i.offset as usize)))
            .map(|i| i.name.clone())
            .collect();
        // No footer and no end of the data section: the writer never finished.
        let cut_off = !pass.footer && !pass.data_end;
        let loss = Loss {
            file_bytes: bytes.len() as u64,
            damage: pass.damage,
            chunks: lost.into_values().collect(),
            attachments: lost_attachments,
            metadata: lost_metadata,
            undecodable_messages: undecodable,
            cut_off,
            total_messages: pass.statistics.map(|s| s.message_count),
            messages_read,
            chunks_read: pass.chunks_read,
        };
        Self {
            bytes,
            items: pass.items,
            channels,
            attachments: pass
                .attachments
                .into_iter()
                .map(|(_, h, d)| (h, d))
                .collect(),
            metadata: pass.metadata.into_iter().map(|(_, m)| m).collect(),
            loss,
        }
    }

    /// Every kept message on a known channel, in file order.
    pub(crate) fn messages(&self) -> impl Iterator<Item = mcap::Message<'a>> + '_ {
        self.items.iter().flat_map(
            move |item| -> Box<dyn Iterator<Item = mcap::Message<'a>> + '_> {
                match item {
                    Item::Chunk(chunk) => {
                        let records = mcap::read::ChunkReader::new(
                            chunk.header.clone(),
                            &self.bytes[chunk.data.clone()],
                        )
                        .into_iter()
                        .flatten()
                        .map_while(std::result::Result::ok);
                        Box::new(records.filter_map(move |r| match r {
                            Record::Message { header, data } => self.message(&header, data),
                            _ => None,
                        }))
                    }
                    Item::Message(header, data) => Box::new(
                        self.message(header, Cow::Borrowed(&self.bytes[data.clone()]))
                            .into_iter(),
                    ),
                }
            },
        )
    }

    fn message(
        &self,
        header: &records::MessageHeader,
        data: Cow<'a, [u8]>,
    ) -> Option<mcap::Message<'a>> {
        Some(mcap::Message {
            channel: self.channels.get(&header.channel_id)?.clone(),
            sequence: header.sequence,
            log_time: header.log_time,
            publish_time: header.publish_time,
            data,
        })
    }
}
