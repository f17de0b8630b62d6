//! Monitoring of the system bus and its errors, on the inverter's side (P120, P513, P700) and
//! on the interface's (P170, P173, the SK 550P's P872).

use serde::Serialize;

use super::super::product::Product;
use super::super::types::Inverter;
use super::{has_p153_p154, serves, CanError, InverterSeries};

/// P120 [-01] "Option monitoring" for the system bus: 1 "Auto", 2 "monitoring active
/// immediately" (examples step 7). What "Auto" waits for, and P120 = 0, are not stated by the
/// manuals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum OptionMonitoring {
    /// 1.
    Auto,
    /// 2.
    Immediate,
}

impl OptionMonitoring {
    /// The P120 value.
    pub fn value(self) -> i32 {
        match self {
            OptionMonitoring::Auto => 1,
            OptionMonitoring::Immediate => 2,
        }
    }

    /// The setting of a P120 value, `None` for values the manuals do not state.
    pub fn from_value(v: i64) -> Option<Self> {
        match v {
            1 => Some(Self::Auto),
            2 => Some(Self::Immediate),
            _ => None,
        }
    }
}

/// P513 in tenths of a second: −0.1 "no error": the inverter ignores all communication errors
/// on the field bus and the system bus and keeps its operating state (BU 2200 §8.1 p. 61
/// "„-0,1“ = Kein Fehler"; BU 0590 §5.2.1 p. 38). BU 0620 §5.1 (p. 92) names it "Off" and
/// BU 2100 §8.1 (p. 57) "0,1" (see the module errata). Element [-03] is CANopen, [-04]
/// Ethernet on the SK 5x0P (BU 0620 §4.5 p. 90).
pub const P513_NO_ERROR: i32 = -1;
/// P513 0.0 "Off: Monitoring is switched off" (BU 0590 §5.2.1 p. 38); the SK 550P's factory
/// and recommended setting "Off" (BU 0620 §4.5 p. 90).
pub const P513_OFF: i32 = 0;
/// P513's element for CANopen (the system bus) on the SK 5x0P (BU 0620 §4.5 p. 90).
pub const P513_CANOPEN_ELEMENT: u8 = 3;

/// Which parameter watches the system bus between an inverter and its interface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Watch {
    /// P120 option monitoring.
    P120,
    /// P513 telegram timeout.
    P513,
    /// "Monitoring is automatic and cannot be set" (footnote 4).
    Automatic,
}

/// The "optional monitoring (system bus timeout)" row of BU 2100 §8.1 (p. 56) and BU 2200 §8.1
/// (p. 61), in BU 2200's six columns (see the module errata): SK CU4/TU4 with SK 1x0E/2xxE P120,
/// SK 511E…535E P513, SK 54xE P120; SK TU3 on its own inverter automatic, SK TU3 over CANopen
/// to SK 511E…535E P513, to SK 54xE P120. The SK 550P's further inverters: P120 (BU 0620 §3.9
/// step 7 p. 74, §5.1 p. 92); `None` for the SK 550P itself (no system bus between them).
pub fn system_bus_watch(
    product: Product,
    series: InverterSeries,
    host: bool,
) -> Result<Option<Watch>, CanError> {
    serves(product, series)?;
    let tu3 = matches!(product, Product::Tu3Eip | Product::Tu3Pol | Product::Tu3Pnt);
    Ok(match (product, series) {
        (Product::Sk550p, _) if host => None,
        _ if tu3 && host => Some(Watch::Automatic),
        (_, InverterSeries::Sk500To535e) => Some(Watch::P513),
        _ => Some(Watch::P120),
    })
}

/// The field-bus timeout parameter of the same table: P151 on SK CU4/TU4, P513 on SK TU3
/// (BU 2100 §8.1 p. 56, BU 2200 §8.1 p. 61), P513 [-04] on the SK 550P (BU 0620 §4.5 p. 90).
pub fn fieldbus_timeout_parameter(product: Product) -> u16 {
    if has_p153_p154(product) {
        151
    } else {
        513
    }
}

