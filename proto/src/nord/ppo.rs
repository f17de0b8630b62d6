//! PPO telegrams: the PROFIBUS parameter/process data objects NORD uses for cyclic data.
//!
//! BU 0620 §2.5.4 and §2.5.5.1 (p. 46–50), BU 0590 §4.1.1 (tables 9–13, p. 17–18): PPO 1 and 2
//! carry the parameter channel (PKW, 4 words) before the process data; PPO 3, 4 and 6 carry
//! process data only. Process data is the control word and setpoints to the inverter, the
//! status word and actual values from it. Words are big-endian, as in the manuals' examples.
//!
//! | type | PKW | PZD words | bytes |
//! |---|---|---|---|
//! | PPO 1 | yes | 2 (CTW/STW, SW1/IW1) | 12 |
//! | PPO 2 | yes | 4 (… SW3/IW3) | 16 |
//! | PPO 3 | no | 2 | 4 |
//! | PPO 4 | no | 4 | 8 |
//! | PPO 6 | no | 6 (… SW5/IW5) | 12 |

use std::fmt;

use super::pkw::{PkwError, PkwRepr, PKW_LEN};
use super::product::{Family, Product};

/// A malformed PPO telegram.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PpoError {
    /// A type number NORD does not use (only 1, 2, 3, 4 and 6, BU 0620 §2.5.4).
    #[error("PPO type {0} is not one of 1, 2, 3, 4, 6")]
    UnknownType(u8),
    /// The telegram is not as long as its type says.
    #[error("PPO {ppo} telegram must be {need} bytes, got {got}")]
    BadLength {
        /// The type.
        ppo: u8,
        /// Its length.
        need: usize,
        /// Bytes present.
        got: usize,
    },
    /// The PKW area did not parse.
    #[error(transparent)]
    Pkw(#[from] PkwError),
}

/// A PPO type (open: unknown numbers are kept and refused by [`PpoType::new`]).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PpoType(pub u8);

impl PpoType {
    /// PKW + control/status word + 1 setpoint/actual value.
    pub const TYPE_1: PpoType = PpoType(1);
    /// PKW + control/status word + 3 setpoints/actual values.
    pub const TYPE_2: PpoType = PpoType(2);
    /// Control/status word + 1 setpoint/actual value.
    pub const TYPE_3: PpoType = PpoType(3);
    /// Control/status word + 3 setpoints/actual values.
    pub const TYPE_4: PpoType = PpoType(4);
    /// Control/status word + 5 setpoints/actual values.
    pub const TYPE_6: PpoType = PpoType(6);
    /// Every type NORD inverters process (BU 0620 §2.5.4).
    pub const ALL: [PpoType; 5] = [
        Self::TYPE_1,
        Self::TYPE_2,
        Self::TYPE_3,
        Self::TYPE_4,
        Self::TYPE_6,
    ];

    /// Checks the type number.
    pub fn new(n: u8) -> Result<PpoType, PpoError> {
        Self::ALL
            .into_iter()
            .find(|t| t.0 == n)
            .ok_or(PpoError::UnknownType(n))
    }

    /// Whether the telegram starts with the 4-word parameter channel.
    pub fn has_pkw(self) -> bool {
        matches!(self.0, 1 | 2)
    }

    /// Process-data words (control/status word included).
    pub fn pzd_words(self) -> usize {
        match self.0 {
            1 | 3 => 2,
            2 | 4 => 4,
            6 => 6,
            _ => 0,
        }
    }

    /// Telegram length in bytes.
    pub fn byte_len(self) -> usize {
        let pkw = if self.has_pkw() { PKW_LEN } else { 0 };
        pkw + 2 * self.pzd_words()
    }

    /// The code the product's PPO-type parameter shows for this type: P879 on the SK 550P
    /// (BU 0620 §4.4.3: 6 = PPO3, 7 = PPO4, 8 = PPO6, 9 = PPO1, 10 = PPO2), P180 on the SK
    /// TU3-PNT (BU 0590 §5.1.4: 3 = PPO3, 4 = PPO4, 5 = PPO6, 6 = PPO1, 7 = PPO2).
    pub fn display_code(self, product: Product) -> Option<u16> {
        let module = match self.0 {
            3 => 3,
            4 => 4,
            6 => 5,
            1 => 6,
            2 => 7,
            _ => return None,
        };
        Some(match product.family() {
            Family::Integrated => module + 3,
            Family::Module => module,
        })
    }
}

impl fmt::Debug for PpoType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "PPO{}", self.0)
    }
}

/// A parsed PPO telegram.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PpoRepr {
    /// The parameter channel, for PPO 1 and 2.
    pub pkw: Option<PkwRepr>,
    /// Process data: control word then setpoints (to the inverter), status word then actual
    /// values (from it).
    pub pzd: Vec<u16>,
}

impl PpoRepr {
    /// Parses a telegram of type `ppo`; its length must match exactly.
    pub fn parse(bytes: &[u8], ppo: PpoType) -> Result<PpoRepr, PpoError> {
        let ppo = PpoType::new(ppo.0)?;
        if bytes.len() != ppo.byte_len() {
            return Err(PpoError::BadLength {
                ppo: ppo.0,
                need: ppo.byte_len(),
                got: bytes.len(),
            });
        }
        let (pkw, rest) = if ppo.has_pkw() {
            (Some(PkwRepr::parse(bytes)?), &bytes[PKW_LEN..])
        } else {
            (None, bytes)
        };
        let pzd = rest
            .chunks_exact(2)
            .map(|w| u16::from_be_bytes([w[0], w[1]]))
            .collect();
        Ok(PpoRepr { pkw, pzd })
    }

