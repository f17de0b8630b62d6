//! The SYNC object (CiA 301 "SYNC protocol"; COB-ID 080h): no data, or 1 byte, the
//! synchronous counter, when the synchronous counter overflow value (object 1019h) is 2..240.
//! The counter runs from 1 up to the overflow value.

use crate::wire::{Error, Reader};

/// The largest synchronous counter overflow value (object 1019h).
pub const MAX_COUNTER: u8 = 240;

/// A SYNC message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SyncFrame {
    /// The counter (1..240), if the producer sends one.
    pub counter: Option<u8>,
}

impl SyncFrame {
    /// Parses 0 or 1 data bytes; a counter of 0 or above 240 is [`Error::Invalid`].
    pub fn parse(bytes: &[u8]) -> Result<SyncFrame, Error> {
        let mut r = Reader::new(bytes);
        let counter = match r.remaining() {
            0 => None,
            _ => Some(r.u8("SYNC counter")?),
        };
        r.finish("SYNC")?;
        if let Some(c) = counter.filter(|c| !(1..=MAX_COUNTER).contains(c)) {
            return Err(Error::Invalid {
                field: "SYNC counter",
                value: u32::from(c),
                why: "the counter runs from 1 to at most 240",
            });
        }
        Ok(SyncFrame { counter })
    }

    /// The data bytes: none, or the counter.
    pub fn emit(&self) -> Vec<u8> {
        self.counter.into_iter().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn with_and_without_counter() {
        assert_eq!(SyncFrame::parse(&[]), Ok(SyncFrame { counter: None }));
        assert_eq!(SyncFrame::parse(&[1]), Ok(SyncFrame { counter: Some(1) }));
        assert_eq!(SyncFrame::parse(&[240]).unwrap().emit(), [240]);
        assert!(SyncFrame::default().emit().is_empty());
        for bad in [0u8, 241, 255] {
            assert!(matches!(
                SyncFrame::parse(&[bad]),
                Err(Error::Invalid {
                    field: "SYNC counter",
                    ..
                })
            ));
        }
        assert_eq!(
            SyncFrame::parse(&[1, 2]),
            Err(Error::Trailing {
                what: "SYNC",
                extra: 1
            })
        );
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(counter in proptest::option::of(1..=MAX_COUNTER)) {
                let s = SyncFrame { counter };
                prop_assert_eq!(SyncFrame::parse(&s.emit()), Ok(s));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..4)) {
                let _ = SyncFrame::parse(&bytes);
            }
        }
    }
}