/// What a module's P151 "Timeout for external bus" switches, each product by its own manual.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum P151Monitoring {
    /// All monitoring off: neither an invalid control word nor a lost master or cable raises an
    /// inverter error (BU 2100 §7.1.1 "-1 = Monitoring Off"; BU 2200 §7.1.1 "0 = Überwachung
    /// Aus").
    Off,
    /// "Control word monitoring Off, bus-communication monitoring active" (BU 2100 §7.1.1, 0):
    /// a lost master is E10.2, an invalid control word (PLC to Stop) leaves the inverter running.
    BusCommunication,
    /// A telegram time-out in ms: no valid telegram for longer raises E10.3 "Timeout by
    /// P151/P513"; the bus-communication monitoring stays on.
    Timeout(u16),
}

/// P151's meaning on `product` for `value`, by the product's own manual; `None` where the
/// product has no P151 (SK TU3-*, SK TU3-PNT, SK 550P) or the manual gives the value no
/// meaning. BU 2100 §7.1.1 (p. 45, SK TU4/CU4-EIP): -1 = Monitoring Off, 0 = Control word
/// monitoring Off, bus-communication monitoring active, 1…32767 ms a time-out. BU 2200 §7.1.1
/// (p. 48, SK TU4/CU4-POL): 0…32767 ms, 0 = Überwachung Aus, no -1.
pub fn p151_monitoring(product: Product, value: i32) -> Option<P151Monitoring> {
    let eip = matches!(product, Product::Tu4Eip | Product::Cu4Eip);
    let pol = matches!(product, Product::Tu4Pol | Product::Cu4Pol);
    match value {
        -1 if eip => Some(P151Monitoring::Off),
        0 if eip => Some(P151Monitoring::BusCommunication),
        0 if pol => Some(P151Monitoring::Off),
        1..=32767 if eip || pol => Some(P151Monitoring::Timeout(value as u16)),
        _ => None,
    }
}

/// A system-bus error the inverter shows in P700 [-01] (tenths: 10.0 → 100).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct FiError {
    /// P700 [-01], tenths.
    pub p700: u16,
    /// The manual's meaning.
    pub text: &'static str,
    /// The products whose inverters show it.
    pub products: &'static [Product],
}

const ALL_BUT_PNT: &[Product] = &[
    Product::Sk550p,
    Product::Tu3Eip,
    Product::Tu4Eip,
    Product::Cu4Eip,
    Product::Tu3Pol,
    Product::Tu4Pol,
    Product::Cu4Pol,
];

/// The inverter's system-bus errors: E10.0 "Connection error: contact to bus interface lost"
/// (BU 2100 §8.3 p. 59, BU 2200 §8.4 p. 67; on the SK 550P the CAN/CANopen errors of
/// [`CanCause`], BU 0620 §5.3 p. 94); E10.8 "connection between bus interface and frequency
/// inverter interrupted due to timeout", SK TU3 only (BU 2100 §8.3, BU 2200 §8.4, BU 0590 §6.3
/// table 29 p. 44); E10.9 the same "(see setting of parameter P120)", SK CU4/TU4 only, and the
/// SK 550P's P120/P513 monitoring error "(E10.0/E10.9)" (BU 0620 §5.5.1.2 p. 100).
pub const FI_ERRORS: [FiError; 3] = [
    FiError {
        p700: 100,
        text: "Connection error: contact to bus interface lost",
        products: ALL_BUT_PNT,
    },
    FiError {
        p700: 108,
        text: "Connection error timeout (SK TU3 only)",
        products: &[Product::Tu3Eip, Product::Tu3Pol, Product::Tu3Pnt],
    },
    FiError {
        p700: 109,
        text: "Connection error timeout, see P120 (SK CU4/TU4 only)",
        products: &[
            Product::Sk550p,
            Product::Tu4Eip,
            Product::Cu4Eip,
            Product::Tu4Pol,
            Product::Cu4Pol,
        ],
    },
];

