//! The SDO server of one CANopen node (CiA 301 §7.2.4.3): expedited and segmented transfers of
//! the node's objects, each refusal the standard's abort code; and the objects every inverter's
//! node has, its parameters at 2000h + P ([`ParameterObjects`]).
//!
//! It sits apart from `crate::can` (the nodes on a CAN segment) because two owners serve with
//! it: each node of a `crate::can::Segment`, and the bus interface's gateway
//! (`crate::system_bus`), which reaches the inverters' nodes behind a field-bus device without a
//! whole segment. One server, so that a parameter answers on the system bus behind a field bus
//! exactly as it answers a CANopen master on the segment.
//!
//! Block transfers are optional in CiA 301 and not served: their initiate gets abort 05040001h
//! ("client/server command specifier not valid or unknown"), as from a server without them.

use proto::canopen::sdo::{Abort, Expedited, InitiateData, SdoRequest, SdoResponse, SegmentData};
use proto::canopen::SdoAbortCode;
use proto::nord::errors::SdoAbort;
use proto::nord::ParamNumber;

use crate::objects::{abort, read_value, write_value, Refused};
use crate::store::{AccessError, ParamStore};

/// The parameters: P at 2000h + P (`proto::nord::can::parameter_sdo`, the project's EtherCAT
/// layout with one node per inverter).
pub(crate) const PARAMETERS: u16 = proto::nord::ecat::PARAMETER_BASE;
/// The last parameter object, 2000h + 999.
pub(crate) const LAST_PARAMETER: u16 = PARAMETERS + 999;

/// One node's SDO server: the transfer under way, and what it answered, counted (a node's
/// own record of its traffic, which tests read to see that a request reached it).
#[derive(Debug, Default)]
pub(crate) struct SdoServer {
    transfer: Transfer,
    answered: u32,
    aborted: u32,
}

impl SdoServer {
    /// Serves one request frame's data (8 bytes from the client); `None` when the standard has
    /// the server stay silent (an abort from the client).
    pub(crate) fn serve(&mut self, frame: &[u8], od: &mut dyn Objects) -> Option<SdoResponse> {
        let answer = self.transfer.serve(frame, od)?;
        self.answered += 1;
        if matches!(answer, SdoResponse::Abort(_)) {
            self.aborted += 1;
        }
        Some(answer)
    }

    /// Drops a transfer under way (NMT reset node / reset communication).
    pub(crate) fn reset(&mut self) {
        self.transfer = Transfer::Idle;
    }

    /// The frames answered so far, and how many of them were aborts.
    #[cfg(test)]
    pub(crate) fn counts(&self) -> (u32, u32) {
        (self.answered, self.aborted)
    }
}

/// The parameter objects 2000h + P of one inverter's store (its sets and elements as
/// sub-indices, `proto::nord::ecat::parameter_subindex`); any other index does not exist here.
///
/// A refusal goes on the wire as its abort code; the store's own reason is kept beside it
/// ([`ParameterObjects::cause`]), because the code is coarser than what some field buses report
/// (see `crate::system_bus`).
pub(crate) struct ParameterObjects<'a> {
    store: &'a mut ParamStore,
    cause: Option<AccessError>,
}

