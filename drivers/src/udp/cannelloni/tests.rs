use super::*;
use proptest::prelude::*;

/// An owned frame of any kind the format carries.
#[derive(Debug, Clone, PartialEq)]
struct Owned {
    can_id: u32,
    len: u8,
    fd_flags: Option<u8>,
    data: Vec<u8>,
}

impl Owned {
    fn view(&self) -> FrameRef<'_> {
        FrameRef {
            can_id: self.can_id,
            len: self.len,
            fd_flags: self.fd_flags,
            data: &self.data,
        }
    }
}

fn any_frame() -> impl Strategy<Value = Owned> {
    let classic =
        (any::<u32>(), proptest::collection::vec(any::<u8>(), 0..=8)).prop_map(|(can_id, data)| {
            let remote = can_id & CAN_RTR_FLAG != 0;
            Owned {
                can_id,
                len: data.len() as u8,
                fd_flags: None,
                data: if remote { Vec::new() } else { data },
            }
        });
    let fd = (
        any::<u32>(),
        any::<u8>(),
        proptest::collection::vec(any::<u8>(), 0..=64),
    )
        .prop_map(|(can_id, flags, data)| {
            let can_id = can_id & !CAN_RTR_FLAG;
            Owned {
                can_id,
                len: data.len() as u8,
                fd_flags: Some(flags),
                data,
            }
        });
    prop_oneof![3 => classic, 1 => fd]
}

fn build(seq: u8, frames: &[Owned]) -> Vec<u8> {
    let mut buf = vec![0u8; MAX_PACKET_LEN];
    let mut w = PacketWriter::new(&mut buf, seq).unwrap();
    for f in frames {
        w.push(&f.view()).unwrap();
    }
    let n = w.finish();
    buf.truncate(n);
    buf
}

#[test]
fn the_documented_layout_byte_for_byte() {
    // cannelloni's doc/udp_format.md: version 2, op DATA (0), seq, count (big endian); per
    // frame can_id (big endian, Linux flags), len, data; CAN FD: len | 0x80, then flags.
    let frames = [
        Owned {
            can_id: 0x101,
            len: 3,
            fd_flags: None,
            data: vec![0xAA, 0xBB, 0xCC],
        },
        Owned {
            can_id: 0x1234_5678 | CAN_EFF_FLAG,
            len: 0,
            fd_flags: None,
            data: vec![],
        },
        Owned {
            can_id: 0x7FF | CAN_RTR_FLAG,
            len: 8,
            fd_flags: None,
            data: vec![],
        },
        Owned {
            can_id: 0x42,
            len: 2,
            fd_flags: Some(0x05),
            data: vec![1, 2],
        },
    ];
    let bytes = build(0x7E, &frames);
    let want: Vec<u8> = vec![
        2, 0, 0x7E, 0, 4, // header
        0, 0, 0x01, 0x01, 3, 0xAA, 0xBB, 0xCC, // standard, 3 bytes
        0x92, 0x34, 0x56, 0x78, 0, // extended, empty
        0x40, 0, 0x07, 0xFF, 8, // remote: a DLC, no data
        0, 0, 0, 0x42, 0x82, 0x05, 1, 2, // CAN FD: len | 0x80, flags, data
    ];
    assert_eq!(bytes, want);
    let p = Packet::parse(&bytes).unwrap();
    assert_eq!((p.seq, p.count), (0x7E, 4));
    let got: Vec<_> = p.frames().collect();
    assert_eq!(got.len(), 4);
    assert_eq!(
        got[0].standard_data(),
        Some((0x101, &[0xAA, 0xBB, 0xCC][..]))
    );
    assert!(got[1].is_extended() && got[1].standard_data().is_none());
    assert_eq!(got[1].id(), 0x1234_5678);
    assert!(got[2].is_remote() && got[2].data.is_empty() && got[2].len == 8);
    assert_eq!(got[3].fd_flags, Some(5));
    assert!(got[3].standard_data().is_none() && got[3].to_classic().is_none());
}

