//! What the manuals state about the EtherNet/IP side of each product: assembly instances and
//! their layout, the parameter classes, the run/idle header rule (P166), the class-1
//! connection sizes that follow from them and the identity.
//!
//! BU 0620 §2.3.4.1 (SK 550P: 100/101, 96 bytes, variable) and BU 2100 §6.2.1 (TU3-EIP:
//! 100/101 12 bytes fixed, 102/103 96 bytes variable; TU4/CU4-EIP: 100/101 and 110/111, 50
//! bytes variable with the interface I/O word first, "truncated … from the end").

use super::params::{self, Owner};
use super::product::Product;
use super::types::{Inverter, ParamNumber};

/// Which way an assembly's data flows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Consumed by the device: control words and setpoints (O→T).
    Output,
    /// Produced by the device: status words and actual values (T→O).
    Input,
}

/// One assembly instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Assembly {
    /// Instance number.
    pub instance: u16,
    /// Data direction.
    pub direction: Direction,
    /// Full length in bytes.
    pub len: u16,
    /// "Variable" (may be truncated from the end, in whole words) or "Fixed".
    pub variable: bool,
    /// A leading word for the bus interface's own digital I/O (instances 110/111).
    pub io_word: bool,
    /// Inverters carried, 6 words each (control/status word + 5 setpoints/actual values).
    pub inverters: u8,
    /// The manual's description.
    pub description: &'static str,
}

/// The O→T connection point of a listen-only connection (heartbeat, no data).
pub const LISTEN_ONLY_POINT: u16 = 255;
/// The RPIs the simulator accepts, µs (the manuals state none; 1 ms … 10 s).
pub const RPI_RANGE: std::ops::RangeInclusive<u32> = 1_000..=10_000_000;
/// Exclusive-owner and listen-only connections (BU 0620 §2.3.1, BU 2100 §3.1: "1 Exclusive
/// Owner, 2 Listen Only").
pub const LISTEN_ONLY_MAX: usize = 2;

/// Words per inverter in an assembly: STW + SW1..SW5, or ZSW + IW1..IW5.
pub const WORDS_PER_INVERTER: usize = 6;

const fn asm(
    instance: u16,
    direction: Direction,
    len: u16,
    variable: bool,
    io_word: bool,
    inverters: u8,
    description: &'static str,
) -> Assembly {
    Assembly {
        instance,
        direction,
        len,
        variable,
        io_word,
        inverters,
        description,
    }
}

const SK550P: &[Assembly] = &[
    asm(
        100,
        Direction::Output,
        96,
        true,
        false,
        8,
        "8 frequency inverters (for each: CTW + SW1 … SW5)",
    ),
    asm(
        101,
        Direction::Input,
        96,
        true,
        false,
        8,
        "8 frequency inverters (for each: STW + IW1 … IW5)",
    ),
];
/// 100/101 of the modules (BU 2100 §6.2.1): FI 1 alone, 12 bytes, fixed size.
const SINGLE_OUTPUT: Assembly = asm(
    100,
    Direction::Output,
    12,
    false,
    false,
    1,
    "STW + SW1 + SW2 + SW3 + SW4 + SW5",
);
const SINGLE_INPUT: Assembly = asm(
    101,
    Direction::Input,
    12,
    false,
    false,
    1,
    "ZSW + IW1 + IW2 + IW3 + IW4 + IW5",
);
const TU3: &[Assembly] = &[
    SINGLE_OUTPUT,
    SINGLE_INPUT,
    asm(
        102,
        Direction::Output,
        96,
        true,
        false,
        8,
        "8 frequency inverters (for each: STW + SW1 … SW5)",
    ),
    asm(
        103,
        Direction::Input,
        96,
        true,
        false,
        8,
        "8 frequency inverters (for each: ZSW + IW1 … IW5)",
    ),
];
const XU4: &[Assembly] = &[
    SINGLE_OUTPUT,
    SINGLE_INPUT,
    asm(
        110,
        Direction::Output,
        50,
        true,
        true,
        4,
        "Bus interface outputs + 4 frequency inverters (for each: STW + SW1 … SW5)",
    ),
    asm(
        111,
        Direction::Input,
        50,
        true,
        true,
        4,
        "Bus interface inputs + 4 frequency inverters (for each: ZSW + IW1 … IW5)",
    ),
];

