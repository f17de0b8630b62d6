//! The NORD POWERLINK controlled nodes as the manuals define them (BU 0620 §2.4, §3.7, §4.2.3
//! for the SK 550P's integrated interface; BU 2200 §5–§7 for SK TU3-POL, SK TU4-POL and
//! SK CU4-POL): identity, addressing, the object dictionary, the parameter objects and the
//! fixed process-data mapping. Pure data: the simulator's controlled node and the XDD writer
//! are made from this one definition.
//!
//! Assumptions (the manuals do not give them), said so here once:
//! - vendor id 000000EDh: the manuals give it only as the "0xED" of the XDD file names
//!   (BU 2200 §5.2.1: "0xED_NORD_TU3_POL.xdd") and of the SK 550P's default station name
//!   (BU 0620 §4.2.3 P854: "Powerlink <nnn>-0xED");
//! - product codes, device type 0 (no DS 402 profile on the bus), the revision numbers (made
//!   from BU 2200 §1.1.2's software versions: V 1.3 R3 → 00010303h);
//! - the Basic Ethernet timeout: DS 301's default of NMT_CNBasicEthernetTimeout_U32 (1F99h),
//!   5 s; the manuals say only "the set time (timeout)" (BU 0620 §2.4.4, BU 2200 §6.2).
//!
//! Errata of the manuals kept here (the code follows the correct value):
//! - BU 2200 §6.3.5, SK TU3-POL table: FU3 setpoint 4 printed "5502.Fh" (5002.Fh by the
//!   table's own rule, 4 sub-indices per setpoint), FU8 setpoint 5 printed "5002.29h" (5002.28h),
//!   FU8 status word printed "5001.8" (5001.8h).
//! - BU 2200 §6.4's device-id table stops at FU4 (4000h) although the SK TU3-POL carries FU1..FU8
//!   (§4.1, §6.3.5, P176/P177): a table that leaves rows out. Its rule continued (4800h,
//!   5000h, …) would collide with the process-data objects 5000h–5003h from FU6 on, so the ids
//!   of FU5..FU8 are not known: the code gives them none ([`device_id_inverters`]).
//! - BU 0620 §5.4.1.1 reads P700 at "3000h" + "700" = "32BC"; 3000h is no device id of
//!   §2.4.6's table (FI 1 is 2000h, so P700 of FI 1 is 22BCh), and 32BCh addresses P188 of
//!   FI 4 there (3200h + BCh).

use std::net::Ipv4Addr;

use super::ecat::{compound, entry, var, DataType, Entry, Object, ObjectCode, PdoMapping, Value};
use super::product::{Family, Product};
use super::types::Inverter;

/// Vendor id (see the module documentation).
pub const VENDOR_ID: u32 = 0x0000_00ED;
/// Device type (1000h): no device profile on the bus.
pub const DEVICE_TYPE: u32 = 0;
/// EPLVersion the node reports: V2.0.
pub const EPL_VERSION: u8 = 0x20;
/// NMT_FeatureFlags_U32 (1F82h): isochronous (bit 0), SDO by UDP/IP (bit 1), SDO by ASnd
/// (bit 2) — BU 0620 §2.4.1 "Isochronous PDO transfer (static mapping), asynchronous data
/// transfer (SDO over ASND or UDP/IP)".
pub const FEATURE_FLAGS: u32 = 0x0000_0007;
/// The largest asynchronous frame (NMT_CycleTiming_REC.AsyncMTU_U16, DS 301 C_DLL_MIN_ASYNC_MTU).
pub const ASYNC_MTU: u16 = 300;
/// PRes response time the node promises (ns).
pub const RESPONSE_TIME_NS: u32 = 25_000;
/// The cycle the node expects (P858 factory setting 1000 µs, BU 0620 §4.2.3).
pub const DEFAULT_CYCLE_US: u32 = 1000;
/// The cycle range the node synchronises to, µs: the SK 550P's P858 "POWERLINK cycle"
/// 400…2000 µs (BU 0620 §4.2.3), the modules' P165 "POWERLINK Zyklus" 400…4000 µs (BU 2200
/// §7.1.2).
pub fn cycle_range_us(product: Product) -> (u32, u32) {
    match product.family() {
        Family::Integrated => (400, 2000),
        Family::Module => (400, 4000),
    }
}
/// NMT_CNBasicEthernetTimeout_U32 default, µs (DS 301; see the module documentation).
pub const BASIC_ETHERNET_TIMEOUT_US: u32 = 5_000_000;
/// The first three bytes of the node's IP address (BU 0620 §3.7.3, BU 2200 §5.2.5:
/// "192.168.100.xxx (xxx = Node-ID)").
pub const IP_PREFIX: [u8; 3] = [192, 168, 100];
/// The subnet mask (same sections: 255.255.255.0).
pub const SUBNET: Ipv4Addr = Ipv4Addr::new(255, 255, 255, 0);
/// The modules' gateway default (BU 2200 §5.2.5 P164: "192.168.100.254").
pub const MODULE_GATEWAY: Ipv4Addr = Ipv4Addr::new(192, 168, 100, 254);

