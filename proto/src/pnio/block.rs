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
use super::{Error, PnioStatus};
use crate::eth::MacAddr;
use crate::wire::Reader;

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

open_code! {
    /// ARType (IEC 61158-6-10 "ARType").
    ArType(u16, 4) {
        /// IOCARSingle: one IO controller AR, RT class 1/2.
        IOC_AR_SINGLE = 0x0001, "IOCARSingle";
        /// IOSAR: a supervisor AR.
        IOS_AR = 0x0006, "IOSAR";
        /// IOCARSingle using RT_CLASS_3.
        IOC_AR_SINGLE_RTC3 = 0x0010, "IOCARSingle RT_CLASS_3";
        /// IOCARSR: a system-redundancy AR.
        IOC_AR_SR = 0x0020, "IOCARSR";
    }
}

open_code! {
    /// IOCRType.
    IocrType(u16, 4) {
        /// Input CR: device → controller.
        INPUT = 0x0001, "Input CR";
        /// Output CR: controller → device.
        OUTPUT = 0x0002, "Output CR";
        /// Multicast provider CR.
        MULTICAST_PROVIDER = 0x0003, "Multicast Provider CR";
        /// Multicast consumer CR.
        MULTICAST_CONSUMER = 0x0004, "Multicast Consumer CR";
    }
}

open_code! {
    /// AlarmCRType.
    AlarmCrType(u16, 4) {
        /// The alarm CR.
        ALARM_CR = 0x0001, "AlarmCR";
    }
}

open_code! {
    /// ModuleState of a ModuleDiffBlock entry.
    ModuleState(u16, 4) {
        /// No module plugged in the slot.
        NO_MODULE = 0x0000, "NoModule";
        /// A module other than the expected one.
        WRONG_MODULE = 0x0001, "WrongModule";
        /// The expected module (its submodules differ).
        PROPER_MODULE = 0x0002, "ProperModule";
        /// A compatible substitute.
        SUBSTITUTE = 0x0003, "Substitute";
    }
}

open_code! {
    /// The DataDescription type of an expected submodule.
    DataDirection(u16, 4) {
        /// Input data (device → controller).
        INPUT = 0x0001, "Input";
        /// Output data (controller → device).
        OUTPUT = 0x0002, "Output";
    }
}

open_code! {
    /// ControlCommand (bits; a response says [`ControlCommand::DONE`]).
    ControlCommand(u16, 4) {
        /// PrmEnd: the controller has written the parameters.
        PRM_END = 0x0001, "PrmEnd";
        /// ApplicationReady: the device is ready for data exchange.
        APPLICATION_READY = 0x0002, "ApplicationReady";
        /// Release: end the AR.
        RELEASE = 0x0004, "Release";
        /// Done: the response to any of them.
        DONE = 0x0008, "Done";
        /// ReadyForCompanion.
        READY_FOR_COMPANION = 0x0010, "ReadyForCompanion";
        /// ReadyForRT_CLASS_3.
        READY_FOR_RTC3 = 0x0020, "ReadyForRT_CLASS_3";
        /// PrmBegin.
        PRM_BEGIN = 0x0040, "PrmBegin";
    }
}

impl ControlCommand {
    /// Whether every bit of `other` is set.
    pub fn contains(self, other: ControlCommand) -> bool {
        self.0 & other.0 == other.0
    }
}

/// Bits of ARProperties (u32).
pub mod ar_properties {
    /// State (bits 0–2): 1 = active.
    pub const STATE_MASK: u32 = 0x0000_0007;
    /// State active.
    pub const STATE_ACTIVE: u32 = 0x0000_0001;
    /// SupervisorTakeoverAllowed.
    pub const SUPERVISOR_TAKEOVER_ALLOWED: u32 = 0x0000_0008;
    /// ParameterizationServer: 1 = the CM initiator (no external parameter server).
    pub const PRM_SERVER_CM_INITIATOR: u32 = 0x0000_0010;
    /// DeviceAccess.
    pub const DEVICE_ACCESS: u32 = 0x0000_0100;
    /// CompanionAR (bits 9–10).
    pub const COMPANION_AR_MASK: u32 = 0x0000_0600;
    /// AcknowledgeCompanionAR.
    pub const ACKNOWLEDGE_COMPANION_AR: u32 = 0x0000_0800;
    /// CombinedObjectContainer.
    pub const COMBINED_OBJECT_CONTAINER: u32 = 0x2000_0000;
    /// StartupMode: 1 = advanced, 0 = legacy.
    pub const STARTUP_MODE_ADVANCED: u32 = 0x4000_0000;
    /// PullModuleAlarmAllowed.
    pub const PULL_MODULE_ALARM_ALLOWED: u32 = 0x8000_0000;
}

/// Bits of IOCRProperties (u32).
pub mod iocr_properties {
    /// RTClass (bits 0–3).
    pub const RT_CLASS_MASK: u32 = 0x0000_000F;
    /// RT_CLASS_1 (legacy value).
    pub const RT_CLASS_1: u32 = 0x0000_0001;
    /// RT_CLASS_2 (also RT_CLASS_1 frames in current editions).
    pub const RT_CLASS_2: u32 = 0x0000_0002;
    /// RT_CLASS_3.
    pub const RT_CLASS_3: u32 = 0x0000_0003;
    /// RT_CLASS_UDP.
    pub const RT_CLASS_UDP: u32 = 0x0000_0004;
}

/// Bits of AlarmCRProperties (u32; Wireshark's and p-net's bit numbering).
pub mod alarm_cr_properties {
    /// Priority: 1 = only the user priority of the tag headers.
    pub const PRIORITY: u32 = 0x0000_0001;
    /// Transport: 1 = RTA_CLASS_UDP, 0 = RTA_CLASS_1 (Ethernet).
    pub const TRANSPORT_UDP: u32 = 0x0000_0002;
}

/// SubmoduleProperties (u16): the type in bits 0–1 decides the DataDescriptions.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default, Debug)]
pub struct SubmoduleProperties(pub u16);

impl SubmoduleProperties {
    /// Type NO_IO: one input DataDescription of length 0.
    pub const NO_IO: SubmoduleProperties = SubmoduleProperties(0);
    /// Type INPUT: one input DataDescription.
    pub const INPUT: SubmoduleProperties = SubmoduleProperties(1);
    /// Type OUTPUT: one output DataDescription.
    pub const OUTPUT: SubmoduleProperties = SubmoduleProperties(2);
    /// Type INPUT_OUTPUT: an input and an output DataDescription.
    pub const INPUT_OUTPUT: SubmoduleProperties = SubmoduleProperties(3);
    /// SharedInput.
    pub const SHARED_INPUT: u16 = 0x0004;
    /// ReduceInputSubmoduleDataLength.
    pub const REDUCE_INPUT_LENGTH: u16 = 0x0008;
    /// ReduceOutputSubmoduleDataLength.
    pub const REDUCE_OUTPUT_LENGTH: u16 = 0x0010;
    /// DiscardIOXS.
    pub const DISCARD_IOXS: u16 = 0x0020;

    /// The type bits (0 no IO, 1 input, 2 output, 3 input and output).
    pub fn io_type(self) -> u16 {
        self.0 & 0x0003
    }

    /// How many DataDescriptions follow: 2 for input and output, else 1.
    pub fn data_description_count(self) -> usize {
        if self.io_type() == 3 {
            2
        } else {
            1
        }
    }
}

/// SubmoduleState (u16) of a ModuleDiffBlock entry, in the detailed format (FormatIndicator
/// bit 15 set): AddInfo bits 0–2, AdviceAvailable 3, MaintenanceRequired 4,
/// MaintenanceDemanded 5, Fault 6, ARInfo bits 7–10, IdentInfo bits 11–14.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default, Debug)]
pub struct SubmoduleState(pub u16);

impl SubmoduleState {
    /// FormatIndicator: the detailed format.
    pub const FORMAT_INDICATOR: u16 = 0x8000;
    /// Fault.
    pub const FAULT: u16 = 0x0040;
    /// MaintenanceDemanded.
    pub const MAINTENANCE_DEMANDED: u16 = 0x0020;
    /// MaintenanceRequired.
    pub const MAINTENANCE_REQUIRED: u16 = 0x0010;
    /// AdviceAvailable.
    pub const ADVICE_AVAILABLE: u16 = 0x0008;
    /// IdentInfo OK.
    pub const IDENT_OK: u16 = 0;
    /// IdentInfo Substitute.
    pub const IDENT_SUBSTITUTE: u16 = 1;
    /// IdentInfo Wrong.
    pub const IDENT_WRONG: u16 = 2;
    /// IdentInfo NoSubmodule.
    pub const IDENT_NO_SUBMODULE: u16 = 3;
    /// ARInfo Own.
    pub const AR_OWN: u16 = 0;
    /// ARInfo ApplicationReadyPending.
    pub const AR_APPLICATION_READY_PENDING: u16 = 1;
    /// ARInfo Superordinated locked.
    pub const AR_SUPERORDINATED_LOCKED: u16 = 2;
    /// ARInfo Locked by IO controller.
    pub const AR_LOCKED_BY_IO_CONTROLLER: u16 = 3;
    /// ARInfo Locked by IO supervisor.
    pub const AR_LOCKED_BY_IO_SUPERVISOR: u16 = 4;