/// The assembly instances of a product (empty for products without EtherNet/IP).
pub fn assemblies(product: Product) -> &'static [Assembly] {
    match product {
        Product::Sk550p => SK550P,
        Product::Tu3Eip => TU3,
        Product::Tu4Eip | Product::Cu4Eip => XU4,
        _ => &[],
    }
}

/// An assembly instance of a product.
pub fn assembly(product: Product, instance: u16) -> Option<&'static Assembly> {
    assemblies(product).iter().find(|a| a.instance == instance)
}

impl Assembly {
    /// Whether a connection may carry `len` data bytes of this assembly: the full length, or
    /// for a variable assembly any whole number of words down to one (truncated from the end,
    /// BU 2100 §6.2.1 "Truncation of data length": 10, 14 and 26 of 50 bytes).
    pub fn accepts(&self, len: usize) -> bool {
        let full = usize::from(self.len);
        if self.variable {
            len >= 2 && len <= full && len.is_multiple_of(2)
        } else {
            len == full
        }
    }

    /// Where an inverter's six words start in the data, in bytes.
    pub fn offset(&self, inverter: Inverter) -> Option<usize> {
        let n = usize::from(inverter.get());
        (n <= usize::from(self.inverters))
            .then(|| usize::from(self.io_word) * 2 + (n - 1) * WORDS_PER_INVERTER * 2)
    }
}

/// P166 "PZD transmission format" of the bus interface, where the product has it: the
/// EtherNet/IP modules (BU 2100 §7.1.2). `None` for the SK 550P, whose parameters stop at
/// P850–P899 and have no such setting (BU 0620 §5), and for products without EtherNet/IP.
///
/// The one place that says whether P166 applies: the simulator reads it from its store, the
/// scanner over the wire and the EDS writer from the catalogue only where this is `Some`.
pub fn transmission_format(product: Product) -> Option<ParamNumber> {
    let number = ParamNumber::new(166).ok()?;
    params::lookup(product, Owner::Interface, number).map(|_| number)
}

/// Whether O→T data of `instance` carries the 32-bit run/idle header.
///
/// BU 2100 §7.1.2 P166 "PZD transmission format": 0 = "32 Bit header + status", 1 = "Modeless
/// Format", which "can only be used for the assembly instances 110 and 111 … For instances 100
/// and 101 the data length is fixed and contains the 32 bit header." The TU3-EIP's variable
/// instance 102 follows P166 like 110. The SK 550P has no such parameter
/// ([`transmission_format`]): its O→T data carries the header, as CIP's default for class-1
/// O→T data.
pub fn o_t_run_idle(product: Product, instance: u16, p166: i32) -> bool {
    match assembly(product, instance) {
        Some(a) if a.variable && transmission_format(product).is_some() => p166 == 0,
        _ => true,
    }
}

/// Bytes of the CIP sequence count in front of every class-1 datagram's data (CIP Vol. 1,
/// class 1 transport: a 16-bit sequence count; [`crate::enip::io`]).
pub const SEQUENCE_COUNT_LEN: u16 = 2;
/// Bytes of the run/idle header ("32 Bit header", BU 2100 §7.1.2 P166; CIP Vol. 1, real-time
/// format "32-bit header").
pub const RUN_IDLE_HEADER_LEN: u16 = 4;

/// Bytes a class-1 connection carries in front of the assembly data: the sequence count, and
/// the run/idle header where the data carries it ([`o_t_run_idle`]; T→O data never does).
pub const fn io_header_len(run_idle: bool) -> u16 {
    SEQUENCE_COUNT_LEN + if run_idle { RUN_IDLE_HEADER_LEN } else { 0 }
}

/// The network connection size a Forward_Open gives for `data` bytes of an assembly: the
/// header of [`io_header_len`] plus the data (BU 2100 §6.2.1 "Truncation of data length": the
/// data may be shorter than the assembly, the header is always there).
pub const fn connection_size(data: u16, run_idle: bool) -> u16 {
    data.saturating_add(io_header_len(run_idle))
}

/// The assembly data bytes a network connection size carries; `None` when the size is smaller
/// than the header of [`io_header_len`].
pub const fn connection_data(size: u16, run_idle: bool) -> Option<u16> {
    size.checked_sub(io_header_len(run_idle))
}