/// The node's IP address for a node id.
pub fn ip_address(node: u8) -> Ipv4Addr {
    Ipv4Addr::new(IP_PREFIX[0], IP_PREFIX[1], IP_PREFIX[2], node)
}

/// Product code (assumed, see the module documentation).
pub fn product_code(product: Product) -> u32 {
    match product {
        Product::Tu3Pol => 0x0000_2203,
        Product::Tu4Pol => 0x0000_2204,
        Product::Cu4Pol => 0x0000_2214,
        _ => 0x0000_0550,
    }
}

/// Revision number: the software version of BU 2200 §1.1.2 (V 1.3 R3 SK TU4-POL, V 1.3 R2
/// SK TU3-POL, V 1.3 R1 SK CU4-POL); the SK 550P's is V 1.1 R1, the version BU 0620 (March
/// 2020) describes (§1.1.2 document history).
pub fn revision(product: Product) -> u32 {
    match product {
        Product::Tu4Pol => 0x0001_0303,
        Product::Tu3Pol => 0x0001_0302,
        Product::Cu4Pol => 0x0001_0301,
        _ => 0x0001_0101,
    }
}

/// The device name (1008h).
pub fn device_name(product: Product) -> &'static str {
    match product {
        Product::Tu3Pol => "SK TU3-POL",
        Product::Tu4Pol => "SK TU4-POL",
        Product::Cu4Pol => "SK CU4-POL",
        _ => "NORDAC PRO SK 550P",
    }
}

/// The station name the node registers with when none is set (BU 0620 §4.2.3 P854 note:
/// "Powerlink <nnn>-0xED", nnn = node id).
pub fn default_hostname(node: u8) -> String {
    format!("Powerlink {node:03}-0xED")
}

/// What a parameter object addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamOwner {
    /// The bus module's own parameters (BU 2200 §6.4: 2000h…27FFh).
    Interface,
    /// FI n.
    Inverter(Inverter),
}

/// How many inverters have an SDO device id, i.e. whose parameters are reached over
/// POWERLINK: the SK 550P's FI 1..8 (BU 0620 §2.4.6, 2000h…4FFFh); the modules' FU1..FU4
/// (BU 2200 §6.4: 2800h, 3000h, 3800h, 4000h). The SK TU3-POL carries FU5..FU8 in its process
/// data ([`Product::max_inverters`], §6.3.5) but §6.4's table has no row for them, and its
/// rule continued (4800h, 5000h, …) would put FU6..FU8 on the process-data objects
/// 5000h–5003h: their parameters have no SDO object here. 0 for a product without POWERLINK.
pub fn device_id_inverters(product: Product) -> u8 {
    match product {
        Product::Sk550p => 8,
        Product::Tu3Pol | Product::Tu4Pol | Product::Cu4Pol => 4,
        _ => 0,
    }
}

