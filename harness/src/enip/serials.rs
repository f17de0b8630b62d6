//! The connection serial numbers the scanner gives its Forward_Opens, and the T→O connection
//! ids made from them.
//!
//! A connection serial number, with the originator's vendor id and serial number, is the
//! triad that names a connection to its target ([`proto::enip::cm::ConnectionKey`], CIP Vol 1
//! ch. 3, Connection Manager); a target refuses a Forward_Open that repeats the triad of a
//! connection it still holds (01h, extended 0100h
//! [`CONNECTION_IN_USE`](proto::enip::cm::ext::CONNECTION_IN_USE)). Where the numbers start
//! decides whether a case's transcript is a function of the case alone:
//!
//! - the embedded adapter is made afresh for every case, with no connection of an earlier case
//!   to clash with: each scanner numbers from 1, so a case sends the same bytes whatever ran
//!   before it (a sharded run merges into the unsharded one; snapshots hold under any
//!   `--filter` or `--shard`);
//! - a device on the network outlives every case, and a connection an earlier case left open
//!   (a cleanup that failed) must not be named again: the scanners of a process number on from
//!   each other. What such a device's transcripts hold of them is for comparisons to normalise,
//!   as its own session handles and connection ids are.

use std::sync::atomic::{AtomicU16, Ordering};

/// The numbers given so far by the scanners of this process that reach a device on the network.
static SHARED: AtomicU16 = AtomicU16::new(1);

/// Where a scanner's connection serial numbers come from.
#[derive(Debug)]
pub(super) enum Serials {
    /// Numbered from 1 for this scanner alone: the next one given.
    Own(u16),
    /// Numbered on across the process, for a device that outlives the case.
    Shared,
}

impl Serials {
    /// A scanner of the embedded adapter, made afresh for every case.
    pub(super) fn per_case() -> Serials {
        Serials::Own(1)
    }

    /// The next connection serial number, never 0.
    pub(super) fn next(&mut self) -> u16 {
        match self {
            Serials::Own(n) => {
                let serial = (*n).max(1);
                *n = serial.wrapping_add(1);
                serial
            }
            Serials::Shared => SHARED.fetch_add(1, Ordering::Relaxed).max(1),
        }
    }
}

/// The T→O connection id the scanner proposes for the connection of `serial`: point to point,
/// the originator chooses it ([`proto::enip::cm::ForwardOpen::t_o_id`]): "SC" and the serial
/// number.
pub(super) fn t_o_id(serial: u16) -> u32 {
    0x5343_0000 | u32::from(serial)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_embedded_scanner_numbers_from_one() {
        // Two cases, each with a scanner of its own: the same numbers, whatever the first did.
        let mut first = Serials::per_case();
        assert_eq!((first.next(), first.next(), first.next()), (1, 2, 3));
        let mut second = Serials::per_case();
        assert_eq!((second.next(), second.next()), (1, 2));
        // A process's shared numbers moved meanwhile change nothing of a case's own.
        Serials::Shared.next();
        assert_eq!(Serials::per_case().next(), 1);
    }

    #[test]
    fn an_own_serial_wraps_past_zero() {
        let mut s = Serials::Own(u16::MAX);
        assert_eq!((s.next(), s.next()), (u16::MAX, 1));
    }

    #[test]
    fn scanners_of_a_network_device_never_repeat_a_number_among_themselves() {
        // Scanners of successive cases against one device: no triad named twice.
        let (mut a, mut b) = (Serials::Shared, Serials::Shared);
        let given = [a.next(), b.next(), a.next(), b.next()];
        let mut distinct = given.to_vec();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), given.len(), "{given:?}");
        assert!(given.iter().all(|&n| n != 0));
    }

    #[test]
    fn the_t_o_id_carries_the_serial() {
        assert_eq!(t_o_id(1), 0x5343_0001);
        assert_eq!(t_o_id(0xBEEF), 0x5343_BEEF);
    }
}