/// The network connection sizes (O→T, T→O) of a class-1 connection between `o_t_instance` and
/// `t_o_instance` at full assembly length: [`connection_size`] of each assembly, with the
/// run/idle header on O→T where [`o_t_run_idle`] says so for `p166`. A listen-only connection
/// ([`LISTEN_ONLY_POINT`]) sends heartbeats without data: O→T 0. An instance the product does
/// not have counts no data.
pub fn connection_sizes(
    product: Product,
    o_t_instance: u16,
    t_o_instance: u16,
    p166: i32,
) -> (u16, u16) {
    let len = |instance| assembly(product, instance).map_or(0, |a| a.len);
    let o_t = if o_t_instance == LISTEN_ONLY_POINT {
        0
    } else {
        connection_size(len(o_t_instance), o_t_run_idle(product, o_t_instance, p166))
    };
    (o_t, connection_size(len(t_o_instance), false))
}

/// The CIP class of a unit's parameters: 100 for a module's own parameters, 100 + n for FI n
/// (BU 0620 §2.3.5, BU 2100 §6.3).
pub fn param_class(inverter: Option<Inverter>) -> u16 {
    100 + inverter.map_or(0, |i| u16::from(i.get()))
}

/// How the product identifies itself on EtherNet/IP (Identity object, ListIdentity, EDS).
///
/// The manuals print none of these values; they name the EDS files (BU 2100 §5.2.1: TU3_EIP.eds,
/// TU4_EIP.eds) and the MAC prefix F0:5F:5A. The simulator's values are its own, kept in one
/// place so the adapter and its EDS agree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct IdentityInfo {
    /// Vendor id.
    pub vendor: u16,
    /// Vendor name.
    pub vendor_name: &'static str,
    /// Device type: 0Ch communications adapter.
    pub device_type: u16,
    /// Product code.
    pub product_code: u16,
    /// Revision major.minor (BU 2100 §4.3: gateway function "with software version V1.3 R0").
    pub revision: (u8, u8),
    /// Product name.
    pub name: &'static str,
    /// The EDS file name the manual gives.
    pub eds_file: &'static str,
}

/// The identity of an EtherNet/IP product.
pub fn identity(product: Product) -> Option<IdentityInfo> {
    let (product_code, name, eds_file) = match product {
        Product::Sk550p => (550, "NORDAC PRO SK 550P", "SK550P_EIP.eds"),
        Product::Tu3Eip => (1003, "SK TU3-EIP", "TU3_EIP.eds"),
        Product::Tu4Eip => (1004, "SK TU4-EIP", "TU4_EIP.eds"),
        Product::Cu4Eip => (1005, "SK CU4-EIP", "TU4_EIP.eds"),
        _ => return None,
    };
    Some(IdentityInfo {
        vendor: VENDOR_ID,
        vendor_name: "NORD Electronic DRIVESYSTEMS GmbH",
        device_type: 0x0C,
        product_code,
        revision: (1, 3),
        name,
        eds_file,
    })
}

/// Process-data update cycle over the NORD system bus of an SK TU3-EIP with `inverters` SK 5xxE
/// behind it, in µs (BU 2100 §4.3, p. 22 "Response times for process data communication"):
/// 1.25 ms per inverter, at least 5 ms — 8 → 10 ms, 7 → 8.75 ms, 4…1 → 5 ms as printed. The
/// printed 6.5 ms (6 FIs) and 5.25 ms (5 FIs) break the table's own 1.25 ms step; this gives
/// 7.5 and 6.25 ms (see the erratum in suites/bu2100).
pub fn tu3_update_cycle_us(inverters: u8) -> Option<u32> {
    (1..=8)
        .contains(&inverters)
        .then(|| (u32::from(inverters) * 1250).max(5000))
}