/// The P700 errors (tenths) an inverter behind `product` may show when it loses its interface.
pub fn loss_errors(product: Product) -> impl Iterator<Item = u16> {
    FI_ERRORS
        .into_iter()
        .filter(move |e| e.products.contains(&product))
        .map(|e| e.p700)
}

/// The heartbeat an inverter watches for its P120 monitoring, and how long it waits for it.
///
/// Not stated by the manuals: they say that P120 monitors the connection to the bus interface
/// and that a lost connection is E10.0/E10.8/E10.9, not with which telegram or after how long.
/// BU 0620 §5.3 (p. 94) names "CANopen HeartBeat monitoring telegram timeout" (7583h) among
/// the causes of E10.0. Choice: CiA 301 heartbeat consumption (object 1016h) of the
/// interface's heartbeat — node [`INTERFACE_NODE_ID_CHOICE`] behind a module, FI 1's node
/// (32) behind the SK 550P, whose interface is built into FI 1 — with a consumer time of
/// [`HEARTBEAT_CONSUMER_MS_CHOICE`]. P120 = 2 watches from boot-up, P120 = 1 "Auto" from the
/// first heartbeat seen, P120 = 0 not at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct InterfaceWatch {
    /// The node-ID whose heartbeat is consumed.
    pub node: u8,
    /// The consumer heartbeat time, ms.
    pub ms: u16,
}

impl InterfaceWatch {
    /// The watch as a CiA 301 1016h entry: the node-ID in bits 16–23, the time in 0–15.
    pub fn consumer_entry(self) -> u32 {
        u32::from(self.node) << 16 | u32::from(self.ms)
    }
}

/// The consumer heartbeat time an inverter gives its interface's heartbeat (not stated by the
/// manuals, see [`InterfaceWatch`]): 600 ms, the telegram time-out BU 2100 §4.3's gateway
/// conditions set in P513.
pub const HEARTBEAT_CONSUMER_MS_CHOICE: u16 = 600;

/// The heartbeat the inverters behind `product` watch (see [`InterfaceWatch`]).
pub fn interface_watch(product: Product) -> InterfaceWatch {
    let node = match product {
        Product::Sk550p => super::FIRST_INVERTER_ADDRESS.get(),
        _ => super::INTERFACE_NODE_ID_CHOICE,
    };
    InterfaceWatch {
        node,
        ms: HEARTBEAT_CONSUMER_MS_CHOICE,
    }
}

/// The error an inverter behind `product` raises when its P120 monitoring loses the
/// interface, P700 [-01] in tenths with the extended code for P700 [-04] where the manual
/// gives one: E10.0 with 7583h "CANopen HeartBeat monitoring telegram timeout" behind the
/// SK 550P (BU 0620 §5.3 p. 94, whose table ends at 10.8), E10.8 behind an SK TU3, E10.9
/// behind an SK CU4/TU4 "(see setting of parameter P120)" (BU 2100 §8.3 p. 59, BU 2200 §8.4
/// p. 67; [`FI_ERRORS`]).
pub fn interface_loss_error(product: Product) -> (u16, Option<u16>) {
    match product {
        Product::Sk550p => (
            CanCause::HeartbeatTimeout.p700(),
            Some(CanCause::HeartbeatTimeout.ds402()),
        ),
        Product::Tu3Eip | Product::Tu3Pol | Product::Tu3Pnt => (108, None),
        Product::Tu4Eip | Product::Cu4Eip | Product::Tu4Pol | Product::Cu4Pol => (109, None),
    }
}

/// The CAN causes of E10.0 with their DS402 extended code in P700 [-04] (BU 0620 §5.3 p. 94;
/// the USS and USB rows of 10.0, 7584h and 7586h, are no system-bus causes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum CanCause {
    /// 7580h "CAN /CANopen connection error".
    Connection,
    /// 7581h "CAN Broadcast telegram timeout".
    BroadcastTimeout,
    /// 7582h "CANopen NodeGuard telegram timeout".
    NodeGuardTimeout,
    /// 7583h "CANopen HeartBeat monitoring telegram timeout".
    HeartbeatTimeout,
    /// 7585h "CAN in Bus Off state".
    BusOff,
    /// 7587h "Ini CAN Hardware Problem".
    Hardware,
}

