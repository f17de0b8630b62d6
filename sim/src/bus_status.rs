//! The bus interface's status parameters, derived from what the interface sees.
//!
//! Each product shows its bus status in its own parameters and bit layout:
//! - SK 550P: P872 "Bus status" (BU 0620 §4.3, p. 84): bit 0 module ready, 1 cyclic PZD
//!   communication, 2 field bus timeout, 3 timeout P513, bits 8–15 FI 1..8 online.
//! - SK TU3/TU4/CU4-EIP: P173 [-01] "Module status" (BU 2100 §7.1.3, p. 51): bits 0–3 as the
//!   SK 550P's (ready, cyclic communication, field bus timeout, timeout P151/P513), bits 8–15
//!   FI 1..4 in bit pairs; [-02] (SK TU3-EIP only) FI 1..8 in bit pairs, as the POWERLINK
//!   modules'.
//! - SK TU3-PNT: P173 "Module status" (BU 0590 §5.1.3, p. 36): bit 1 AR installed, bit 3
//!   timeout (P151/P513), bits 9–8 FI status (10b = online); P170 [-01] "Present error" 1020
//!   "Bus Time Out via P151 or P513" (p. 35).
//! - SK TU3/TU4/CU4-POL: P173 "Baugruppen Zustand" (BU 2200 §7.1.3, p. 54): [-01] bit 0 ready,
//!   1 cyclic communication, 2 timeout Ethernet bus, 3 timeout P151/P513, 5 general
//!   configuration error (the gateway P164 refused, "5605 Konfig. setzen"), bits 8–15 FI 1..4 in
//!   bit pairs; [-02] FI 1..8 in bit pairs; a pair reads 00 offline, 01 unknown, 10 online,
//!   11 lost.
//!
//! An inverter lost from the system bus (`inject: { error: lost }`) reads 11 "lost or switched
//! off" in the modules' pairs (BU 2100 §7.1.3, BU 2200 §7.1.3), its bit 0 "not online" in the
//! SK 550P's P872, and 00 "offline" on the SK TU3-PNT, whose table has no 11 (BU 0590 §5.1.3:
//! 00 offline, 01 not supported, 10 online). No simulated inverter is of an unknown type, so no
//! pair reads 01.
//!
//! The embedded link stands in for the field bus: its cyclic process data count as cyclic
//! communication (and, for PROFINET, as an established application relation), and the
//! TU3-PNT's bit 5 "Ethernet connection" is set, as every other bit of its list reads 1 = the
//! condition named (the simulated module is always on its network). The system-bus bits 6 "Bus
//! WARNING" and 7 "Bus Off" follow an injected CAN controller state (`inject: { error:
//! bus-warning | bus-off }`). Bits the simulator has no cause for (TU3-PNT bit 0
//! "Initialisation"; ASIC errors) stay 0.

use proto::nord::Product;

/// What the interface knows of its bus and its inverters at one moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct BusFlags {
    /// Valid process data arrived within the last window.
    pub(crate) cyclic: bool,
    /// The field-bus watchdog (the master's connection) has expired.
    pub(crate) fieldbus_timeout: bool,
    /// The POWERLINK module's configuration is refused (P173 [-01] bit 5).
    pub(crate) config_error: bool,
    /// An inverter's telegram monitoring (P513 / P151) has tripped (E10.3).
    pub(crate) telegram_timeout: bool,
    /// Inverters on the system bus: FI 1..=online are online, unless lost.
    pub(crate) online: u8,
    /// Inverters lost from the system bus (bit n: FI n + 1).
    pub(crate) lost: u8,
    /// The interface's CAN controller on the system bus is in "Bus Warning" (error counters
    /// past the warning limit).
    pub(crate) bus_warning: bool,
    /// ... or "Bus Off": it no longer takes part in the system bus.
    pub(crate) bus_off: bool,
}

/// P173 [-01] bits 6 "Bus WARNING" and 7 "Bus Off" of the products that show them
/// (`proto::nord::can::p173_bus_bits`).
fn bus_bits(product: Product, f: BusFlags) -> i32 {
    match proto::nord::can::p173_bus_bits(product) {
        Some((warning, off)) => i32::from(f.bus_warning) << warning | i32::from(f.bus_off) << off,
        None => 0,
    }
}

/// The FI status bit pairs of the first `slots` inverters, from bit `first`: 11b "lost or
/// switched off" for each FI in `lost`, 10b "online" for the others of FI 1..=`online`, 00b
/// "offline" for the rest (BU 2100 §7.1.3, BU 2200 §7.1.3).
fn fi_pairs(online: u8, lost: u8, slots: u8, first: u32) -> i32 {
    (0..u32::from(slots)).fold(0, |w, n| {
        let pair = if lost & 1 << n != 0 {
            0b11
        } else if n < u32::from(online) {
            0b10
        } else {
            0b00
        };
        w | pair << (first + 2 * n)
    })
}

