//! The bus interface's gateway to its inverters' parameters: the SDO client side of the system
//! bus. A field-bus read or write of a parameter of FI n on the system bus becomes CiA 301 SDO
//! request frames to FI n's node (32 + 2·(n − 1), object 2000h + P, sub-index from set and
//! element; `proto::nord::can::parameter_sdo`), which the node's own SDO server
//! ([`crate::sdo_server`]) answers on FI n's parameter store; the response frames, parsed back
//! from their bytes, give the value or the refusal the field bus reports.
//!
//! Transfers: expedited for 1 to 4 bytes, segmented otherwise (CiA 301 §7.2.4.3.3–§7.2.4.3.7).
//! Every NORD parameter is 1, 2 or 4 bytes, so a parameter is read and written expedited; a
//! field-bus write of another length (a CoE or POWERLINK download of the wrong size) goes
//! segmented, and the node refuses it as the parameter's length check says (06070012h,
//! 06070013h). Beyond the longest download the node takes (256 bytes), the gateway refuses
//! with 06070012h itself instead of sending segments the node would refuse as "out of memory":
//! a parameter is never that long, and the field bus then answers as it did before the gateway
//! was real.
//!
//! The client checks what comes back as CiA 301 has a client check it: an answer of another
//! kind, index or sub-index, or a segment with the wrong toggle bit, is aborted by the client
//! (an abort request to the node, 05040001h or 05030000h); a node that stays silent is
//! 05040000h "SDO protocol timed out".
//!
//! In-process and sans-IO: no thread, no socket, no clock; one request, then the node's answer,
//! until the transfer ends. The frames are the ones exchanged, in order, handed to the caller to
//! record ([`super::Tap::exchanged`]).

use proto::can::CanFrame;
use proto::canopen::cob_id::Function;
use proto::canopen::command::SEGMENT_DATA;
use proto::canopen::sdo::{Abort, Expedited, InitiateData, SdoRequest, SdoResponse, SegmentData};
use proto::canopen::SdoAbortCode;
use proto::nord::can::SystemBusAddress;
use proto::nord::errors::SdoAbort;
use proto::nord::{Family, Inverter, Product};

use crate::objects::{abort, Refused};
use crate::sdo_server::{ParameterObjects, SdoServer};
use crate::store::ParamStore;

use super::ProcessData;

/// The longest transfer the gateway starts: the node's server takes no longer download.
const MAX_TRANSFER: usize = 256;

/// The gateway: the SDO server of each inverter's node, FI 1 first, and the process data with
/// the nodes ([`super::ProcessData`]).
#[derive(Debug)]
pub(crate) struct Gateway {
    product: Product,
    servers: Vec<SdoServer>,
    process: ProcessData,
}

impl Gateway {
    /// The gateway of `product` to `inverters` inverters.
    pub(crate) fn new(product: Product, inverters: u8) -> Gateway {
        Gateway {
            product,
            servers: (0..inverters).map(|_| SdoServer::default()).collect(),
            process: ProcessData::new(product, inverters),
        }
    }

    /// The process data with the nodes: for the inverters it reaches ([`Gateway::reaches`]).
    pub(crate) fn process_data(&mut self) -> &mut ProcessData {
        &mut self.process
    }

    /// Whether FI `fi` is reached over the system bus: every inverter behind a bus module;
    /// behind the SK 550P FI 2…8, FI 1 being the device itself (BU 0620 §2.1).
    pub(crate) fn reaches(&self, fi: Inverter) -> bool {
        let own = self.product.family() == Family::Integrated && fi.get() == 1;
        !own && usize::from(fi.get()) <= self.servers.len()
    }

    /// FI `fi`'s node's SDO server.
    #[cfg(test)]
    pub(crate) fn server(&self, fi: Inverter) -> Option<&SdoServer> {
        self.servers.get(usize::from(fi.get()) - 1)
    }

