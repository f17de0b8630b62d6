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
use proto::nord::epl::{self as def, ParamOwner};
use proto::nord::errors::SdoAbort;
use proto::nord::{ParamNumber, Product};

use super::mapping::PdoMap;
use crate::device::Device;
use crate::ecat::od::upload_standard;
use crate::ecat::pdo::ProcessWords;
use crate::link::Unit;
use crate::objects::{abort, decode_number};

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
    /// The PReq mapping (1600h): dynamic on the SK TU3-POL (BU 2200 §6.3.6).
    pub(crate) rx_map: PdoMap,
    /// The PRes mapping (1A00h).
    pub(crate) tx_map: PdoMap,
    /// Inverters no longer on the system bus (bit n − 1 = FI n): their parameters cannot be
    /// read or stored (08000020h, BU 2200 §5.2.4 and §6.4.1).
    pub(crate) lost: u8,
}

/// PDO_RxMappParam_00h_AU64 (the PReq) and PDO_TxMappParam_00h_AU64 (the PRes).
const RX_MAPPING: u16 = 0x1600;
const TX_MAPPING: u16 = 0x1A00;

/// 08000020h "keine Verbindung zwischen Busschnittstelle und Frequenzumrichter" for an inverter
/// that has dropped off the system bus.
fn reachable(vars: &NodeVars, unit: Unit) -> Result<(), SdoAbort> {
    match unit {
        Unit::Inverter(fi) if vars.lost & 1 << (fi.get() - 1) != 0 => Err(abort::NO_INVERTER),
        _ => Ok(()),
    }
}

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

    /// The mapping object `index` where the product maps dynamically — the SK 550P (BU 0620
    /// §2.4.5 "The frequency inverter supports dynamic mapping") and the SK TU3-POL (BU 2200
    /// §6.3.6); the SK TU4-POL and SK CU4-POL map statically (BU 2200 §3.1).
    fn dynamic_map<'v>(&self, vars: &'v NodeVars, index: u16) -> Option<&'v PdoMap> {
        match index {
            _ if !matches!(self.product, Product::Sk550p | Product::Tu3Pol) => None,
            RX_MAPPING => Some(&vars.rx_map),
            TX_MAPPING => Some(&vars.tx_map),
            _ => None,
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
        if let Some(map) = self.dynamic_map(cx.vars, index) {
            return map.read(sub);
        }
        if let Some(o) = self.object(index) {
            return upload_standard(o, cx.words, sub, false);
        }
        let (unit, number, _) = self.parameter(cx.device, index)?;
        reachable(cx.vars, unit)?;
        cx.device.store(unit).map_err(|_| abort::NO_INVERTER)?;
        // Behind the gateway, an SDO upload from the inverter's node.
        cx.device
            .gateway_read(unit, number, sub)
            .map_err(|r| r.abort)
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
            _ => {}
        }
        if self.dynamic_map(cx.vars, index).is_some() {
            // The MN maps while it configures the node (Pre-Operational 1 and 2); from Ready
            // To Operate on the mapping stays as configured (BU 0620 §2.4.1 "static mapping").
            if !matches!(
                cx.vars.state,
                NmtState::PRE_OPERATIONAL_1 | NmtState::PRE_OPERATIONAL_2
            ) {
                return Err(abort::DEVICE_STATE);
            }
            let outputs = index == RX_MAPPING;
            let map = if outputs {
                &mut cx.vars.rx_map
            } else {
                &mut cx.vars.tx_map
            };
            return map.write(self.product, outputs, sub, data);
        }
        if let Some(o) = self.object(index) {
            // The mapping is static (BU 0620 §2.4.1 "static mapping"), the identity fixed,
            // the process data objects written by PReq only.
            o.entry(sub).ok_or(abort::NO_SUBINDEX)?;
            return Err(abort::READ_ONLY);
        }
        let (unit, number, _) = self.parameter(cx.device, index)?;
        reachable(cx.vars, unit)?;
        cx.device.store(unit).map_err(|_| abort::NO_INVERTER)?;
        // Behind the gateway, an SDO download through the inverter's node.
        cx.device
            .gateway_write(unit, number, sub, data)
            .map_err(|r| r.abort)?;
        if unit == Unit::Interface {
            // P150 / P152 act at once (BU 2200 §7.1.1).
            cx.device.settle_interface();
        }
        Ok(())
    }
}