    /// Detailed format with that IdentInfo and ARInfo.
    pub const fn new(ident_info: u16, ar_info: u16) -> SubmoduleState {
        SubmoduleState(
            Self::FORMAT_INDICATOR | ((ident_info & 0x0F) << 11) | ((ar_info & 0x0F) << 7),
        )
    }

    /// The expected submodule, owned by this AR (8000h).
    pub const fn ok() -> SubmoduleState {
        SubmoduleState::new(Self::IDENT_OK, Self::AR_OWN)
    }

    /// A substitute submodule (8800h).
    pub const fn substitute() -> SubmoduleState {
        SubmoduleState::new(Self::IDENT_SUBSTITUTE, Self::AR_OWN)
    }

    /// A wrong submodule (9000h).
    pub const fn wrong() -> SubmoduleState {
        SubmoduleState::new(Self::IDENT_WRONG, Self::AR_OWN)
    }

    /// No submodule in the subslot (9800h).
    pub const fn no_submodule() -> SubmoduleState {
        SubmoduleState::new(Self::IDENT_NO_SUBMODULE, Self::AR_OWN)
    }

    /// The expected submodule, waiting for ApplicationReady (8080h).
    pub const fn application_ready_pending() -> SubmoduleState {
        SubmoduleState::new(Self::IDENT_OK, Self::AR_APPLICATION_READY_PENDING)
    }

    /// IdentInfo (bits 11–14).
    pub fn ident_info(self) -> u16 {
        (self.0 >> 11) & 0x0F
    }

    /// ARInfo (bits 7–10).
    pub fn ar_info(self) -> u16 {
        (self.0 >> 7) & 0x0F
    }

