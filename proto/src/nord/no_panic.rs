//! The NORD parameter channel and process data on any bytes: the PKW and PPO parsers return
//! `Ok` or a typed `Err`, never panic, and what parses emits back the same bytes. The fuzz
//! target `nord` (`fuzz/`) runs [`parse_all`] on its inputs.

use super::pkw::{PkwFrame, PkwRepr, PKW_LEN};
use super::ppo::{PpoRepr, PpoType};

/// Runs the PKW parser, and the PPO parser as each PPO type, on `b`; the first byte, when
/// there is one, is also tried as a PPO type number (unknown types are refused by name).
pub fn parse_all(b: &[u8]) {
    if let Ok(f) = PkwFrame::new_checked(b) {
        let _ = f.pke();
    }
    if let Ok(r) = PkwRepr::parse(b) {
        assert_eq!(r.emit_bytes()[..], b[..PKW_LEN]);
    }
    for t in PpoType::ALL {
        if let Ok(r) = PpoRepr::parse(b, t) {
            assert_eq!(r.emit(t), b);
        }
    }
    if let Some((&n, rest)) = b.split_first() {
        if let Ok(r) = PpoRepr::parse(rest, PpoType(n)) {
            assert_eq!(r.emit(PpoType(n)), rest);
        }
    }
}