    /// The telegram's bytes for type `ppo`: a missing PKW is sent as zeros ("no order"), the
    /// process data is cut or zero-padded to the type's word count.
    pub fn emit(&self, ppo: PpoType) -> Vec<u8> {
        let mut out = Vec::with_capacity(ppo.byte_len());
        if ppo.has_pkw() {
            out.extend_from_slice(&self.pkw.unwrap_or_default().emit_bytes());
        }
        for i in 0..ppo.pzd_words() {
            out.extend_from_slice(&self.pzd.get(i).copied().unwrap_or(0).to_be_bytes());
        }
        out
    }

    fn words(&self) -> String {
        self.pzd
            .iter()
            .map(|w| format!("{w:04X}h"))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The telegram as the master sends it, in the manuals' terms.
    pub fn describe_order(&self) -> String {
        let pzd = format!("PZD [{}] (control word, setpoints)", self.words());
        match &self.pkw {
            Some(p) if p.ak != 0 => format!("{}; {pzd}", p.describe_order()),
            _ => pzd,
        }
    }

    /// The telegram as the inverter answers, in the manuals' terms.
    pub fn describe_response(&self) -> String {
        let pzd = format!("PZD [{}] (status word, actual values)", self.words());
        match &self.pkw {
            Some(p) => format!("{}; {pzd}", p.describe_response()),
            None => pzd,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    // BU 0620 §2.5.5.1: PPO3 4 bytes, PPO4 8, PPO6 12, PPO1 12, PPO2 16.
    #[case(1, true, 2, 12)]
    #[case(2, true, 4, 16)]
    #[case(3, false, 2, 4)]
    #[case(4, false, 4, 8)]
    #[case(6, false, 6, 12)]
    fn layouts(#[case] n: u8, #[case] pkw: bool, #[case] words: usize, #[case] bytes: usize) {
        let t = PpoType::new(n).unwrap();
        assert_eq!(
            (t.has_pkw(), t.pzd_words(), t.byte_len()),
            (pkw, words, bytes)
        );
    }

    #[test]
    fn unknown_types_are_refused() {
        for n in [0, 5, 7, 255] {
            assert_eq!(PpoType::new(n), Err(PpoError::UnknownType(n)));
        }
    }

    #[rstest]
    #[case(Product::Sk550p, 3, 6)]
    #[case(Product::Sk550p, 2, 10)]
    #[case(Product::Tu3Pnt, 6, 5)]
    #[case(Product::Tu3Pnt, 1, 6)]
    fn display_codes(#[case] p: Product, #[case] t: u8, #[case] code: u16) {
        assert_eq!(PpoType(t).display_code(p), Some(code));
    }

    #[test]
    fn ppo1_round_trip_with_the_p102_order() {
        // BU 0620 §2.5.6.4 order in the PKW area, control word 047Eh, setpoint 0.
        let r = PpoRepr {
            pkw: PkwRepr::parse(&[0x24, 0x4E, 0x01, 0, 0, 0, 0, 0xFA]).ok(),
            pzd: vec![0x047E, 0],
        };
        let b = r.emit(PpoType::TYPE_1);
        assert_eq!(b, [0x24, 0x4E, 0x01, 0, 0, 0, 0, 0xFA, 0x04, 0x7E, 0, 0]);
        assert_eq!(PpoRepr::parse(&b, PpoType::TYPE_1), Ok(r));
    }

    #[test]
    fn wrong_lengths_at_every_size() {
        for t in PpoType::ALL {
            for n in 0..=t.byte_len() + 1 {
                let r = PpoRepr::parse(&vec![0; n], t);
                assert_eq!(r.is_ok(), n == t.byte_len(), "{t:?} {n}");
            }
        }
    }

    mod properties {
        use super::*;
        use crate::nord::pkw::tests::properties::pkw_repr;
        use proptest::prelude::*;

        /// A type and a telegram of exactly that type: PKW present iff the type has one, as many
        /// PZD words as the type carries.
        fn typed_repr() -> impl Strategy<Value = (PpoType, PpoRepr)> {
            proptest::sample::select(PpoType::ALL.to_vec()).prop_flat_map(|t| {
                let pkw = if t.has_pkw() {
                    pkw_repr().prop_map(Some).boxed()
                } else {
                    Just(None).boxed()
                };
                let pzd = proptest::collection::vec(any::<u16>(), t.pzd_words());
                (
                    Just(t),
                    (pkw, pzd).prop_map(|(pkw, pzd)| PpoRepr { pkw, pzd }),
                )
            })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips((t, r) in typed_repr()) {
                let bytes = r.emit(t);
                prop_assert_eq!(bytes.len(), t.byte_len());
                prop_assert_eq!(PpoRepr::parse(&bytes, t).unwrap(), r);
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(
                n in any::<u8>(),
                bytes in proptest::collection::vec(any::<u8>(), 0..24),
            ) {
                let _ = PpoRepr::parse(&bytes, PpoType(n));
            }
        }
    }
}