/// The device id of FI `inverter` (BU 0620 §2.4.6: 2000h + 600h·(FI−1); BU 2200 §6.4: 2800h +
/// 800h·(FU−1), the module itself at 2000h); `None` for an inverter the product's table has no
/// row for ([`device_id_inverters`]).
pub fn device_id(product: Product, inverter: Inverter) -> Option<u16> {
    let n = u16::from(inverter.get());
    if inverter.get() > device_id_inverters(product) {
        return None;
    }
    Some(match product.family() {
        Family::Integrated => 0x2000 + 0x600 * (n - 1),
        Family::Module => 0x2000 + 0x800 * n,
    })
}

/// The parameter an SDO index addresses: its owner and number, `None` outside the device-id
/// tables (index below 2000h, above the last device's range: for the modules 47FFh, FU4's
/// last, also on the SK TU3-POL that carries FU5..FU8 — see [`device_id_inverters`]).
pub fn parameter_object(product: Product, index: u16) -> Option<(ParamOwner, u16)> {
    let offset = index.checked_sub(0x2000)?;
    let (owner, number) = match product.family() {
        Family::Integrated => {
            let fi = offset / 0x600 + 1;
            (ParamOwner::Inverter(fi_of(fi)?), offset % 0x600)
        }
        Family::Module if offset < 0x800 => (ParamOwner::Interface, offset),
        Family::Module => (ParamOwner::Inverter(fi_of(offset / 0x800)?), offset % 0x800),
    };
    match owner {
        ParamOwner::Inverter(i) if i.get() > device_id_inverters(product) => None,
        _ => Some((owner, number)),
    }
}

fn fi_of(n: u16) -> Option<Inverter> {
    Inverter::new(i64::from(n)).ok()
}

/// What a process data word carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Slot {
    /// Word `word` of FI `fi`: 0 the control/status word, 1..5 setpoints/actual values.
    Inverter {
        /// FI 1..8.
        fi: u8,
        /// 0..=5.
        word: u8,
    },
    /// The digital inputs/outputs of an SK TU4-POL / SK CU4-POL (BU 2200 §6.3.7).
    Io,
}

/// One mapped 16-bit word of the PReq (outputs, "to the FI") or PRes (inputs) payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct MappedWord {
    /// The object mapped.
    pub index: u16,
    /// Its sub-index.
    pub sub: u8,
    /// What it carries.
    pub slot: Slot,
}

impl MappedWord {
    /// The PDO mapping entry (DS 301 §6.4.9.2, UNSIGNED64): index bits 0–15, sub-index 16–23,
    /// offset in bits 32–47, length in bits 48–63.
    pub fn mapping(&self, offset_bits: u16) -> u64 {
        u64::from(self.index)
            | u64::from(self.sub) << 16
            | u64::from(offset_bits) << 32
            | 16u64 << 48
    }
}

/// Sub-index of setpoint/actual value `k` (1..5) of FU `n` in 5002h/5003h of an SK TU3-POL
/// (BU 2200 §6.3.5: FU1..4 at n + 4·(k−1), FU5..8 at 15h + (n−5) + 4·(k−1)).
fn tu3_sub(n: u8, k: u8) -> u8 {
    let base = if n <= 4 { n } else { 0x15 + (n - 5) };
    base + 4 * (k - 1)
}