    /// Whether the Fault bit is set.
    pub fn fault(self) -> bool {
        self.0 & Self::FAULT != 0
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
            });
        }
        if len > got - 4 {
            return Err(Error::BadLength {
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

type R<'a> = Reader<'a, Error>;

fn uuid(r: &mut R<'_>, what: &'static str) -> Result<Uuid, Error> {
    let mut b = [0u8; 16];
    b.copy_from_slice(r.bytes(16, what)?);
    Ok(Uuid(b))
}

fn mac(r: &mut R<'_>, what: &'static str) -> Result<MacAddr, Error> {
    let mut b = [0u8; 6];
    b.copy_from_slice(r.bytes(6, what)?);
    Ok(MacAddr(b))
}

/// A count of items of at least `min` bytes each: they must fit in what is left.
fn count(r: &mut R<'_>, min: usize, field: &'static str) -> Result<usize, Error> {
    let n = usize::from(r.u16_be(field)?);
    if n * min > r.remaining() {
        return Err(Error::BadLength {
            field,
            value: n * min,
            available: r.remaining(),
        });
    }
    Ok(n)
}

/// A length-prefixed station name.
fn station_name(r: &mut R<'_>, field: &'static str) -> Result<Vec<u8>, Error> {
    let n = usize::from(r.u16_be(field)?);
    if n > r.remaining() {
        return Err(Error::BadLength {
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

/// ARBlockReq (0101h): the AR a controller asks for.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ArBlockReq {
    /// ARType.
    pub ar_type: ArType,
    /// ARUUID: names the AR in every later call.
    pub ar_uuid: Uuid,
    /// SessionKey: counts the controller's connects.
    pub session_key: u16,
    /// CMInitiatorMacAdd: the controller's MAC address.
    pub initiator_mac: MacAddr,
    /// CMInitiatorObjectUUID: the controller's PNIO object (the object UUID of its
    /// ApplicationReady server).
    pub initiator_object: Uuid,
    /// ARProperties ([`ar_properties`]).
    pub properties: u32,
    /// CMInitiatorActivityTimeoutFactor (100 ms units).
    pub activity_timeout_factor: u16,
    /// CMInitiatorUDPRTPort (8892h for RT over Ethernet).
    pub udp_rt_port: u16,
    /// CMInitiatorStationName: the controller's station name.
    pub station_name: Vec<u8>,
}

impl ArBlockReq {
    fn parse(r: &mut R<'_>) -> Result<ArBlockReq, Error> {
        Ok(ArBlockReq {
            ar_type: ArType(r.u16_be("ARBlockReq ARType")?),
            ar_uuid: uuid(r, "ARBlockReq ARUUID")?,
            session_key: r.u16_be("ARBlockReq SessionKey")?,
            initiator_mac: mac(r, "ARBlockReq CMInitiatorMacAdd")?,
            initiator_object: uuid(r, "ARBlockReq CMInitiatorObjectUUID")?,
            properties: r.u32_be("ARBlockReq ARProperties")?,
            activity_timeout_factor: r.u16_be("ARBlockReq CMInitiatorActivityTimeoutFactor")?,
            udp_rt_port: r.u16_be("ARBlockReq CMInitiatorUDPRTPort")?,
            station_name: station_name(r, "ARBlockReq StationNameLength")?,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
        put16(b, self.ar_type.0);
        b.extend(self.ar_uuid.0);
        put16(b, self.session_key);
        b.extend(self.initiator_mac.0);
        b.extend(self.initiator_object.0);
        put32(b, self.properties);
        put16(b, self.activity_timeout_factor);
        put16(b, self.udp_rt_port);
        put_name(b, &self.station_name, "CMInitiatorStationName")
    }
}

/// ARBlockRes (8101h): the device's answer to an ARBlockReq.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ArBlockRes {
    /// ARType (the request's).
    pub ar_type: ArType,
    /// ARUUID (the request's).
    pub ar_uuid: Uuid,
    /// SessionKey (the request's).
    pub session_key: u16,
    /// CMResponderMacAdd: the device's MAC address.
    pub responder_mac: MacAddr,
    /// CMResponderUDPRTPort (8892h).
    pub udp_rt_port: u16,
}

impl ArBlockRes {
    fn parse(r: &mut R<'_>) -> Result<ArBlockRes, Error> {
        Ok(ArBlockRes {
            ar_type: ArType(r.u16_be("ARBlockRes ARType")?),
            ar_uuid: uuid(r, "ARBlockRes ARUUID")?,
            session_key: r.u16_be("ARBlockRes SessionKey")?,
            responder_mac: mac(r, "ARBlockRes CMResponderMacAdd")?,
            udp_rt_port: r.u16_be("ARBlockRes CMResponderUDPRTPort")?,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        put16(b, self.ar_type.0);
        b.extend(self.ar_uuid.0);
        put16(b, self.session_key);
        b.extend(self.responder_mac.0);
        put16(b, self.udp_rt_port);
    }
}

/// One IO data object or IOCS of an IOCR API: where a submodule's data or consumer status
/// sits in the RT frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IocrEntry {
    /// SlotNumber.
    pub slot: u16,
    /// SubslotNumber.
    pub subslot: u16,
    /// IODataObjectFrameOffset / IOCSFrameOffset: offset in the C_SDU.
    pub frame_offset: u16,
}

impl IocrEntry {
    fn parse(r: &mut R<'_>) -> Result<IocrEntry, Error> {
        Ok(IocrEntry {
            slot: r.u16_be("IOCRBlockReq SlotNumber")?,
            subslot: r.u16_be("IOCRBlockReq SubslotNumber")?,
            frame_offset: r.u16_be("IOCRBlockReq FrameOffset")?,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        put16(b, self.slot);
        put16(b, self.subslot);
        put16(b, self.frame_offset);
    }
}

/// One API of an IOCRBlockReq.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct IocrApi {
    /// API (0: the default application process).
    pub api: u32,
    /// The IO data objects (the data this CR carries).
    pub io_data: Vec<IocrEntry>,
    /// The IOCS (the consumer statuses this CR carries for the other direction's data).
    pub iocs: Vec<IocrEntry>,
}

/// IOCRBlockReq (0102h): one cyclic IO communication relation.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct IocrBlockReq {
    /// IOCRType.
    pub iocr_type: IocrType,
    /// IOCRReference: the controller's number of this CR.
    pub reference: u16,
    /// LT: 8892h.
    pub lt: u16,
    /// IOCRProperties ([`iocr_properties`]).
    pub properties: u32,
    /// DataLength: the C_SDU length.
    pub data_length: u16,
    /// FrameID (the controller's proposal for an input CR; the device's answer may differ).
    pub frame_id: u16,
    /// SendClockFactor (× 31.25 µs).
    pub send_clock_factor: u16,
    /// ReductionRatio.
    pub reduction_ratio: u16,
    /// Phase.
    pub phase: u16,
    /// Sequence.
    pub sequence: u16,
    /// FrameSendOffset (FFFFFFFFh: as soon as possible).
    pub frame_send_offset: u32,
    /// WatchdogFactor.
    pub watchdog_factor: u16,
    /// DataHoldFactor.
    pub data_hold_factor: u16,
    /// IOCRTagHeader: VLAN priority (bits 13–15) and VLAN id.
    pub tag_header: u16,
    /// IOCRMulticastMACAdd.
    pub multicast_mac: MacAddr,
    /// The APIs.
    pub apis: Vec<IocrApi>,
}

impl IocrBlockReq {
    fn parse(r: &mut R<'_>) -> Result<IocrBlockReq, Error> {
        let mut b = IocrBlockReq {
            iocr_type: IocrType(r.u16_be("IOCRBlockReq IOCRType")?),
            reference: r.u16_be("IOCRBlockReq IOCRReference")?,
            lt: r.u16_be("IOCRBlockReq LT")?,
            properties: r.u32_be("IOCRBlockReq IOCRProperties")?,
            data_length: r.u16_be("IOCRBlockReq DataLength")?,
            frame_id: r.u16_be("IOCRBlockReq FrameID")?,
            send_clock_factor: r.u16_be("IOCRBlockReq SendClockFactor")?,
            reduction_ratio: r.u16_be("IOCRBlockReq ReductionRatio")?,
            phase: r.u16_be("IOCRBlockReq Phase")?,
            sequence: r.u16_be("IOCRBlockReq Sequence")?,
            frame_send_offset: r.u32_be("IOCRBlockReq FrameSendOffset")?,
            watchdog_factor: r.u16_be("IOCRBlockReq WatchdogFactor")?,
            data_hold_factor: r.u16_be("IOCRBlockReq DataHoldFactor")?,
            tag_header: r.u16_be("IOCRBlockReq IOCRTagHeader")?,
            multicast_mac: mac(r, "IOCRBlockReq IOCRMulticastMACAdd")?,
            apis: Vec::new(),
        };
        for _ in 0..count(r, 8, "IOCRBlockReq NumberOfAPIs")? {
            let api = r.u32_be("IOCRBlockReq API")?;
            let mut io_data = Vec::new();
            for _ in 0..count(r, 6, "IOCRBlockReq NumberOfIODataObjects")? {
                io_data.push(IocrEntry::parse(r)?);
            }
            let mut iocs = Vec::new();
            for _ in 0..count(r, 6, "IOCRBlockReq NumberOfIOCS")? {
                iocs.push(IocrEntry::parse(r)?);
            }
            b.apis.push(IocrApi { api, io_data, iocs });
        }
        Ok(b)
    }

    fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
        put16(b, self.iocr_type.0);
        put16(b, self.reference);
        put16(b, self.lt);
        put32(b, self.properties);
        for v in [
            self.data_length,
            self.frame_id,
            self.send_clock_factor,
            self.reduction_ratio,
            self.phase,
            self.sequence,
        ] {
            put16(b, v);
        }
        put32(b, self.frame_send_offset);
        put16(b, self.watchdog_factor);
        put16(b, self.data_hold_factor);
        put16(b, self.tag_header);
        b.extend(self.multicast_mac.0);
        put_count(b, self.apis.len(), "IOCRBlockReq NumberOfAPIs")?;
        for api in &self.apis {
            put32(b, api.api);
            put_count(b, api.io_data.len(), "IOCRBlockReq NumberOfIODataObjects")?;
            api.io_data.iter().for_each(|e| e.emit(b));
            put_count(b, api.iocs.len(), "IOCRBlockReq NumberOfIOCS")?;
            api.iocs.iter().for_each(|e| e.emit(b));
        }
        Ok(())
    }
}

/// IOCRBlockRes (8102h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IocrBlockRes {
    /// IOCRType (the request's).
    pub iocr_type: IocrType,
    /// IOCRReference (the request's).
    pub reference: u16,
    /// FrameID the device uses (its choice for an input CR).
    pub frame_id: u16,
}

impl IocrBlockRes {
    fn parse(r: &mut R<'_>) -> Result<IocrBlockRes, Error> {
        Ok(IocrBlockRes {
            iocr_type: IocrType(r.u16_be("IOCRBlockRes IOCRType")?),
            reference: r.u16_be("IOCRBlockRes IOCRReference")?,
            frame_id: r.u16_be("IOCRBlockRes FrameID")?,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        put16(b, self.iocr_type.0);
        put16(b, self.reference);
        put16(b, self.frame_id);
    }
}

/// AlarmCRBlockReq (0103h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AlarmCrBlockReq {
    /// AlarmCRType (1).
    pub alarm_cr_type: AlarmCrType,
    /// LT: 8892h (0800h for RTA over UDP).
    pub lt: u16,
    /// AlarmCRProperties ([`alarm_cr_properties`]).
    pub properties: u32,
    /// RTATimeoutFactor (× 100 ms).
    pub rta_timeout_factor: u16,
    /// RTARetries (3..15).
    pub rta_retries: u16,
    /// LocalAlarmReference: the controller's alarm reference.
    pub local_alarm_reference: u16,
    /// MaxAlarmDataLength (200..1432).
    pub max_alarm_data_length: u16,
    /// AlarmCRTagHeaderHigh.
    pub tag_header_high: u16,
    /// AlarmCRTagHeaderLow.
    pub tag_header_low: u16,
}

impl AlarmCrBlockReq {
    fn parse(r: &mut R<'_>) -> Result<AlarmCrBlockReq, Error> {
        Ok(AlarmCrBlockReq {
            alarm_cr_type: AlarmCrType(r.u16_be("AlarmCRBlockReq AlarmCRType")?),
            lt: r.u16_be("AlarmCRBlockReq LT")?,
            properties: r.u32_be("AlarmCRBlockReq AlarmCRProperties")?,
            rta_timeout_factor: r.u16_be("AlarmCRBlockReq RTATimeoutFactor")?,
            rta_retries: r.u16_be("AlarmCRBlockReq RTARetries")?,
            local_alarm_reference: r.u16_be("AlarmCRBlockReq LocalAlarmReference")?,
            max_alarm_data_length: r.u16_be("AlarmCRBlockReq MaxAlarmDataLength")?,
            tag_header_high: r.u16_be("AlarmCRBlockReq AlarmCRTagHeaderHigh")?,
            tag_header_low: r.u16_be("AlarmCRBlockReq AlarmCRTagHeaderLow")?,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        put16(b, self.alarm_cr_type.0);
        put16(b, self.lt);
        put32(b, self.properties);
        for v in [
            self.rta_timeout_factor,
            self.rta_retries,
            self.local_alarm_reference,
            self.max_alarm_data_length,
            self.tag_header_high,
            self.tag_header_low,
        ] {
            put16(b, v);
        }
    }
}

/// AlarmCRBlockRes (8103h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AlarmCrBlockRes {
    /// AlarmCRType (1).
    pub alarm_cr_type: AlarmCrType,
    /// LocalAlarmReference: the device's alarm reference.
    pub local_alarm_reference: u16,
    /// MaxAlarmDataLength the device accepts.
    pub max_alarm_data_length: u16,
}

impl AlarmCrBlockRes {
    fn parse(r: &mut R<'_>) -> Result<AlarmCrBlockRes, Error> {
        Ok(AlarmCrBlockRes {
            alarm_cr_type: AlarmCrType(r.u16_be("AlarmCRBlockRes AlarmCRType")?),
            local_alarm_reference: r.u16_be("AlarmCRBlockRes LocalAlarmReference")?,
            max_alarm_data_length: r.u16_be("AlarmCRBlockRes MaxAlarmDataLength")?,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        put16(b, self.alarm_cr_type.0);
        put16(b, self.local_alarm_reference);
        put16(b, self.max_alarm_data_length);
    }
}

/// One DataDescription of an expected submodule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DataDescription {
    /// Input or output.
    pub direction: DataDirection,
    /// SubmoduleDataLength: the data bytes.
    pub length: u16,
    /// LengthIOCS (1).
    pub length_iocs: u8,
    /// LengthIOPS (1).
    pub length_iops: u8,
}

impl DataDescription {
    /// A description of `length` bytes with one-byte IOCS and IOPS.
    pub fn new(direction: DataDirection, length: u16) -> DataDescription {
        DataDescription {
            direction,
            length,
            length_iocs: 1,
            length_iops: 1,
        }
    }

    fn parse(r: &mut R<'_>) -> Result<DataDescription, Error> {
        Ok(DataDescription {
            direction: DataDirection(r.u16_be("ExpectedSubmoduleBlockReq DataDescription")?),
            length: r.u16_be("ExpectedSubmoduleBlockReq SubmoduleDataLength")?,
            length_iocs: r.u8("ExpectedSubmoduleBlockReq LengthIOCS")?,
            length_iops: r.u8("ExpectedSubmoduleBlockReq LengthIOPS")?,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        put16(b, self.direction.0);
        put16(b, self.length);
        b.extend([self.length_iocs, self.length_iops]);
    }
}

/// One expected submodule.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ExpectedSubmodule {
    /// SubslotNumber.
    pub subslot: u16,
    /// SubmoduleIdentNumber.
    pub ident: u32,
    /// SubmoduleProperties: its type says how many descriptions follow.
    pub properties: SubmoduleProperties,
    /// The DataDescriptions: one (input for NO_IO and INPUT, output for OUTPUT) or two
    /// (input, output) for INPUT_OUTPUT.
    pub data: Vec<DataDescription>,
}

/// One API/slot entry of an ExpectedSubmoduleBlockReq: a module and its submodules.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ExpectedApi {
    /// API.
    pub api: u32,
    /// SlotNumber.
    pub slot: u16,
    /// ModuleIdentNumber.
    pub module_ident: u32,
    /// ModuleProperties.
    pub module_properties: u16,
    /// The submodules.
    pub submodules: Vec<ExpectedSubmodule>,
}

/// ExpectedSubmoduleBlockReq (0104h): the configuration the controller expects.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ExpectedSubmoduleBlockReq {
    /// The API/slot entries (NumberOfAPIs of them).
    pub apis: Vec<ExpectedApi>,
}

impl ExpectedSubmoduleBlockReq {
    fn parse(r: &mut R<'_>) -> Result<ExpectedSubmoduleBlockReq, Error> {
        let mut apis = Vec::new();
        for _ in 0..count(r, 14, "ExpectedSubmoduleBlockReq NumberOfAPIs")? {
            let mut a = ExpectedApi {
                api: r.u32_be("ExpectedSubmoduleBlockReq API")?,
                slot: r.u16_be("ExpectedSubmoduleBlockReq SlotNumber")?,
                module_ident: r.u32_be("ExpectedSubmoduleBlockReq ModuleIdentNumber")?,
                module_properties: r.u16_be("ExpectedSubmoduleBlockReq ModuleProperties")?,
                submodules: Vec::new(),
            };
            for _ in 0..count(r, 14, "ExpectedSubmoduleBlockReq NumberOfSubmodules")? {
                let subslot = r.u16_be("ExpectedSubmoduleBlockReq SubslotNumber")?;
                let ident = r.u32_be("ExpectedSubmoduleBlockReq SubmoduleIdentNumber")?;
                let properties =
                    SubmoduleProperties(r.u16_be("ExpectedSubmoduleBlockReq SubmoduleProperties")?);
                let mut data = Vec::new();
                for _ in 0..properties.data_description_count() {
                    data.push(DataDescription::parse(r)?);
                }
                a.submodules.push(ExpectedSubmodule {
                    subslot,
                    ident,
                    properties,
                    data,
                });
            }
            apis.push(a);
        }
        Ok(ExpectedSubmoduleBlockReq { apis })
    }

    fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
        put_count(b, self.apis.len(), "ExpectedSubmoduleBlockReq NumberOfAPIs")?;
        for a in &self.apis {
            put32(b, a.api);
            put16(b, a.slot);
            put32(b, a.module_ident);
            put16(b, a.module_properties);
            put_count(
                b,
                a.submodules.len(),
                "ExpectedSubmoduleBlockReq NumberOfSubmodules",
            )?;
            for s in &a.submodules {
                if s.data.len() != s.properties.data_description_count() {
                    return Err(Error::Invalid {
                        field: "ExpectedSubmoduleBlockReq DataDescription count",
                        value: s.data.len() as u32,
                    });
                }
                put16(b, s.subslot);
                put32(b, s.ident);
                put16(b, s.properties.0);
                s.data.iter().for_each(|d| d.emit(b));
            }
        }
        Ok(())
    }
}

/// One submodule entry of a ModuleDiffBlock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DiffSubmodule {
    /// SubslotNumber.
    pub subslot: u16,
    /// SubmoduleIdentNumber (the real one).
    pub ident: u32,
    /// SubmoduleState.
    pub state: SubmoduleState,
}

/// One module entry of a ModuleDiffBlock.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct DiffModule {
    /// SlotNumber.
    pub slot: u16,
    /// ModuleIdentNumber (the real one; 0 for no module).
    pub ident: u32,
    /// ModuleState.
    pub state: ModuleState,
    /// The submodules that differ.
    pub submodules: Vec<DiffSubmodule>,
}

/// One API of a ModuleDiffBlock.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct DiffApi {
    /// API.
    pub api: u32,
    /// The modules that differ.
    pub modules: Vec<DiffModule>,
}

/// ModuleDiffBlock (8104h): where the real configuration differs from the expected one.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ModuleDiffBlock {
    /// The APIs.
    pub apis: Vec<DiffApi>,
}

impl ModuleDiffBlock {
    fn parse(r: &mut R<'_>) -> Result<ModuleDiffBlock, Error> {
        let mut apis = Vec::new();
        for _ in 0..count(r, 6, "ModuleDiffBlock NumberOfAPIs")? {
            let mut a = DiffApi {
                api: r.u32_be("ModuleDiffBlock API")?,
                modules: Vec::new(),
            };
            for _ in 0..count(r, 10, "ModuleDiffBlock NumberOfModules")? {
                let mut m = DiffModule {
                    slot: r.u16_be("ModuleDiffBlock SlotNumber")?,
                    ident: r.u32_be("ModuleDiffBlock ModuleIdentNumber")?,
                    state: ModuleState(r.u16_be("ModuleDiffBlock ModuleState")?),
                    submodules: Vec::new(),
                };
                for _ in 0..count(r, 8, "ModuleDiffBlock NumberOfSubmodules")? {
                    m.submodules.push(DiffSubmodule {
                        subslot: r.u16_be("ModuleDiffBlock SubslotNumber")?,
                        ident: r.u32_be("ModuleDiffBlock SubmoduleIdentNumber")?,
                        state: SubmoduleState(r.u16_be("ModuleDiffBlock SubmoduleState")?),
                    });
                }
                a.modules.push(m);
            }
            apis.push(a);
        }
        Ok(ModuleDiffBlock { apis })
    }

    fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
        put_count(b, self.apis.len(), "ModuleDiffBlock NumberOfAPIs")?;
        for a in &self.apis {
            put32(b, a.api);
            put_count(b, a.modules.len(), "ModuleDiffBlock NumberOfModules")?;
            for m in &a.modules {
                put16(b, m.slot);
                put32(b, m.ident);
                put16(b, m.state.0);
                put_count(b, m.submodules.len(), "ModuleDiffBlock NumberOfSubmodules")?;
                for s in &m.submodules {
                    put16(b, s.subslot);
                    put32(b, s.ident);
                    put16(b, s.state.0);
                }
            }
        }
        Ok(())
    }
}

/// ARServerBlock (8106h): the device's station name. Emitted with zero padding to make the
/// whole block a multiple of 4 bytes (as p-net does); parsed with up to 3 padding bytes.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ArServerBlock {
    /// CMResponderStationName.
    pub station_name: Vec<u8>,
}

impl ArServerBlock {
    fn parse(r: &mut R<'_>) -> Result<ArServerBlock, Error> {
        let station_name = station_name(r, "ARServerBlock StationNameLength")?;
        let pad = r.rest();
        if pad.len() > 3 {
            return Err(Error::Trailing {
                what: "ARServerBlock",
                extra: pad.len(),
            });
        }
        Ok(ArServerBlock { station_name })
    }

    fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
        put_name(b, &self.station_name, "CMResponderStationName")?;
        // The block so far: 6 header bytes, 2 length bytes, the name.
        let pad = (4 - (BLOCK_HEADER_LEN + 2 + self.station_name.len()) % 4) % 4;
        b.extend(std::iter::repeat_n(0, pad));
        Ok(())
    }
}