impl CanCause {
    /// Every cause, in the table's order.
    pub const ALL: [CanCause; 6] = [
        CanCause::Connection,
        CanCause::BroadcastTimeout,
        CanCause::NodeGuardTimeout,
        CanCause::HeartbeatTimeout,
        CanCause::BusOff,
        CanCause::Hardware,
    ];

    /// P700 [-01]: 10.0 for every cause.
    pub fn p700(self) -> u16 {
        100
    }

    /// P700 [-04], the DS402 extended error number.
    pub fn ds402(self) -> u16 {
        match self {
            CanCause::Connection => 0x7580,
            CanCause::BroadcastTimeout => 0x7581,
            CanCause::NodeGuardTimeout => 0x7582,
            CanCause::HeartbeatTimeout => 0x7583,
            CanCause::BusOff => 0x7585,
            CanCause::Hardware => 0x7587,
        }
    }
}

/// P170 [-01] of a module whose system bus is off: 103.0 "System bus Off", "No 24 V voltage on
/// bus, connections not correct" (BU 2100 §8.3 p. 59, BU 2200 §8.4 p. 67), in tenths. The
/// SK TU3-PNT lists only 1020 (BU 0590 §5.1.3 p. 35); the SK 550P has no P170 — its "BUS" LED
/// lights red: "System bus in state 'Bus off'" (BU 0620 §5.5.1.2 p. 100, `nord::led::BUS`).
pub fn p170_bus_off(product: Product) -> Option<u16> {
    match product {
        Product::Sk550p | Product::Tu3Pnt => None,
        _ => Some(1030),
    }
}

/// P173 [-01] bit 6: system bus "Bus WARNING"; bit 7: "Bus Off" (BU 2100 §7.1.3 p. 51 for all
/// three EtherNet/IP modules; BU 2200 §7.1.3 p. 54 "nur Busschnittstellen SK xU4-POL"). The
/// SK TU3-PNT reserves both bits (BU 0590 §5.1.3 p. 36), the SK 550P's P872 too (BU 0620 §4.3
/// p. 84; its "BUS" LED flashes green 4 Hz for "Bus warning").
pub fn p173_bus_bits(product: Product) -> Option<(u8, u8)> {
    match product {
        Product::Tu3Eip | Product::Tu4Eip | Product::Cu4Eip | Product::Tu4Pol | Product::Cu4Pol => {
            Some((6, 7))
        }
        _ => None,
    }
}

/// An inverter's link state in P173: the bit pair ("Bit High", "Bit Low") of BU 2100 §7.1.3
/// (p. 51) and BU 2200 §7.1.3 (p. 54).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum FiLink {
    /// 00 "offline".
    Offline,
    /// 01 "Unknown frequency inverter" (SK TU3-PNT: "FI not supported", BU 0590 §5.1.3).
    Unknown,
    /// 10 "online".
    Online,
    /// 11 "lost or switched off".
    Lost,
}

impl FiLink {
    /// The state of a bit pair (high bit 1, low bit 0).
    pub fn from_bits(pair: u16) -> Self {
        match pair & 0b11 {
            0b00 => FiLink::Offline,
            0b01 => FiLink::Unknown,
            0b10 => FiLink::Online,
            _ => FiLink::Lost,
        }
    }

    /// The bit pair.
    pub fn bits(self) -> u16 {
        match self {
            FiLink::Offline => 0b00,
            FiLink::Unknown => 0b01,
            FiLink::Online => 0b10,
            FiLink::Lost => 0b11,
        }
    }
}

