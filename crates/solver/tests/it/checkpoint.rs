//! Each way a checkpoint can be wrong gets its own error: truncation,
//! trailing bytes and bad UTF-8 here (the inputs are re-sealed after
//! tampering so that the checksum does not catch them first); unknown codes
//! come from the monitor's decoder, so only their message is checked here.

use solver::checkpoint::{unseal, Reader, Writer};
use solver::*;

use crate::common;

const MAGIC: &[u8; 8] = b"KICKTEST";

fn stepped_solver() -> Solver {
    let scene = common::box_scene([0.2, 0.2], [0.0, 0.0, 0.1, 0.1], Material::tait(1e4), 9.81);
    let mut s = common::solver(
        scene,
        common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usf),
    );
    for _ in 0..3 {
        s.step().unwrap();
    }
    s
}

/// A sealed buffer's body (magic included) with a fresh checksum.
fn reseal(body: &[u8]) -> Vec<u8> {
    Writer(body.to_vec()).seal()
}

#[test]
fn truncated_checkpoints_are_truncated() {
    let a = stepped_solver();
    let bytes = a.checkpoint();
    let body = &bytes[..bytes.len() - 8];
    let mut b = stepped_solver();
    // Every cut of the body, from magic only to one byte short, re-sealed.
    for len in (8..body.len()).rev().step_by(7).chain([8, 9, 16, 23, 24]) {
        assert_eq!(
            b.restore(&reseal(&body[..len])),
            Err(CheckpointError::Truncated),
            "body cut to {len} of {} bytes",
            body.len()
        );
    }
    // Too short to hold magic and checksum.
    for len in [0, 1, 8, 15] {
        assert_eq!(b.restore(&bytes[..len]), Err(CheckpointError::Truncated));
    }
    // A cut file without a fresh seal: its last 8 bytes are no checksum.
    assert!(matches!(
        b.restore(&bytes[..bytes.len() - 9]),
        Err(CheckpointError::Checksum { .. })
    ));
    b.restore(&bytes).unwrap();
    assert_eq!(b.state_hash(), a.state_hash());
}

#[test]
fn trailing_bytes_are_counted() {
    let a = stepped_solver();
    let bytes = a.checkpoint();
    let body = &bytes[..bytes.len() - 8];
    let mut b = stepped_solver();
    for count in [1, 7, 8, 100] {
        let mut longer = body.to_vec();
        longer.extend(vec![0u8; count]);
        assert_eq!(
            b.restore(&reseal(&longer)),
            Err(CheckpointError::TrailingBytes { count })
        );
    }
    // Bytes appended after the seal break the checksum instead.
    let mut appended = bytes.clone();
    appended.push(0);
    assert!(matches!(
        b.restore(&appended),
        Err(CheckpointError::Checksum { .. })
    ));
    b.restore(&bytes).unwrap();
    assert_eq!(b.state_hash(), a.state_hash());
}

#[test]
fn reader_reports_bad_utf8_leftovers_and_short_fields() {
    let mut w = Writer::default();
    w.0.extend_from_slice(MAGIC);
    w.str("kick");
    w.bytes(&[b'k', 0xff, 0xfe]);
    w.u64(9);
    let sealed = w.seal();
    let mut r = Reader(unseal(&sealed, MAGIC).unwrap());
    assert_eq!(r.str(), Ok("kick".to_string()));
    assert_eq!(r.str(), Err(CheckpointError::BadUtf8));
    assert_eq!(r.finish(), Err(CheckpointError::TrailingBytes { count: 8 }));
    assert_eq!(r.u64(), Ok(9));
    assert_eq!(r.finish(), Ok(()));
    assert_eq!(r.u64(), Err(CheckpointError::Truncated));
    // A length prefix longer than what is left.
    let mut w = Writer::default();
    w.0.extend_from_slice(MAGIC);
    w.u64(5);
    w.0.extend_from_slice(b"kic");
    let sealed = w.seal();
    let mut r = Reader(unseal(&sealed, MAGIC).unwrap());
    assert_eq!(r.bytes(), Err(CheckpointError::Truncated));
    assert_eq!(unseal(&sealed, b"KICKSTAT"), Err(CheckpointError::BadMagic));
    // Another version of the same format is named as such.
    assert_eq!(
        unseal(&sealed, b"KICKTESU"),
        Err(CheckpointError::Format {
            found: "KICKTEST".into(),
            reads: "KICKTESU".into()
        })
    );
}

#[test]
fn each_cause_has_its_own_message() {
    let messages = [
        (CheckpointError::Truncated, "truncated"),
        (
            CheckpointError::TrailingBytes { count: 12 },
            "12 unexpected bytes after its last field",
        ),
        (CheckpointError::BadUtf8, "not UTF-8"),
        (
            CheckpointError::UnknownCode {
                what: "event kind",
                code: 7,
            },
            "unknown event kind code 7",
        ),
        (CheckpointError::BadMagic, "bad magic"),
        (
            CheckpointError::Format {
                found: "KICKMONA".into(),
                reads: "KICKMONB".into(),
            },
            "format KICKMONA, this build reads KICKMONB",
        ),
        (
            CheckpointError::Checksum {
                stored: 1,
                computed: 2,
            },
            "corrupted",
        ),
    ];
    for (e, text) in &messages {
        assert!(e.to_string().contains(text), "{e:?}: {e}");
    }
    let all: Vec<String> = messages.iter().map(|(e, _)| e.to_string()).collect();
    for (i, m) in all.iter().enumerate() {
        assert!(!all[i + 1..].contains(m), "{m} is not specific");
    }
}

#[test]
fn the_clock_is_read_without_restoring() {
    let s = stepped_solver();
    let bytes = s.checkpoint();
    assert_eq!(checkpoint::clock(&bytes), Ok((s.step_count(), s.time())));
    assert!(s.step_count() > 0);
    // A corrupted byte is caught by the seal, as a restore would catch it.
    let mut bad = bytes.clone();
    let mid = bad.len() / 2;
    bad[mid] ^= 1;
    assert!(matches!(
        checkpoint::clock(&bad),
        Err(CheckpointError::Checksum { .. })
    ));
}
