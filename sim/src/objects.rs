//! The NORD parameters as SDO objects, shared by the CANopen-style buses (EtherCAT CoE,
//! POWERLINK): one sub-index of a parameter read or written on a parameter store, and the one
//! mapping of a store's refusal to an SDO abort code (CiA 301 table 22, EPSG DS 301 §6.3.2.4.3
//! — the same codes).
//!
//! Sub-indices (BU 0620 §2.2.7 and §2.4.6, BU 2200 §6.4, one table): a plain parameter's value
//! is sub-index 0; a parameter with sets or elements has the count at sub-index 0 and its values
//! from sub-index 1 (`proto::nord::ecat::parameter_subindex`).

use proto::canopen::Emergency;
use proto::nord::ecat::{parameter_data_type, parameter_subindex, DataType, ParamSub};
use proto::nord::errors::SdoAbort;
use proto::nord::params::{Access, ParamDef};
use proto::nord::ParamNumber;

use crate::store::{AccessError, ParamStore, Persist};

/// The CiA 301 abort codes the slave answers (CiA 301 table 22, ETG.1000.6 §5.6.2.7, EPSG DS 301 §6.3.2.4.3; BU 0620
/// §2.2.7.2 and §2.4.7 and BU 2200 §6.4.1 list them, with two printed differently: see
/// `proto::nord::errors`).
pub(crate) mod abort {
    use proto::nord::errors::SdoAbort;
    /// Toggle bit not alternated.
    pub(crate) const TOGGLE: SdoAbort = SdoAbort(0x0503_0000);
    /// SDO protocol timed out (a client's: the server did not answer).
    pub(crate) const TIMEOUT: SdoAbort = SdoAbort(0x0504_0000);
    /// Client/server command specifier not valid or unknown.
    pub(crate) const COMMAND: SdoAbort = SdoAbort(0x0504_0001);
    /// Out of memory.
    pub(crate) const NO_MEMORY: SdoAbort = SdoAbort(0x0504_0005);
    /// Unsupported access to an object (complete access where it cannot be).
    pub(crate) const UNSUPPORTED_ACCESS: SdoAbort = SdoAbort(0x0601_0000);
    /// Attempt to write a read-only object (BU 0620 prints 06020002h).
    pub(crate) const READ_ONLY: SdoAbort = SdoAbort(0x0601_0002);
    /// Object does not exist in the object dictionary.
    pub(crate) const NO_OBJECT: SdoAbort = SdoAbort(0x0602_0000);
    /// Object cannot be mapped to the PDO (a dynamic mapping entry, BU 2200 §6.3.6).
    pub(crate) const NOT_MAPPABLE: SdoAbort = SdoAbort(0x0604_0041);
    /// General parameter incompatibility (a dynamic mapping that does not fit together).
    pub(crate) const PARAMETER_INCOMPATIBLE: SdoAbort = SdoAbort(0x0604_0043);
    /// Data type does not match, length of service parameter too high.
    pub(crate) const TOO_LONG: SdoAbort = SdoAbort(0x0607_0012);
    /// Data type does not match, length of service parameter too low.
    pub(crate) const TOO_SHORT: SdoAbort = SdoAbort(0x0607_0013);
    /// Sub-index does not exist.
    pub(crate) const NO_SUBINDEX: SdoAbort = SdoAbort(0x0609_0011);
    /// Value range of parameter exceeded (written value not allowed).
    pub(crate) const VALUE_RANGE: SdoAbort = SdoAbort(0x0609_0030);
    /// Value of parameter written too high.
    pub(crate) const VALUE_TOO_HIGH: SdoAbort = SdoAbort(0x0609_0031);
    /// Value of parameter written too low.
    pub(crate) const VALUE_TOO_LOW: SdoAbort = SdoAbort(0x0609_0032);
    /// General error.
    pub(crate) const GENERAL: SdoAbort = SdoAbort(0x0800_0000);
    /// BU 0620 §2.2.7.2: "no communication between the bus interface and the frequency
    /// inverter": the addressed FI is not on the system bus.
    pub(crate) const NO_INVERTER: SdoAbort = SdoAbort(0x0800_0020);
    /// Data cannot be transferred or stored to the application because of the present device
    /// state.
    pub(crate) const DEVICE_STATE: SdoAbort = SdoAbort(0x0800_0022);
}

/// The one mapping of a parameter store's refusal to a CiA 301 abort code. `value` is the
/// value a write tried (for "too large" versus "too small").
pub(crate) fn abort_of(e: AccessError, value: i32, def: Option<&ParamDef>) -> SdoAbort {
    match e {
        AccessError::NoSuchParameter => abort::NO_OBJECT,
        AccessError::ReadOnly => abort::READ_ONLY,
        AccessError::OutOfRange => match def {
            Some(d) if value > d.max => abort::VALUE_TOO_HIGH,
            Some(d) if value < d.min => abort::VALUE_TOO_LOW,
            _ => abort::VALUE_RANGE,
        },
        AccessError::OnlyResettable => abort::VALUE_RANGE,
        AccessError::BadSubIndex | AccessError::NotAnArray => abort::NO_SUBINDEX,
    }
}

