//! Every parser of `proto::epl` against mutated and random input: each returns `Ok` or a
//! typed `Err`, none panics.

use super::asnd::{ErrorEntry, IdentResponse, NmtCommandFrame, NmtRequestFrame, StatusResponse};
use super::frame::{Body, EplFrame, EplRepr};
use super::sdo::SdoFrame;

/// A small deterministic generator (xorshift).
#[cfg(test)]
struct Rng(u64);

#[cfg(test)]
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Runs the frame parser on `b`, each ASnd service's parser on what an ASnd frame carries, and
/// the SDO parsers (over ASnd and over UDP). The fuzz target `epl` (`fuzz/`) runs it on its
/// inputs.
pub fn parse_all(b: &[u8]) {
    if let Ok(f) = EplFrame::new_checked(b) {
        if let Ok(r) = EplRepr::parse(&f) {
            let _ = r.emit();
            if let Body::Asnd(a) = r.body {
                let _ = IdentResponse::parse(&a.payload);
                let _ = StatusResponse::parse(&a.payload);
                let _ = NmtCommandFrame::parse(&a.payload);
                let _ = NmtRequestFrame::parse(&a.payload);
                if let Ok(s) = SdoFrame::parse(&a.payload) {
                    let _ = s.emit();
                    if let Some(c) = s.command {
                        let _ = (c.abort_code(), c.by_index());
                    }
                }
            }
        }
    }
    let _ = SdoFrame::strip_udp(b).map(SdoFrame::parse);
    let _ = ErrorEntry::parse(b);
}

#[test]
fn random_and_truncated_input_never_panics() {
    let mut rng = Rng(0x5EED_0EB1);
    for _ in 0..20_000 {
        let n = (rng.next() % 200) as usize;
        let mut b: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
        if let Some(first) = b.first_mut() {
            *first = [1, 3, 4, 5, 6][(rng.next() % 5) as usize];
        }
        if b.len() > 3 {
            b[3] = (rng.next() % 7) as u8;
        }
        for cut in [0, n / 2, n] {
            parse_all(&b[..cut]);
        }
    }
}