    fn client<'a>(
        &'a mut self,
        fi: Inverter,
        store: &'a mut ParamStore,
        index: u16,
        sub: u8,
        wire: &'a mut Vec<CanFrame>,
    ) -> Result<Client<'a>, Refused> {
        if !self.reaches(fi) {
            return Err(abort::NO_INVERTER.into());
        }
        let server = self
            .servers
            .get_mut(usize::from(fi.get()) - 1)
            .ok_or(Refused::from(abort::NO_INVERTER))?;
        Ok(Client {
            node: SystemBusAddress::inverter(fi).get(),
            index,
            sub,
            server,
            objects: ParameterObjects::new(store),
            wire,
        })
    }

    /// Reads `index`:`sub` of FI `fi` (its parameters in `store`) from its node; the frames
    /// exchanged are appended to `wire`.
    pub(crate) fn upload(
        &mut self,
        fi: Inverter,
        store: &mut ParamStore,
        index: u16,
        sub: u8,
        wire: &mut Vec<CanFrame>,
    ) -> Result<Vec<u8>, Refused> {
        self.client(fi, store, index, sub, wire)?.upload()
    }

    /// Writes `data` to `index`:`sub` of FI `fi` (its parameters in `store`) through its node;
    /// the frames exchanged are appended to `wire`.
    pub(crate) fn download(
        &mut self,
        fi: Inverter,
        store: &mut ParamStore,
        index: u16,
        sub: u8,
        data: &[u8],
        wire: &mut Vec<CanFrame>,
    ) -> Result<(), Refused> {
        self.client(fi, store, index, sub, wire)?.download(data)
    }
}

/// One transfer with one node.
struct Client<'a> {
    node: u8,
    index: u16,
    sub: u8,
    server: &'a mut SdoServer,
    /// The node's parameter objects, which its server answers from.
    objects: ParameterObjects<'a>,
    wire: &'a mut Vec<CanFrame>,
}

