//! The PNIO-CM blocks (IEC 61158-6-10 "Coding of the fields of the IO device and IO
//! controller services"): what the NDR data of a Connect, Release, Control, Read or Write
//! call carries. All fields are big-endian.
//!
//! Every block starts with a header: BlockType (u16), BlockLength (u16: the bytes after it,
//! so the two version bytes count), BlockVersionHigh (1), BlockVersionLow (0 for every block
//! typed here). Body layouts, offsets from the first byte after the version bytes:
//!
//! | block | body |
//! |---|---|
//! | ARBlockReq 0101h | 0 ARType; 2 ARUUID; 18 SessionKey; 20 CMInitiatorMacAdd; 26 CMInitiatorObjectUUID; 42 ARProperties u32; 46 CMInitiatorActivityTimeoutFactor; 48 CMInitiatorUDPRTPort; 50 StationNameLength; 52 CMInitiatorStationName |
//! | ARBlockRes 8101h | 0 ARType; 2 ARUUID; 18 SessionKey; 20 CMResponderMacAdd; 26 CMResponderUDPRTPort |
//! | IOCRBlockReq 0102h | 0 IOCRType; 2 IOCRReference; 4 LT; 6 IOCRProperties u32; 10 DataLength; 12 FrameID; 14 SendClockFactor; 16 ReductionRatio; 18 Phase; 20 Sequence; 22 FrameSendOffset u32; 26 WatchdogFactor; 28 DataHoldFactor; 30 IOCRTagHeader; 32 IOCRMulticastMACAdd; 38 NumberOfAPIs; per API: API u32, NumberOfIODataObjects, (SlotNumber, SubslotNumber, IODataObjectFrameOffset)*, NumberOfIOCS, (SlotNumber, SubslotNumber, IOCSFrameOffset)* |
//! | IOCRBlockRes 8102h | 0 IOCRType; 2 IOCRReference; 4 FrameID |
//! | AlarmCRBlockReq 0103h | 0 AlarmCRType; 2 LT; 4 AlarmCRProperties u32; 8 RTATimeoutFactor; 10 RTARetries; 12 LocalAlarmReference; 14 MaxAlarmDataLength; 16 AlarmCRTagHeaderHigh; 18 AlarmCRTagHeaderLow |
//! | AlarmCRBlockRes 8103h | 0 AlarmCRType; 2 LocalAlarmReference; 4 MaxAlarmDataLength |
//! | ExpectedSubmoduleBlockReq 0104h | 0 NumberOfAPIs; per API: API u32, SlotNumber, ModuleIdentNumber u32, ModuleProperties, NumberOfSubmodules, per submodule: SubslotNumber, SubmoduleIdentNumber u32, SubmoduleProperties, DataDescription (type, SubmoduleDataLength, LengthIOCS u8, LengthIOPS u8) — one, or two (input, output) for an IO submodule |
//! | ModuleDiffBlock 8104h | 0 NumberOfAPIs; per API: API u32, NumberOfModules, per module: SlotNumber, ModuleIdentNumber u32, ModuleState, NumberOfSubmodules, per submodule: SubslotNumber, SubmoduleIdentNumber u32, SubmoduleState |
//! | ARServerBlock 8106h | 0 StationNameLength; 2 CMResponderStationName; padding to a multiple of 4 of the whole block |
//! | IODWriteReqHeader 0008h | 0 SeqNumber; 2 ARUUID; 18 API u32; 22 SlotNumber; 24 SubslotNumber; 26 padding 2; 28 Index; 30 RecordDataLength u32; 34 RWPadding 24 — then RecordDataLength bytes of record data |
//! | IODReadReqHeader 0009h | as 0008h to 34; 34 TargetARUUID (nil unless an implicit read); 50 RWPadding 8 |
//! | IODWriteResHeader 8008h | as 0008h to 34; 34 AdditionalValue1; 36 AdditionalValue2; 38 PNIOStatus; 42 RWPadding 16 |
//! | IODReadResHeader 8009h | as 8008h without the status: 34 AdditionalValue1; 36 AdditionalValue2; 38 RWPadding 20 — then RecordDataLength bytes of record data |
//! | IODControlReq/Res 0110h..0118h / 8110h..8118h | 0 reserved 2; 2 ARUUID; 18 SessionKey; 20 reserved (AlarmSequenceNumber of a plug); 22 ControlCommand; 24 ControlBlockProperties |
//!
//! The read/write headers are 64 bytes with the block header (BlockLength 60). The record data
//! of a write request and of a read response follows its header block outside the block's
//! length; [`Block::WriteReq`] and [`Block::ReadRes`] hold it, [`Block::parse_all`] takes it.
//! Layouts cross-checked against Wireshark's packet-dcerpc-pn-io.c, scapy's pnio_rpc.py and
//! p-net's pf_block_reader.c/pf_block_writer.c.
//!
//! Every parser returns `Err` on malformed input and never panics: a BlockLength past the
//! buffer or under 2, a block too short for its fields, bytes left in a fixed block, a block
//! version other than 1.0, a count whose items cannot fit, record data shorter than
//! RecordDataLength.

