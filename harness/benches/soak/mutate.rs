//! The fuzzed clients' bytes: good messages built with `proto`'s emitters, then broken by a
//! seeded generator (random bytes, bit flips, truncations, lying lengths, garbage appended),
//! so a run can be repeated frame for frame.

use std::ops::Range;

/// A seeded source of broken messages.
pub(crate) struct Mutator {
    rng: fastrand::Rng,
}

impl Mutator {
    pub(crate) fn new(seed: u64) -> Mutator {
        Mutator {
            rng: fastrand::Rng::with_seed(seed),
        }
    }

    /// The generator, for the clients' own choices (which message, which socket).
    pub(crate) fn rng(&mut self) -> &mut fastrand::Rng {
        &mut self.rng
    }

    /// One of `good` broken one way: random bytes (up to `max_len`), one to eight bytes
    /// XORed, cut short, a length field (one of `lengths`, byte ranges in the message, little
    /// endian) given a random value, or garbage appended; now and then two at once.
    pub(crate) fn mutate(
        &mut self,
        good: &[Vec<u8>],
        lengths: &[Range<usize>],
        max_len: usize,
    ) -> Vec<u8> {
        let mut m = good
            .get(self.rng.usize(..good.len().max(1)))
            .cloned()
            .unwrap_or_default();
        for _ in 0..self.rng.usize(1..=2) {
            match self.rng.u8(..5) {
                0 => {
                    m = (0..self.rng.usize(..=max_len))
                        .map(|_| self.rng.u8(..))
                        .collect();
                }
                1 if !m.is_empty() => {
                    for _ in 0..self.rng.usize(1..=8) {
                        let at = self.rng.usize(..m.len());
                        m[at] ^= self.rng.u8(1..);
                    }
                }
                2 => m.truncate(self.rng.usize(..=m.len())),
                3 => {
                    if let Some(field) = lengths.get(self.rng.usize(..lengths.len().max(1))) {
                        let len = m.len();
                        for at in field.clone().filter(|&at| at < len) {
                            m[at] = self.rng.u8(..);
                        }
                    }
                }
                _ => {
                    let extra = self.rng.usize(1..=64);
                    m.extend((0..extra).map(|_| self.rng.u8(..)));
                }
            }
        }
        m
    }
}