impl Client<'_> {
    /// Puts `request` on the bus to the node and parses the node's answer from the bus.
    fn ask(&mut self, request: SdoRequest) -> Result<SdoResponse, Refused> {
        let sent = self.frame(Function::SdoRx, &request.emit())?;
        let answer = self.server.serve(sent.data(), &mut self.objects);
        self.wire.push(sent);
        let Some(answer) = answer else {
            return Err(abort::TIMEOUT.into());
        };
        let got = self.frame(Function::SdoTx, &answer.emit())?;
        let parsed = SdoResponse::parse(got.data());
        self.wire.push(got);
        match parsed {
            Ok(SdoResponse::Abort(a)) => Err(Refused {
                abort: SdoAbort(a.code.0),
                // The node's store's own reason, where the store refused: kept beside the code
                // for the field buses whose errors are finer (see `crate::system_bus`).
                cause: self.objects.cause(),
            }),
            Ok(r) => Ok(r),
            Err(_) => self.abort(abort::COMMAND),
        }
    }

    /// The client aborts the transfer: an abort request to the node, and the refusal.
    fn abort<T>(&mut self, code: SdoAbort) -> Result<T, Refused> {
        let request = SdoRequest::Abort(Abort {
            index: self.index,
            sub: self.sub,
            code: SdoAbortCode(code.0),
        });
        let sent = self.frame(Function::SdoRx, &request.emit())?;
        // The server stays silent to an abort (CiA 301 §7.2.4.3.17).
        let _ = self.server.serve(sent.data(), &mut self.objects);
        self.wire.push(sent);
        Err(code.into())
    }

    fn frame(&self, function: Function, data: &[u8]) -> Result<CanFrame, Refused> {
        function
            .cob_id(self.node)
            .ok()
            .and_then(|id| CanFrame::new(id, data).ok())
            .ok_or(Refused::from(abort::GENERAL))
    }

    /// Whether an answer is about the object asked for.
    fn about(&self, index: u16, sub: u8) -> bool {
        (index, sub) == (self.index, self.sub)
    }

    fn upload(mut self) -> Result<Vec<u8>, Refused> {
        let (index, sub) = (self.index, self.sub);
        match self.ask(SdoRequest::InitiateUpload { index, sub })? {
            SdoResponse::InitiateUpload { index, sub, data } if self.about(index, sub) => {
                match data {
                    InitiateData::Expedited(e) => Ok(e.data().to_vec()),
                    InitiateData::Segmented { size } => self.upload_segments(size),
                }
            }
            _ => self.abort(abort::COMMAND),
        }
    }

    fn upload_segments(&mut self, size: Option<u32>) -> Result<Vec<u8>, Refused> {
        let mut data = Vec::new();
        let mut toggle = false;
        while data.len() <= MAX_TRANSFER {
            match self.ask(SdoRequest::UploadSegment { toggle })? {
                SdoResponse::UploadSegment {
                    toggle: t,
                    last,
                    data: segment,
                } if t == toggle => {
                    data.extend_from_slice(segment.data());
                    if last {
                        return match size.map(|s| (s as usize).cmp(&data.len())) {
                            Some(std::cmp::Ordering::Less) => self.abort(abort::TOO_LONG),
                            Some(std::cmp::Ordering::Greater) => self.abort(abort::TOO_SHORT),
                            _ => Ok(data),
                        };
                    }
                    toggle = !toggle;
                }
                SdoResponse::UploadSegment { .. } => return self.abort(abort::TOGGLE),
                _ => return self.abort(abort::COMMAND),
            }
        }
        self.abort(abort::NO_MEMORY)
    }

    fn download(mut self, data: &[u8]) -> Result<(), Refused> {
        let (index, sub) = (self.index, self.sub);
        if data.len() > MAX_TRANSFER {
            return Err(abort::TOO_LONG.into());
        }
        let initiate = match Expedited::new(data) {
            Ok(e) => InitiateData::Expedited(e),
            Err(_) => InitiateData::Segmented {
                size: Some(data.len() as u32),
            },
        };
        let segmented = matches!(initiate, InitiateData::Segmented { .. });
        match self.ask(SdoRequest::InitiateDownload {
            index,
            sub,
            data: initiate,
        })? {
            SdoResponse::InitiateDownload { index, sub } if self.about(index, sub) => {}
            _ => return self.abort(abort::COMMAND),
        }
        if !segmented {
            return Ok(());
        }
        // At least one segment, the last: an empty download is one segment of no data.
        let mut chunks = data.chunks(SEGMENT_DATA).peekable();
        let mut toggle = false;
        loop {
            let chunk = chunks.next().unwrap_or_default();
            let last = chunks.peek().is_none();
            let segment = SegmentData::new(chunk).map_err(|_| Refused::from(abort::GENERAL))?;
            match self.ask(SdoRequest::DownloadSegment {
                toggle,
                last,
                data: segment,
            })? {
                SdoResponse::DownloadSegment { toggle: t } if t == toggle => {}
                SdoResponse::DownloadSegment { .. } => return self.abort(abort::TOGGLE),
                _ => return self.abort(abort::COMMAND),
            }
            if last {
                return Ok(());
            }
            toggle = !toggle;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::{AccessError, Target};
    use crate::system_bus::hex;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    /// FI 3 behind an SK TU4-EIP: its store and the gateway to it.
    fn fi3() -> (Gateway, ParamStore) {
        let store = ParamStore::new(Product::Tu4Eip, Target::Inverter(fi(3)));
        (Gateway::new(Product::Tu4Eip, 4), store)
    }

    #[test]
    fn a_write_and_a_read_are_expedited_transfers_the_node_serves() {
        let (mut gw, mut store) = fi3();
        let mut wire = Vec::new();
        // P102 set 1 (2066h:01) := 250, then read back.
        let written = gw.download(
            fi(3),
            &mut store,
            0x2066,
            1,
            &250i16.to_le_bytes(),
            &mut wire,
        );
        assert_eq!(written, Ok(()));
        let read = gw.upload(fi(3), &mut store, 0x2066, 1, &mut wire);
        assert_eq!(read, Ok(vec![0xFA, 0x00]));
        // Node 36 (FI 3): requests on 624h, the node's answers on 5A4h (CiA 301 §7.2.4.3.3,
        // §7.2.4.3.6: 2Bh download of 2 bytes, 60h done, 40h upload, 4Bh 2 bytes).
        assert_eq!(
            hex(&wire),
            [
                "624 2B 66 20 01 FA 00 00 00",
                "5A4 60 66 20 01 00 00 00 00",
                "624 40 66 20 01 00 00 00 00",
                "5A4 4B 66 20 01 FA 00 00 00",
            ]
        );
        assert_eq!(gw.server(fi(3)).map(SdoServer::counts), Some((2, 0)));
        assert_eq!(gw.server(fi(2)).map(SdoServer::counts), Some((0, 0)));
    }

    #[test]
    fn the_nodes_aborts_come_back_with_the_stores_reason() {
        let (mut gw, mut store) = fi3();
        let mut wire = Vec::new();
        // P102 above its 32000: the node's store refuses, 06090031h "value too high".
        let too_high = gw.download(
            fi(3),
            &mut store,
            0x2066,
            1,
            &32001i16.to_le_bytes(),
            &mut wire,
        );
        assert_eq!(
            too_high,
            Err(Refused {
                abort: abort::VALUE_TOO_HIGH,
                cause: Some(AccessError::OutOfRange),
            })
        );
        assert_eq!(hex(&wire[1..]), ["5A4 80 66 20 01 31 00 09 06"]);
        // P150 is the module's, not the inverter's: 06020000h, refused by the object layout
        // before any store (no reason beside the code).
        let none = gw.upload(fi(3), &mut store, 0x2096, 0, &mut wire);
        assert_eq!(none, Err(abort::NO_OBJECT.into()));
        assert_eq!(hex(&wire[3..]), ["5A4 80 96 20 00 00 00 02 06"]);
        // P102 set 5 does not exist: 06090011h, the layout's.
        let sub = gw.upload(fi(3), &mut store, 0x2066, 5, &mut wire);
        assert_eq!(sub, Err(abort::NO_SUBINDEX.into()));
        assert_eq!(gw.server(fi(3)).map(SdoServer::counts), Some((3, 3)));
    }

    #[test]
    fn a_write_of_another_length_is_segmented_and_refused_by_the_node() {
        let (mut gw, mut store) = fi3();
        let mut wire = Vec::new();
        let r = gw.download(
            fi(3),
            &mut store,
            0x2066,
            1,
            &[1, 2, 3, 4, 5, 6, 7, 8],
            &mut wire,
        );
        assert_eq!(r, Err(abort::TOO_LONG.into()));
        // Initiate with the size (21h, 8 bytes), a segment of 7 (00h), the last of 1 (1Dh:
        // toggle, 6 bytes unused, last), the node's 06070012h.
        assert_eq!(
            hex(&wire),
            [
                "624 21 66 20 01 08 00 00 00",
                "5A4 60 66 20 01 00 00 00 00",
                "624 00 01 02 03 04 05 06 07",
                "5A4 20 00 00 00 00 00 00 00",
                "624 1D 08 00 00 00 00 00 00",
                "5A4 80 66 20 01 12 00 07 06",
            ]
        );
        // An empty write: one empty last segment (0Fh), the node's 06070013h.
        let mut wire = Vec::new();
        let r = gw.download(fi(3), &mut store, 0x2066, 1, &[], &mut wire);
        assert_eq!(r, Err(abort::TOO_SHORT.into()));
        assert_eq!(hex(&wire[2..3]), ["624 0F 00 00 00 00 00 00 00"]);
        // Longer than any node takes: refused before the bus.
        let mut wire = Vec::new();
        let r = gw.download(fi(3), &mut store, 0x2066, 1, &[0; 300], &mut wire);
        assert_eq!((r, wire.len()), (Err(abort::TOO_LONG.into()), 0));
    }

    #[test]
    fn behind_the_sk550p_fi_1_is_not_on_the_system_bus() {
        let gw = Gateway::new(Product::Sk550p, 3);
        assert!(!gw.reaches(fi(1)));
        assert!(gw.reaches(fi(2)) && gw.reaches(fi(3)));
        assert!(!gw.reaches(fi(4)));
        let modules = Gateway::new(Product::Tu3Eip, 2);
        assert!(modules.reaches(fi(1)));
    }
}
