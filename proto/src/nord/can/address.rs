//! Bit rate, node addresses and the participants of one system bus.

use serde::Serialize;

use super::super::mutant::Constant;
use super::super::product::Product;
use super::super::types::{Inverter, RangeError};
use super::{check_inverter, CanError};

/// The system bus bit rate, bit/s: "250 kBaud" on every inverter and absolute encoder (BU 0620
/// §2.1.2 p. 15, §3.1 p. 62; BU 2100 §4.1 p. 19; BU 2200 §4.1 p. 20). An SK TU3 gateway allows
/// any rate that is the same on all inverters when no I/O extension is on the bus (BU 2100 §4.3
/// p. 22; BU 2200 §7.2 p. 59 marks P514 "*" for the SK TU3).
pub const BAUD_RATE: u32 = 250_000;

/// P514 "CAN baud rate" value for 250 kBaud: 5 (BU 0620 §4.5 p. 90, BU 2100 §7.2 p. 54,
/// BU 2200 §7.2 p. 59). The other values are not stated by the manuals.
pub const P514_250_KBAUD: i32 = 5;

/// The bit rate of a P514 value, `None` for the values the manuals do not state.
pub fn baud_rate(p514: i32) -> Option<u32> {
    (p514 == P514_250_KBAUD).then_some(BAUD_RATE)
}

/// P515 [-01] "Slave Address" of FI 1: 32 (BU 0620 §3.1 p. 61 `P515[1] = 32`, §4.5 p. 90).
pub static FIRST_INVERTER_ADDRESS: Constant<u8> = Constant::new(
    "can-first-inverter",
    32,
    "P515 [-01] of FI 1",
    "BU 0620 §3.1 system bus addresses",
);
/// From one inverter's address to the next: 2 (BU 0620 §4.5 "34, 36, 38 … 46"; BU 2100 §4.3
/// table FI 1…8 = 32…46).
pub static ADDRESS_STEP: Constant<u8> = Constant::new(
    "can-address-step",
    2,
    "system bus address step per inverter",
    "BU 0620 §4.5 P515",
);
/// "Absolute encoder address = CAN ID of the frequency inverter + 1" (BU 0620 §2.1.2 p. 15,
/// §3.1 p. 61; BU 2100 §4.1 p. 19; BU 2200 §4.1 p. 20).
pub static ENCODER_OFFSET: Constant<u8> = Constant::new(
    "can-encoder-offset",
    1,
    "absolute encoder address offset",
    "BU 0620 §2.1.2 absolute encoder address",
);

/// The bus interface's own node-ID. BU 2100 §4.1 (p. 19) and BU 2200 §4.1 (p. 20): "The
/// address of the bus interface is pre-set at the factory and cannot be changed" (also step 3
/// of both examples); the value is not stated by the manuals. This project's choice: 1, the
/// lowest CiA 301 node-ID, clear of the 32…47 the manuals give inverters and encoders. The
/// SK 550P has no separate interface node: it is FI 1 (BU 0620 §2.1.2).
pub const INTERFACE_NODE_ID_CHOICE: u8 = 1;

/// A node address on the system bus ("CAN ID"), 1…127. The manuals give P515's values (32…46)
/// but not its range; 1…127 is the CiA 301 node-ID range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct SystemBusAddress(u8);

/// What sits at a system-bus address, by the manuals' address rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Participant {
    /// Frequency inverter FI n (P515).
    Inverter(Inverter),
    /// The absolute encoder assigned to FI n (DIP switches, CAN ID of FI n + 1).
    Encoder(Inverter),
}

impl SystemBusAddress {
    /// Checks the CiA 301 node-ID range.
    pub fn new(value: i64) -> Result<Self, RangeError> {
        match u8::try_from(value) {
            Ok(v @ 1..=127) => Ok(Self(v)),
            _ => Err(RangeError {
                what: "system bus address",
                value,
                min: 1,
                max: 127,
            }),
        }
    }