use super::rpc::{open_code, Uuid};
use super::PnioStatus;
use crate::eth::MacAddr;
use crate::wire::{Error, Reader};

mod codes;
mod connect;
pub mod no_panic;
mod record;
#[cfg(test)]
mod vectors;

pub use codes::*;
pub use connect::*;
pub use record::*;

/// Length of the block header (type, length, version).
pub const BLOCK_HEADER_LEN: usize = 6;
/// Length of an IODWrite/IODRead request or response header, block header included.
pub const RECORD_HEADER_LEN: usize = 64;
/// BlockVersionHigh of every block typed here.
pub const VERSION_HIGH: u8 = 1;
/// BlockVersionLow of every block typed here.
pub const VERSION_LOW: u8 = 0;

open_code! {
    /// BlockType (IEC 61158-6-10 "BlockType"; open: unknown types parse as
    /// [`Block::Unknown`]). A response's type is its request's with bit 15 set.
    BlockType(u16, 4) {
        /// Alarm notification, high priority.
        ALARM_NOTIFICATION_HIGH = 0x0001, "AlarmNotificationHigh";
        /// Alarm notification, low priority.
        ALARM_NOTIFICATION_LOW = 0x0002, "AlarmNotificationLow";
        /// IODWriteReqHeader.
        IOD_WRITE_REQ = 0x0008, "IODWriteReqHeader";
        /// IODReadReqHeader.
        IOD_READ_REQ = 0x0009, "IODReadReqHeader";
        /// ARBlockReq.
        AR_BLOCK_REQ = 0x0101, "ARBlockReq";
        /// IOCRBlockReq.
        IOCR_BLOCK_REQ = 0x0102, "IOCRBlockReq";
        /// AlarmCRBlockReq.
        ALARM_CR_BLOCK_REQ = 0x0103, "AlarmCRBlockReq";
        /// ExpectedSubmoduleBlockReq.
        EXPECTED_SUBMODULE_BLOCK_REQ = 0x0104, "ExpectedSubmoduleBlockReq";
        /// PrmServerBlockReq.
        PRM_SERVER_BLOCK_REQ = 0x0105, "PrmServerBlockReq";
        /// MCRBlockReq.
        MCR_BLOCK_REQ = 0x0106, "MCRBlockReq";
        /// ARRPCBlockReq.
        AR_RPC_BLOCK_REQ = 0x0107, "ARRPCBlockReq";
        /// ARVendorBlockReq.
        AR_VENDOR_BLOCK_REQ = 0x0108, "ARVendorBlockReq";
        /// IODControlReq, PrmEnd of a connect (controller → device).
        PRM_END_REQ = 0x0110, "IODControlReq PrmEnd";
        /// IODControlReq, PrmEnd of a plug.
        PRM_END_PLUG_REQ = 0x0111, "IODControlReq PrmEnd plug";
        /// IOXControlReq, ApplicationReady of a connect (device → controller).
        APPLICATION_READY_REQ = 0x0112, "IOXControlReq ApplicationReady";
        /// IOXControlReq, ApplicationReady of a plug.
        APPLICATION_READY_PLUG_REQ = 0x0113, "IOXControlReq ApplicationReady plug";
        /// ReleaseBlockReq (IODReleaseReq).
        RELEASE_REQ = 0x0114, "IODReleaseReq";
        /// IOXControlReq, ReadyForCompanion.
        READY_FOR_COMPANION_REQ = 0x0116, "IOXControlReq ReadyForCompanion";
        /// IOXControlReq, ReadyForRT_CLASS_3.
        READY_FOR_RTC3_REQ = 0x0117, "IOXControlReq ReadyForRT_CLASS_3";
        /// IODControlReq, PrmBegin.
        PRM_BEGIN_REQ = 0x0118, "IODControlReq PrmBegin";
        /// Alarm acknowledge, high priority.
        ALARM_ACK_HIGH = 0x8001, "AlarmAckHigh";
        /// Alarm acknowledge, low priority.
        ALARM_ACK_LOW = 0x8002, "AlarmAckLow";
        /// IODWriteResHeader.
        IOD_WRITE_RES = 0x8008, "IODWriteResHeader";
        /// IODReadResHeader.
        IOD_READ_RES = 0x8009, "IODReadResHeader";
        /// ARBlockRes.
        AR_BLOCK_RES = 0x8101, "ARBlockRes";
        /// IOCRBlockRes.
        IOCR_BLOCK_RES = 0x8102, "IOCRBlockRes";
        /// AlarmCRBlockRes.
        ALARM_CR_BLOCK_RES = 0x8103, "AlarmCRBlockRes";
        /// ModuleDiffBlock.
        MODULE_DIFF_BLOCK = 0x8104, "ModuleDiffBlock";
        /// PrmServerBlockRes.
        PRM_SERVER_BLOCK_RES = 0x8105, "PrmServerBlockRes";
        /// ARServerBlock.
        AR_SERVER_BLOCK = 0x8106, "ARServerBlock";
        /// ARRPCBlockRes.
        AR_RPC_BLOCK_RES = 0x8107, "ARRPCBlockRes";
        /// ARVendorBlockRes.
        AR_VENDOR_BLOCK_RES = 0x8108, "ARVendorBlockRes";
        /// IODControlRes, PrmEnd of a connect.
        PRM_END_RES = 0x8110, "IODControlRes PrmEnd";
        /// IODControlRes, PrmEnd of a plug.
        PRM_END_PLUG_RES = 0x8111, "IODControlRes PrmEnd plug";
        /// IOXControlRes, ApplicationReady of a connect (controller → device).
        APPLICATION_READY_RES = 0x8112, "IOXControlRes ApplicationReady";
        /// IOXControlRes, ApplicationReady of a plug.
        APPLICATION_READY_PLUG_RES = 0x8113, "IOXControlRes ApplicationReady plug";
        /// ReleaseBlockRes (IODReleaseRes).
        RELEASE_RES = 0x8114, "IODReleaseRes";
        /// IOXControlRes, ReadyForCompanion.
        READY_FOR_COMPANION_RES = 0x8116, "IOXControlRes ReadyForCompanion";
        /// IOXControlRes, ReadyForRT_CLASS_3.
        READY_FOR_RTC3_RES = 0x8117, "IOXControlRes ReadyForRT_CLASS_3";
        /// IODControlRes, PrmBegin.
        PRM_BEGIN_RES = 0x8118, "IODControlRes PrmBegin";
    }
}

