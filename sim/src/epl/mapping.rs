//! Dynamic PDO mapping of the SK 550P (BU 0620 §2.4.5 "The frequency inverter supports dynamic
//! mapping") and the SK TU3-POL (BU 2200 §6.3.6: "Die Busschnittstellen SK TU3-POL …
//! unterstützen dynamisches Mapping. D. h. die festen Einstellungen zu Länge und Aufbau der
//! Prozessdaten … können durch vorkonfigurierte Einträge im SPS-Projekt überschrieben werden").
//!
//! The MN writes the mapping objects 1600h (PReq, "zur Busschnittstelle") and 1A00h (PRes) the
//! DS 301 way: sub-index 0 = 0 switches the mapping off, the entries (UNSIGNED64: length in bits
//! 63–48, offset in bits 47–32, sub-index 23–16, index 15–0) are written, sub-index 0 = n
//! switches the first n on. An entry may map any word of the fixed layout (§6.3.5), 16 bits
//! long, the words following each other from offset 0. The MN maps while it configures the node
//! (Pre-Operational 1 and 2, see `od.rs`). The SK TU4-POL and SK CU4-POL keep the static
//! mapping (BU 2200 §3.1): their mapping objects stay read-only.

use proto::nord::epl::{self as def, MappedWord};
use proto::nord::errors::SdoAbort;
use proto::nord::Product;

use crate::objects::abort;

/// The mapping of one direction: the words in use and the entries as last written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct PdoMap {
    /// The words of the payload, in order.
    pub(crate) words: Vec<MappedWord>,
    /// Sub-index 0: the entries switched on (0 while the MN rewrites them).
    count: u8,
    /// Sub-indices 1…: the entries as written.
    entries: Vec<u64>,
}

impl PdoMap {
    /// The product's fixed mapping (§6.3.5).
    pub(crate) fn fixed(product: Product, outputs: bool) -> PdoMap {
        let words = def::process_map(product, outputs);
        let entries = entries_of(&words);
        PdoMap {
            count: words.len() as u8,
            words,
            entries,
        }
    }

    /// Sub-index 0 (the number of entries) or an entry.
    pub(crate) fn read(&self, sub: u8) -> Result<Vec<u8>, SdoAbort> {
        match sub {
            0 => Ok(vec![self.count]),
            s => self
                .entries
                .get(usize::from(s) - 1)
                .map(|e| e.to_le_bytes().to_vec())
                .ok_or(abort::NO_SUBINDEX),
        }
    }

    /// A write to sub-index `sub` of the mapping object, checked against the words
    /// `product` can map in this direction.
    pub(crate) fn write(
        &mut self,
        product: Product,
        outputs: bool,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        let mappable = def::process_map(product, outputs);
        let capacity = mappable.len();
        if sub == 0 {
            let [n] = data else {
                return Err(if data.len() > 1 {
                    abort::TOO_LONG
                } else {
                    abort::TOO_SHORT
                });
            };
            let n = usize::from(*n);
            if n > capacity {
                return Err(abort::VALUE_TOO_HIGH);
            }
            let mut words = Vec::with_capacity(n);
            for (i, e) in self.entries.iter().take(n).enumerate() {
                words.push(word_of(&mappable, *e, i)?);
            }
            if words.len() < n {
                // Fewer entries written than switched on.
                return Err(abort::PARAMETER_INCOMPATIBLE);
            }
            self.count = n as u8;
            if n > 0 {
                self.words = words;
            } else {
                self.words.clear();
            }
            return Ok(());
        }
        if usize::from(sub) > capacity {
            return Err(abort::NO_SUBINDEX);
        }
        let bytes: [u8; 8] = data.try_into().map_err(|_| {
            if data.len() > 8 {
                abort::TOO_LONG
            } else {
                abort::TOO_SHORT
            }
        })?;
        let i = usize::from(sub) - 1;
        let entry = u64::from_le_bytes(bytes);
        if self.count != 0 {
            // DS 301: entries change only while sub-index 0 is 0; writing the value an entry
            // has changes nothing and is taken (a master restoring its settings).
            return if self.entries.get(i) == Some(&entry) {
                Ok(())
            } else {
                Err(abort::UNSUPPORTED_ACCESS)
            };
        }
        if self.entries.len() <= i {
            self.entries.resize(i + 1, 0);
        }
        self.entries[i] = entry;
        Ok(())
    }
}

/// The entries of a word list: 16 bits each, one after the other.
fn entries_of(words: &[MappedWord]) -> Vec<u64> {
    words
        .iter()
        .enumerate()
        .map(|(i, w)| w.mapping(16 * i as u16))
        .collect()
}

/// The word entry `e` maps as the `i`-th word, if it is one of `mappable`.
fn word_of(mappable: &[MappedWord], e: u64, i: usize) -> Result<MappedWord, SdoAbort> {
    let (index, sub) = (e as u16, (e >> 16) as u8);
    let (offset, length) = ((e >> 32) as u16, (e >> 48) as u16);
    let w = mappable
        .iter()
        .find(|w| w.index == index && w.sub == sub)
        .ok_or(abort::NOT_MAPPABLE)?;
    if length != 16 || usize::from(offset) != 16 * i {
        return Err(abort::PARAMETER_INCOMPATIBLE);
    }
    Ok(*w)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(index: u16, sub: u8, i: u16) -> [u8; 8] {
        (u64::from(index) | u64::from(sub) << 16 | u64::from(16 * i) << 32 | 16 << 48).to_le_bytes()
    }

    #[test]
    fn fixed_mapping_of_the_tu3_is_96_bytes() {
        let m = PdoMap::fixed(Product::Tu3Pol, true);
        assert_eq!(m.read(0).unwrap(), [48]);
        assert_eq!(m.words.len(), 48);
    }

    #[test]
    fn the_mn_maps_two_words() {
        let mut m = PdoMap::fixed(Product::Tu3Pol, true);
        // Entries change only while sub-index 0 is 0; the value an entry has is taken.
        assert_eq!(
            m.write(Product::Tu3Pol, true, 1, &entry(0x5002, 1, 0)),
            Err(abort::UNSUPPORTED_ACCESS)
        );
        assert_eq!(
            m.write(Product::Tu3Pol, true, 1, &entry(0x5000, 1, 0)),
            Ok(())
        );
        m.write(Product::Tu3Pol, true, 0, &[0]).unwrap();
        m.write(Product::Tu3Pol, true, 1, &entry(0x5000, 1, 0))
            .unwrap();
        m.write(Product::Tu3Pol, true, 2, &entry(0x5002, 1, 1))
            .unwrap();
        m.write(Product::Tu3Pol, true, 0, &[2]).unwrap();
        assert_eq!(m.words.len(), 2);
        assert_eq!((m.words[1].index, m.words[1].sub), (0x5002, 1));
        // An object that is no word of the layout, or a gap in the offsets, is refused.
        m.write(Product::Tu3Pol, true, 0, &[0]).unwrap();
        m.write(Product::Tu3Pol, true, 1, &entry(0x5003, 1, 0))
            .unwrap();
        assert_eq!(
            m.write(Product::Tu3Pol, true, 0, &[1]),
            Err(abort::NOT_MAPPABLE)
        );
        m.write(Product::Tu3Pol, true, 1, &entry(0x5000, 1, 1))
            .unwrap();
        assert_eq!(
            m.write(Product::Tu3Pol, true, 0, &[1]),
            Err(abort::PARAMETER_INCOMPATIBLE)
        );
    }
}
