//! The CoE object dictionary: the objects of BU 0620 §2.2.7.1 (`proto::nord::ecat`) and the
//! NORD parameter objects 2000h + 800h·(FI−1) + P (§2.2.7) on the device's parameter stores.
//!
//! Sub-indices of a parameter (§2.2.7 "Information"): a plain parameter's value is sub-index 0;
//! a parameter with sets or elements has "the maximum size of the array" at sub-index 0 and its
//! values from sub-index 1 (`proto::nord::ecat::parameter_subindex`). Complete access (ETG.1000.6
//! §5.6.2.1) transfers sub-index 0 as 16 bits (the U8 and a padding byte), then every value.
//!
//! Refusals are CiA 301 abort codes; [`abort_of`] is the one place a parameter store's refusal
//! becomes one.

use proto::nord::ecat::{
    self as def, parameter_data_type, parameter_object, parameter_subindex, DataType, EntryAccess,
    Object, ObjectCode, ParamSub, Value,
};
use proto::nord::params::{Access, ParamDef};
use proto::nord::ParamNumber;

use super::pdo::ProcessWords;
use crate::device::Device;
use crate::link::Unit;
use crate::objects::{abort, abort_of, check_len, decode_number, encode_number, read_sub};
use crate::store::Persist;
use proto::nord::errors::SdoAbort;

/// The parameter that holds the Hot Connect "Second Address" under EtherCAT (BU 0620 §4.2.1
/// P850, 0…4096, adopted at POWER ON).
pub(crate) const SECOND_ADDRESS_PARAM: u16 = 850;

/// What the dictionary reads and writes besides itself.
pub(crate) struct Context<'a> {
    /// The device and its parameter stores.
    pub(crate) device: &'a mut Device,
    /// The process data words last exchanged.
    pub(crate) words: &'a ProcessWords,
    /// P850 "Second Address" as set (adopted at the next power-on).
    pub(crate) second_address: &'a mut u16,
}

/// What an index addresses.
enum Target<'o> {
    Standard(&'o Object),
    Parameter {
        unit: Unit,
        number: ParamNumber,
        def: &'static ParamDef,
    },
    SecondAddress,
}

/// The object dictionary of a device with a given number of inverters.
#[derive(Debug, Clone)]
pub(crate) struct Dictionary {
    objects: Vec<Object>,
    inverters: u8,
}

impl Dictionary {
    /// The dictionary of `inverters` inverters.
    pub(crate) fn new(inverters: u8) -> Dictionary {
        Dictionary {
            objects: def::object_dictionary(inverters),
            inverters,
        }
    }

    /// The standard object at `index`, if any.
    pub(crate) fn object(&self, index: u16) -> Option<&Object> {
        self.objects.iter().find(|o| o.index == index)
    }