/// The words of the PReq (`outputs`) or PRes payload of a product, in order (BU 0620 §2.4.5:
/// 8 FIs, 96 bytes, 5000h+FI−1 / 5010h+FI−1 sub-indices 1..6; BU 2200 §6.3.5: SK TU3-POL
/// "12 Byte" per FU — its table restarts the word count at every FU — for FU1..8, control/
/// status word 5000h/5001h sub FU, values 5002h/5003h (the words of an FU not on the system
/// bus stay 0); SK TU4-POL/CU4-POL 50 bytes: the I/O word 5005h.0/5001h.0, then FU1..4 with
/// values at 5·(FU−1) + k).
pub fn process_map(product: Product, outputs: bool) -> Vec<MappedWord> {
    let (word0, values) = if outputs {
        (0x5000, 0x5002)
    } else {
        (0x5001, 0x5003)
    };
    let w = |index, sub, fi, word| MappedWord {
        index,
        sub,
        slot: Slot::Inverter { fi, word },
    };
    let mut map = Vec::new();
    match product {
        Product::Tu3Pol => {
            for n in 1..=8u8 {
                map.push(w(word0, n, n, 0));
                map.extend((1..=5).map(|k| w(values, tu3_sub(n, k), n, k)));
            }
        }
        Product::Tu4Pol | Product::Cu4Pol => {
            map.push(MappedWord {
                index: if outputs { 0x5005 } else { 0x5001 },
                sub: 0,
                slot: Slot::Io,
            });
            for n in 1..=4u8 {
                map.push(w(word0, n, n, 0));
                map.extend((1..=5).map(|k| w(values, 5 * (n - 1) + k, n, k)));
            }
        }
        _ => {
            let base = if outputs { 0x5000 } else { 0x5010 };
            for n in 1..=8u8 {
                map.extend((0..6).map(|k| w(base + u16::from(n - 1), k + 1, n, k)));
            }
        }
    }
    map
}

/// The object dictionary of the node (without the parameter objects, see
/// [`parameter_object`], and without the objects whose value lives in the node: 1001h error
/// register, 1003h error history, 1006h cycle length, 1F8Ch NMT state, 1F93h node id, 1F99h
/// Basic Ethernet timeout — the simulator answers those).
pub fn object_dictionary(product: Product) -> Vec<Object> {
    let num = |v: u32| Value::Number(u64::from(v));
    let text = |s: &'static str| (DataType::String(s.len() as u16), Value::Text(s));
    let (t, v) = text(device_name(product));
    let mut od = vec![
        var(
            0x1000,
            "NMT_DeviceType_U32",
            DataType::U32,
            num(DEVICE_TYPE),
        ),
        var(0x1008, "NMT_ManufactDevName_VS", t, v),
        var(
            0x1F82,
            "NMT_FeatureFlags_U32",
            DataType::U32,
            num(FEATURE_FLAGS),
        ),
    ];
    od.push(compound(
        0x1018,
        "NMT_IdentityObject_REC".into(),
        ObjectCode::Record,
        vec![
            entry(1, "VendorId_U32", DataType::U32, num(VENDOR_ID)),
            entry(
                2,
                "ProductCode_U32",
                DataType::U32,
                num(product_code(product)),
            ),
            entry(3, "RevisionNo_U32", DataType::U32, num(revision(product))),
            entry(4, "SerialNo_U32", DataType::U32, num(0)),
        ],
    ));
    for (outputs, comm, mapping, name) in [
        (true, 0x1400, 0x1600, "PDO_RxMappParam_00h_AU64"),
        (false, 0x1800, 0x1A00, "PDO_TxMappParam_00h_AU64"),
    ] {
        od.push(compound(
            comm,
            if outputs {
                "PDO_RxCommParam_00h_REC"
            } else {
                "PDO_TxCommParam_00h_REC"
            }
            .into(),
            ObjectCode::Record,
            vec![
                entry(1, "NodeID_U8", DataType::U8, num(0)),
                entry(2, "MappingVersion_U8", DataType::U8, num(0)),
            ],
        ));
        let entries = (1u8..)
            .zip(process_map(product, outputs))
            .map(|(s, m)| {
                let offset = 16 * u16::from(s - 1);
                entry(
                    s,
                    format!("ObjectMapping_{s:02X}h"),
                    DataType::U64,
                    Value::Number(m.mapping(offset)),
                )
            })
            .collect();
        od.push(compound(mapping, name.into(), ObjectCode::Array, entries));
    }
    for outputs in [true, false] {
        let mut by_index: Vec<(u16, Vec<Entry>)> = Vec::new();
        for m in process_map(product, outputs) {
            let (value, name) = match m.slot {
                Slot::Inverter { fi, word } => {
                    let v = if outputs {
                        Value::Output { inverter: fi, word }
                    } else {
                        Value::Input { inverter: fi, word }
                    };
                    (v, word_name(outputs, fi, word))
                }
                Slot::Io => (
                    Value::Number(0),
                    if outputs { "Digital OUT" } else { "Digital IN" }.to_string(),
                ),
            };
            // Control/status words and the I/O word are bit fields, the values signed
            // percentages (as under EtherCAT, `proto::nord::ecat::word_type`).
            let ty = match m.slot {
                Slot::Inverter { word, .. } => super::ecat::word_type(word),
                Slot::Io => DataType::U16,
            };
            let e = Entry {
                pdo: if outputs {
                    PdoMapping::Rx
                } else {
                    PdoMapping::Tx
                },
                ..entry(m.sub, name, ty, value)
            };
            match by_index.iter_mut().find(|(i, _)| *i == m.index) {
                Some((_, v)) => v.push(e),
                None => by_index.push((m.index, vec![e])),
            }
        }
        for (index, mut entries) in by_index {
            entries.sort_by_key(|e| e.sub);
            if entries.iter().any(|e| e.sub == 0) {
                // The modules' I/O word sits at sub-index 0 of 5001h/5005h (BU 2200 §6.3.5):
                // 5005h is a VAR; 5001h holds it beside the status words, which leaves no
                // room for a count — the object is then a RECORD without one.
                od.push(Object {
                    index,
                    name: format!("PDO_{index:04X}h"),
                    code: if entries.len() == 1 {
                        ObjectCode::Var
                    } else {
                        ObjectCode::Record
                    },
                    entries,
                });
            } else {
                od.push(compound(
                    index,
                    format!("PDO_{index:04X}h"),
                    ObjectCode::Record,
                    entries,
                ));
            }
        }
    }
    od.sort_by_key(|o| o.index);
    od
}