    /// The address of FI n: 32 + 2·(n−1) (see the module's errata for BU 0620 §3.1).
    pub fn inverter(fi: Inverter) -> Self {
        Self(FIRST_INVERTER_ADDRESS.get() + ADDRESS_STEP.get() * (fi.get() - 1))
    }

    /// The address of FI n's absolute encoder: the inverter's + 1.
    pub fn encoder(fi: Inverter) -> Self {
        Self(Self::inverter(fi).0 + ENCODER_OFFSET.get())
    }

    /// The address FI n has behind `product`, refused beyond the inverters the product serves.
    pub fn for_inverter(product: Product, fi: Inverter) -> Result<Self, CanError> {
        check_inverter(product, fi)?;
        Ok(Self::inverter(fi))
    }

    /// Checks a P515 [-01] value read from FI n against the address the manuals assign it.
    pub fn from_p515(product: Product, fi: Inverter, p515: i64) -> Result<Self, CanError> {
        let expected = Self::for_inverter(product, fi)?;
        let got = Self::new(p515)?;
        if got != expected {
            return Err(CanError::WrongAddress {
                inverter: fi.get(),
                expected: expected.0,
                got: p515,
            });
        }
        Ok(got)
    }

    /// The node-ID.
    pub fn get(self) -> u8 {
        self.0
    }

    /// The inverter or encoder at this address behind `product`, `None` for any other.
    pub fn participant(self, product: Product) -> Option<Participant> {
        let offset = self.0.checked_sub(FIRST_INVERTER_ADDRESS.get())?;
        let fi = Inverter::new(i64::from(offset / ADDRESS_STEP.get() + 1)).ok()?;
        if fi.get() > product.max_inverters() {
            return None;
        }
        Some(if offset % ADDRESS_STEP.get() == 0 {
            Participant::Inverter(fi)
        } else {
            Participant::Encoder(fi)
        })
    }
}

/// The P515 [-01] values of the inverters behind `product`, as the parameter tables give them:
/// SK CU4/TU4 "32, 34, 36 or 38", SK TU3 "32, 34, …46" when more than one inverter is connected,
/// SK 550P 32 and "34, 36, 38 … 46" (BU 2100 §7.2 p. 54 with its §4.3 table, BU 2200 §7.2
/// p. 59, BU 0620 §4.5 p. 90). BU 0590 names no P515: the SK TU3-PNT's one inverter is given
/// FI 1's. The SK TU3-POL's list reaches FI 8, as do its process data (BU 2200 §6.3.5) and
/// [`Product::max_inverters`]; only its SDO device ids (§6.4) stop at FU 4.
pub fn p515_addresses(product: Product) -> Vec<SystemBusAddress> {
    let count = match product {
        Product::Sk550p | Product::Tu3Eip | Product::Tu3Pol => 8,
        Product::Tu3Pnt => 1,
        Product::Tu4Eip | Product::Cu4Eip | Product::Tu4Pol | Product::Cu4Pol => 4,
    };
    (1..=count)
        .filter_map(|n| Inverter::new(i64::from(n)).ok())
        .map(SystemBusAddress::inverter)
        .collect()
}

/// An inverter series the manuals distinguish on the system bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum InverterSeries {
    /// SK 1x0E (decentralised).
    Sk1x0e,
    /// SK 2xxE (decentralised).
    Sk2xxe,
    /// SK 500E…SK 535E (central); the system bus only from SK 511E, over its RJ45 sockets with
    /// 24 V DC (BU 2100 §4.1 p. 19, BU 2200 §4.1 p. 20).
    Sk500To535e,
    /// SK 54xE (central).
    Sk54xe,
    /// SK 5x0P, the inverters behind an SK 550P (BU 0620 §2.1).
    Sk5x0p,
}

/// How many nodes of each kind one system bus takes. `None`: not stated by the manuals;
/// `Some(0)`: printed "—".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Participants {
    /// Frequency inverters.
    pub inverters: u8,
    /// Input/output extensions (SK xU4-IOE). They "must be assigned to the frequency
    /// inverters" as their data sheets say (BU 2100 §4.1, BU 2200 §4.1); their addresses are not
    /// stated by the manuals.
    pub io_extensions: Option<u8>,
    /// CANopen (absolute) encoders.
    pub encoders: u8,
    /// Bus interfaces.
    pub bus_interfaces: Option<u8>,
    /// NORD CON computers.
    pub nordcon: Option<u8>,
}