/// The emergency for an inverter error that appeared (P700 [-01] = `p700`, 0: none any more):
/// the DS402 code of BU 0620 §5.3 for communication errors (error register 11h), else FF00h
/// (manufacturer specific, error register 81h); bytes 3–4 the P700 value, byte 5 the FI. An
/// error reset is code 0000h with register 0 (CiA 301 "Emergency object"). Where the error
/// has several rows, `extended` (P700 [-04]) picks the row.
pub(crate) fn emergency_of(
    p700: i32,
    extended: Option<u16>,
    fi: proto::nord::Inverter,
) -> Emergency {
    if p700 == 0 {
        return Emergency::default();
    }
    let rows = || {
        proto::nord::errors::COMM_ERRORS
            .iter()
            .filter(|c| i32::from(c.p700) == p700)
    };
    let (code, register) = rows()
        .find(|c| Some(c.ds402) == extended)
        .or_else(|| rows().next())
        .map_or((0xFF00, 0x81), |c| (c.ds402, 0x11));
    let v = (p700 as u16).to_le_bytes();
    Emergency {
        code,
        register,
        data: [v[0], v[1], fi.get(), 0, 0],
    }
}

/// Little-endian bytes of `value` as `ty`.
pub(crate) fn encode_number(value: i64, ty: DataType) -> Vec<u8> {
    value.to_le_bytes()[..ty.bytes().min(8)].to_vec()
}

/// The value of a data-type-sized download, sign-extended for the signed types; the data
/// length is checked first (too long 06070012h, too short 06070013h).
pub(crate) fn decode_number(data: &[u8], ty: DataType) -> Result<i32, SdoAbort> {
    check_len(data.len(), ty.bytes())?;
    Ok(match ty {
        DataType::U8 => i32::from(data[0]),
        DataType::U16 => i32::from(u16::from_le_bytes([data[0], data[1]])),
        DataType::I16 => i32::from(i16::from_le_bytes([data[0], data[1]])),
        _ => i32::from_le_bytes([data[0], data[1], data[2], data[3]]),
    })
}

pub(crate) fn check_len(got: usize, want: usize) -> Result<(), SdoAbort> {
    match got.cmp(&want) {
        std::cmp::Ordering::Greater => Err(abort::TOO_LONG),
        std::cmp::Ordering::Less => Err(abort::TOO_SHORT),
        std::cmp::Ordering::Equal => Ok(()),
    }
}

/// A parameter access refused: the abort code, and the store's own reason where the store
/// refused (`None` where the object layout did: a sub-index, a data length, the count at
/// sub-index 0). The code is what goes on the wire; the reason is finer for some field buses
/// (a parameter channel tells "no array" from "faulty sub-index", one abort code for both).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Refused {
    /// The CiA 301 abort code.
    pub(crate) abort: SdoAbort,
    /// The store's reason.
    pub(crate) cause: Option<AccessError>,
}

impl From<SdoAbort> for Refused {
    fn from(abort: SdoAbort) -> Refused {
        Refused { abort, cause: None }
    }
}

/// Uploads sub-index `sub` of parameter `number` (`def` its definition) from `store`.
pub(crate) fn read_sub(
    store: &ParamStore,
    number: ParamNumber,
    def: &ParamDef,
    sub: u8,
) -> Result<Vec<u8>, SdoAbort> {
    read_value(store, number, def, sub).map_err(|r| r.abort)
}

/// [`read_sub`], with the store's reason of a refusal.
pub(crate) fn read_value(
    store: &ParamStore,
    number: ParamNumber,
    def: &ParamDef,
    sub: u8,
) -> Result<Vec<u8>, Refused> {
    match parameter_subindex(sub, def.set_dependent, def.array) {
        None => Err(abort::NO_SUBINDEX.into()),
        Some(ParamSub::Count(n)) => Ok(vec![n]),
        Some(ParamSub::Value(set, element)) => store
            .read(number, set, element)
            .map(|v| encode_number(i64::from(v), parameter_data_type(def)))
            .map_err(|e| Refused {
                abort: abort_of(e, 0, Some(def)),
                cause: Some(e),
            }),
    }
}

/// Downloads `data` to sub-index `sub` of parameter `number` in `store` (kept in EEPROM, as a
/// bus write is): the count at sub-index 0 and read-only parameters refuse, the data length
/// must be the parameter's type's, the value its range.
pub(crate) fn write_value(
    store: &mut ParamStore,
    number: ParamNumber,
    def: &ParamDef,
    sub: u8,
    data: &[u8],
) -> Result<(), Refused> {
    let (set, element) = match parameter_subindex(sub, def.set_dependent, def.array) {
        None => return Err(abort::NO_SUBINDEX.into()),
        Some(ParamSub::Count(_)) => return Err(abort::READ_ONLY.into()),
        Some(ParamSub::Value(s, e)) => (s, e),
    };
    if def.access == Access::ReadOnly {
        return Err(Refused {
            abort: abort::READ_ONLY,
            cause: Some(AccessError::ReadOnly),
        });
    }
    let v = decode_number(data, parameter_data_type(def))?;
    store
        .write(number, set, element, v, Persist::Eeprom)
        .map_err(|e| Refused {
            abort: abort_of(e, v, Some(def)),
            cause: Some(e),
        })
}