/// The addressing fields every IODRead/IODWrite header shares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RecordAddress {
    /// SeqNumber: the controller counts its record requests; a response carries its
    /// request's.
    pub seq_number: u16,
    /// ARUUID (nil for an implicit read).
    pub ar_uuid: Uuid,
    /// API.
    pub api: u32,
    /// SlotNumber.
    pub slot: u16,
    /// SubslotNumber.
    pub subslot: u16,
    /// Index: the record.
    pub index: u16,
}

impl RecordAddress {
    /// Reads SeqNumber .. RecordDataLength; returns the address and RecordDataLength.
    fn parse(r: &mut R<'_>, what: &'static str) -> Result<(RecordAddress, u32), Error> {
        let seq_number = r.u16_be(what)?;
        let ar_uuid = uuid(r, what)?;
        let api = r.u32_be(what)?;
        let slot = r.u16_be(what)?;
        let subslot = r.u16_be(what)?;
        r.bytes(2, what)?;
        let index = r.u16_be(what)?;
        let len = r.u32_be(what)?;
        Ok((
            RecordAddress {
                seq_number,
                ar_uuid,
                api,
                slot,
                subslot,
                index,
            },
            len,
        ))
    }

    fn emit(&self, b: &mut Vec<u8>, record_data_length: u32) {
        put16(b, self.seq_number);
        b.extend(self.ar_uuid.0);
        put32(b, self.api);
        put16(b, self.slot);
        put16(b, self.subslot);
        b.extend([0, 0]);
        put16(b, self.index);
        put32(b, record_data_length);
    }
}