fn word_name(outputs: bool, fi: u8, word: u8) -> String {
    match (outputs, word) {
        (true, 0) => format!("FI {fi} control word"),
        (false, 0) => format!("FI {fi} status word"),
        (true, k) => format!("FI {fi} setpoint {k}"),
        (false, k) => format!("FI {fi} actual value {k}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn device_ids_of_both_tables() {
        // BU 0620 §2.4.6 example: P102 of FI 5 = 3800h + 66h = 3866h.
        assert_eq!(device_id(Product::Sk550p, fi(5)), Some(0x3800));
        assert_eq!(device_id(Product::Sk550p, fi(8)), Some(0x4A00));
        assert_eq!(
            parameter_object(Product::Sk550p, 0x3866),
            Some((ParamOwner::Inverter(fi(5)), 102))
        );
        assert_eq!(
            parameter_object(Product::Sk550p, 0x4FFF).map(|p| p.1),
            Some(0x5FF)
        );
        assert_eq!(parameter_object(Product::Sk550p, 0x5000), None);
        // BU 2200 §6.4 example: P102 of FU1 = 2800h + 66h = 2866h; the module at 2000h.
        assert_eq!(device_id(Product::Tu4Pol, fi(1)), Some(0x2800));
        assert_eq!(
            parameter_object(Product::Tu4Pol, 0x2866),
            Some((ParamOwner::Inverter(fi(1)), 102))
        );
        assert_eq!(
            parameter_object(Product::Cu4Pol, 0x20A0),
            Some((ParamOwner::Interface, 160))
        );
        // §6.4's table ends at FU4 (4000h…47FFh), though the SK TU3-POL carries FU1..FU8
        // (§6.3.5): no device id for FU5..FU8, and 4800h addresses nothing.
        assert_eq!(Product::Tu3Pol.max_inverters(), 8);
        assert_eq!(device_id_inverters(Product::Tu3Pol), 4);
        assert_eq!(device_id(Product::Tu3Pol, fi(4)), Some(0x4000));
        assert_eq!(device_id(Product::Tu3Pol, fi(5)), None);
        assert_eq!(
            parameter_object(Product::Tu3Pol, 0x47FF),
            Some((ParamOwner::Inverter(fi(4)), 0x7FF))
        );
        assert_eq!(parameter_object(Product::Tu3Pol, 0x4800), None);
        assert_eq!(parameter_object(Product::Tu3Pol, 0x5000), None);
        assert_eq!(parameter_object(Product::Tu3Pol, 0x1FFF), None);
    }

    #[test]
    fn process_maps_of_the_manuals() {
        let sk = process_map(Product::Sk550p, true);
        assert_eq!(sk.len(), 48); // 96 bytes
        assert_eq!((sk[6].index, sk[6].sub), (0x5001, 1)); // FI 2 control word
        let sk_in = process_map(Product::Sk550p, false);
        assert_eq!((sk_in[47].index, sk_in[47].sub), (0x5017, 6));
        let tu3 = process_map(Product::Tu3Pol, true);
        let subs: Vec<u8> = tu3[..12].iter().map(|m| m.sub).collect();
        assert_eq!(
            subs,
            [1, 0x01, 0x05, 0x09, 0x0D, 0x11, 2, 0x02, 0x06, 0x0A, 0x0E, 0x12]
        );
        assert_eq!(tu3.len(), 48);
        assert_eq!((tu3[29].index, tu3[29].sub), (0x5002, 0x15 + 4 * 4)); // FU5 setpoint 5
        assert_eq!((tu3_sub(3, 4), tu3_sub(8, 5)), (0x0F, 0x28)); // errata 5502.Fh, 5002.29h
        let tu4 = process_map(Product::Tu4Pol, false);
        assert_eq!(tu4.len(), 25); // 50 bytes
        assert_eq!(
            (tu4[0].index, tu4[0].sub, tu4[0].slot),
            (0x5001, 0, Slot::Io)
        );
        assert_eq!((tu4[7].index, tu4[7].sub), (0x5001, 2)); // FU2 status word
        assert_eq!((tu4[12].index, tu4[12].sub), (0x5003, 0x0A)); // FU2 actual value 5
    }

    #[test]
    fn dictionary_has_identity_and_mappings() {
        let od = object_dictionary(Product::Sk550p);
        let id = od.iter().find(|o| o.index == 0x1018).unwrap();
        assert_eq!(id.entry(1).unwrap().value, Value::Number(0xED));
        let rx = od.iter().find(|o| o.index == 0x1600).unwrap();
        assert_eq!(rx.entry(0).unwrap().value, Value::Number(48));
        // Entry 2: 5000h sub 2, offset 16 bits, length 16 bits.
        assert_eq!(
            rx.entry(2).unwrap().value,
            Value::Number(0x0010_0010_0002_5000)
        );
        assert!(od.windows(2).all(|w| w[0].index < w[1].index));
        let tu4 = object_dictionary(Product::Tu4Pol);
        assert!(tu4.windows(2).all(|w| w[0].index < w[1].index));
    }

    #[test]
    fn io_word_objects_of_the_modules() {
        // BU 2200 §6.3.5: the I/O word at sub-index 0 of 5005h (PReq) and 5001h (PRes); 5005h
        // holds nothing else, 5001h holds the status words beside it.
        let od = object_dictionary(Product::Tu4Pol);
        let out = od.iter().find(|o| o.index == 0x5005).unwrap();
        assert_eq!((out.code, out.entries.len()), (ObjectCode::Var, 1));
        let inp = od.iter().find(|o| o.index == 0x5001).unwrap();
        assert_eq!(inp.code, ObjectCode::Record);
        assert!(inp.entries.len() > 1 && inp.entries[0].sub == 0);
    }
}