impl BlockType {
    /// The response type of a request type (bit 15 set).
    pub fn response(self) -> BlockType {
        BlockType(self.0 | 0x8000)
    }

    /// Whether it is a response type (bit 15).
    pub fn is_response(self) -> bool {
        self.0 & 0x8000 != 0
    }

    /// Whether it is an IODControl/IOXControl/Release request or response (0110h..0118h
    /// without 0115h, and their responses): the layout of [`IodControl`].
    pub fn is_control(self) -> bool {
        matches!(self.0 & 0x7FFF, 0x0110..=0x0114 | 0x0116..=0x0118)
    }
}

/// The block header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlockHeader {
    /// BlockType.
    pub block_type: BlockType,
    /// BlockLength: the bytes after this field (version bytes included).
    pub length: u16,
    /// BlockVersionHigh.
    pub version_high: u8,
    /// BlockVersionLow.
    pub version_low: u8,
}

/// A checked view of one block: the header is there, BlockLength is at least 2 and does not
/// pass the buffer. Bytes after the block (the next block, record data) are not its.
#[derive(Debug, Clone)]
pub struct BlockView<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> BlockView<T> {
    /// Checks the header and BlockLength.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let got = buffer.as_ref().len();
        if got < BLOCK_HEADER_LEN {
            return Err(Error::Truncated {
                what: "BlockHeader",
                need: BLOCK_HEADER_LEN,
                got,
            });
        }
        let v = BlockView { buffer };
        let len = usize::from(v.block_length());
        if len < 2 {
            return Err(Error::Invalid {
                field: "BlockLength",
                value: len as u32,
                why: "shorter than the block version (2 bytes)",
            });
        }
        if len > got - 4 {
            return Err(Error::Length {
                field: "BlockLength",
                value: len,
                available: got - 4,
            });
        }
        Ok(v)
    }

    fn b(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    /// BlockType.
    pub fn block_type(&self) -> BlockType {
        BlockType(u16::from_be_bytes([self.b()[0], self.b()[1]]))
    }

    /// BlockLength.
    pub fn block_length(&self) -> u16 {
        u16::from_be_bytes([self.b()[2], self.b()[3]])
    }

    /// (BlockVersionHigh, BlockVersionLow).
    pub fn version(&self) -> (u8, u8) {
        (self.b()[4], self.b()[5])
    }

    /// The header.
    pub fn header(&self) -> BlockHeader {
        let (version_high, version_low) = self.version();
        BlockHeader {
            block_type: self.block_type(),
            length: self.block_length(),
            version_high,
            version_low,
        }
    }

    /// The block's bytes after the version bytes.
    pub fn body(&self) -> &[u8] {
        &self.b()[BLOCK_HEADER_LEN..self.total_len()]
    }

    /// The whole block's length: 4 + BlockLength.
    pub fn total_len(&self) -> usize {
        4 + usize::from(self.block_length())
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> BlockView<T> {
    /// Sets BlockType.
    pub fn set_block_type(&mut self, t: BlockType) {
        self.buffer.as_mut()[0..2].copy_from_slice(&t.0.to_be_bytes());
    }

    /// Sets BlockLength (a value past the buffer makes a malformed block, which
    /// [`BlockView::new_checked`] then refuses).
    pub fn set_block_length(&mut self, len: u16) {
        self.buffer.as_mut()[2..4].copy_from_slice(&len.to_be_bytes());
    }

    /// Sets the version bytes.
    pub fn set_version(&mut self, high: u8, low: u8) {
        self.buffer.as_mut()[4] = high;
        self.buffer.as_mut()[5] = low;
    }
}

fn uuid(r: &mut Reader<'_>, what: &'static str) -> Result<Uuid, Error> {
    let mut b = [0u8; 16];
    b.copy_from_slice(r.bytes(16, what)?);
    Ok(Uuid(b))
}

fn mac(r: &mut Reader<'_>, what: &'static str) -> Result<MacAddr, Error> {
    let mut b = [0u8; 6];
    b.copy_from_slice(r.bytes(6, what)?);
    Ok(MacAddr(b))
}

/// A count of items of at least `min` bytes each: they must fit in what is left.
fn count(r: &mut Reader<'_>, min: usize, field: &'static str) -> Result<usize, Error> {
    let n = usize::from(r.u16_be(field)?);
    if n * min > r.remaining() {
        return Err(Error::Length {
            field,
            value: n * min,
            available: r.remaining(),
        });
    }
    Ok(n)
}

/// A length-prefixed station name.
fn station_name(r: &mut Reader<'_>, field: &'static str) -> Result<Vec<u8>, Error> {
    let n = usize::from(r.u16_be(field)?);
    if n > r.remaining() {
        return Err(Error::Length {
            field,
            value: n,
            available: r.remaining(),
        });
    }
    Ok(r.bytes(n, field)?.to_vec())
}

fn put16(b: &mut Vec<u8>, v: u16) {
    b.extend(v.to_be_bytes());
}

fn put32(b: &mut Vec<u8>, v: u32) {
    b.extend(v.to_be_bytes());
}

fn put_count(b: &mut Vec<u8>, n: usize, what: &'static str) -> Result<(), Error> {
    let n = u16::try_from(n).map_err(|_| Error::TooLong {
        what,
        len: n,
        max: usize::from(u16::MAX),
    })?;
    put16(b, n);
    Ok(())
}

fn put_name(b: &mut Vec<u8>, name: &[u8], what: &'static str) -> Result<(), Error> {
    put_count(b, name.len(), what)?;
    b.extend(name);
    Ok(())
}

fn padding(r: &mut Reader<'_>, n: usize, what: &'static str) -> Result<(), Error> {
    r.bytes(n, what).map(|_| ())
}

/// A PNIO-CM block (and, for a write request and a read response, the record data after
/// it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Block {
    /// ARBlockReq (0101h).
    ArReq(ArBlockReq),
    /// ARBlockRes (8101h).
    ArRes(ArBlockRes),
    /// IOCRBlockReq (0102h).
    IocrReq(IocrBlockReq),
    /// IOCRBlockRes (8102h).
    IocrRes(IocrBlockRes),
    /// AlarmCRBlockReq (0103h).
    AlarmCrReq(AlarmCrBlockReq),
    /// AlarmCRBlockRes (8103h).
    AlarmCrRes(AlarmCrBlockRes),
    /// ExpectedSubmoduleBlockReq (0104h).
    ExpectedSubmoduleReq(ExpectedSubmoduleBlockReq),
    /// ModuleDiffBlock (8104h).
    ModuleDiff(ModuleDiffBlock),
    /// ARServerBlock (8106h).
    ArServer(ArServerBlock),
    /// IODWriteReqHeader (0008h) and its record data.
    WriteReq(IodWriteReq),
    /// IODReadReqHeader (0009h).
    ReadReq(IodReadReq),
    /// IODWriteResHeader (8008h).
    WriteRes(IodWriteRes),
    /// IODReadResHeader (8009h) and its record data.
    ReadRes(IodReadRes),
    /// IODControl/IOXControl/Release request or response.
    Control(IodControl),
    /// Any other block, kept as it travels.
    Unknown {
        /// BlockType.
        block_type: BlockType,
        /// (BlockVersionHigh, BlockVersionLow).
        version: (u8, u8),
        /// The bytes after the version bytes.
        body: Vec<u8>,
    },
}

impl Block {
    /// The block's type.
    pub fn block_type(&self) -> BlockType {
        match self {
            Block::ArReq(_) => BlockType::AR_BLOCK_REQ,
            Block::ArRes(_) => BlockType::AR_BLOCK_RES,
            Block::IocrReq(_) => BlockType::IOCR_BLOCK_REQ,
            Block::IocrRes(_) => BlockType::IOCR_BLOCK_RES,
            Block::AlarmCrReq(_) => BlockType::ALARM_CR_BLOCK_REQ,
            Block::AlarmCrRes(_) => BlockType::ALARM_CR_BLOCK_RES,
            Block::ExpectedSubmoduleReq(_) => BlockType::EXPECTED_SUBMODULE_BLOCK_REQ,
            Block::ModuleDiff(_) => BlockType::MODULE_DIFF_BLOCK,
            Block::ArServer(_) => BlockType::AR_SERVER_BLOCK,
            Block::WriteReq(_) => BlockType::IOD_WRITE_REQ,
            Block::ReadReq(_) => BlockType::IOD_READ_REQ,
            Block::WriteRes(_) => BlockType::IOD_WRITE_RES,
            Block::ReadRes(_) => BlockType::IOD_READ_RES,
            Block::Control(c) => c.block_type,
            Block::Unknown { block_type, .. } => *block_type,
        }
    }

    /// Parses the block at the start of `buf` (with its record data for a write request or
    /// read response); returns it and the bytes it took.
    pub fn parse(buf: &[u8]) -> Result<(Block, usize), Error> {
        let view = BlockView::new_checked(buf)?;
        let t = view.block_type();
        let version = view.version();
        let typed = matches!(
            t,
            BlockType::AR_BLOCK_REQ
                | BlockType::AR_BLOCK_RES
                | BlockType::IOCR_BLOCK_REQ
                | BlockType::IOCR_BLOCK_RES
                | BlockType::ALARM_CR_BLOCK_REQ
                | BlockType::ALARM_CR_BLOCK_RES
                | BlockType::EXPECTED_SUBMODULE_BLOCK_REQ
                | BlockType::MODULE_DIFF_BLOCK
                | BlockType::AR_SERVER_BLOCK
                | BlockType::IOD_WRITE_REQ
                | BlockType::IOD_READ_REQ
                | BlockType::IOD_WRITE_RES
                | BlockType::IOD_READ_RES
        ) || t.is_control();
        if !typed {
            return Ok((
                Block::Unknown {
                    block_type: t,
                    version,
                    body: view.body().to_vec(),
                },
                view.total_len(),
            ));
        }
        if version != (VERSION_HIGH, VERSION_LOW) {
            return Err(Error::Invalid {
                field: "BlockVersion",
                value: u32::from(u16::from_be_bytes([version.0, version.1])),
                why: "the typed blocks are version 1.0",
            });
        }
        let mut r = Reader::new(view.body());
        let mut used = view.total_len();
        // Record data after the header block.
        let mut record_data = |len: u32| -> Result<Vec<u8>, Error> {
            let rest = &buf[used..];
            let n = len as usize;
            if n > rest.len() {
                return Err(Error::Length {
                    field: "RecordDataLength",
                    value: n,
                    available: rest.len(),
                });
            }
            used += n;
            Ok(rest[..n].to_vec())
        };
        let (block, what) = match t {
            BlockType::AR_BLOCK_REQ => (Block::ArReq(ArBlockReq::parse(&mut r)?), "ARBlockReq"),
            BlockType::AR_BLOCK_RES => (Block::ArRes(ArBlockRes::parse(&mut r)?), "ARBlockRes"),
            BlockType::IOCR_BLOCK_REQ => {
                (Block::IocrReq(IocrBlockReq::parse(&mut r)?), "IOCRBlockReq")
            }
            BlockType::IOCR_BLOCK_RES => {
                (Block::IocrRes(IocrBlockRes::parse(&mut r)?), "IOCRBlockRes")
            }
            BlockType::ALARM_CR_BLOCK_REQ => (
                Block::AlarmCrReq(AlarmCrBlockReq::parse(&mut r)?),
                "AlarmCRBlockReq",
            ),
            BlockType::ALARM_CR_BLOCK_RES => (
                Block::AlarmCrRes(AlarmCrBlockRes::parse(&mut r)?),
                "AlarmCRBlockRes",
            ),
            BlockType::EXPECTED_SUBMODULE_BLOCK_REQ => (
                Block::ExpectedSubmoduleReq(ExpectedSubmoduleBlockReq::parse(&mut r)?),
                "ExpectedSubmoduleBlockReq",
            ),
            BlockType::MODULE_DIFF_BLOCK => (
                Block::ModuleDiff(ModuleDiffBlock::parse(&mut r)?),
                "ModuleDiffBlock",
            ),
            BlockType::AR_SERVER_BLOCK => (
                Block::ArServer(ArServerBlock::parse(&mut r)?),
                "ARServerBlock",
            ),
            BlockType::IOD_WRITE_REQ => {
                let (addr, len) = RecordAddress::parse(&mut r, "IODWriteReqHeader")?;
                padding(&mut r, 24, "IODWriteReqHeader RWPadding")?;
                r.finish("IODWriteReqHeader")?;
                let data = record_data(len)?;
                (
                    Block::WriteReq(IodWriteReq { addr, data }),
                    "IODWriteReqHeader",
                )
            }
            BlockType::IOD_READ_REQ => {
                let (addr, record_data_length) = RecordAddress::parse(&mut r, "IODReadReqHeader")?;
                let target_ar_uuid = uuid(&mut r, "IODReadReqHeader TargetARUUID")?;
                padding(&mut r, 8, "IODReadReqHeader RWPadding")?;
                (
                    Block::ReadReq(IodReadReq {
                        addr,
                        record_data_length,
                        target_ar_uuid,
                    }),
                    "IODReadReqHeader",
                )
            }
            BlockType::IOD_WRITE_RES => {
                let (addr, record_data_length) = RecordAddress::parse(&mut r, "IODWriteResHeader")?;
                let additional_value1 = r.u16_be("IODWriteResHeader AdditionalValue1")?;
                let additional_value2 = r.u16_be("IODWriteResHeader AdditionalValue2")?;
                let s = r.bytes(4, "IODWriteResHeader PNIOStatus")?;
                let status = PnioStatus::new(s[0], s[1], s[2], s[3]);
                padding(&mut r, 16, "IODWriteResHeader RWPadding")?;
                (
                    Block::WriteRes(IodWriteRes {
                        addr,
                        record_data_length,
                        additional_value1,
                        additional_value2,
                        status,
                    }),
                    "IODWriteResHeader",
                )
            }
            BlockType::IOD_READ_RES => {
                let (addr, len) = RecordAddress::parse(&mut r, "IODReadResHeader")?;
                let additional_value1 = r.u16_be("IODReadResHeader AdditionalValue1")?;
                let additional_value2 = r.u16_be("IODReadResHeader AdditionalValue2")?;
                padding(&mut r, 20, "IODReadResHeader RWPadding")?;
                r.finish("IODReadResHeader")?;
                let data = record_data(len)?;
                (
                    Block::ReadRes(IodReadRes {
                        addr,
                        additional_value1,
                        additional_value2,
                        data,
                    }),
                    "IODReadResHeader",
                )
            }
            _ => (Block::Control(IodControl::parse(t, &mut r)?), "IODControl"),
        };
        r.finish(what)?;
        Ok((block, used))
    }

    /// Parses a sequence of blocks filling `buf` (the NDR data of a PNIO call).
    pub fn parse_all(buf: &[u8]) -> Result<Vec<Block>, Error> {
        let mut blocks = Vec::new();
        let mut at = 0;
        while at < buf.len() {
            let (b, n) = Block::parse(&buf[at..])?;
            blocks.push(b);
            at += n;
        }
        Ok(blocks)
    }

    /// Appends the block (and its record data) to `out`. A body longer than BlockLength can
    /// say, a count or name longer than its u16, record data longer than u32, or an
    /// expected submodule whose DataDescriptions do not match its type is an error.
    pub fn emit(&self, out: &mut Vec<u8>) -> Result<(), Error> {
        let start = out.len();
        let (hi, lo) = match self {
            Block::Unknown { version, .. } => *version,
            _ => (VERSION_HIGH, VERSION_LOW),
        };
        put16(out, self.block_type().0);
        put16(out, 0); // BlockLength, set below
        out.extend([hi, lo]);
        let mut data: &[u8] = &[];
        match self {
            Block::ArReq(b) => b.emit(out)?,
            Block::ArRes(b) => b.emit(out),
            Block::IocrReq(b) => b.emit(out)?,
            Block::IocrRes(b) => b.emit(out),
            Block::AlarmCrReq(b) => b.emit(out),
            Block::AlarmCrRes(b) => b.emit(out),
            Block::ExpectedSubmoduleReq(b) => b.emit(out)?,
            Block::ModuleDiff(b) => b.emit(out)?,
            Block::ArServer(b) => b.emit(out)?,
            Block::WriteReq(w) => {
                w.addr.emit(out, record_len(&w.data)?);
                out.extend([0; 24]);
                data = &w.data;
            }
            Block::ReadReq(q) => {
                q.addr.emit(out, q.record_data_length);
                out.extend(q.target_ar_uuid.0);
                out.extend([0; 8]);
            }
            Block::WriteRes(w) => {
                w.addr.emit(out, w.record_data_length);
                put16(out, w.additional_value1);
                put16(out, w.additional_value2);
                out.extend(w.status.to_bytes());
                out.extend([0; 16]);
            }
            Block::ReadRes(q) => {
                q.addr.emit(out, record_len(&q.data)?);
                put16(out, q.additional_value1);
                put16(out, q.additional_value2);
                out.extend([0; 20]);
                data = &q.data;
            }
            Block::Control(c) => c.emit(out),
            Block::Unknown { body, .. } => out.extend(body),
        }
        let len = out.len() - start - 4;
        let len = u16::try_from(len).map_err(|_| Error::TooLong {
            what: "BlockLength",
            len,
            max: usize::from(u16::MAX),
        })?;
        out[start + 2..start + 4].copy_from_slice(&len.to_be_bytes());
        out.extend(data);
        Ok(())
    }

    /// The bytes of a sequence of blocks.
    pub fn emit_all(blocks: &[Block]) -> Result<Vec<u8>, Error> {
        let mut out = Vec::new();
        for b in blocks {
            b.emit(&mut out)?;
        }
        Ok(out)
    }

    /// The bytes of this block (and its record data).
    pub fn to_bytes(&self) -> Result<Vec<u8>, Error> {
        Block::emit_all(std::slice::from_ref(self))
    }
}

fn record_len(data: &[u8]) -> Result<u32, Error> {
    u32::try_from(data.len()).map_err(|_| Error::TooLong {
        what: "RecordDataLength",
        len: data.len(),
        max: u32::MAX as usize,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pnio::block::vectors::*;

    #[test]
    fn connect_request_body_parses_and_round_trips() {
        // ARBlockReq, IOCRBlockReq, AlarmCRBlockReq, ExpectedSubmoduleBlockReq and an
        // ARRPCBlockReq (0107h, version 1.0, InitiatorRPCServerPort 34964) kept as unknown.
        let mut body = ar_block_req_bytes();
        body.extend(iocr_req_bytes());
        body.extend(alarm_cr_req_bytes());
        body.extend(expected_bytes());
        body.extend([0x01, 0x07, 0x00, 0x04, 0x01, 0x00, 0x88, 0x94]);
        let blocks = Block::parse_all(&body).unwrap();
        let types: Vec<BlockType> = blocks.iter().map(Block::block_type).collect();
        assert_eq!(
            types,
            [
                BlockType::AR_BLOCK_REQ,
                BlockType::IOCR_BLOCK_REQ,
                BlockType::ALARM_CR_BLOCK_REQ,
                BlockType::EXPECTED_SUBMODULE_BLOCK_REQ,
                BlockType::AR_RPC_BLOCK_REQ
            ]
        );
        assert_eq!(
            blocks[4],
            Block::Unknown {
                block_type: BlockType::AR_RPC_BLOCK_REQ,
                version: (1, 0),
                body: vec![0x88, 0x94]
            }
        );
        assert_eq!(Block::emit_all(&blocks).unwrap(), body);
        assert_eq!(Block::parse_all(&[]), Ok(vec![]));
    }

    #[test]
    fn malformed_blocks_are_typed_errors() {
        let ar = ar_block_req_bytes();
        assert_eq!(
            Block::parse(&ar[..5]),
            Err(Error::Truncated {
                what: "BlockHeader",
                need: 6,
                got: 5
            })
        );
        // BlockLength 57 with 56 bytes after it.
        assert_eq!(
            Block::parse(&ar[..ar.len() - 1]),
            Err(Error::Length {
                field: "BlockLength",
                value: 57,
                available: 56
            })
        );
        // BlockLength 1 cannot hold the version.
        let mut b = ar.clone();
        BlockView::new_checked(&mut b[..])
            .unwrap()
            .set_block_length(1);
        assert_eq!(
            Block::parse(&b),
            Err(Error::Invalid {
                field: "BlockLength",
                value: 1,
                why: "shorter than the block version (2 bytes)",
            })
        );
        // Version 1.1.
        let mut b = ar.clone();
        BlockView::new_checked(&mut b[..])
            .unwrap()
            .set_version(1, 1);
        assert_eq!(
            Block::parse(&b),
            Err(Error::Invalid {
                field: "BlockVersion",
                value: 0x0101,
                why: "the typed blocks are version 1.0",
            })
        );
        // A block length too small for the type: the name's length byte cut off.
        let mut b = ar[..ar.len() - 4].to_vec();
        b[3] = 0x35; // BlockLength 53
        assert_eq!(
            Block::parse(&b),
            Err(Error::Truncated {
                what: "ARBlockReq StationNameLength",
                need: 2,
                got: 1
            })
        );
        // StationNameLength 4 with 3 bytes.
        let mut b = ar.clone();
        b[57] = 4;
        assert_eq!(
            Block::parse(&b),
            Err(Error::Length {
                field: "ARBlockReq StationNameLength",
                value: 4,
                available: 3
            })
        );
        // An IOCRBlockRes with a byte too many.
        let res = [
            0x81, 0x02, 0x00, 0x09, 0x01, 0x00, 0, 1, 0, 1, 0x80, 0x01, 0xFF,
        ];
        assert_eq!(
            Block::parse(&res),
            Err(Error::Trailing {
                what: "IOCRBlockRes",
                extra: 1
            })
        );
        // NumberOfAPIs 5 in an ExpectedSubmoduleBlockReq: 5 entries of at least 14 bytes
        // cannot fit in the 62 bytes left.
        let mut e = expected_bytes();
        e[7] = 5;
        assert_eq!(
            Block::parse(&e),
            Err(Error::Length {
                field: "ExpectedSubmoduleBlockReq NumberOfAPIs",
                value: 70,
                available: 62
            })
        );
        // NumberOfAPIs 3: room for the minimum, but the third entry is not there.
        e[7] = 3;
        assert_eq!(
            Block::parse(&e),
            Err(Error::Truncated {
                what: "ExpectedSubmoduleBlockReq API",
                need: 4,
                got: 0
            })
        );
        // NumberOfIOCS 2 with one entry.
        let mut c = iocr_req_bytes();
        c[59] = 2;
        assert!(matches!(
            Block::parse(&c),
            Err(Error::Length {
                field: "IOCRBlockReq NumberOfIOCS",
                ..
            })
        ));
        // Unknown blocks take any version.
        let u = [0x02, 0x00, 0x00, 0x03, 0x02, 0x07, 0xAB];
        assert_eq!(
            one(&u),
            Block::Unknown {
                block_type: BlockType(0x0200),
                version: (2, 7),
                body: vec![0xAB]
            }
        );
    }

    #[test]
    fn emit_refuses_what_does_not_fit() {
        let long = Block::ArServer(ArServerBlock {
            station_name: vec![b'a'; 70_000],
        });
        assert!(matches!(long.to_bytes(), Err(Error::TooLong { .. })));
        let body = Block::Unknown {
            block_type: BlockType(0x0F00),
            version: (1, 0),
            body: vec![0; 65_534],
        };
        assert_eq!(
            body.to_bytes(),
            Err(Error::TooLong {
                what: "BlockLength",
                len: 65_536,
                max: 65_535
            })
        );
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// The block types parsed into typed blocks.
        fn typed_types() -> Vec<u16> {
            let mut t = vec![
                0x0008, 0x0009, 0x8008, 0x8009, 0x0101, 0x8101, 0x0102, 0x8102, 0x0103, 0x8103,
                0x0104, 0x8104, 0x8106,
            ];
            for c in (0x0110..=0x0114).chain(0x0116..=0x0118) {
                t.extend([c, c | 0x8000]);
            }
            t
        }

        fn is_typed(t: u16) -> bool {
            typed_types().contains(&t)
        }

        /// A block as it travels: header (BlockLength from the body) and body.
        fn framed(t: u16, version: (u8, u8), body: &[u8]) -> Vec<u8> {
            let mut b = t.to_be_bytes().to_vec();
            b.extend(((body.len() + 2) as u16).to_be_bytes());
            b.extend([version.0, version.1]);
            b.extend(body);
            b
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            /// Blocks of types not typed here keep type, version and body.
            #[test]
            fn unknown_blocks_round_trip(
                blocks in vec(
                    (
                        any::<u16>().prop_filter("typed block type", |t| !is_typed(*t)),
                        any::<(u8, u8)>(),
                        vec(any::<u8>(), 0..24),
                    ),
                    0..4,
                ),
            ) {
                let blocks: Vec<Block> = blocks
                    .into_iter()
                    .map(|(t, version, body)| Block::Unknown { block_type: BlockType(t), version, body })
                    .collect();
                let b = Block::emit_all(&blocks).unwrap();
                prop_assert_eq!(Block::parse_all(&b), Ok(blocks));
            }

            /// Whatever a typed block's parser accepts emits to bytes that parse to the same
            /// block (parse ∘ emit is the identity on parsed blocks); no parser panics on an
            /// arbitrary body under its header.
            #[test]
            fn typed_blocks_reparse_to_themselves(
                t in proptest::sample::select(typed_types()),
                body in vec(any::<u8>(), 0..96),
                tail in vec(any::<u8>(), 0..8),
            ) {
                let mut b = framed(t, (VERSION_HIGH, VERSION_LOW), &body);
                b.extend(tail);
                if let Ok((block, n)) = Block::parse(&b) {
                    prop_assert!(n <= b.len());
                    let again = block.to_bytes().unwrap();
                    prop_assert_eq!(Block::parse(&again), Ok((block, again.len())));
                }
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..64)) {
                let _ = Block::parse(&bytes);
                let _ = Block::parse_all(&bytes);
                if let Ok(v) = BlockView::new_checked(&bytes[..]) {
                    let _ = (v.header(), v.body().len(), v.total_len());
                }
            }
        }
    }
}
