//! Recovery that tells the truth (issue #27): a real log of a simulated walk, damaged at a dozen
//! places and cut at a dozen lengths. What was in every chunk is counted independently, from
//! the undamaged original with the official `mcap` reader; `recover` must keep every message of
//! every chunk the damage did not touch, report exactly the loss, and write a file the official
//! reader reads whole. The readers (`read_info`, `joint_series`) read the same damaged files
//! past their damage.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use runtime::telemetry::log_read::{joint_series, read_info};
use runtime::telemetry::recover::recover;
use std::collections::BTreeSet;
use std::ops::Range;
use std::path::PathBuf;

/// A message as the official reader sees it: topic, log time, sequence.
type Key = (String, u64, u32);

/// One chunk of the original: its bytes in the file, times and messages.
struct Chunk {
    span: Range<usize>,
    time_ns: (u64, u64),
    messages: Vec<Key>,
}

/// The undamaged original and its layout, from the official reader.
struct Original {
    bytes: Vec<u8>,
    chunks: Vec<Chunk>,
    attachments: Vec<Range<usize>>,
    metadata: Vec<Range<usize>>,
    summary_start: usize,
}

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
}

/// 4 s of simulated walking (some 30,000 messages in a dozen chunks), read once.
fn original() -> &'static Original {
    static LOG: std::sync::OnceLock<Original> = std::sync::OnceLock::new();
    LOG.get_or_init(|| {
        let setup = runtime::Setup::shipped().expect("shipped setup");
        // Per process: cargo-nextest runs each test in a process of its own, each writing it.
        let path = dir().join(format!("log-damage-original-{}.mcap", std::process::id()));
        let mut options = runtime::sim::run::SimWalkOptions::new(4.0);
        options.log_path = Some(path.clone());
        runtime::sim::run::walk(&setup, &options).expect("walk");
        let bytes = std::fs::read(&path).expect("log");
        // Held in memory from here: the file would only pile up in target/tmp.
        std::fs::remove_file(&path).ok();
        let summary = mcap::Summary::read(&bytes).unwrap().expect("summary");
        let chunks = summary
            .chunk_indexes
            .iter()
            .map(|ci| {
                let start = ci.chunk_start_offset as usize;
                let messages = summary
                    .stream_chunk(&bytes, ci)
                    .unwrap()
                    .map(|m| {
                        let m = m.unwrap();
                        (m.channel.topic.clone(), m.log_time, m.sequence)
                    })
                    .collect();
                Chunk {
                    span: start..start + ci.chunk_length as usize,
                    time_ns: (ci.message_start_time, ci.message_end_time),
                    messages,
                }
            })
            .collect();
        let range = |offset: u64, length: u64| offset as usize..(offset + length) as usize;
        let footer = mcap::read::footer(&bytes).unwrap();
        Original {
            chunks,
            attachments: summary
                .attachment_indexes
                .iter()
                .map(|i| range(i.offset, i.length))
                .collect(),
            metadata: summary
                .metadata_indexes
                .iter()
                .map(|i| range(i.offset, i.length))
                .collect(),
            summary_start: footer.summary_start as usize,
            bytes,
        }
    })
}

fn overlaps(a: &Range<usize>, b: &Range<usize>) -> bool {
    a.start < b.end && b.start < a.end
}

/// Every message of the file `bytes`, read by the official reader (strict: end magic too).
fn official_messages(bytes: &[u8]) -> Vec<Key> {
    mcap::MessageStream::new(bytes)
        .expect("official reader opens it")
        .map(|m| {
            let m = m.expect("official reader reads every message");
            (m.channel.topic.clone(), m.log_time, m.sequence)
        })
        .collect()
}

