//! The controlled node's object dictionary: the objects of `proto::nord::epl` (identity,
//! feature flags, PDO mapping, process data), the objects whose value lives in the node (EPSG
//! DS 301: 1001h error register, 1003h error history, 1006h cycle length, 1F8Ch NMT state, 1F93h
//! node id, 1F99h Basic Ethernet timeout, 1F9Ah host name — the default name of BU 0620 §4.2.3
//! P854, "Powerlink <nnn>-0xED") and the NORD parameters at device id + parameter
//! number (BU 0620 §2.4.6, BU 2200 §6.4) on the device's parameter stores.
//!
//! Refusals are the abort codes of BU 0620 §2.4.7 / BU 2200 §6.4.1 (DS 301's, which are
//! CiA 301's): [`crate::objects`] maps a store's refusal to one.

use proto::epl::asnd::ErrorEntry;
use proto::epl::NmtState;
use proto::nord::ecat::Object;
use proto::nord::epl::{self as def, MappedWord, ParamOwner};
use proto::nord::errors::SdoAbort;
use proto::nord::{ParamNumber, Product};

use crate::device::Device;
use crate::ecat::od::upload_standard;
use crate::ecat::pdo::ProcessWords;
use crate::link::Unit;
use crate::objects::{abort, decode_number, read_sub, write_sub};

/// What the node itself holds that the dictionary shows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct NodeVars {
    /// The node id in use.
    pub(crate) node_id: u8,
    /// The NMT state.
    pub(crate) state: NmtState,
    /// NMT_CycleLen_U32 (µs).
    pub(crate) cycle_us: u32,
    /// NMT_CNBasicEthernetTimeout_U32 (µs).
    pub(crate) basic_ethernet_us: u32,
    /// ERR_ErrorRegister_U8.
    pub(crate) error_register: u8,
    /// ERR_History_ADOM, newest first.
    pub(crate) history: Vec<ErrorEntry>,
    /// 1600h, the PReq's mapping.
    pub(crate) rx_mapping: Mapping,
    /// 1A00h, the PRes's mapping.
    pub(crate) tx_mapping: Mapping,
}

/// One PDO mapping object (1600h RX / 1A00h TX, DS 301 PDO_RxMappParam / PDO_TxMappParam):
/// its entries (UNSIGNED64: index bits 0–15, sub-index 16–23, offset 32–47, length 48–63) and
/// how many are in use (sub-index 0).
///
/// BU 0620 §2.4.5 "The frequency inverter supports dynamic mapping" (BU 2200 §6.3.6: the fixed
/// default can be overwritten by entries the PLC project configures), §2.4.1 "Isochronous PDO
/// transfer (static mapping)": the Managing Node may rewrite the mapping while it configures
/// the node (Pre-Operational 1 and 2); from Ready To Operate on it stays as configured. An
/// entry may map a process data word of the default mapping (5000h…/5010h…, 16 bits); the
/// words follow each other from bit 0 (entry n at offset 16·(n−1)).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Mapping {
    /// Whether the PReq (RX, "to the FI") or the PRes.
    outputs: bool,
    entries: Vec<u64>,
    count: u8,
}

impl Mapping {
    /// The default mapping of `product` (BU 0620 §2.4.5: all 8 FIs, 96 bytes).
    pub(crate) fn default_of(product: Product, outputs: bool) -> Mapping {
        let entries: Vec<u64> = (0u16..)
            .zip(def::process_map(product, outputs))
            .map(|(i, m)| m.mapping(16 * i))
            .collect();
        Mapping {
            outputs,
            count: entries.len() as u8,
            entries,
        }
    }

    /// The words in use, in payload order.
    pub(crate) fn words(&self, product: Product) -> Vec<MappedWord> {
        let all = def::process_map(product, self.outputs);
        self.entries[..usize::from(self.count)]
            .iter()
            .filter_map(|e| {
                let (index, sub) = ((*e & 0xFFFF) as u16, ((*e >> 16) & 0xFF) as u8);
                all.iter()
                    .find(|m| m.index == index && m.sub == sub)
                    .copied()
            })
            .collect()
    }