fn padding(r: &mut R<'_>, n: usize, what: &'static str) -> Result<(), Error> {
    r.bytes(n, what).map(|_| ())
}

/// An IODWrite request: the IODWriteReqHeader (0008h) and the record data after it
/// (RecordDataLength is the data's length).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct IodWriteReq {
    /// Which record.
    pub addr: RecordAddress,
    /// The record data.
    pub data: Vec<u8>,
}

/// An IODRead request header (0009h): RecordDataLength is the most the controller reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IodReadReq {
    /// Which record.
    pub addr: RecordAddress,
    /// RecordDataLength: the largest answer wanted.
    pub record_data_length: u32,
    /// TargetARUUID: the AR an implicit read (nil ARUUID) asks about; nil otherwise (the
    /// first 16 bytes of RWPadding then).
    pub target_ar_uuid: Uuid,
}

/// An IODWrite response header (8008h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IodWriteRes {
    /// The request's address.
    pub addr: RecordAddress,
    /// RecordDataLength: the bytes written.
    pub record_data_length: u32,
    /// AdditionalValue1.
    pub additional_value1: u16,
    /// AdditionalValue2.
    pub additional_value2: u16,
    /// The write's PNIO status (DFh 80h class/code on a refused write).
    pub status: PnioStatus,
}

/// An IODRead response: the IODReadResHeader (8009h) and the record data after it
/// (RecordDataLength is the data's length).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct IodReadRes {
    /// The request's address.
    pub addr: RecordAddress,
    /// AdditionalValue1.
    pub additional_value1: u16,
    /// AdditionalValue2.
    pub additional_value2: u16,
    /// The record data.
    pub data: Vec<u8>,
}

/// An IODControl / IOXControl / Release block, request or response (0110h..0118h,
/// 8110h..8118h): the type says which.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IodControl {
    /// BlockType ([`BlockType::PRM_END_REQ`], [`BlockType::APPLICATION_READY_REQ`],
    /// [`BlockType::RELEASE_REQ`], their responses …).
    pub block_type: BlockType,
    /// ARUUID.
    pub ar_uuid: Uuid,
    /// SessionKey (the AR's).
    pub session_key: u16,
    /// The reserved field, AlarmSequenceNumber of a plug (0 otherwise).
    pub alarm_sequence_number: u16,
    /// ControlCommand.
    pub command: ControlCommand,
    /// ControlBlockProperties (0).
    pub properties: u16,
}

impl IodControl {
    fn request(
        block_type: BlockType,
        command: ControlCommand,
        ar_uuid: Uuid,
        session_key: u16,
    ) -> IodControl {
        IodControl {
            block_type,
            ar_uuid,
            session_key,
            alarm_sequence_number: 0,
            command,
            properties: 0,
        }
    }

    /// The controller's PrmEnd (0110h, command PrmEnd).
    pub fn prm_end(ar_uuid: Uuid, session_key: u16) -> IodControl {
        IodControl::request(
            BlockType::PRM_END_REQ,
            ControlCommand::PRM_END,
            ar_uuid,
            session_key,
        )
    }

    /// The device's ApplicationReady (0112h, command ApplicationReady).
    pub fn application_ready(ar_uuid: Uuid, session_key: u16) -> IodControl {
        IodControl::request(
            BlockType::APPLICATION_READY_REQ,
            ControlCommand::APPLICATION_READY,
            ar_uuid,
            session_key,
        )
    }

    /// The controller's Release (0114h, command Release).
    pub fn release(ar_uuid: Uuid, session_key: u16) -> IodControl {
        IodControl::request(
            BlockType::RELEASE_REQ,
            ControlCommand::RELEASE,
            ar_uuid,
            session_key,
        )
    }

    /// The response to this request: the response type, command Done, the rest the same.
    pub fn done(&self) -> IodControl {
        IodControl {
            block_type: self.block_type.response(),
            command: ControlCommand::DONE,
            properties: 0,
            ..*self
        }
    }