/// Recover `damaged`; check the kept messages are exactly those of the chunks not in `lost`,
/// and the report's counts and times are those of the lost chunks.
fn check_recovery(name: &str, damaged: &[u8], lost: &BTreeSet<usize>, cut: bool) {
    let log = original();
    let input = dir().join(format!("log-damage-{name}.mcap"));
    let output = dir().join(format!("log-damage-{name}.recovered.mcap"));
    std::fs::write(&input, damaged).unwrap();
    let stats = recover(&input, &output).unwrap_or_else(|e| panic!("{name}: {e}"));
    let text = stats.to_string();
    let mut expected: Vec<Key> = Vec::new();
    let mut lost_messages = 0;
    for (k, c) in log.chunks.iter().enumerate() {
        if lost.contains(&k) {
            lost_messages += c.messages.len() as u64;
        } else {
            expected.extend(c.messages.iter().cloned());
        }
    }
    // Every message of every intact chunk, in order, read back by the official reader.
    let recovered = std::fs::read(&output).unwrap();
    assert!(mcap::Summary::read(&recovered).unwrap().is_some(), "{name}");
    let got = official_messages(&recovered);
    assert_eq!(got.len(), expected.len(), "{name}: {text}");
    assert!(got == expected, "{name}: messages differ\n{text}");
    assert_eq!(stats.messages, expected.len() as u64, "{name}");
    // The account: never "intact" about a damaged file; lost chunks with their true counts.
    assert!(!stats.input_intact(), "{name}: {text}");
    assert!(!text.contains("intact"), "{name}: {text}");
    if cut {
        // Whatever followed the cut is unknowable: the report says so.
        assert!(stats.loss.cut_off, "{name}: {text}");
        assert_eq!(stats.loss.lost_messages(), None, "{name}: {text}");
        assert!(text.contains("unknown"), "{name}: {text}");
        return;
    }
    assert_eq!(
        stats.loss.lost_messages(),
        Some(lost_messages),
        "{name}: {text}"
    );
    assert_eq!(stats.loss.chunks.len(), lost.len(), "{name}: {text}");
    for (lost_chunk, k) in stats.loss.chunks.iter().zip(lost) {
        let c = &log.chunks[*k];
        assert_eq!(lost_chunk.offset as usize, c.span.start, "{name}");
        assert_eq!(lost_chunk.time_ns, Some(c.time_ns), "{name}: {text}");
        // Its count comes from its message indexes; where the damage took those too, the
        // report says the count is unknown (the total above is exact all the same).
        match lost_chunk.message_count() {
            Some(count) => assert_eq!(count, c.messages.len() as u64, "{name}: {text}"),
            None => assert!(text.contains("message count unknown"), "{name}: {text}"),
        }
        let line = format!(
            "messages t = {:.2}–{:.2} s",
            c.time_ns.0 as f64 * 1e-9,
            c.time_ns.1 as f64 * 1e-9
        );
        assert!(text.contains(&line), "{name}: {line}\n{text}");
    }
    if lost.is_empty() {
        assert!(text.contains("no messages lost"), "{name}: {text}");
    }
    // The readers read the damaged file past its damage, and say so.
    let info = read_info(&input).unwrap_or_else(|e| panic!("{name}: {e}"));
    let read: u64 = info.channels.iter().map(|c| c.messages).sum();
    assert_eq!(read, expected.len() as u64, "{name}: {info}");
    assert!(info.truncated.is_some(), "{name}");
    let series = joint_series(&input).unwrap_or_else(|e| panic!("{name}: {e}"));
    let joints = expected.iter().filter(|k| k.0 == "/joints").count();
    assert_eq!(series.t_s.len(), joints, "{name}");
    assert!(series.damage.is_some(), "{name}");
    // The recovered file reads whole, and says it was recovered.
    let info = read_info(&output).unwrap();
    assert_eq!(info.truncated, None, "{name}: {info}");
    assert!(
        info.to_string().contains("recovered from"),
        "{name}: {info}"
    );
    for p in [&input, &output] {
        std::fs::remove_file(p).ok();
    }
}

fn zeroed(bytes: &[u8], range: Range<usize>) -> Vec<u8> {
    let mut b = bytes.to_vec();
    b[range].fill(0);
    b
}

#[test]
fn damage_at_a_dozen_places_loses_exactly_the_chunks_it_hit() {
    let log = original();
    let n = log.chunks.len();
    assert!(n >= 8, "want a log of several chunks, have {n}");
    let len = log.bytes.len();
    // Chunks with messages, spread over the file.
    let with_messages: Vec<usize> = (0..n)
        .filter(|&k| !log.chunks[k].messages.is_empty())
        .collect();
    let pick = |f: f64| with_messages[((with_messages.len() - 1) as f64 * f) as usize];
    let (a, b, c, d) = (pick(0.2), pick(0.4), pick(0.6), pick(0.8));
    let mid = |k: usize| {
        let s = &log.chunks[k].span;
        s.start + s.len() / 2
    };
    let first_attachment = log.attachments[0].clone();
    let mut cases: Vec<(String, Range<usize>, Option<BTreeSet<usize>>)> = vec![
        ("start magic".into(), 0..8, None),
        ("header record".into(), 8..40, None),
        (
            "a chunk's length field".into(),
            log.chunks[a].span.start + 1..log.chunks[a].span.start + 9,
            Some(BTreeSet::new()),
        ),
        (
            "a chunk's header".into(),
            log.chunks[b].span.start..log.chunks[b].span.start + 40,
            None,
        ),
        (
            "inside compressed data".into(),
            mid(c)..(mid(c) + 4096).min(log.chunks[c].span.end),
            None,
        ),
        (
            "between chunks (message indexes)".into(),
            log.chunks[d].span.end..log.chunks[d].span.end + 24,
            None,
        ),
        (
            "4 KiB across two chunks".into(),
            log.chunks[c + 1].span.end - 2048..log.chunks[c + 1].span.end + 2048,
            None,
        ),
        (
            "an attachment".into(),
            first_attachment.start + 40..first_attachment.start + 72,
            None,
        ),
        (
            "a metadata record".into(),
            log.metadata[0].start..log.metadata[0].start + 12,
            None,
        ),
        (
            "the summary".into(),
            log.summary_start + 100..log.summary_start + 164,
            None,
        ),
        ("the footer".into(), len - 8 - 29..len - 8, None),
        ("the end magic".into(), len - 8..len, None),
    ];
    // The last chunk with messages, wholly.
    let last = *with_messages.last().unwrap();
    cases.push(("the last chunk".into(), log.chunks[last].span.clone(), None));
    let mut places = 0;
    for (name, range, lost) in cases {
        let lost = lost.unwrap_or_else(|| {
            (0..n)
                .filter(|&k| overlaps(&log.chunks[k].span, &range))
                .collect()
        });
        let damaged = zeroed(&log.bytes, range.clone());
        check_recovery(&name.replace(' ', "-"), &damaged, &lost, false);
        places += 1;
    }
    assert!(places >= 10);
}