    fn upload(&self, sub: u8) -> Result<Vec<u8>, SdoAbort> {
        match sub {
            0 => Ok(vec![self.count]),
            n => self
                .entries
                .get(usize::from(n) - 1)
                .map(|e| e.to_le_bytes().to_vec())
                .ok_or(abort::NO_SUBINDEX),
        }
    }

    fn mappable(&self, product: Product, entry: u64, position: usize) -> bool {
        let (index, sub) = ((entry & 0xFFFF) as u16, ((entry >> 16) & 0xFF) as u8);
        let (offset, length) = (((entry >> 32) & 0xFFFF) as usize, entry >> 48);
        length == 16
            && offset == 16 * position
            && def::process_map(product, self.outputs)
                .iter()
                .any(|m| m.index == index && m.sub == sub)
    }

    fn download(&mut self, product: Product, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        if usize::from(sub) > self.entries.len() {
            return Err(abort::NO_SUBINDEX);
        }
        if sub == 0 {
            let n = decode_number(data, proto::nord::ecat::DataType::U8)? as u8;
            if usize::from(n) > self.entries.len() {
                return Err(PDO_LENGTH_EXCEEDED);
            }
            let valid = self.entries[..usize::from(n)]
                .iter()
                .enumerate()
                .all(|(k, e)| self.mappable(product, *e, k));
            if !valid {
                return Err(NOT_MAPPABLE);
            }
            self.count = n;
            return Ok(());
        }
        let bytes: [u8; 8] = data.try_into().map_err(|_| {
            if data.len() > 8 {
                abort::TOO_LONG
            } else {
                abort::TOO_SHORT
            }
        })?;
        let entry = u64::from_le_bytes(bytes);
        // An entry changes only while sub-index 0 is 0 (the mapping is switched off); writing
        // the value it has changes nothing and is taken (a master restoring its settings).
        if self.count != 0 {
            return if self.entries[usize::from(sub) - 1] == entry {
                Ok(())
            } else {
                Err(abort::UNSUPPORTED_ACCESS)
            };
        }
        if !self.mappable(product, entry, usize::from(sub) - 1) {
            return Err(NOT_MAPPABLE);
        }
        self.entries[usize::from(sub) - 1] = entry;
        Ok(())
    }
}

/// DS 301 (CiA 301) abort codes of the mapping objects.
const NOT_MAPPABLE: SdoAbort = SdoAbort(0x0604_0041);
const PDO_LENGTH_EXCEEDED: SdoAbort = SdoAbort(0x0604_0042);
/// "Data cannot be transferred or stored to the application because of the present device
/// state": the mapping is not changed from Ready To Operate on.
const DEVICE_STATE: SdoAbort = SdoAbort(0x0800_0022);
const RX_MAPPING: u16 = 0x1600;
const TX_MAPPING: u16 = 0x1A00;

/// The history keeps this many entries (DS 301 allows 1..254).
pub(crate) const HISTORY_LEN: usize = 8;

/// What the dictionary reads and writes besides itself.
pub(crate) struct Context<'a> {
    /// The device and its parameter stores.
    pub(crate) device: &'a mut Device,
    /// The process words last exchanged.
    pub(crate) words: &'a ProcessWords,
    /// The node's own values.
    pub(crate) vars: &'a mut NodeVars,
}

/// The dictionary of one product.
#[derive(Debug, Clone)]
pub(crate) struct Dictionary {
    product: Product,
    objects: Vec<Object>,
}

/// Objects answered from [`NodeVars`].
const ERROR_REGISTER: u16 = 0x1001;
const ERROR_HISTORY: u16 = 0x1003;
const CYCLE_LEN: u16 = 0x1006;
const NMT_STATE: u16 = 0x1F8C;
const NODE_ID: u16 = 0x1F93;
const BASIC_ETHERNET_TIMEOUT: u16 = 0x1F99;
const HOST_NAME: u16 = 0x1F9A;

impl Dictionary {
    pub(crate) fn new(product: Product) -> Dictionary {
        Dictionary {
            product,
            objects: def::object_dictionary(product),
        }
    }

    fn object(&self, index: u16) -> Option<&Object> {
        self.objects.iter().find(|o| o.index == index)
    }