    fn parse(block_type: BlockType, r: &mut R<'_>) -> Result<IodControl, Error> {
        padding(r, 2, "IODControl reserved")?;
        Ok(IodControl {
            block_type,
            ar_uuid: uuid(r, "IODControl ARUUID")?,
            session_key: r.u16_be("IODControl SessionKey")?,
            alarm_sequence_number: r.u16_be("IODControl AlarmSequenceNumber")?,
            command: ControlCommand(r.u16_be("IODControl ControlCommand")?),
            properties: r.u16_be("IODControl ControlBlockProperties")?,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        b.extend([0, 0]);
        b.extend(self.ar_uuid.0);
        put16(b, self.session_key);
        put16(b, self.alarm_sequence_number);
        put16(b, self.command.0);
        put16(b, self.properties);
    }
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
            });
        }
        let mut r = R::new(view.body());
        let mut used = view.total_len();
        // Record data after the header block.
        let mut record_data = |len: u32| -> Result<Vec<u8>, Error> {
            let rest = &buf[used..];
            let n = len as usize;
            if n > rest.len() {
                return Err(Error::BadLength {
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

    /// ARUUID of the tests: 11223344-5566-7788-99AA-BBCCDDEEFF00 (big-endian in blocks).
    const AR: Uuid = Uuid([
        0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x99, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE, 0xFF,
        0x00,
    ]);
    const MAC: MacAddr = MacAddr([0x00, 0x1B, 0x1B, 0x01, 0x02, 0x03]);

    fn one(bytes: &[u8]) -> Block {
        let (b, n) = Block::parse(bytes).unwrap();
        assert_eq!(n, bytes.len());
        assert_eq!(b.to_bytes().unwrap(), bytes, "{b:?}");
        b
    }

    fn ar_block_req_bytes() -> Vec<u8> {
        let mut b = Vec::new();
        b.extend([0x01, 0x01]); // BlockType ARBlockReq
        b.extend([0x00, 0x39]); // BlockLength 57 = 2 + 52 + 3
        b.extend([0x01, 0x00]); // version 1.0
        b.extend([0x00, 0x01]); // ARType IOCARSingle
        b.extend(AR.0); // ARUUID
        b.extend([0x00, 0x02]); // SessionKey 2
        b.extend(MAC.0); // CMInitiatorMacAdd
                         // CMInitiatorObjectUUID DEA00000-6C97-11D1-8271-0001-0203-002A
        b.extend([0xDE, 0xA0, 0x00, 0x00, 0x6C, 0x97, 0x11, 0xD1]);
        b.extend([0x82, 0x71, 0x00, 0x01, 0x02, 0x03, 0x00, 0x2A]);
        b.extend([0x00, 0x00, 0x00, 0x11]); // ARProperties: state active, CM initiator prm server
        b.extend([0x00, 0x64]); // CMInitiatorActivityTimeoutFactor 100 (10 s)
        b.extend([0x88, 0x92]); // CMInitiatorUDPRTPort
        b.extend([0x00, 0x03]); // StationNameLength 3
        b.extend(*b"plc"); // CMInitiatorStationName
        b
    }

    fn iocr_req_bytes() -> Vec<u8> {
        let mut b = Vec::new();
        b.extend([0x01, 0x02, 0x00, 0x3E, 0x01, 0x00]); // IOCRBlockReq, length 62, 1.0
        b.extend([0x00, 0x01]); // IOCRType input
        b.extend([0x00, 0x01]); // IOCRReference 1
        b.extend([0x88, 0x92]); // LT
        b.extend([0x00, 0x00, 0x00, 0x01]); // IOCRProperties RT_CLASS_1
        b.extend([0x00, 0x28]); // DataLength 40
        b.extend([0x80, 0x01]); // FrameID 8001h
        b.extend([0x00, 0x20]); // SendClockFactor 32 (1 ms)
        b.extend([0x00, 0x04]); // ReductionRatio 4
        b.extend([0x00, 0x01]); // Phase 1
        b.extend([0x00, 0x00]); // Sequence 0
        b.extend([0xFF, 0xFF, 0xFF, 0xFF]); // FrameSendOffset: as soon as possible
        b.extend([0x00, 0x03]); // WatchdogFactor 3
        b.extend([0x00, 0x03]); // DataHoldFactor 3
        b.extend([0xC0, 0x00]); // IOCRTagHeader: priority 6, VLAN 0
        b.extend([0x01, 0x0E, 0xCF, 0x00, 0x00, 0x00]); // IOCRMulticastMACAdd
        b.extend([0x00, 0x01]); // NumberOfAPIs 1
        b.extend([0x00, 0x00, 0x00, 0x00]); // API 0
        b.extend([0x00, 0x01]); // NumberOfIODataObjects 1
        b.extend([0x00, 0x01, 0x00, 0x01, 0x00, 0x00]); // slot 1, subslot 1, offset 0
        b.extend([0x00, 0x01]); // NumberOfIOCS 1
        b.extend([0x00, 0x01, 0x00, 0x01, 0x00, 0x0D]); // slot 1, subslot 1, offset 13
        b
    }

    fn alarm_cr_req_bytes() -> Vec<u8> {
        let mut b = Vec::new();
        b.extend([0x01, 0x03, 0x00, 0x16, 0x01, 0x00]); // AlarmCRBlockReq, length 22, 1.0
        b.extend([0x00, 0x01]); // AlarmCRType
        b.extend([0x88, 0x92]); // LT
        b.extend([0x00, 0x00, 0x00, 0x00]); // AlarmCRProperties: RTA_CLASS_1
        b.extend([0x00, 0x01]); // RTATimeoutFactor 1 (100 ms)
        b.extend([0x00, 0x03]); // RTARetries 3
        b.extend([0x00, 0x01]); // LocalAlarmReference 1
        b.extend([0x00, 0xC8]); // MaxAlarmDataLength 200
        b.extend([0xC0, 0x00]); // AlarmCRTagHeaderHigh
        b.extend([0xA0, 0x00]); // AlarmCRTagHeaderLow
        b
    }

    fn expected_bytes() -> Vec<u8> {
        let mut b = Vec::new();
        b.extend([0x01, 0x04, 0x00, 0x42, 0x01, 0x00]); // ExpectedSubmoduleBlockReq, 66, 1.0
        b.extend([0x00, 0x02]); // NumberOfAPIs 2
                                // API 0, slot 0, ModuleIdentNumber 1, ModuleProperties 0, 1 submodule:
        b.extend([0, 0, 0, 0, 0x00, 0x00, 0, 0, 0, 1, 0x00, 0x00, 0x00, 0x01]);
        // subslot 1, SubmoduleIdentNumber 1, properties NO_IO,
        b.extend([0x00, 0x01, 0, 0, 0, 1, 0x00, 0x00]);
        // DataDescription input, length 0, IOCS 1, IOPS 1
        b.extend([0x00, 0x01, 0x00, 0x00, 0x01, 0x01]);
        // API 0, slot 1, ModuleIdentNumber 0000_0101h, ModuleProperties 0, 1 submodule:
        b.extend([0, 0, 0, 0, 0x00, 0x01, 0, 0, 1, 1, 0x00, 0x00, 0x00, 0x01]);
        // subslot 1, SubmoduleIdentNumber 0000_0102h, properties INPUT_OUTPUT,
        b.extend([0x00, 0x01, 0, 0, 1, 2, 0x00, 0x03]);
        // DataDescription input 12 bytes; output 12 bytes
        b.extend([0x00, 0x01, 0x00, 0x0C, 0x01, 0x01]);
        b.extend([0x00, 0x02, 0x00, 0x0C, 0x01, 0x01]);
        b
    }

    #[test]
    fn ar_block_req() {
        let b = one(&ar_block_req_bytes());
        let Block::ArReq(a) = b else { panic!("{b:?}") };
        assert_eq!(a.ar_type, ArType::IOC_AR_SINGLE);
        assert_eq!(a.ar_uuid, AR);
        assert_eq!(a.session_key, 2);
        assert_eq!(a.initiator_mac, MAC);
        assert_eq!(
            a.initiator_object.pnio_object_parts(),
            Some((1, 0x0203, 0x002A))
        );
        assert_eq!(
            a.properties & ar_properties::STATE_MASK,
            ar_properties::STATE_ACTIVE
        );
        assert_ne!(a.properties & ar_properties::PRM_SERVER_CM_INITIATOR, 0);
        assert_eq!(a.activity_timeout_factor, 100);
        assert_eq!(a.udp_rt_port, 0x8892);
        assert_eq!(a.station_name, b"plc");
    }

    #[test]
    fn ar_block_res() {
        let mut b = Vec::new();
        b.extend([0x81, 0x01, 0x00, 0x1E, 0x01, 0x00]); // ARBlockRes, length 30, 1.0
        b.extend([0x00, 0x01]); // ARType
        b.extend(AR.0); // ARUUID
        b.extend([0x00, 0x02]); // SessionKey
        b.extend([0x00, 0x09, 0xE5, 0x00, 0x00, 0x01]); // CMResponderMacAdd
        b.extend([0x88, 0x92]); // CMResponderUDPRTPort
        let blk = one(&b);
        assert_eq!(
            blk,
            Block::ArRes(ArBlockRes {
                ar_type: ArType::IOC_AR_SINGLE,
                ar_uuid: AR,
                session_key: 2,
                responder_mac: MacAddr([0x00, 0x09, 0xE5, 0x00, 0x00, 0x01]),
                udp_rt_port: 0x8892,
            })
        );
    }

    #[test]
    fn iocr_blocks() {
        let b = one(&iocr_req_bytes());
        let Block::IocrReq(c) = b else {
            panic!("{b:?}")
        };
        assert_eq!(c.iocr_type, IocrType::INPUT);
        assert_eq!(
            c.properties & iocr_properties::RT_CLASS_MASK,
            iocr_properties::RT_CLASS_1
        );
        assert_eq!((c.data_length, c.frame_id), (40, 0x8001));
        assert_eq!((c.send_clock_factor, c.reduction_ratio), (32, 4));
        assert_eq!(c.frame_send_offset, 0xFFFF_FFFF);
        assert_eq!(c.apis.len(), 1);
        assert_eq!(
            c.apis[0].iocs,
            [IocrEntry {
                slot: 1,
                subslot: 1,
                frame_offset: 13
            }]
        );
        // IOCRBlockRes, length 8, 1.0: input CR, reference 1, FrameID 8001h.
        let res = [
            0x81, 0x02, 0x00, 0x08, 0x01, 0x00, 0x00, 0x01, 0x00, 0x01, 0x80, 0x01,
        ];
        assert_eq!(
            one(&res),
            Block::IocrRes(IocrBlockRes {
                iocr_type: IocrType::INPUT,
                reference: 1,
                frame_id: 0x8001
            })
        );
    }

    #[test]
    fn alarm_cr_blocks() {
        let b = one(&alarm_cr_req_bytes());
        let Block::AlarmCrReq(a) = b else {
            panic!("{b:?}")
        };
        assert_eq!(a.alarm_cr_type, AlarmCrType::ALARM_CR);
        assert_eq!((a.rta_timeout_factor, a.rta_retries), (1, 3));
        assert_eq!((a.local_alarm_reference, a.max_alarm_data_length), (1, 200));
        assert_eq!((a.tag_header_high, a.tag_header_low), (0xC000, 0xA000));
        // AlarmCRBlockRes, length 8, 1.0: type 1, LocalAlarmReference 2, MaxAlarmDataLength
        // 200.
        let res = [
            0x81, 0x03, 0x00, 0x08, 0x01, 0x00, 0x00, 0x01, 0x00, 0x02, 0x00, 0xC8,
        ];
        assert_eq!(
            one(&res),
            Block::AlarmCrRes(AlarmCrBlockRes {
                alarm_cr_type: AlarmCrType::ALARM_CR,
                local_alarm_reference: 2,
                max_alarm_data_length: 200
            })
        );
    }

    #[test]
    fn expected_submodule_block() {
        let b = one(&expected_bytes());
        let Block::ExpectedSubmoduleReq(e) = b else {
            panic!("{b:?}")
        };
        assert_eq!(e.apis.len(), 2);
        assert_eq!(
            e.apis[0].submodules[0].properties,
            SubmoduleProperties::NO_IO
        );
        assert_eq!(
            e.apis[0].submodules[0].data,
            [DataDescription::new(DataDirection::INPUT, 0)]
        );
        let io = &e.apis[1].submodules[0];
        assert_eq!((e.apis[1].slot, e.apis[1].module_ident), (1, 0x0101));
        assert_eq!((io.subslot, io.ident), (1, 0x0102));
        assert_eq!(io.properties.io_type(), 3);
        assert_eq!(
            io.data,
            [
                DataDescription::new(DataDirection::INPUT, 12),
                DataDescription::new(DataDirection::OUTPUT, 12)
            ]
        );
        // An IO submodule with one description cannot be emitted.
        let mut bad = e.clone();
        bad.apis[1].submodules[0].data.pop();
        assert_eq!(
            Block::ExpectedSubmoduleReq(bad).to_bytes(),
            Err(Error::Invalid {
                field: "ExpectedSubmoduleBlockReq DataDescription count",
                value: 1
            })
        );
    }

    #[test]
    fn module_diff_block() {
        let mut b = Vec::new();
        b.extend([0x81, 0x04, 0x00, 0x1C, 0x01, 0x00]); // ModuleDiffBlock, length 28, 1.0
        b.extend([0x00, 0x01]); // NumberOfAPIs 1
        b.extend([0x00, 0x00, 0x00, 0x00]); // API 0
        b.extend([0x00, 0x01]); // NumberOfModules 1
        b.extend([0x00, 0x01]); // SlotNumber 1
        b.extend([0x00, 0x00, 0x01, 0x01]); // ModuleIdentNumber 0101h
        b.extend([0x00, 0x02]); // ModuleState proper module
        b.extend([0x00, 0x01]); // NumberOfSubmodules 1
        b.extend([0x00, 0x01]); // SubslotNumber 1
        b.extend([0x00, 0x00, 0x01, 0x03]); // SubmoduleIdentNumber 0103h (the real one)
        b.extend([0x90, 0x00]); // SubmoduleState: detailed, IdentInfo wrong, ARInfo own
        let blk = one(&b);
        let d = ModuleDiffBlock {
            apis: vec![DiffApi {
                api: 0,
                modules: vec![DiffModule {
                    slot: 1,
                    ident: 0x0101,
                    state: ModuleState::PROPER_MODULE,
                    submodules: vec![DiffSubmodule {
                        subslot: 1,
                        ident: 0x0103,
                        state: SubmoduleState::wrong(),
                    }],
                }],
            }],
        };
        assert_eq!(blk, Block::ModuleDiff(d));
        assert_eq!(SubmoduleState::ok().0, 0x8000);
        assert_eq!(SubmoduleState::substitute().0, 0x8800);
        assert_eq!(SubmoduleState::no_submodule().0, 0x9800);
        assert_eq!(SubmoduleState::application_ready_pending().0, 0x8080);
        assert_eq!(
            SubmoduleState::wrong().ident_info(),
            SubmoduleState::IDENT_WRONG
        );
        assert_eq!(SubmoduleState(0x80C0).ar_info(), 1);
        assert!(SubmoduleState(0x80C0).fault());
        assert_eq!(format!("{:?}", ModuleState::NO_MODULE), "NoModule(0000h)");
    }

    #[test]
    fn ar_server_block_pads_to_four() {
        // ARServerBlock, length 12, 1.0; StationNameLength 6, "sk550p", 2 padding bytes:
        // 6 + 2 + 6 + 2 = 16 bytes.
        let mut b = Vec::new();
        b.extend([0x81, 0x06, 0x00, 0x0C, 0x01, 0x00]);
        b.extend([0x00, 0x06]);
        b.extend(*b"sk550p");
        b.extend([0x00, 0x00]);
        assert_eq!(
            one(&b),
            Block::ArServer(ArServerBlock {
                station_name: b"sk550p".to_vec()
            })
        );
        // 8 name bytes: 6 + 2 + 8 = 16, no padding.
        let s = Block::ArServer(ArServerBlock {
            station_name: b"drive-01".to_vec(),
        });
        assert_eq!(s.to_bytes().unwrap().len(), 16);
        // Four padding bytes are one too many.
        let mut long = b.clone();
        long.extend([0, 0]);
        long[3] = 0x0E;
        assert_eq!(
            Block::parse(&long),
            Err(Error::Trailing {
                what: "ARServerBlock",
                extra: 4
            })
        );
    }

    fn write_req_bytes() -> Vec<u8> {
        let mut b = Vec::new();
        b.extend([0x00, 0x08, 0x00, 0x3C, 0x01, 0x00]); // IODWriteReqHeader, length 60, 1.0
        b.extend([0x00, 0x05]); // SeqNumber 5
        b.extend(AR.0); // ARUUID
        b.extend([0x00, 0x00, 0x00, 0x00]); // API 0
        b.extend([0x00, 0x01]); // SlotNumber 1
        b.extend([0x00, 0x01]); // SubslotNumber 1
        b.extend([0x00, 0x00]); // padding
        b.extend([0x00, 0x2F]); // Index 47
        b.extend([0x00, 0x00, 0x00, 0x04]); // RecordDataLength 4
        b.extend([0; 24]); // RWPadding
        b.extend([0x12, 0x34, 0x56, 0x78]); // record data
        b
    }

    #[test]
    fn write_request_carries_its_record_data() {
        let bytes = write_req_bytes();
        assert_eq!(bytes.len(), RECORD_HEADER_LEN + 4);
        let blocks = Block::parse_all(&bytes).unwrap();
        let addr = RecordAddress {
            seq_number: 5,
            ar_uuid: AR,
            api: 0,
            slot: 1,
            subslot: 1,
            index: 47,
        };
        assert_eq!(
            blocks,
            [Block::WriteReq(IodWriteReq {
                addr,
                data: vec![0x12, 0x34, 0x56, 0x78]
            })]
        );
        assert_eq!(Block::emit_all(&blocks).unwrap(), bytes);
        // RecordDataLength 4 with 3 bytes.
        assert_eq!(
            Block::parse_all(&bytes[..bytes.len() - 1]),
            Err(Error::BadLength {
                field: "RecordDataLength",
                value: 4,
                available: 3
            })
        );

        // IODWriteResHeader, length 60: the same address, RecordDataLength 4,
        // AdditionalValue1/2 0, PNIOStatus DF 80 B6 00 (access denied), RWPadding 16.
        let mut b = vec![0x80, 0x08, 0x00, 0x3C, 0x01, 0x00];
        b.extend(&bytes[6..40]);
        b.extend([0x00, 0x00, 0x00, 0x00]); // AdditionalValue1, AdditionalValue2
        b.extend([0xDF, 0x80, 0xB6, 0x00]); // PNIOStatus
        b.extend([0; 16]); // RWPadding
        assert_eq!(b.len(), RECORD_HEADER_LEN);
        assert_eq!(
            one(&b),
            Block::WriteRes(IodWriteRes {
                addr,
                record_data_length: 4,
                additional_value1: 0,
                additional_value2: 0,
                status: PnioStatus::record(true, super::super::status::pniorw::ACCESS_DENIED),
            })
        );
    }

    #[test]
    fn read_request_and_response() {
        // IODReadReqHeader of an implicit read: nil ARUUID, TargetARUUID set.
        let mut b = Vec::new();
        b.extend([0x00, 0x09, 0x00, 0x3C, 0x01, 0x00]); // IODReadReqHeader, length 60, 1.0
        b.extend([0x00, 0x06]); // SeqNumber 6
        b.extend([0; 16]); // ARUUID nil
        b.extend([0x00, 0x00, 0x00, 0x00]); // API 0
        b.extend([0x00, 0x00, 0x00, 0x01]); // slot 0, subslot 1
        b.extend([0x00, 0x00]); // padding
        b.extend([0xAF, 0xF0]); // Index AFF0h (I&M0)
        b.extend([0x00, 0x00, 0x10, 0x00]); // RecordDataLength 4096 (the most wanted)
        b.extend(AR.0); // TargetARUUID
        b.extend([0; 8]); // RWPadding
        let addr = RecordAddress {
            seq_number: 6,
            ar_uuid: Uuid::NIL,
            api: 0,
            slot: 0,
            subslot: 1,
            index: 0xAFF0,
        };
        assert_eq!(
            one(&b),
            Block::ReadReq(IodReadReq {
                addr,
                record_data_length: 4096,
                target_ar_uuid: AR
            })
        );

        // IODReadResHeader, length 60, RecordDataLength 2, AdditionalValue1/2 0, RWPadding 20,
        // then the 2 record bytes.
        let mut b = vec![0x80, 0x09, 0x00, 0x3C, 0x01, 0x00];
        b.extend([0x00, 0x06]);
        b.extend([0; 16]);
        b.extend([0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0xAF, 0xF0]);
        b.extend([0x00, 0x00, 0x00, 0x02]); // RecordDataLength 2
        b.extend([0x00, 0x00, 0x00, 0x00]); // AdditionalValue1, AdditionalValue2
        b.extend([0; 20]); // RWPadding
        b.extend([0xCA, 0xFE]); // record data
        assert_eq!(
            one(&b),
            Block::ReadRes(IodReadRes {
                addr,
                additional_value1: 0,
                additional_value2: 0,
                data: vec![0xCA, 0xFE],
            })
        );
    }

    #[test]
    fn control_blocks() {
        let mut b = Vec::new();
        b.extend([0x01, 0x10, 0x00, 0x1C, 0x01, 0x00]); // IODControlReq PrmEnd, 28, 1.0
        b.extend([0x00, 0x00]); // reserved
        b.extend(AR.0); // ARUUID
        b.extend([0x00, 0x02]); // SessionKey 2
        b.extend([0x00, 0x00]); // reserved
        b.extend([0x00, 0x01]); // ControlCommand PrmEnd
        b.extend([0x00, 0x00]); // ControlBlockProperties
        let req = IodControl::prm_end(AR, 2);
        assert_eq!(one(&b), Block::Control(req));
        // The response: 8110h, command Done.
        let mut res = b.clone();
        res[0] = 0x81;
        res[29] = 0x08;
        assert_eq!(one(&res), Block::Control(req.done()));
        let app = IodControl::application_ready(AR, 2);
        assert_eq!(app.block_type.0, 0x0112);
        assert_eq!(app.done().block_type, BlockType::APPLICATION_READY_RES);
        assert!(app.command.contains(ControlCommand::APPLICATION_READY));
        let rel = Block::Control(IodControl::release(AR, 2));
        assert_eq!(rel.block_type(), BlockType::RELEASE_REQ);
        assert_eq!(rel.to_bytes().unwrap()[..2], [0x01, 0x14]);
        assert!(BlockType(0x8118).is_control() && !BlockType(0x0115).is_control());
        assert_eq!(BlockType::RELEASE_RES.to_string(), "IODReleaseRes");
    }

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
            Err(Error::BadLength {
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
                value: 1
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
                value: 0x0101
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
            Err(Error::BadLength {
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
            Err(Error::BadLength {
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
            Err(Error::BadLength {
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
}

#[cfg(test)]
mod no_panic {
    //! Every parser of `rpc` and `block` against random, mutated and truncated input: each
    //! returns `Ok` or a typed `Err`, none panics, and what parses emits and parses back the
    //! same.

    use super::super::rpc::{Drep, NcaStatus, NdrRequest, NdrResponse, RpcPacket, RpcRepr};
    use super::*;

    /// A small deterministic generator (xorshift).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
    }

    fn blocks(b: &[u8]) {
        if let Ok(v) = BlockView::new_checked(b) {
            let _ = (v.header(), v.body());
        }
        if let Ok(blocks) = Block::parse_all(b) {
            let again = Block::emit_all(&blocks).expect("a parsed block emits");
            assert_eq!(Block::parse_all(&again).as_ref(), Ok(&blocks));
        }
    }

    fn rpc(b: &[u8]) {
        if let Ok(p) = RpcPacket::new_checked(b) {
            let _ = (p.object(), p.interface(), p.activity(), p.opnum(), p.body());
            let _ = (p.sequence_number(), p.flags1(), p.packet_type());
        }
        if let Ok(r) = RpcRepr::parse_bytes(b) {
            let again = r.emit().expect("a parsed PDU emits");
            assert_eq!(RpcRepr::parse_bytes(&again).as_ref(), Ok(&r));
            let _ = r.nca_status();
        }
        for drep in [Drep::LITTLE_ENDIAN, Drep::BIG_ENDIAN] {
            if let Ok(q) = NdrRequest::parse(b, drep) {
                assert_eq!(NdrRequest::parse(&q.emit(drep), drep).as_ref(), Ok(&q));
                blocks(&q.data);
            }
            if let Ok(q) = NdrResponse::parse(b, drep) {
                assert_eq!(NdrResponse::parse(&q.emit(drep), drep).as_ref(), Ok(&q));
            }
            let _ = NcaStatus::parse(b, drep);
        }
    }

    /// Valid bodies to mutate: a connect request's blocks, a write request, control blocks.
    fn seeds() -> Vec<Vec<u8>> {
        let ar = Uuid::pnio_object(1, 2, 3);
        let mut connect = Vec::new();
        let exp = ExpectedSubmoduleBlockReq {
            apis: vec![ExpectedApi {
                api: 0,
                slot: 1,
                module_ident: 7,
                module_properties: 0,
                submodules: vec![ExpectedSubmodule {
                    subslot: 1,
                    ident: 8,
                    properties: SubmoduleProperties::INPUT_OUTPUT,
                    data: vec![
                        DataDescription::new(DataDirection::INPUT, 4),
                        DataDescription::new(DataDirection::OUTPUT, 4),
                    ],
                }],
            }],
        };
        let iocr = IocrBlockReq {
            iocr_type: IocrType::OUTPUT,
            apis: vec![IocrApi {
                api: 0,
                io_data: vec![IocrEntry::default(); 2],
                iocs: vec![IocrEntry::default()],
            }],
            ..IocrBlockReq::default()
        };
        let diff = ModuleDiffBlock {
            apis: vec![DiffApi {
                api: 0,
                modules: vec![DiffModule {
                    submodules: vec![DiffSubmodule::default(); 2],
                    ..DiffModule::default()
                }],
            }],
        };
        for b in [
            Block::ArReq(ArBlockReq {
                station_name: b"controller".to_vec(),
                ..ArBlockReq::default()
            }),
            Block::IocrReq(iocr),
            Block::AlarmCrReq(AlarmCrBlockReq::default()),
            Block::ExpectedSubmoduleReq(exp),
            Block::ArRes(ArBlockRes::default()),
            Block::IocrRes(IocrBlockRes::default()),
            Block::AlarmCrRes(AlarmCrBlockRes::default()),
            Block::ModuleDiff(diff),
            Block::ArServer(ArServerBlock {
                station_name: b"sk550p".to_vec(),
            }),
        ] {
            b.emit(&mut connect).unwrap();
        }
        let record = Block::emit_all(&[
            Block::WriteReq(IodWriteReq {
                addr: RecordAddress::default(),
                data: vec![1, 2, 3],
            }),
            Block::ReadReq(IodReadReq::default()),
            Block::WriteRes(IodWriteRes::default()),
            Block::ReadRes(IodReadRes {
                data: vec![9; 5],
                ..IodReadRes::default()
            }),
            Block::Control(IodControl::prm_end(ar, 1)),
            Block::Control(IodControl::application_ready(ar, 1).done()),
        ])
        .unwrap();
        let ndr = NdrRequest::new(1000, connect.clone()).unwrap();
        let pdu = RpcRepr::request(
            ar,
            Uuid::PNIO_DEVICE_INTERFACE,
            ar,
            1,
            super::super::rpc::Opnum::CONNECT,
            ndr.emit(Drep::LITTLE_ENDIAN),
        )
        .emit()
        .unwrap();
        vec![connect, record, pdu]
    }

    #[test]
    fn random_mutated_and_truncated_input_never_panics() {
        let seeds = seeds();
        for s in &seeds {
            blocks(s);
            rpc(s);
            for cut in 0..s.len() {
                blocks(&s[..cut]);
                rpc(&s[..cut]);
            }
        }
        let mut rng = Rng(0x5EED_0B10);
        for i in 0..20_000 {
            let mut b = if i % 2 == 0 {
                seeds[(rng.next() % seeds.len() as u64) as usize].clone()
            } else {
                let n = (rng.next() % 200) as usize;
                (0..n).map(|_| rng.next() as u8).collect()
            };
            for _ in 0..(rng.next() % 4) + 1 {
                if b.is_empty() {
                    break;
                }
                let at = (rng.next() % b.len() as u64) as usize;
                b[at] = match rng.next() % 4 {
                    0 => 0,
                    1 => 0xFF,
                    2 => b[at].wrapping_add(1),
                    _ => rng.next() as u8,
                };
            }
            let cut = (rng.next() % (b.len() as u64 + 1)) as usize;
            blocks(&b);
            blocks(&b[..cut]);
            rpc(&b);
            rpc(&b[..cut]);
        }
    }
}