/// The status parameters of `product` as (parameter, element, value).
pub(crate) fn status_parameters(
    product: Product,
    f: BusFlags,
) -> impl Iterator<Item = (u16, u8, i32)> {
    let low = 1
        | i32::from(f.cyclic) << 1
        | i32::from(f.fieldbus_timeout) << 2
        | i32::from(f.telegram_timeout) << 3
        | bus_bits(product, f);
    // At most two words: no allocation, this runs for every process-data exchange.
    let words = match product {
        Product::Sk550p => {
            let online = (0..f.online.min(8))
                .filter(|n| f.lost & 1 << n == 0)
                .fold(0, |w, n| w | 1 << (8 + n));
            [Some((872, 1, low | online)), None]
        }
        Product::Tu3Pnt => [
            Some((
                173,
                1,
                i32::from(f.cyclic) << 1
                    | i32::from(f.telegram_timeout) << 3
                    | 1 << 5
                    | fi_pairs(f.online, 0, 1, 8),
            )),
            Some((170, 1, if f.telegram_timeout { 1020 } else { 0 })),
        ],
        Product::Tu3Pol | Product::Tu4Pol | Product::Cu4Pol => [
            Some((
                173,
                1,
                low | i32::from(f.config_error) << 5 | fi_pairs(f.online, f.lost, 4, 8),
            )),
            Some((173, 2, fi_pairs(f.online, f.lost, 8, 0))),
        ],
        // The SK xU4-EIP's P173 has no array: element 2 is ignored by their store.
        Product::Tu3Eip | Product::Tu4Eip | Product::Cu4Eip => [
            Some((173, 1, low | fi_pairs(f.online, f.lost, 4, 8))),
            Some((173, 2, fi_pairs(f.online, f.lost, 8, 0))),
        ],
    };
    words.into_iter().flatten()
}

/// P170 [-01] "Aktueller Fehler" of a module while its telegram monitoring has tripped: 102.0
/// "Bus Time-Out P151" ("Durch Timeout-Überwachung Parameter P151/P513"), shown in tenths as
/// 1020 (BU 2200 §8.4, p. 67; BU 2100 §8.4 "102.0 Bus timeout P151").
pub(crate) const BUS_TIMEOUT_ERROR: i32 = 1020;