    /// The parameter store and definition an index addresses.
    fn parameter(
        &self,
        device: &mut Device,
        index: u16,
    ) -> Result<(Unit, ParamNumber, &'static proto::nord::params::ParamDef), SdoAbort> {
        let (owner, raw) = def::parameter_object(self.product, index).ok_or(abort::NO_OBJECT)?;
        let number = ParamNumber::new(i64::from(raw)).map_err(|_| abort::NO_OBJECT)?;
        let unit = match owner {
            ParamOwner::Interface => Unit::Interface,
            ParamOwner::Inverter(fi) => {
                if fi.get() > device.config().inverters {
                    // §2.4.7 08000020h: "no communication between the bus interface and the
                    // frequency inverter": the FI is not on the system bus.
                    return Err(abort::NO_INVERTER);
                }
                // The SK 550P's interface is built into FI 1: its P85x–P89x answer there.
                let iface = device.store(Unit::Interface).ok();
                match iface.and_then(|s| s.def(number)) {
                    Some(_) if fi.get() == 1 && self.product == Product::Sk550p => Unit::Interface,
                    _ => Unit::Inverter(fi),
                }
            }
        };
        let store = device.store(unit).map_err(|_| abort::NO_INVERTER)?;
        let d = store.def(number).ok_or(abort::NO_OBJECT)?;
        Ok((unit, number, d))
    }

    /// SDO read of `index`:`sub`.
    pub(crate) fn upload(
        &self,
        cx: &mut Context<'_>,
        index: u16,
        sub: u8,
    ) -> Result<Vec<u8>, SdoAbort> {
        let v = &*cx.vars;
        let u8v = |x: u8| Ok(vec![x]);
        let u32v = |x: u32| Ok(x.to_le_bytes().to_vec());
        match (index, sub) {
            (ERROR_REGISTER, 0) => return u8v(v.error_register),
            (ERROR_HISTORY, 0) => return u8v(v.history.len() as u8),
            (ERROR_HISTORY, n) => {
                return v
                    .history
                    .get(usize::from(n) - 1)
                    .map(|e| e.emit().to_vec())
                    .ok_or(abort::NO_SUBINDEX)
            }
            (CYCLE_LEN, 0) => return u32v(v.cycle_us),
            (NMT_STATE, 0) => return u8v(v.state.0),
            (NODE_ID, 0) => return u8v(2),
            (NODE_ID, 1) => return u8v(v.node_id),
            (NODE_ID, 2) => return u8v(0),
            (BASIC_ETHERNET_TIMEOUT, 0) => return u32v(v.basic_ethernet_us),
            (HOST_NAME, 0) => return Ok(def::default_hostname(v.node_id).into_bytes()),
            (RX_MAPPING, s) => return v.rx_mapping.upload(s),
            (TX_MAPPING, s) => return v.tx_mapping.upload(s),
            (
                ERROR_REGISTER
                | CYCLE_LEN
                | NMT_STATE
                | NODE_ID
                | BASIC_ETHERNET_TIMEOUT
                | HOST_NAME,
                _,
            ) => return Err(abort::NO_SUBINDEX),
            _ => {}
        }
        if let Some(o) = self.object(index) {
            return upload_standard(o, cx.words, sub, false);
        }
        let (unit, number, d) = self.parameter(cx.device, index)?;
        let store = cx.device.store(unit).map_err(|_| abort::NO_INVERTER)?;
        read_sub(store, number, d, sub)
    }

