//! What a damaged or cut-off log lost, as far as the file can tell: the unreadable stretches,
//! the chunks they took (time range from the chunk's header or the summary's chunk index,
//! message count from its message indexes; "unknown" where neither survived), lost attachments
//! and metadata. [`crate::telemetry::salvage`] finds it; every reader reports it.

use std::collections::BTreeMap;

/// A stretch of the file that did not read, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Damage {
    /// First unreadable byte.
    pub start: u64,
    /// First byte read again (the file's length when nothing after `start` read).
    pub end: u64,
    /// What the reader found at `start`.
    pub reason: String,
}

/// A chunk the damage took.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LostChunk {
    /// Where it started in the file.
    pub offset: u64,
    /// Log time of its first and last message, ns (from its own header or the summary's chunk
    /// index; `None` when neither survived).
    pub time_ns: Option<(u64, u64)>,
    /// Messages per channel id (from its message indexes; `None` when they did not survive).
    pub messages: Option<BTreeMap<u16, u64>>,
}

/// What reading the file lost, as far as the file can tell.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Loss {
    /// The file's length.
    pub file_bytes: u64,
    /// Unreadable stretches, in file order.
    pub damage: Vec<Damage>,
    /// Chunks lost, in file order.
    pub chunks: Vec<LostChunk>,
    /// Attachments lost (names from the summary's index, or the byte where one started).
    pub attachments: Vec<String>,
    /// Metadata records lost (names from the summary's index).
    pub metadata: Vec<String>,
    /// Messages of kept chunks on channels whose definition did not survive.
    pub undecodable_messages: u64,
    /// The file ends inside a record or before its footer (a log cut off by a crash).
    pub cut_off: bool,
    /// The summary's statistics survived: the file's total message count.
    pub total_messages: Option<u64>,
    /// Messages read.
    pub messages_read: u64,
    /// Chunks read.
    pub chunks_read: u64,
}

fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn plural(n: u64, one: &str, many: &str) -> String {
    format!("{} {}", thousands(n), if n == 1 { one } else { many })
}

impl LostChunk {
    /// Messages the chunk held, if known.
    pub fn message_count(&self) -> Option<u64> {
        self.messages.as_ref().map(|m| m.values().sum())
    }
}

impl Loss {
    /// Nothing unreadable, nothing missing: the file was read whole.
    pub fn is_intact(&self) -> bool {
        self.damage.is_empty() && !self.cut_off
    }

    /// Messages lost, if every lost chunk's count is known (or the statistics survived).
    pub fn lost_messages(&self) -> Option<u64> {
        if let Some(total) = self.total_messages {
            return Some(total.saturating_sub(self.messages_read));
        }
        if self.cut_off || self.damage.iter().any(|d| d.end == self.file_bytes) {
            // What followed the damage at the end of the file is unknown.
            if self.chunks.is_empty() && !self.cut_off {
                return Some(self.undecodable_messages);
            }
            return None;
        }
        let mut sum = self.undecodable_messages;
        for c in &self.chunks {
            sum += c.message_count()?;
        }
        Some(sum)
    }

    /// One line: what was read and what was lost (`None` for an intact file).
    pub fn summary(&self) -> Option<String> {
        if self.is_intact() {
            return None;
        }
        let read = format!(
            "read {} in {}",
            plural(self.messages_read, "message", "messages"),
            plural(self.chunks_read, "chunk", "chunks")
        );
        let lost = match self.lost_messages() {
            Some(0) if self.chunks.is_empty() => "lost no messages".to_string(),
            Some(n) => format!(
                "lost {} in {}",
                plural(n, "message", "messages"),
                plural(self.chunks.len() as u64, "chunk", "chunks")
            ),
            None => format!(
                "lost {}{}, how many messages is unknown",
                plural(self.chunks.len() as u64, "known chunk", "known chunks"),
                if self.cut_off {
                    " and whatever followed the cut"
                } else {
                    ""
                }
            ),
        };
        let first = &self.damage.first();
        let place = match (self.cut_off, first) {
            (true, None) => format!("cut off at byte {} (no footer)", self.file_bytes),
            (true, Some(d)) if d.end == self.file_bytes && self.damage.len() == 1 => {
                format!(
                    "cut off at byte {} ({}, from byte {})",
                    self.file_bytes, d.reason, d.start
                )
            }
            (_, Some(d)) => format!(
                "damaged at {} ({}: bytes {}–{})",
                plural(self.damage.len() as u64, "place", "places"),
                d.reason,
                d.start,
                d.end
            ),
            (false, None) => "damaged".to_string(),
        };
        Some(format!("{place}; {read}; {lost}"))
    }
}

impl std::fmt::Display for Loss {
    /// The full account: every damaged stretch and every lost chunk with its time range.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.is_intact() {
            return writeln!(f, "nothing lost: the input was read whole");
        }
        for d in &self.damage {
            writeln!(f, "damage at bytes {}–{}: {}", d.start, d.end, d.reason)?;
        }
        if self.cut_off {
            writeln!(
                f,
                "the file is cut off (no footer): whatever was written after byte {} is unknown",
                self.file_bytes
            )?;
        }
        for c in &self.chunks {
            let time = match c.time_ns {
                Some((a, b)) => format!(
                    "messages t = {:.2}–{:.2} s",
                    a as f64 * 1e-9,
                    b as f64 * 1e-9
                ),
                None => "message times unknown".to_string(),
            };
            let count = match &c.messages {
                Some(m) => format!(
                    "{} on {}",
                    plural(m.values().sum(), "message", "messages"),
                    plural(m.len() as u64, "channel", "channels")
                ),
                None => "message count unknown (its indexes were lost)".to_string(),
            };
            writeln!(f, "lost 1 chunk at byte {}: {time}, {count}", c.offset)?;
        }
        if self.undecodable_messages > 0 {
            writeln!(
                f,
                "lost {} of kept chunks: their channel's definition did not survive",
                plural(self.undecodable_messages, "message", "messages")
            )?;
        }
        for a in &self.attachments {
            writeln!(f, "lost attachment {a}")?;
        }
        for m in &self.metadata {
            writeln!(f, "lost metadata record {m}")?;
        }
        match self.lost_messages() {
            Some(0) if self.chunks.is_empty() => writeln!(
                f,
                "no messages lost: the damage was outside the data ({} read)",
                plural(self.messages_read, "message", "messages")
            ),
            Some(n) => writeln!(
                f,
                "in all: {} read, {} lost",
                plural(self.messages_read, "message", "messages"),
                plural(n, "message", "messages")
            ),
            None => writeln!(
                f,
                "in all: {} read; how many were lost is unknown",
                plural(self.messages_read, "message", "messages")
            ),
        }
    }
}