/// The vendor id the simulator reports. The manuals print none; 834 is "NORD Electronic
/// DRIVESYSTEMS GmbH" in the CIP vendor table that EtherNet/IP tools ship (pycomm3's, for one).
pub const VENDOR_ID: u16 = 834;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tu3_update_cycle_per_inverter_count() {
        // BU 2100 §4.3: 8 → 10 ms, 7 → 8.75 ms, 4…1 → 5 ms; 6 and 5 by the same 1.25 ms step.
        let got: Vec<_> = (0..=9).map(tu3_update_cycle_us).collect();
        let ms = |v: u32| Some(v);
        assert_eq!(
            got,
            [
                None,
                ms(5000),
                ms(5000),
                ms(5000),
                ms(5000),
                ms(6250),
                ms(7500),
                ms(8750),
                ms(10000),
                None
            ]
        );
    }
    use rstest::rstest;

    #[rstest]
    #[case(Product::Sk550p, 100, 96, 96, true)]
    #[case(Product::Tu3Eip, 100, 12, 12, true)]
    #[case(Product::Tu3Eip, 100, 10, 12, false)]
    #[case(Product::Tu4Eip, 110, 10, 50, true)]
    #[case(Product::Tu4Eip, 110, 14, 50, true)]
    #[case(Product::Tu4Eip, 110, 26, 50, true)]
    #[case(Product::Tu4Eip, 110, 52, 50, false)]
    #[case(Product::Cu4Eip, 111, 11, 50, false)]
    fn assembly_lengths(
        #[case] p: Product,
        #[case] instance: u16,
        #[case] len: usize,
        #[case] full: u16,
        #[case] ok: bool,
    ) {
        let a = assembly(p, instance).unwrap();
        assert_eq!(a.len, full);
        assert_eq!(a.accepts(len), ok);
    }

    #[test]
    fn every_assembly_length_is_its_words() {
        for p in Product::ALL {
            for a in assemblies(p) {
                let words = usize::from(a.io_word) + usize::from(a.inverters) * WORDS_PER_INVERTER;
                assert_eq!(usize::from(a.len), words * 2, "{p:?} {}", a.instance);
            }
        }
        assert!(assemblies(Product::Tu3Pnt).is_empty());
    }

    #[test]
    fn inverter_offsets_and_run_idle() {
        let fi = |n| Inverter::new(n).unwrap();
        let a110 = assembly(Product::Tu4Eip, 110).unwrap();
        assert_eq!(a110.offset(fi(1)), Some(2));
        assert_eq!(a110.offset(fi(4)), Some(38));
        assert_eq!(a110.offset(fi(5)), None);
        assert!(o_t_run_idle(Product::Tu4Eip, 100, 1));
        assert!(!o_t_run_idle(Product::Tu4Eip, 110, 1));
        assert!(o_t_run_idle(Product::Tu4Eip, 110, 0));
        assert!(o_t_run_idle(Product::Sk550p, 100, 1));
        assert!(o_t_run_idle(Product::Tu3Eip, 100, 1));
        assert!(!o_t_run_idle(Product::Tu3Eip, 102, 1));
        assert_eq!(param_class(None), 100);
        assert_eq!(param_class(Some(fi(8))), 108);
    }

    #[test]
    fn p166_only_on_the_ethernet_ip_modules() {
        let p166 = ParamNumber::new(166).unwrap();
        for p in [Product::Tu3Eip, Product::Tu4Eip, Product::Cu4Eip] {
            assert_eq!(transmission_format(p), Some(p166), "{p:?}");
        }
        for p in [Product::Sk550p, Product::Tu3Pnt, Product::Tu4Pol] {
            assert_eq!(transmission_format(p), None, "{p:?}");
        }
    }

    #[rstest]
    // 2 sequence count + 4 run/idle header + 12 data; T→O 2 + 12 (BU 2100 §6.2.1).
    #[case(Product::Tu3Eip, 100, 101, 1, (18, 14))]
    #[case(Product::Tu3Eip, 102, 103, 0, (102, 98))]
    // Modeless 102 (P166 = 1): 2 + 96.
    #[case(Product::Tu3Eip, 102, 103, 1, (98, 98))]
    #[case(Product::Tu4Eip, 110, 111, 0, (56, 52))]
    #[case(Product::Cu4Eip, 110, 111, 1, (52, 52))]
    #[case(Product::Cu4Eip, 100, 101, 1, (18, 14))]
    // SK 550P: the header whatever the argument says (no P166).
    #[case(Product::Sk550p, 100, 101, 1, (102, 98))]
    // Listen-only: heartbeats, O→T 0.
    #[case(Product::Tu4Eip, LISTEN_ONLY_POINT, 111, 0, (0, 52))]
    fn connection_sizes_at_full_length(
        #[case] p: Product,
        #[case] o_t: u16,
        #[case] t_o: u16,
        #[case] p166: i32,
        #[case] want: (u16, u16),
    ) {
        assert_eq!(connection_sizes(p, o_t, t_o, p166), want);
    }

    #[test]
    fn connection_size_and_data_are_inverse() {
        assert_eq!(io_header_len(true), 6);
        assert_eq!(io_header_len(false), 2);
        assert_eq!(connection_size(10, true), 16);
        assert_eq!(connection_data(16, true), Some(10));
        assert_eq!(connection_data(16, false), Some(14));
        assert_eq!(connection_data(5, true), None);
        assert_eq!(connection_data(2, false), Some(0));
        assert_eq!(connection_size(u16::MAX, true), u16::MAX);
    }
}