/// The participant table of BU 2100 §4.1 (p. 19) and BU 2200 §4.1 (p. 20), and BU 0620 §2.1.2
/// (p. 15) for the SK 5x0P: "Up to 8 frequency inverters with the associated absolute
/// encoders" (the SK 550P is FI 1 and the interface; I/O extensions are not mentioned).
pub fn participants(series: InverterSeries) -> Participants {
    let row = |inverters, io, encoders| Participants {
        inverters,
        io_extensions: Some(io),
        encoders,
        bus_interfaces: Some(1),
        nordcon: Some(1),
    };
    match series {
        InverterSeries::Sk1x0e | InverterSeries::Sk2xxe => row(4, 8, 4),
        InverterSeries::Sk500To535e => row(8, 0, 8),
        InverterSeries::Sk54xe => row(8, 16, 8),
        InverterSeries::Sk5x0p => Participants {
            inverters: 8,
            io_extensions: None,
            encoders: 8,
            bus_interfaces: None,
            nordcon: None,
        },
    }
}

/// The inverter series a product is used with: SK CU4/TU4 on SK 1x0E/SK 2xxE, and over the
/// system bus SK 511E…535E and SK 54xE (BU 2100 §7.2 p. 54, §8.1 p. 56); SK TU3 on SK 500E…535E
/// and SK 54xE (same tables; BU 0590: SK 5xxE); the SK 550P with SK 5x0P (BU 0620 §2.1).
pub fn inverter_series(product: Product) -> &'static [InverterSeries] {
    use InverterSeries::*;
    match product {
        Product::Sk550p => &[Sk5x0p],
        Product::Tu4Eip | Product::Cu4Eip | Product::Tu4Pol | Product::Cu4Pol => {
            &[Sk1x0e, Sk2xxe, Sk500To535e, Sk54xe]
        }
        Product::Tu3Eip | Product::Tu3Pol | Product::Tu3Pnt => &[Sk500To535e, Sk54xe],
    }
}