/// P170 of the EtherNet/IP and POWERLINK modules when the timeout monitoring (P151/P513)
/// changes from `was` to `now`, given the present error `present` ([-01]): the fault shows in
/// [-01] while it is active; once it is no longer active [-01] clears itself and the fault is
/// archived in [-02] as the last fault (BU 2200 §8.2 "Fehlermeldung archivieren", BU 2100
/// §8.2). Another present error (the POWERLINK modules' 5605 "Konfig. setzen") is left as it is.
/// The SK TU3-PNT shows its P170 through [`status_parameters`] (BU 0590 §5.1.3).
pub(crate) fn present_error(
    product: Product,
    was: bool,
    now: bool,
    present: i32,
) -> impl Iterator<Item = (u16, u8, i32)> {
    let module = matches!(
        product,
        Product::Tu3Eip
            | Product::Tu4Eip
            | Product::Cu4Eip
            | Product::Tu3Pol
            | Product::Tu4Pol
            | Product::Cu4Pol
    );
    let writes = match (module, was, now) {
        (true, false, true) if present == 0 => [Some((170, 1, BUS_TIMEOUT_ERROR)), None],
        (true, true, false) if present == BUS_TIMEOUT_ERROR => {
            [Some((170, 1, 0)), Some((170, 2, BUS_TIMEOUT_ERROR))]
        }
        _ => [None, None],
    };
    writes.into_iter().flatten()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    fn flags(cyclic: bool, timeout: bool, online: u8) -> BusFlags {
        BusFlags {
            cyclic,
            fieldbus_timeout: false,
            config_error: false,
            telegram_timeout: timeout,
            online,
            ..BusFlags::default()
        }
    }

    #[rstest]
    // BU 0620 §4.3: ready + cyclic + FI 1..3 online = 0703h.
    #[case(Product::Sk550p, flags(true, false, 3), vec![(872, 1, 0x0703)])]
    #[case(Product::Sk550p, flags(false, true, 8), vec![(872, 1, 0xFF09)])]
    // BU 2100 §7.1.3: ready, cyclic, timeout P151; FI 1..4 online (10b each).
    #[case(Product::Tu4Eip, flags(true, true, 4), vec![(173, 1, 0xAA0B), (173, 2, 0x00AA)])]
    #[case(Product::Tu3Eip, flags(false, false, 6), vec![(173, 1, 0xAA01), (173, 2, 0x0AAA)])]
    // BU 0590 §5.1.3: AR installed, FI online = bits 9–8 10b; P170 1020 on a timeout.
    #[case(Product::Tu3Pnt, flags(true, false, 1), vec![(173, 1, 0x0222), (170, 1, 0)])]
    #[case(Product::Tu3Pnt, flags(false, true, 1), vec![(173, 1, 0x0228), (170, 1, 1020)])]
    // BU 2200 §7.1.3: [-01] FI 1..4 in bits 8–15, [-02] FI 1..8 in bits 0–15, 10b each.
    #[case(Product::Tu4Pol, flags(true, false, 4), vec![(173, 1, 0xAA03), (173, 2, 0x00AA)])]
    #[case(Product::Tu3Pol, flags(false, false, 1), vec![(173, 1, 0x0201), (173, 2, 0x0002)])]
    #[case(Product::Cu4Pol, flags(false, false, 8), vec![(173, 1, 0xAA01), (173, 2, 0xAAAA)])]
    fn status_words(
        #[case] product: Product,
        #[case] f: BusFlags,
        #[case] want: Vec<(u16, u8, i32)>,
    ) {
        assert_eq!(status_parameters(product, f).collect::<Vec<_>>(), want);
    }

    #[rstest]
    // BU 2200 §7.1.3 / BU 2100 §7.1.3: FI 2 lost reads 11b, FI 1, 3, 4 online 10b.
    #[case(Product::Tu4Pol, 4, vec![(173, 1, 0xAE01), (173, 2, 0x00AE)])]
    #[case(Product::Tu3Eip, 4, vec![(173, 1, 0xAE01), (173, 2, 0x00AE)])]
    // FI 2 of 2 lost; FI 3…8 offline (00b).
    #[case(Product::Cu4Eip, 2, vec![(173, 1, 0x0E01), (173, 2, 0x000E)])]
    // BU 0620 §4.3: P872 bit 9 "FI 2 online" cleared.
    #[case(Product::Sk550p, 3, vec![(872, 1, 0x0501)])]
    // BU 0590 §5.1.3 has no 11b: the TU3-PNT's one FI is shown by `online` alone.
    #[case(Product::Tu3Pnt, 1, vec![(173, 1, 0x0220), (170, 1, 0)])]
    fn a_lost_inverter(
        #[case] product: Product,
        #[case] online: u8,
        #[case] want: Vec<(u16, u8, i32)>,
    ) {
        let f = BusFlags {
            online,
            lost: 0b10,
            ..BusFlags::default()
        };
        assert_eq!(status_parameters(product, f).collect::<Vec<_>>(), want);
    }

    #[test]
    fn configuration_error_is_bit_5_of_the_powerlink_modules() {
        let f = BusFlags {
            config_error: true,
            online: 1,
            ..BusFlags::default()
        };
        assert_eq!(
            status_parameters(Product::Tu4Pol, f).next().unwrap(),
            (173, 1, 0x0221),
            "ready, general configuration error, FI 1 online"
        );
    }

    #[test]
    fn field_bus_timeout_is_bit_2() {
        let f = BusFlags {
            fieldbus_timeout: true,
            online: 1,
            ..BusFlags::default()
        };
        assert_eq!(
            status_parameters(Product::Tu3Pol, f).next().unwrap(),
            (173, 1, 0x0205),
            "ready, Ethernet bus timeout, FI 1 online"
        );
    }

    #[rstest]
    // BU 2200 §8.4: 102.0 shows as 1020 while the timeout is active …
    #[case(Product::Tu4Pol, false, true, 0, vec![(170, 1, 1020)])]
    #[case(Product::Tu3Eip, false, true, 0, vec![(170, 1, 1020)])]
    // … §8.2: then [-01] clears itself and [-02] archives it.
    #[case(Product::Cu4Pol, true, false, 1020, vec![(170, 1, 0), (170, 2, 1020)])]
    // Another present error (5605 Konfig. setzen) stays; nothing while unchanged.
    #[case(Product::Tu3Pol, false, true, 5605, vec![])]
    #[case(Product::Tu3Pol, true, false, 5605, vec![])]
    #[case(Product::Tu4Eip, true, true, 1020, vec![])]
    // The SK 550P has no P170; the SK TU3-PNT's comes with its status word.
    #[case(Product::Sk550p, false, true, 0, vec![])]
    #[case(Product::Tu3Pnt, false, true, 0, vec![])]
    fn p170_follows_the_timeout(
        #[case] product: Product,
        #[case] was: bool,
        #[case] now: bool,
        #[case] present: i32,
        #[case] want: Vec<(u16, u8, i32)>,
    ) {
        assert_eq!(
            present_error(product, was, now, present).collect::<Vec<_>>(),
            want
        );
    }
}