    /// SDO write of `data` to `index`:`sub`.
    pub(crate) fn download(
        &self,
        cx: &mut Context<'_>,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        let ranged = |data: &[u8], (lo, hi): (u32, u32)| -> Result<u32, SdoAbort> {
            let v = decode_number(data, proto::nord::ecat::DataType::U32)? as u32;
            if v < lo {
                Err(abort::VALUE_TOO_LOW)
            } else if v > hi {
                Err(abort::VALUE_TOO_HIGH)
            } else {
                Ok(v)
            }
        };
        match (index, sub) {
            // P858 / P165 "POWERLINK cycle" (BU 0620 §4.2.3, BU 2200 §7.1.2) bound the cycle
            // the node synchronises to.
            (CYCLE_LEN, 0) => {
                cx.vars.cycle_us = ranged(data, def::cycle_range_us(self.product))?;
                return Ok(());
            }
            (BASIC_ETHERNET_TIMEOUT, 0) => {
                cx.vars.basic_ethernet_us = ranged(data, (0, u32::MAX))?;
                return Ok(());
            }
            (ERROR_REGISTER | ERROR_HISTORY | NMT_STATE | NODE_ID | HOST_NAME, s) => {
                let count = match index {
                    ERROR_HISTORY => cx.vars.history.len() as u8,
                    NODE_ID => 2,
                    _ => 0,
                };
                return Err(if s > count {
                    abort::NO_SUBINDEX
                } else {
                    abort::READ_ONLY
                });
            }
            (CYCLE_LEN | BASIC_ETHERNET_TIMEOUT, _) => return Err(abort::NO_SUBINDEX),
            (RX_MAPPING | TX_MAPPING, s) => {
                let configuring = matches!(
                    cx.vars.state,
                    NmtState::PRE_OPERATIONAL_1 | NmtState::PRE_OPERATIONAL_2
                );
                let mapping = if index == RX_MAPPING {
                    &mut cx.vars.rx_mapping
                } else {
                    &mut cx.vars.tx_mapping
                };
                if usize::from(s) > mapping.entries.len() {
                    return Err(abort::NO_SUBINDEX);
                }
                if !configuring {
                    return Err(DEVICE_STATE);
                }
                return mapping.download(self.product, s, data);
            }
            _ => {}
        }
        if let Some(o) = self.object(index) {
            // The identity is fixed, the process data objects are written by PReq only
            // (the mapping objects are above).
            o.entry(sub).ok_or(abort::NO_SUBINDEX)?;
            return Err(abort::READ_ONLY);
        }
        let (unit, number, d) = self.parameter(cx.device, index)?;
        let store = cx.device.store(unit).map_err(|_| abort::NO_INVERTER)?;
        write_sub(store, number, d, sub, data)
    }
}

#[cfg(test)]
mod mapping_tests {
    use super::*;

    fn entry(index: u16, sub: u8, offset: u16) -> [u8; 8] {
        (u64::from(index) | u64::from(sub) << 16 | u64::from(offset) << 32 | 16u64 << 48)
            .to_le_bytes()
    }

    #[test]
    fn the_mn_remaps_the_pres_to_fi_2s_status_word() {
        let p = Product::Sk550p;
        let mut m = Mapping::default_of(p, false);
        assert_eq!(m.words(p).len(), 48);
        // Entries change only while sub-index 0 is 0.
        assert_eq!(
            m.download(p, 1, &entry(0x5011, 1, 0)),
            Err(abort::UNSUPPORTED_ACCESS)
        );
        assert_eq!(
            m.download(p, 1, &entry(0x5010, 1, 0)),
            Ok(()),
            "the value it has"
        );
        m.download(p, 0, &[0]).unwrap();
        m.download(p, 1, &entry(0x5011, 1, 0)).unwrap();
        m.download(p, 0, &[1]).unwrap();
        let w = m.words(p);
        assert_eq!((w.len(), w[0].index, w[0].sub), (1, 0x5011, 1));
        assert_eq!(m.upload(0), Ok(vec![1]));
        assert_eq!(m.upload(1), Ok(entry(0x5011, 1, 0).to_vec()));
    }

    #[test]
    fn only_process_words_are_mappable_and_in_sequence() {
        let p = Product::Sk550p;
        let mut m = Mapping::default_of(p, true);
        m.download(p, 0, &[0]).unwrap();
        // 1018h is no process data word; a TX word is not an RX word; a gap in the offsets.
        assert_eq!(m.download(p, 1, &entry(0x1018, 1, 0)), Err(NOT_MAPPABLE));
        assert_eq!(m.download(p, 1, &entry(0x5010, 1, 0)), Err(NOT_MAPPABLE));
        assert_eq!(m.download(p, 2, &entry(0x5000, 2, 32)), Err(NOT_MAPPABLE));
        assert_eq!(m.download(p, 0, &[49]), Err(PDO_LENGTH_EXCEEDED));
        assert_eq!(m.download(p, 49, &[0]), Err(abort::NO_SUBINDEX));
        // The default entries are still there: 6 words of FI 1.
        m.download(p, 0, &[6]).unwrap();
        assert_eq!(m.words(p).len(), 6);
    }
}