#[test]
fn every_malformation_is_named() {
    let good = build(
        1,
        &[Owned {
            can_id: 0x181,
            len: 8,
            fd_flags: None,
            data: vec![9; 8],
        }],
    );
    assert!(Packet::parse(&good).is_ok());
    assert_eq!(
        Packet::parse(&good[..4]),
        Err(PacketError::TooShort { len: 4 })
    );
    let mut v = good.clone();
    v[0] = 1;
    assert_eq!(
        Packet::parse(&v),
        Err(PacketError::WrongVersion { version: 1 })
    );
    let mut v = good.clone();
    v[1] = 1; // ACK: TCP's, never UDP data
    assert_eq!(
        Packet::parse(&v),
        Err(PacketError::WrongOpCode { op_code: 1 })
    );
    assert_eq!(
        Packet::parse(&good[..good.len() - 1]),
        Err(PacketError::Truncated { frame: 0, count: 1 })
    );
    let mut v = good.clone();
    v.push(0);
    assert_eq!(
        Packet::parse(&v),
        Err(PacketError::Trailing { extra: 1, count: 1 })
    );
    let mut v = good.clone();
    v[HEADER_LEN + 4] = 9; // classic length 9
    assert_eq!(
        Packet::parse(&v),
        Err(PacketError::BadLength { frame: 0, len: 9 })
    );
    let mut v = good.clone();
    v[4] = 2; // two frames announced, one present
    assert_eq!(
        Packet::parse(&v),
        Err(PacketError::Truncated { frame: 1, count: 2 })
    );
    assert_eq!(
        Packet::parse(&vec![2; MAX_PACKET_LEN + 1]),
        Err(PacketError::TooLong {
            len: MAX_PACKET_LEN + 1
        })
    );
    // An empty data packet is valid (cannelloni ignores it).
    assert_eq!(Packet::parse(&[2, 0, 9, 0, 0]).unwrap().frames().count(), 0);
}

#[test]
fn the_writer_refuses_what_it_cannot_send() {
    let mut small = [0u8; HEADER_LEN + 10];
    let mut w = PacketWriter::new(&mut small, 0).unwrap();
    let f = CanFrame::standard(0x100, &[1; 8]).unwrap();
    assert_eq!(
        w.push(&f.as_ref()),
        Err(WriteError::Full {
            needed: 13,
            free: 10
        })
    );
    let bad = FrameRef {
        can_id: 1,
        len: 9,
        fd_flags: None,
        data: &[0; 9],
    };
    assert!(matches!(w.push(&bad), Err(WriteError::BadFrame { .. })));
    let lying = FrameRef {
        can_id: 1,
        len: 4,
        fd_flags: None,
        data: &[0; 3],
    };
    assert!(matches!(w.push(&lying), Err(WriteError::BadFrame { .. })));
    assert_eq!(w.finish(), HEADER_LEN);
    assert!(PacketWriter::new(&mut [0u8; 4], 0).is_none());
    assert!(CanFrame::standard(0x800, &[]).is_none());
    assert!(CanFrame::extended(0x2000_0000, &[]).is_none());
    assert!(CanFrame::standard(1, &[0; 9]).is_none());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// What the writer builds, the parser reads back, frame for frame.
    #[test]
    fn round_trip(seq in any::<u8>(), frames in proptest::collection::vec(any_frame(), 0..20)) {
        let bytes = build(seq, &frames);
        let p = Packet::parse(&bytes).unwrap();
        prop_assert_eq!(p.seq, seq);
        prop_assert_eq!(usize::from(p.count), frames.len());
        let got: Vec<Owned> = p.frames().map(|f| Owned {
            can_id: f.can_id, len: f.len, fd_flags: f.fd_flags, data: f.data.to_vec(),
        }).collect();
        prop_assert_eq!(got, frames);
    }

    /// Any cut of a non-empty packet is refused, never misread.
    #[test]
    fn truncation_is_always_an_error(
        frames in proptest::collection::vec(any_frame(), 1..6), cut in any::<prop::sample::Index>()
    ) {
        let bytes = build(0, &frames);
        let n = cut.index(bytes.len());
        prop_assert!(Packet::parse(&bytes[..n]).is_err());
    }

    /// Random bytes, and valid packets with random bytes changed: never a panic; whatever
    /// parses yields exactly `count` frames, each within its kind's length.
    #[test]
    fn garbage_never_panics(
        noise in proptest::collection::vec(any::<u8>(), 0..200),
        frames in proptest::collection::vec(any_frame(), 0..6),
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
    ) {
        let mut mutated = build(3, &frames);
        for (at, byte) in edits {
            let i = at.index(mutated.len());
            mutated[i] = byte;
        }
        for input in [&noise[..], &mutated[..]] {
            if let Ok(p) = Packet::parse(input) {
                let frames: Vec<_> = p.frames().collect();
                prop_assert_eq!(frames.len(), usize::from(p.count));
                for f in frames {
                    let max = if f.fd_flags.is_some() { FD_MAX_LEN } else { CLASSIC_MAX_LEN };
                    prop_assert!(usize::from(f.len) <= max);
                    prop_assert!(f.data.len() <= usize::from(f.len));
                }
            }
        }
    }
}