/// Participants when a ParameterBox is the gateway's peer over the system bus: at most 6 (5
/// devices plus the box); a NORD CON computer: at most 32 (31 devices plus NORD CON). Both
/// speak USS through the CANopen interface as a gateway (BU 2100 §4.2.2 p. 20, §4.2.3 p. 21;
/// BU 2200 §4.2.2, §4.2.3).
pub const PARAMETERBOX_MAX_PARTICIPANTS: u8 = 6;
/// See [`PARAMETERBOX_MAX_PARTICIPANTS`].
pub const NORDCON_MAX_PARTICIPANTS: u8 = 32;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nord::addr;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn addresses_of_the_manuals() {
        // BU 0620 §3.1 p. 61 / §3.9 step 3, BU 2100 §5.3 step 3: FI 1…3 32, 34, 36; AG 33, 35, 37.
        let got: Vec<_> = (1..=3)
            .map(|n| {
                (
                    SystemBusAddress::inverter(fi(n)).get(),
                    SystemBusAddress::encoder(fi(n)).get(),
                )
            })
            .collect();
        assert_eq!(got, [(32, 33), (34, 35), (36, 37)]);
        // BU 2100 §4.3 p. 22: FI 1…8 = 32…46; 37 (printed in BU 0620 §3.1) is no inverter's.
        let sk: Vec<u8> = p515_addresses(Product::Sk550p)
            .iter()
            .map(|a| a.get())
            .collect();
        assert_eq!(sk, [32, 34, 36, 38, 40, 42, 44, 46]);
        assert_eq!(
            SystemBusAddress::new(37)
                .unwrap()
                .participant(Product::Sk550p),
            Some(Participant::Encoder(fi(3)))
        );
        // BU 2100 §7.2, BU 2200 §7.2: SK CU4/TU4 "32, 34, 36 or 38"; SK TU3 32 … 46.
        let xu4: Vec<u8> = p515_addresses(Product::Tu4Pol)
            .iter()
            .map(|a| a.get())
            .collect();
        assert_eq!(xu4, [32, 34, 36, 38]);
        assert_eq!(p515_addresses(Product::Tu3Eip).len(), 8);
        assert_eq!(p515_addresses(Product::Tu3Pol).len(), 8);
        assert_eq!(p515_addresses(Product::Tu3Pnt).len(), 1);
        // BU 2200 §4.1 p. 20: the SK TU3-POL's system bus carries 8 inverters, FU 8 at 46.
        assert_eq!(
            SystemBusAddress::for_inverter(Product::Tu3Pol, fi(8)).map(|a| a.get()),
            Ok(46)
        );
        for n in 1..=8 {
            let ids = addr::can(fi(n));
            assert_eq!(SystemBusAddress::inverter(fi(n)).get(), ids.inverter);
            assert_eq!(SystemBusAddress::encoder(fi(n)).get(), ids.encoder);
        }
    }

    #[test]
    fn p515_checked_against_the_inverter() {
        assert_eq!(
            SystemBusAddress::from_p515(Product::Sk550p, fi(1), 32).map(|a| a.get()),
            Ok(32)
        );
        assert_eq!(
            SystemBusAddress::from_p515(Product::Sk550p, fi(3), 37),
            Err(CanError::WrongAddress {
                inverter: 3,
                expected: 36,
                got: 37
            })
        );
        assert!(matches!(
            SystemBusAddress::from_p515(Product::Cu4Eip, fi(5), 40),
            Err(CanError::NoSuchInverter { max: 4, .. })
        ));
        assert!(matches!(
            SystemBusAddress::from_p515(Product::Sk550p, fi(1), 128),
            Err(CanError::Range(_))
        ));
        assert!(SystemBusAddress::new(0).is_err());
        assert_eq!(
            SystemBusAddress::new(31)
                .unwrap()
                .participant(Product::Sk550p),
            None
        );
        assert_eq!(
            SystemBusAddress::new(40)
                .unwrap()
                .participant(Product::Tu4Eip),
            None
        );
        assert_eq!(
            SystemBusAddress::new(INTERFACE_NODE_ID_CHOICE.into())
                .unwrap()
                .participant(Product::Tu4Eip),
            None
        );
    }

    #[test]
    fn baud_rate_is_250_kbaud() {
        assert_eq!(baud_rate(5), Some(250_000));
        assert_eq!(baud_rate(4), None);
    }

    #[test]
    fn participant_table() {
        // BU 2100 §4.1 p. 19 / BU 2200 §4.1 p. 20: FI 4 4 8 8, IOE 8 8 — 16, encoders 4 4 8 8.
        let rows: Vec<_> = [
            InverterSeries::Sk1x0e,
            InverterSeries::Sk2xxe,
            InverterSeries::Sk500To535e,
            InverterSeries::Sk54xe,
        ]
        .map(participants)
        .iter()
        .map(|p| {
            (
                p.inverters,
                p.io_extensions,
                p.encoders,
                p.bus_interfaces,
                p.nordcon,
            )
        })
        .collect();
        let one = Some(1);
        assert_eq!(
            rows,
            [
                (4, Some(8), 4, one, one),
                (4, Some(8), 4, one, one),
                (8, Some(0), 8, one, one),
                (8, Some(16), 8, one, one)
            ]
        );
        assert_eq!(participants(InverterSeries::Sk5x0p).inverters, 8);
        // The decentralised series' 4 inverters are what the SK xU4 modules reach.
        for p in [
            Product::Tu4Eip,
            Product::Cu4Eip,
            Product::Tu4Pol,
            Product::Cu4Pol,
        ] {
            assert_eq!(
                participants(InverterSeries::Sk2xxe).inverters,
                p.max_inverters()
            );
        }
    }
}
