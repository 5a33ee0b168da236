//! A guard for the MCAP readers of [`crate::telemetry::log_read`]: a damaged length field (a chunk's
//! uncompressed size, a record's length) makes the `mcap` reader try to allocate that many bytes,
//! and an allocation of exabytes aborts the process. Before any reader runs, one linear pass with
//! a record-length limit refuses such a file with an error that names it.

use crate::{Result, RuntimeError};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::McapError;
use std::path::Path;

/// The limit: 64 × the file (zstd on our JSON stays far below that ratio), at least 256 MiB.
fn limit(file_bytes: usize) -> usize {
    file_bytes.saturating_mul(64).max(256 << 20)
}

/// Refuse `bytes` if a record or chunk claims more than [`limit`] bytes; any other damage is
/// left for the readers to report (a cut-off log stays readable up to the cut).
pub(crate) fn check_lengths(path: &Path, bytes: &[u8]) -> Result<()> {
    let options = LinearReaderOptions::default()
        .with_skip_end_magic(true)
        .with_record_length_limit(limit(bytes.len()));
    let mut reader = LinearReader::new_with_options(options);
    let mut rest = bytes;
    while let Some(event) = reader.next_event() {
        match event {
            Ok(LinearReadEvent::ReadRequest(n)) => {
                let n = n.min(rest.len());
                reader.insert(n).copy_from_slice(&rest[..n]);
                reader.notify_read(n);
                rest = &rest[n..];
            }
            Ok(LinearReadEvent::Record { .. }) => {}
            Err(
                e @ (McapError::RecordTooLarge { .. }
                | McapError::ChunkTooLarge(_)
                | McapError::ChunkBufferTooLarge(_)),
            ) => {
                return Err(RuntimeError::Log {
                    path: path.to_path_buf(),
                    message: format!("damaged: {e}"),
                })
            }
            Err(_) => break,
        }
    }
    Ok(())
}