#[test]
fn a_log_cut_at_a_dozen_lengths_keeps_every_whole_chunk() {
    let log = original();
    let len = log.bytes.len();
    let mut cuts: Vec<usize> = (1..12)
        .map(|i| i * log.summary_start / 12 + 3 * i)
        .collect();
    // Exactly at the end of a chunk, just after its start, inside the summary.
    let k = log.chunks.len() / 2;
    cuts.extend([
        log.chunks[k].span.end,
        log.chunks[k].span.start + 20,
        log.summary_start + 50,
        len - 3,
    ]);
    for cut in cuts {
        let whole: BTreeSet<usize> = (0..log.chunks.len())
            .filter(|&k| log.chunks[k].span.end > cut)
            .collect();
        // Cut inside the summary: no data lost, the summary is rebuilt.
        let in_data = cut < log.summary_start;
        check_recovery(&format!("cut-{cut}"), &log.bytes[..cut], &whole, in_data);
    }
}

#[test]
fn the_undamaged_log_recovers_whole_and_says_it_was_intact() {
    let log = original();
    let input = dir().join("log-damage-intact.mcap");
    let output = dir().join("log-damage-intact.recovered.mcap");
    std::fs::write(&input, &log.bytes).unwrap();
    let stats = recover(&input, &output).unwrap();
    assert!(stats.input_intact(), "{stats}");
    assert!(stats.to_string().contains("intact"), "{stats}");
    let all: Vec<Key> = log.chunks.iter().flat_map(|c| c.messages.clone()).collect();
    assert_eq!(official_messages(&std::fs::read(&output).unwrap()), all);
    let info = read_info(&input).unwrap();
    assert_eq!(info.truncated, None);
}

/// A seeded generator (splitmix64): the same damage on every run.
fn next(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[test]
fn random_damage_keeps_every_untouched_chunk_and_invents_nothing() {
    let log = original();
    let all: Vec<Key> = log.chunks.iter().flat_map(|c| c.messages.clone()).collect();
    let len = log.bytes.len();
    let mut seed = 27;
    for case in 0..40 {
        // Zeros or random bytes over 1 B – 8 KiB anywhere.
        let start = (next(&mut seed) % len as u64) as usize;
        let n = 1 + (next(&mut seed) % 8192) as usize;
        let range = start..(start + n).min(len);
        let mut damaged = log.bytes.clone();
        let random = case % 2 == 1;
        for b in &mut damaged[range.clone()] {
            *b = if random { next(&mut seed) as u8 } else { 0 };
        }
        let input = dir().join("log-damage-random.mcap");
        let output = dir().join("log-damage-random.recovered.mcap");
        std::fs::write(&input, &damaged).unwrap();
        let what = format!(
            "case {case}: bytes {range:?} {}",
            if random { "random" } else { "zeroed" }
        );
        let stats = recover(&input, &output).unwrap_or_else(|e| panic!("{what}: {e}"));
        let got = official_messages(&std::fs::read(&output).unwrap());
        // Every message of every chunk the damage did not touch ...
        let untouched: BTreeSet<&Key> = log
            .chunks
            .iter()
            .filter(|c| !overlaps(&c.span, &range))
            .flat_map(|c| c.messages.iter())
            .collect();
        let got_set: BTreeSet<&Key> = got.iter().collect();
        let missing = untouched.difference(&got_set).count();
        assert_eq!(
            missing, 0,
            "{what}: {missing} messages of intact chunks missing\n{stats}"
        );
        // ... in the original order, and nothing that was not written.
        let mut rest = all.iter();
        assert!(
            got.iter().all(|k| rest.any(|o| o == k)),
            "{what}: messages out of order or invented\n{stats}"
        );
        // The account matches what is missing, where it claims to know.
        if let Some(lost) = stats.loss.lost_messages() {
            assert_eq!(lost, (all.len() - got.len()) as u64, "{what}\n{stats}");
        }
        if got.len() < all.len() {
            assert!(!stats.input_intact(), "{what}\n{stats}");
        }
        read_info(&input).unwrap_or_else(|e| panic!("{what}: {e}"));
    }
}