    fn resolve(&self, cx: &mut Context<'_>, index: u16) -> Result<Target<'_>, SdoAbort> {
        if let Some(o) = self.object(index) {
            return Ok(Target::Standard(o));
        }
        let (fi, raw) = parameter_object(index).ok_or(abort::NO_OBJECT)?;
        let number = ParamNumber::new(i64::from(raw)).map_err(|_| abort::NO_OBJECT)?;
        if fi.get() > self.inverters {
            // §2.2.7.2 08000020h: "no communication between the bus interface and the FI".
            return Err(abort::NO_INVERTER);
        }
        if fi.get() == 1 && raw == SECOND_ADDRESS_PARAM {
            return Ok(Target::SecondAddress);
        }
        // The SK 550P's interface is built into FI 1: its P85x–P89x answer there.
        let iface = cx.device.store(Unit::Interface).ok();
        let unit = match iface.and_then(|s| s.def(number)) {
            Some(_) if fi.get() == 1 => Unit::Interface,
            _ => Unit::Inverter(fi),
        };
        let store = cx.device.store(unit).map_err(|_| abort::NO_INVERTER)?;
        let def = store.def(number).ok_or(abort::NO_OBJECT)?;
        Ok(Target::Parameter { unit, number, def })
    }

    /// SDO upload of `index`:`sub` (every sub-index from `sub` with complete access).
    pub(crate) fn upload(
        &self,
        cx: &mut Context<'_>,
        index: u16,
        sub: u8,
        complete: bool,
    ) -> Result<Vec<u8>, SdoAbort> {
        match self.resolve(cx, index)? {
            Target::Standard(o) => upload_standard(o, cx.words, sub, complete),
            Target::SecondAddress => match (sub, complete) {
                (0, false) => Ok(encode_number(i64::from(*cx.second_address), DataType::U16)),
                (_, true) => Err(abort::UNSUPPORTED_ACCESS),
                _ => Err(abort::NO_SUBINDEX),
            },
            Target::Parameter { unit, number, def } => {
                if !complete {
                    // Behind the gateway, an SDO upload from the inverter's node.
                    return cx
                        .device
                        .gateway_read(unit, number, sub)
                        .map_err(|r| r.abort);
                }
                let store = cx.device.store(unit).map_err(|_| abort::NO_INVERTER)?;
                let read = |s: u8| read_sub(store, number, def, s);
                let count = def::parameter_count(def.set_dependent, def.array)
                    .ok_or(abort::UNSUPPORTED_ACCESS)?;
                let mut out = Vec::new();
                match sub {
                    0 => out.extend([count, 0]),
                    1 => {}
                    _ => return Err(abort::UNSUPPORTED_ACCESS),
                }
                for s in 1..=count {
                    out.extend(read(s)?);
                }
                Ok(out)
            }
        }
    }

    /// SDO download of `data` to `index`:`sub` (every sub-index from `sub` with complete
    /// access).
    pub(crate) fn download(
        &self,
        cx: &mut Context<'_>,
        index: u16,
        sub: u8,
        complete: bool,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        match self.resolve(cx, index)? {
            Target::Standard(o) => {
                if !complete && o.entry(sub).is_none() {
                    return Err(abort::NO_SUBINDEX);
                }
                if complete && (o.code == ObjectCode::Var || sub > 1) {
                    return Err(abort::UNSUPPORTED_ACCESS);
                }
                // Every object of §2.2.7.1 is RO (the process data layout is fixed, §2.2.6).
                debug_assert!(o.entries.iter().all(|e| e.access == EntryAccess::Ro));
                Err(abort::READ_ONLY)
            }
            Target::SecondAddress => {
                if complete {
                    return Err(abort::UNSUPPORTED_ACCESS);
                }
                if sub != 0 {
                    return Err(abort::NO_SUBINDEX);
                }
                let v = decode_number(data, DataType::U16)?;
                if v > i32::from(def::SECOND_ADDRESS_MAX) {
                    return Err(abort::VALUE_TOO_HIGH);
                }
                *cx.second_address = v as u16;
                Ok(())
            }
            Target::Parameter { unit, number, def } => {
                let store = cx.device.store(unit).map_err(|_| abort::NO_INVERTER)?;
                let ty = parameter_data_type(def);
                let count = def::parameter_count(def.set_dependent, def.array);
                if complete {
                    let count = count.ok_or(abort::UNSUPPORTED_ACCESS)?;
                    let values = match sub {
                        0 => data.get(2..).unwrap_or_default(),
                        1 => data,
                        _ => return Err(abort::UNSUPPORTED_ACCESS),
                    };
                    if def.access == Access::ReadOnly {
                        return Err(abort::READ_ONLY);
                    }
                    let header = if sub == 0 { 2 } else { 0 };
                    check_len(data.len(), header + usize::from(count) * ty.bytes())?;
                    for (s, chunk) in (1..=count).zip(values.chunks_exact(ty.bytes())) {
                        let Some(ParamSub::Value(set, element)) =
                            parameter_subindex(s, def.set_dependent, def.array)
                        else {
                            return Err(abort::NO_SUBINDEX);
                        };
                        let v = decode_number(chunk, ty)?;
                        store
                            .write(number, set, element, v, Persist::Eeprom)
                            .map_err(|e| abort_of(e, v, Some(def)))?;
                    }
                    return Ok(());
                }
                // Behind the gateway, an SDO download through the inverter's node.
                cx.device
                    .gateway_write(unit, number, sub, data)
                    .map_err(|r| r.abort)
            }
        }
    }
}

/// The bytes of a standard object's entry.
fn encode_entry(value: &Value, ty: DataType, words: &ProcessWords) -> Vec<u8> {
    let word = |table: &[[u16; 6]; 8], inverter: u8, w: u8| {
        let fi = usize::from(inverter.saturating_sub(1)).min(7);
        table[fi][usize::from(w).min(5)]
    };
    match value {
        Value::Number(n) => n.to_le_bytes()[..ty.bytes().min(8)].to_vec(),
        Value::Text(s) => s.as_bytes().to_vec(),
        Value::Output { inverter, word: w } => {
            encode_number(i64::from(word(&words.outputs, *inverter, *w)), ty)
        }
        Value::Input { inverter, word: w } => {
            encode_number(i64::from(word(&words.inputs, *inverter, *w)), ty)
        }
    }
}

pub(crate) fn upload_standard(
    o: &Object,
    words: &ProcessWords,
    sub: u8,
    complete: bool,
) -> Result<Vec<u8>, SdoAbort> {
    if !complete {
        let e = o.entry(sub).ok_or(abort::NO_SUBINDEX)?;
        return Ok(encode_entry(&e.value, e.data_type, words));
    }
    if o.code == ObjectCode::Var || sub > 1 {
        return Err(abort::UNSUPPORTED_ACCESS);
    }
    let mut out = Vec::new();
    for e in o.entries.iter().filter(|e| e.sub >= sub) {
        out.extend(encode_entry(&e.value, e.data_type, words));
        if e.sub == 0 {
            out.push(0);
        }
    }
    Ok(out)
}
