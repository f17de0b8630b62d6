//! Every parser of `proto::can` against mutated and random input: each returns `Ok` or a
//! typed `Err`, none panics (the promise of the module documentation).

use super::socketcan::{SocketCanFrame, SocketCanRepr};
use super::socketcand::{Framed, Message};
#[cfg(test)]
use super::{
    socketcan::{ErrorClass, ErrorFrame},
    socketcand::Timestamp,
    CanFrame,
};

/// `count` pseudo-random byte strings of 0..`max_len` bytes from `seed` (a 64-bit LCG whose
/// high bytes are taken), reproducible run after run.
#[cfg(test)]
pub(crate) fn random_inputs(seed: u64, count: usize, max_len: usize) -> Vec<Vec<u8>> {
    let mut x = seed;
    let mut byte = move || {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (x >> 56) as u8
    };
    (0..count)
        .map(|_| {
            let n = usize::from(byte()) % (max_len + 1);
            (0..n).map(|_| byte()).collect()
        })
        .collect()
}

/// Every prefix of each valid message, the message with a byte appended, and the message with
/// one byte's bits flipped by each of a set of masks at each position.
#[cfg(test)]
pub(crate) fn mutations(valid: &[Vec<u8>]) -> Vec<Vec<u8>> {
    let mut out = vec![];
    for m in valid {
        out.extend((0..=m.len()).map(|n| m[..n].to_vec()));
        out.push([m.as_slice(), &[0]].concat());
        for (i, mask) in (0..m.len())
            .flat_map(|i| [0x01, 0x02, 0x04, 0x10, 0x20, 0x40, 0x80, 0xFF].map(|x| (i, x)))
        {
            let mut b = m.clone();
            b[i] ^= mask;
            out.push(b);
        }
    }
    out
}

/// Runs the SocketCAN frame and socketcand parsers on `b` (a whole stream of socketcand
/// messages, cut one after another); what parses emits and parses back the same. The fuzz
/// target `can` (`fuzz/`) runs it on its inputs.
pub fn parse_all(b: &[u8]) {
    if let Ok(f) = SocketCanFrame::new_checked(b) {
        let _ = (f.can_id(), f.data_len(), f.data().len());
        if let Ok(r) = SocketCanRepr::parse(&f) {
            assert_eq!(SocketCanRepr::parse_bytes(&r.to_bytes()), Ok(r));
        }
    }
    let mut at = 0;
    while let Ok(Framed::Complete { message, consumed }) = Message::parse(&b[at..]) {
        assert!(consumed > 0 && at + consumed <= b.len());
        at += consumed;
        if let Ok(text) = message.emit() {
            // What this codec writes, it reads back.
            let Ok(Framed::Complete { message: back, .. }) = Message::parse(text.as_bytes()) else {
                panic!("{text:?} does not parse");
            };
            assert_eq!(back, message, "{text:?}");
        }
    }
}

#[cfg(test)]
fn valid_messages() -> Vec<Vec<u8>> {
    let f = CanFrame::new(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap();
    let e = ErrorFrame {
        class: ErrorClass::BUSOFF,
        data: [0; 8],
    };
    let time = Timestamp {
        secs: 1,
        usecs: 999_999,
    };
    let mut v = vec![
        SocketCanRepr::Frame(f).to_bytes().to_vec(),
        SocketCanRepr::Frame(CanFrame::remote(0x705, 1).unwrap())
            .to_bytes()
            .to_vec(),
        SocketCanRepr::Error(e).to_bytes().to_vec(),
    ];
    for m in [
        Message::Hi,
        Message::Open {
            channel: "can0".into(),
        },
        Message::Send { frame: f },
        Message::Frame { frame: f, time },
        Message::ErrorFrame {
            class: ErrorClass::CRTL,
            time,
            data: vec![0, 4, 0, 0, 0, 0, 0, 0],
        },
        Message::Error {
            text: "unknown command".into(),
        },
    ] {
        v.push(m.emit().unwrap().into_bytes());
    }
    v
}

#[test]
fn mutated_and_random_input() {
    mutations(&valid_messages())
        .iter()
        .for_each(|b| parse_all(b));
    random_inputs(0xC0FF_EE00_0601_0000, 8_000, 40)
        .iter()
        .for_each(|b| parse_all(b));
    // Text from the socketcand alphabet hits more branches than uniform bytes.
    let alphabet = b"<> 0123456789abcdefABCDEF.xsendframeopenerrorhi\t";
    for raw in random_inputs(7, 8_000, 60) {
        let text: Vec<u8> = raw
            .iter()
            .map(|b| alphabet[usize::from(*b) % alphabet.len()])
            .collect();
        parse_all(&text);
    }
}