/// Where FI n's bit pair stands in the module's P173, as (element, low bit): [-01] bits 8…15
/// for FI 1…4, [-02] bits 0…15 for FI 1…8 where the parameter has two elements (SK TU3-EIP and
/// the POWERLINK modules; the SK xU4-EIP has no array, BU 2100 §7.1.3 footnote 1); the
/// SK TU3-PNT bits 9–8 for its one FI (BU 0590 §5.1.3 p. 36). The SK 550P shows one bit per FI
/// instead, [`p872_online_bit`].
pub fn p173_fi_fields(product: Product, fi: Inverter) -> Vec<(u8, u8)> {
    let n = fi.get();
    if product == Product::Sk550p || n > product.max_inverters() {
        return Vec::new();
    }
    let mut fields = Vec::new();
    if n <= 4 {
        fields.push((1, 8 + 2 * (n - 1)));
    }
    if !matches!(product, Product::Tu4Eip | Product::Cu4Eip | Product::Tu3Pnt) {
        fields.push((2, 2 * (n - 1)));
    }
    fields
}

/// P872 "Bus status" of the SK 550P: bit 8 + (n−1) "FI n online" (BU 0620 §4.3 p. 84).
pub fn p872_online_bit(fi: Inverter) -> u8 {
    7 + fi.get()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nord::errors::{self, COMM_ERRORS};
    use crate::nord::led::{self, Pattern};

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn p151_follows_each_products_manual() {
        use P151Monitoring::*;
        // BU 2100 §7.1.1: -1 off, 0 bus communication only, ms a time-out.
        for p in [Product::Tu4Eip, Product::Cu4Eip] {
            assert_eq!(p151_monitoring(p, -1), Some(Off));
            assert_eq!(p151_monitoring(p, 0), Some(BusCommunication));
            assert_eq!(p151_monitoring(p, 200), Some(Timeout(200)));
        }
        // BU 2200 §7.1.1: 0 "Überwachung Aus", no -1.
        for p in [Product::Tu4Pol, Product::Cu4Pol] {
            assert_eq!(p151_monitoring(p, -1), None);
            assert_eq!(p151_monitoring(p, 0), Some(Off));
            assert_eq!(p151_monitoring(p, 32767), Some(Timeout(32767)));
        }
        for p in [
            Product::Tu3Eip,
            Product::Tu3Pol,
            Product::Tu3Pnt,
            Product::Sk550p,
        ] {
            assert_eq!(p151_monitoring(p, 0), None);
        }
    }

    #[test]
    fn a_lost_interface_is_the_error_each_manual_gives() {
        for product in Product::ALL {
            let (p700, extended) = interface_loss_error(product);
            assert!(loss_errors(product).any(|e| e == p700), "{product:?}");
            assert_eq!(extended.is_some(), product == Product::Sk550p);
        }
        assert_eq!(
            interface_watch(Product::Sk550p).consumer_entry(),
            0x0020_0258
        );
        assert_eq!(
            interface_watch(Product::Tu4Pol).node,
            super::super::INTERFACE_NODE_ID_CHOICE
        );
    }

    #[test]
    fn monitoring_table_in_six_columns() {
        use InverterSeries::*;
        // BU 2200 §8.1 p. 61: P120 P513 P120 — P513 P120.
        let row = [
            system_bus_watch(Product::Tu4Pol, Sk2xxe, true),
            system_bus_watch(Product::Tu4Pol, Sk500To535e, false),
            system_bus_watch(Product::Tu4Pol, Sk54xe, false),
            system_bus_watch(Product::Tu3Pol, Sk500To535e, true),
            system_bus_watch(Product::Tu3Pol, Sk500To535e, false),
            system_bus_watch(Product::Tu3Pol, Sk54xe, false),
        ];
        let w = |x| Ok(Some(x));
        assert_eq!(
            row,
            [
                w(Watch::P120),
                w(Watch::P513),
                w(Watch::P120),
                w(Watch::Automatic),
                w(Watch::P513),
                w(Watch::P120)
            ]
        );
        assert_eq!(
            system_bus_watch(Product::Sk550p, Sk5x0p, false),
            w(Watch::P120)
        );
        assert_eq!(system_bus_watch(Product::Sk550p, Sk5x0p, true), Ok(None));
        // "Field bus timeout P151 P151 P151 P513 P513 P513".
        assert_eq!(fieldbus_timeout_parameter(Product::Cu4Eip), 151);
        assert_eq!(fieldbus_timeout_parameter(Product::Tu3Eip), 513);
        assert_eq!((P513_NO_ERROR, P513_OFF), (-1, 0));
    }

    #[test]
    fn errors_on_both_sides() {
        // E10.8 SK TU3 only, E10.9 SK CU4/TU4 only (BU 2100 §8.3, BU 2200 §8.4, BU 0590 table 29).
        assert_eq!(loss_errors(Product::Tu3Eip).collect::<Vec<_>>(), [100, 108]);
        assert_eq!(loss_errors(Product::Cu4Pol).collect::<Vec<_>>(), [100, 109]);
        assert_eq!(loss_errors(Product::Tu3Pnt).collect::<Vec<_>>(), [108]);
        assert_eq!(loss_errors(Product::Sk550p).collect::<Vec<_>>(), [100, 109]);
        // The CAN causes of 10.0 are rows of BU 0620 §5.3 (errors::COMM_ERRORS).
        for c in CanCause::ALL {
            assert!(COMM_ERRORS
                .iter()
                .any(|e| e.p700 == c.p700() && e.ds402 == c.ds402()));
        }
        // POWERLINK reports 10.0 as 8100h, 10.8 as 5000h, 10.9 as 8111h (BU 0620 §5.4.1.2).
        let pl = |p| errors::powerlink_error(p).map(|e| e.code);
        assert_eq!(
            (pl(100), pl(108), pl(109)),
            (Some(0x8100), Some(0x5000), Some(0x8111))
        );
        // P170 103.0 "System bus Off" (BU 2100 §8.3, BU 2200 §8.4), P173 bits 6/7.
        assert_eq!(p170_bus_off(Product::Tu4Pol), Some(1030));
        assert_eq!(errors::module_error(1030), Some("System bus off"));
        assert_eq!(p170_bus_off(Product::Tu3Pnt), None);
        assert_eq!(p173_bus_bits(Product::Tu3Eip), Some((6, 7)));
        assert_eq!(p173_bus_bits(Product::Tu3Pol), None);
        assert_eq!(p173_bus_bits(Product::Sk550p), None);
        // The SK 550P shows both on its "BUS" LED instead (BU 0620 §5.5.1.2 p. 100).
        let bus = |m: &str| led::BUS.iter().find(|r| r.meaning == m).map(|r| r.pattern);
        assert_eq!(bus("System bus in state \"Bus off\""), Some(Pattern::Red));
        assert_eq!(
            bus("Bus warning"),
            Some(Pattern::FlashingGreen { tenths_hz: 40 })
        );
    }

    #[test]
    fn inverter_link_bits() {
        assert_eq!(FiLink::from_bits(0b10), FiLink::Online);
        assert!([
            FiLink::Offline,
            FiLink::Unknown,
            FiLink::Online,
            FiLink::Lost
        ]
        .iter()
        .all(|l| FiLink::from_bits(l.bits()) == *l));
        assert_eq!(p173_fi_fields(Product::Tu3Eip, fi(1)), [(1, 8), (2, 0)]);
        assert_eq!(p173_fi_fields(Product::Tu3Eip, fi(8)), [(2, 14)]);
        assert_eq!(p173_fi_fields(Product::Tu4Eip, fi(4)), [(1, 14)]);
        assert_eq!(p173_fi_fields(Product::Tu3Pnt, fi(1)), [(1, 8)]);
        assert!(p173_fi_fields(Product::Tu4Pol, fi(5)).is_empty());
        assert_eq!(p872_online_bit(fi(1)), 8);
        assert_eq!(p872_online_bit(fi(8)), 15);
    }
}