impl<'a> ParameterObjects<'a> {
    /// The parameters of `store`.
    pub(crate) fn new(store: &'a mut ParamStore) -> ParameterObjects<'a> {
        ParameterObjects { store, cause: None }
    }

    /// Why the store refused the last access, where the store refused it (not a sub-index or a
    /// data length the object layout refused before).
    pub(crate) fn cause(&self) -> Option<AccessError> {
        self.cause
    }

    fn serve<T>(
        &mut self,
        index: u16,
        access: impl FnOnce(
            &mut ParamStore,
            ParamNumber,
            &'static proto::nord::params::ParamDef,
        ) -> Result<T, Refused>,
    ) -> Result<T, SdoAbort> {
        self.cause = None;
        if !(PARAMETERS..=LAST_PARAMETER).contains(&index) {
            return Err(abort::NO_OBJECT);
        }
        let number =
            ParamNumber::new(i64::from(index - PARAMETERS)).map_err(|_| abort::NO_OBJECT)?;
        let def = self.store.def(number).ok_or(abort::NO_OBJECT)?;
        access(self.store, number, def).map_err(|r| {
            self.cause = r.cause;
            r.abort
        })
    }
}

impl Objects for ParameterObjects<'_> {
    fn upload(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, SdoAbort> {
        self.serve(index, |store, number, def| {
            read_value(store, number, def, sub)
        })
    }

    fn download(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.serve(index, |store, number, def| {
            write_value(store, number, def, sub, data)
        })
    }
}

/// A transfer under way.
#[derive(Debug, Clone, Default)]
enum Transfer {
    /// None.
    #[default]
    Idle,
    /// A segmented download: the segments so far, the size announced, the toggle expected.
    Download {
        index: u16,
        sub: u8,
        size: Option<u32>,
        data: Vec<u8>,
        toggle: bool,
    },
    /// A segmented upload: the object's bytes, how many went out, the toggle expected.
    Upload {
        index: u16,
        sub: u8,
        data: Vec<u8>,
        sent: usize,
        toggle: bool,
    },
}

/// The longest segmented download the server takes (bytes); the node's objects are far
/// shorter, and a longer one is refused with 05040005h "out of memory" instead of growing.
const MAX_DOWNLOAD: usize = 256;

/// What the server needs of the node's object dictionary.
pub(crate) trait Objects {
    /// The bytes of `index`:`sub`.
    fn upload(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, SdoAbort>;
    /// Writes `data` to `index`:`sub`.
    fn download(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort>;
}

fn refuse(index: u16, sub: u8, code: SdoAbort) -> SdoResponse {
    SdoResponse::Abort(Abort {
        index,
        sub,
        code: SdoAbortCode(code.0),
    })
}

impl Transfer {
    /// The object a transfer under way is about (0, 0 when none).
    fn object(&self) -> (u16, u8) {
        match self {
            Transfer::Idle => (0, 0),
            Transfer::Download { index, sub, .. } | Transfer::Upload { index, sub, .. } => {
                (*index, *sub)
            }
        }
    }

    /// Serves one request frame (8 bytes from the client); `None` when the standard has the
    /// server stay silent (an abort from the client).
    fn serve(&mut self, frame: &[u8], od: &mut dyn Objects) -> Option<SdoResponse> {
        let (index, sub) = self.object();
        let request = match SdoRequest::parse(frame) {
            Ok(r) => r,
            Err(_) => {
                *self = Transfer::Idle;
                return Some(refuse(index, sub, abort::COMMAND));
            }
        };
        match (request, std::mem::take(self)) {
            (SdoRequest::Abort(_), _) => None,
            (SdoRequest::InitiateUpload { index, sub }, _) => {
                Some(self.initiate_upload(index, sub, od))
            }
            (SdoRequest::InitiateDownload { index, sub, data }, _) => match data {
                InitiateData::Expedited(e) => Some(match od.download(index, sub, e.data()) {
                    Ok(()) => SdoResponse::InitiateDownload { index, sub },
                    Err(code) => refuse(index, sub, code),
                }),
                InitiateData::Segmented { size } => {
                    if size.is_some_and(|s| s as usize > MAX_DOWNLOAD) {
                        return Some(refuse(index, sub, abort::NO_MEMORY));
                    }
                    *self = Transfer::Download {
                        index,
                        sub,
                        size,
                        data: Vec::new(),
                        toggle: false,
                    };
                    Some(SdoResponse::InitiateDownload { index, sub })
                }
            },
            (
                SdoRequest::DownloadSegment { toggle, last, data },
                Transfer::Download {
                    index,
                    sub,
                    size,
                    data: mut so_far,
                    toggle: expected,
                },
            ) => {
                if toggle != expected {
                    return Some(refuse(index, sub, abort::TOGGLE));
                }
                so_far.extend_from_slice(data.data());
                if so_far.len() > MAX_DOWNLOAD {
                    return Some(refuse(index, sub, abort::NO_MEMORY));
                }
                if !last {
                    *self = Transfer::Download {
                        index,
                        sub,
                        size,
                        data: so_far,
                        toggle: !toggle,
                    };
                    return Some(SdoResponse::DownloadSegment { toggle });
                }
                let written = match size {
                    Some(s) if s as usize > so_far.len() => Err(abort::TOO_SHORT),
                    Some(s) if (s as usize) < so_far.len() => Err(abort::TOO_LONG),
                    _ => od.download(index, sub, &so_far),
                };
                Some(match written {
                    Ok(()) => SdoResponse::DownloadSegment { toggle },
                    Err(code) => refuse(index, sub, code),
                })
            }
            (
                SdoRequest::UploadSegment { toggle },
                Transfer::Upload {
                    index,
                    sub,
                    data,
                    sent,
                    toggle: expected,
                },
            ) => {
                if toggle != expected {
                    return Some(refuse(index, sub, abort::TOGGLE));
                }
                let end = (sent + proto::canopen::command::SEGMENT_DATA).min(data.len());
                let last = end == data.len();
                let segment = SegmentData::new(&data[sent..end]).ok()?;
                if !last {
                    *self = Transfer::Upload {
                        index,
                        sub,
                        data,
                        sent: end,
                        toggle: !toggle,
                    };
                }
                Some(SdoResponse::UploadSegment {
                    toggle,
                    last,
                    data: segment,
                })
            }
            // A segment outside its transfer, or a block transfer.
            (_, _) => Some(refuse(index, sub, abort::COMMAND)),
        }
    }

    fn initiate_upload(&mut self, index: u16, sub: u8, od: &mut dyn Objects) -> SdoResponse {
        match od.upload(index, sub) {
            Err(code) => refuse(index, sub, code),
            Ok(data) if data.len() <= 4 && !data.is_empty() => SdoResponse::InitiateUpload {
                index,
                sub,
                data: InitiateData::Expedited(
                    Expedited::new(&data).unwrap_or_else(|_| Expedited::without_size([0; 4])),
                ),
            },
            Ok(data) => {
                let size = data.len() as u32;
                *self = Transfer::Upload {
                    index,
                    sub,
                    data,
                    sent: 0,
                    toggle: false,
                };
                SdoResponse::InitiateUpload {
                    index,
                    sub,
                    data: InitiateData::Segmented { size: Some(size) },
                }
            }
        }
    }
}
