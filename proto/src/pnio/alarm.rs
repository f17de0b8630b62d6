//! Alarms: the RTA-PDU of the alarm CR (frame ids FC01h high, FE01h low) and the
//! AlarmNotification / AlarmAck blocks it carries (IEC 61158-6-10 §4.5 "RTA" and the
//! AlarmNotification-PDU / AlarmAck-PDU coding; BU 0620 §2.5.7 and BU 0590 §5 for the alarms a
//! NORD device raises).
//!
//! RTA-PDU, from the frame id on (all fields big-endian):
//!
//! | bytes | field |
//! |---|---|
//! | 0–1 | FrameID FC01h / FE01h |
//! | 2–3 | AlarmDstEndpoint (the receiver's alarm reference) |
//! | 4–5 | AlarmSrcEndpoint (the sender's alarm reference) |
//! | 6 | PDUType: bits 0–3 type (1 DATA, 2 NACK, 3 ACK, 4 ERR), bits 4–7 version (1) |
//! | 7 | AddFlags: bits 0–3 WindowSize (1), bit 4 TACK (immediate acknowledge wanted) |
//! | 8–9 | SendSeqNum |
//! | 10–11 | AckSeqNum |
//! | 12–13 | VarPartLen |
//! | 14.. | RTA-SDU (VarPartLen bytes); Ethernet padding may follow |
//!
//! The RTA-SDU of a DATA PDU is one block (BlockType, BlockLength = bytes after the length
//! field, BlockVersionHigh 1, BlockVersionLow 0):
//!
//! - AlarmNotification (0001h high, 0002h low): AlarmType u16, API u32, SlotNumber u16,
//!   SubslotNumber u16, ModuleIdentNumber u32, SubmoduleIdentNumber u32, AlarmSpecifier u16,
//!   then alarm items, each a UserStructureIdentifier u16 and its data: 8000h ChannelDiagnosis
//!   (ChannelNumber, ChannelProperties, ChannelErrorType), 8002h ExtChannelDiagnosis (+
//!   ExtChannelErrorType u16, ExtChannelAddValue u32), 8003h QualifiedChannelDiagnosis (+
//!   QualifiedChannelQualifier u32), 8100h MaintenanceItem (a 0F00h block: 2 reserved bytes and
//!   MaintenanceStatus u32); any other USI (0000h–7FFFh manufacturer specific) takes the rest.
//! - AlarmAck (8001h high, 8002h low): AlarmType, API, SlotNumber, SubslotNumber,
//!   AlarmSpecifier, PNIOStatus.
//!
//! The RTA-SDU of an ERR PDU is a PNIOStatus (ErrorCode CFh "RTA error", ErrorDecode 81h,
//! ErrorCode1 FDh "RTA_ERR_CLS_PROTOCOL", ErrorCode2 the reason), optionally followed by vendor
//! data; ACK and NACK PDUs carry none.

use std::fmt;

use super::frame::{read_frame_id, FrameId};
use super::PnioStatus;
use crate::wire::{Error, Reader};

/// The RTA-PDU header after the frame id (endpoints, type, flags, sequence numbers, length).
pub const RTA_HEADER_LEN: usize = 12;

/// PDUType's type nibble (IEC 61158-6-10 "PDUType.Type").
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct RtaPduType(pub u8);

impl RtaPduType {
    /// DATA: carries an AlarmNotification or AlarmAck.
    pub const DATA: RtaPduType = RtaPduType(1);
    /// NACK: negative acknowledge (sequence error).
    pub const NACK: RtaPduType = RtaPduType(2);
    /// ACK: transport acknowledge.
    pub const ACK: RtaPduType = RtaPduType(3);
    /// ERR: the alarm CR is closed; carries a PNIOStatus.
    pub const ERR: RtaPduType = RtaPduType(4);

    /// The type's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            RtaPduType::DATA => "DATA",
            RtaPduType::NACK => "NACK",
            RtaPduType::ACK => "ACK",
            RtaPduType::ERR => "ERR",
            _ => return None,
        })
    }
}

impl fmt::Debug for RtaPduType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => f.write_str(n),
            None => write!(f, "RtaPduType({:X}h)", self.0),
        }
    }
}

/// AlarmType (IEC 61158-6-10 "AlarmType").
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AlarmType(pub u16);

impl AlarmType {
    /// Diagnosis (appears).
    pub const DIAGNOSIS: AlarmType = AlarmType(0x0001);
    /// Process.
    pub const PROCESS: AlarmType = AlarmType(0x0002);
    /// Pull (submodule).
    pub const PULL: AlarmType = AlarmType(0x0003);
    /// Plug.
    pub const PLUG: AlarmType = AlarmType(0x0004);
    /// Status.
    pub const STATUS: AlarmType = AlarmType(0x0005);
    /// Update.
    pub const UPDATE: AlarmType = AlarmType(0x0006);
    /// Media redundancy.
    pub const MEDIA_REDUNDANCY: AlarmType = AlarmType(0x0007);
    /// Controlled by supervisor.
    pub const CONTROLLED_BY_SUPERVISOR: AlarmType = AlarmType(0x0008);
    /// Released (by supervisor).
    pub const RELEASED: AlarmType = AlarmType(0x0009);
    /// Plug wrong submodule.
    pub const PLUG_WRONG_SUBMODULE: AlarmType = AlarmType(0x000A);
    /// Return of submodule.
    pub const RETURN_OF_SUBMODULE: AlarmType = AlarmType(0x000B);
    /// Diagnosis disappears.
    pub const DIAGNOSIS_DISAPPEARS: AlarmType = AlarmType(0x000C);
    /// Multicast communication mismatch.
    pub const MULTICAST_MISMATCH: AlarmType = AlarmType(0x000D);
    /// Port data change notification.
    pub const PORT_DATA_CHANGE: AlarmType = AlarmType(0x000E);
    /// Sync data changed.
    pub const SYNC_DATA_CHANGED: AlarmType = AlarmType(0x000F);
    /// Isochronous mode problem.
    pub const ISOCHRONOUS_MODE_PROBLEM: AlarmType = AlarmType(0x0010);
    /// Network component problem.
    pub const NETWORK_COMPONENT_PROBLEM: AlarmType = AlarmType(0x0011);
    /// Time data changed.
    pub const TIME_DATA_CHANGED: AlarmType = AlarmType(0x0012);
    /// Upload and retrieval notification.
    pub const UPLOAD_AND_RETRIEVAL: AlarmType = AlarmType(0x001E);
    /// Pull module.
    pub const PULL_MODULE: AlarmType = AlarmType(0x001F);

    /// The type's name, if defined here.
    pub fn name(self) -> Option<&'static str> {
        Some(match self.0 {
            0x0001 => "Diagnosis",
            0x0002 => "Process",
            0x0003 => "Pull",
            0x0004 => "Plug",
            0x0005 => "Status",
            0x0006 => "Update",
            0x0007 => "Media redundancy",
            0x0008 => "Controlled by supervisor",
            0x0009 => "Released",
            0x000A => "Plug wrong submodule",
            0x000B => "Return of submodule",
            0x000C => "Diagnosis disappears",
            0x000D => "Multicast communication mismatch",
            0x000E => "Port data change notification",
            0x000F => "Sync data changed",
            0x0010 => "Isochronous mode problem",
            0x0011 => "Network component problem",
            0x0012 => "Time data changed",
            0x001E => "Upload and retrieval notification",
            0x001F => "Pull module",
            _ => return None,
        })
    }
}

impl fmt::Debug for AlarmType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "AlarmType({n})"),
            None => write!(f, "AlarmType({:04X}h)", self.0),
        }
    }
}

/// AlarmSpecifier: bits 0–10 SequenceNumber, 11 ChannelDiagnosis, 12
/// ManufacturerSpecificDiagnosis, 13 SubmoduleDiagnosisState, 14 reserved, 15
/// ARDiagnosisState.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AlarmSpecifier(pub u16);

impl AlarmSpecifier {
    /// Bit 11: channel diagnosis present.
    pub const CHANNEL_DIAGNOSIS: u16 = 1 << 11;
    /// Bit 12: manufacturer specific diagnosis present.
    pub const MANUFACTURER_DIAGNOSIS: u16 = 1 << 12;
    /// Bit 13: the submodule has diagnosis.
    pub const SUBMODULE_DIAGNOSIS: u16 = 1 << 13;
    /// Bit 15: some submodule of the AR has diagnosis.
    pub const AR_DIAGNOSIS: u16 = 1 << 15;

    /// A specifier from its sequence number (taken modulo 2048) and flag bits.
    pub fn new(sequence: u16, flags: u16) -> AlarmSpecifier {
        AlarmSpecifier((sequence & 0x07FF) | (flags & 0xF800))
    }
    /// SequenceNumber (0..2047).
    pub fn sequence(self) -> u16 {
        self.0 & 0x07FF
    }
    /// ChannelDiagnosis.
    pub fn channel_diagnosis(self) -> bool {
        self.0 & Self::CHANNEL_DIAGNOSIS != 0
    }
    /// ManufacturerSpecificDiagnosis.
    pub fn manufacturer_diagnosis(self) -> bool {
        self.0 & Self::MANUFACTURER_DIAGNOSIS != 0
    }
    /// SubmoduleDiagnosisState.
    pub fn submodule_diagnosis(self) -> bool {
        self.0 & Self::SUBMODULE_DIAGNOSIS != 0
    }
    /// ARDiagnosisState.
    pub fn ar_diagnosis(self) -> bool {
        self.0 & Self::AR_DIAGNOSIS != 0
    }
}

/// ChannelProperties: bits 0–7 Type (data width of the channel, 0 if not used), 8
/// Accumulative, 9–10 Maintenance (0 fault, 1 maintenance required, 2 maintenance demanded,
/// 3 qualified), 11–12 Specifier (0 all disappear, 1 appears, 2 disappears, 3 disappears but
/// others remain), 13–15 Direction (0 manufacturer specific, 1 input, 2 output, 3 in/out).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ChannelProperties(pub u16);

impl ChannelProperties {
    /// Specifier "appears" (bits 11–12 = 1).
    pub const APPEARS: ChannelProperties = ChannelProperties(1 << 11);
    /// Specifier "disappears" (2).
    pub const DISAPPEARS: ChannelProperties = ChannelProperties(2 << 11);

    /// Type (bits 0–7).
    pub fn channel_type(self) -> u8 {
        (self.0 & 0xFF) as u8
    }
    /// Accumulative (bit 8).
    pub fn accumulative(self) -> bool {
        self.0 & 0x0100 != 0
    }
    /// Maintenance (bits 9–10).
    pub fn maintenance(self) -> u8 {
        ((self.0 >> 9) & 0x03) as u8
    }
    /// Specifier (bits 11–12).
    pub fn specifier(self) -> u8 {
        ((self.0 >> 11) & 0x03) as u8
    }
    /// Direction (bits 13–15).
    pub fn direction(self) -> u8 {
        (self.0 >> 13) as u8
    }
}

/// A UserStructureIdentifier (IEC 61158-6-10 "UserStructureIdentifier").
pub mod usi {
    /// Channel diagnosis.
    pub const CHANNEL_DIAGNOSIS: u16 = 0x8000;
    /// Multiple (several alarm items).
    pub const MULTIPLE: u16 = 0x8001;
    /// Extended channel diagnosis.
    pub const EXT_CHANNEL_DIAGNOSIS: u16 = 0x8002;
    /// Qualified channel diagnosis.
    pub const QUALIFIED_CHANNEL_DIAGNOSIS: u16 = 0x8003;
    /// Maintenance item.
    pub const MAINTENANCE: u16 = 0x8100;
}

/// ChannelNumber meaning "the whole submodule".
pub const CHANNEL_WHOLE_SUBMODULE: u16 = 0x8000;

/// The block type of the MaintenanceItem inside an alarm.
const BLOCK_MAINTENANCE_ITEM: u16 = 0x0F00;

/// One ChannelDiagnosis (USI 8000h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ChannelDiagnosis {
    /// ChannelNumber (8000h: the whole submodule).
    pub channel: u16,
    /// ChannelProperties.
    pub properties: ChannelProperties,
    /// ChannelErrorType (0001h–00FFh standard, 0100h–7FFFh manufacturer specific: the NORD
    /// devices put their error number + 100h here).
    pub error_type: u16,
}

/// One ExtChannelDiagnosis (USI 8002h), and with a qualifier a QualifiedChannelDiagnosis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ExtChannelDiagnosis {
    /// The channel part.
    pub channel: ChannelDiagnosis,
    /// ExtChannelErrorType.
    pub ext_error_type: u16,
    /// ExtChannelAddValue.
    pub add_value: u32,
}

/// One alarm item of an AlarmNotification.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AlarmItem {
    /// USI 8000h.
    ChannelDiagnosis(ChannelDiagnosis),
    /// USI 8002h.
    ExtChannelDiagnosis(ExtChannelDiagnosis),
    /// USI 8003h.
    QualifiedChannelDiagnosis {
        /// The extended channel diagnosis.
        diagnosis: ExtChannelDiagnosis,
        /// QualifiedChannelQualifier.
        qualifier: u32,
    },
    /// USI 8100h: MaintenanceStatus.
    Maintenance(u32),
    /// Any other USI (manufacturer specific 0000h–7FFFh, or one not typed here): its data
    /// runs to the end of the block.
    Other {
        /// The USI.
        usi: u16,
        /// The data.
        data: Vec<u8>,
    },
}

impl AlarmItem {
    fn parse(r: &mut Reader<'_>) -> Result<AlarmItem, Error> {
        let usi = r.u16_be("UserStructureIdentifier")?;
        let channel = |r: &mut Reader<'_>| -> Result<ChannelDiagnosis, Error> {
            Ok(ChannelDiagnosis {
                channel: r.u16_be("ChannelNumber")?,
                properties: ChannelProperties(r.u16_be("ChannelProperties")?),
                error_type: r.u16_be("ChannelErrorType")?,
            })
        };
        let ext = |r: &mut Reader<'_>| -> Result<ExtChannelDiagnosis, Error> {
            Ok(ExtChannelDiagnosis {
                channel: channel(r)?,
                ext_error_type: r.u16_be("ExtChannelErrorType")?,
                add_value: r.u32_be("ExtChannelAddValue")?,
            })
        };
        Ok(match usi {
            usi::CHANNEL_DIAGNOSIS => AlarmItem::ChannelDiagnosis(channel(r)?),
            usi::EXT_CHANNEL_DIAGNOSIS => AlarmItem::ExtChannelDiagnosis(ext(r)?),
            usi::QUALIFIED_CHANNEL_DIAGNOSIS => AlarmItem::QualifiedChannelDiagnosis {
                diagnosis: ext(r)?,
                qualifier: r.u32_be("QualifiedChannelQualifier")?,
            },
            usi::MAINTENANCE => {
                let (block_type, body) = block(r, "MaintenanceItem")?;
                if block_type != BLOCK_MAINTENANCE_ITEM {
                    return Err(Error::Unknown {
                        field: "MaintenanceItem BlockType",
                        value: u32::from(block_type),
                    });
                }
                let mut b = Reader::new(body);
                b.u16_be("MaintenanceItem padding")?;
                let status = b.u32_be("MaintenanceStatus")?;
                b.finish("MaintenanceItem")?;
                AlarmItem::Maintenance(status)
            }
            _ => AlarmItem::Other {
                usi,
                data: r.rest().to_vec(),
            },
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        let channel = |b: &mut Vec<u8>, c: &ChannelDiagnosis| {
            b.extend(c.channel.to_be_bytes());
            b.extend(c.properties.0.to_be_bytes());
            b.extend(c.error_type.to_be_bytes());
        };
        let ext = |b: &mut Vec<u8>, e: &ExtChannelDiagnosis| {
            channel(b, &e.channel);
            b.extend(e.ext_error_type.to_be_bytes());
            b.extend(e.add_value.to_be_bytes());
        };
        match self {
            AlarmItem::ChannelDiagnosis(c) => {
                b.extend(usi::CHANNEL_DIAGNOSIS.to_be_bytes());
                channel(b, c);
            }
            AlarmItem::ExtChannelDiagnosis(e) => {
                b.extend(usi::EXT_CHANNEL_DIAGNOSIS.to_be_bytes());
                ext(b, e);
            }
            AlarmItem::QualifiedChannelDiagnosis {
                diagnosis,
                qualifier,
            } => {
                b.extend(usi::QUALIFIED_CHANNEL_DIAGNOSIS.to_be_bytes());
                ext(b, diagnosis);
                b.extend(qualifier.to_be_bytes());
            }
            AlarmItem::Maintenance(status) => {
                b.extend(usi::MAINTENANCE.to_be_bytes());
                b.extend(BLOCK_MAINTENANCE_ITEM.to_be_bytes());
                b.extend(8u16.to_be_bytes()); // version 2 + padding 2 + status 4
                b.extend([1, 0, 0, 0]);
                b.extend(status.to_be_bytes());
            }
            AlarmItem::Other { usi, data } => {
                b.extend(usi.to_be_bytes());
                b.extend(data);
            }
        }
    }
}

/// Reads a block header (type, length, version 1.0) and returns the type and the body after
/// the version bytes.
fn block<'a>(r: &mut Reader<'a>, what: &'static str) -> Result<(u16, &'a [u8]), Error> {
    let block_type = r.u16_be(what)?;
    let len = usize::from(r.u16_be("BlockLength")?);
    if len < 2 || len > r.remaining() {
        return Err(Error::Length {
            field: "BlockLength",
            value: len,
            available: r.remaining(),
        });
    }
    let body = r.bytes(len, what)?;
    if body[..2] != [1, 0] {
        return Err(Error::Invalid {
            field: "BlockVersion",
            value: u32::from(u16::from_be_bytes([body[0], body[1]])),
            why: "the typed blocks are version 1.0",
        });
    }
    Ok((block_type, &body[2..]))
}

/// Block types of the alarm blocks.
pub mod block_type {
    /// AlarmNotification, high priority.
    pub const NOTIFICATION_HIGH: u16 = 0x0001;
    /// AlarmNotification, low priority.
    pub const NOTIFICATION_LOW: u16 = 0x0002;
    /// AlarmAck, high priority.
    pub const ACK_HIGH: u16 = 0x8001;
    /// AlarmAck, low priority.
    pub const ACK_LOW: u16 = 0x8002;
}

/// The AlarmNotification block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AlarmNotification {
    /// High priority (block type 0001h; low 0002h).
    pub high: bool,
    /// AlarmType.
    pub alarm_type: AlarmType,
    /// API.
    pub api: u32,
    /// SlotNumber.
    pub slot: u16,
    /// SubslotNumber.
    pub subslot: u16,
    /// ModuleIdentNumber.
    pub module_ident: u32,
    /// SubmoduleIdentNumber.
    pub submodule_ident: u32,
    /// AlarmSpecifier.
    pub specifier: AlarmSpecifier,
    /// The alarm items (none, a maintenance item, one or more diagnoses, or manufacturer
    /// data last).
    pub items: Vec<AlarmItem>,
}

/// The AlarmAck block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AlarmAck {
    /// High priority (block type 8001h; low 8002h).
    pub high: bool,
    /// AlarmType of the acknowledged alarm.
    pub alarm_type: AlarmType,
    /// API.
    pub api: u32,
    /// SlotNumber.
    pub slot: u16,
    /// SubslotNumber.
    pub subslot: u16,
    /// AlarmSpecifier of the acknowledged alarm.
    pub specifier: AlarmSpecifier,
    /// PNIOStatus (OK, or why the alarm was not accepted).
    pub status: PnioStatus,
}

impl AlarmAck {
    /// The acknowledge of a notification, with `status`.
    pub fn of(n: &AlarmNotification, status: PnioStatus) -> AlarmAck {
        AlarmAck {
            high: n.high,
            alarm_type: n.alarm_type,
            api: n.api,
            slot: n.slot,
            subslot: n.subslot,
            specifier: n.specifier,
            status,
        }
    }
}

/// The RTA-SDU by PDU type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RtaBody {
    /// Nothing (ACK, NACK).
    Empty,
    /// DATA with an AlarmNotification.
    Notification(AlarmNotification),
    /// DATA with an AlarmAck.
    Ack(AlarmAck),
    /// ERR: the PNIOStatus and any vendor data after it.
    Error {
        /// Why the alarm CR closes.
        status: PnioStatus,
        /// VendorDeviceErrorInfo, if any.
        vendor: Vec<u8>,
    },
    /// Anything else: a DATA block of another type, a var part on an ACK/NACK or a PDU type
    /// not typed here.
    Raw(Vec<u8>),
}

/// ErrorCode of an RTA ERR PDU's PNIOStatus ("RTA error").
pub const RTA_ERROR_CODE: u8 = 0xCF;
/// ErrorCode1 of an RTA ERR PDU's PNIOStatus ("RTA_ERR_CLS_PROTOCOL").
pub const RTA_ERR_CLS_PROTOCOL: u8 = 0xFD;

/// The PNIOStatus of an RTA ERR PDU with `reason` in ErrorCode2.
pub const fn rta_error(reason: u8) -> PnioStatus {
    PnioStatus::new(
        RTA_ERROR_CODE,
        PnioStatus::DECODE_PNIO,
        RTA_ERR_CLS_PROTOCOL,
        reason,
    )
}

/// A whole alarm frame from its frame id on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AlarmRepr {
    /// FC01h (high) or FE01h (low).
    pub frame_id: FrameId,
    /// AlarmDstEndpoint: the receiver's local alarm reference (from the Alarm CR blocks).
    pub dst_endpoint: u16,
    /// AlarmSrcEndpoint: the sender's.
    pub src_endpoint: u16,
    /// PDUType.Type.
    pub pdu_type: RtaPduType,
    /// PDUType.Version (1).
    pub version: u8,
    /// AddFlags.WindowSize (1).
    pub window_size: u8,
    /// AddFlags.TACK: the receiver shall acknowledge at once.
    pub tack: bool,
    /// SendSeqNum.
    pub send_seq: u16,
    /// AckSeqNum.
    pub ack_seq: u16,
    /// The RTA-SDU.
    pub body: RtaBody,
}

impl AlarmRepr {
    /// A DATA PDU, version 1, window size 1, TACK set, on the frame id of the block's priority.
    pub fn data(dst: u16, src: u16, send_seq: u16, ack_seq: u16, body: RtaBody) -> AlarmRepr {
        let high = match &body {
            RtaBody::Notification(n) => n.high,
            RtaBody::Ack(a) => a.high,
            _ => false,
        };
        AlarmRepr {
            frame_id: if high {
                FrameId::ALARM_HIGH
            } else {
                FrameId::ALARM_LOW
            },
            dst_endpoint: dst,
            src_endpoint: src,
            pdu_type: RtaPduType::DATA,
            version: 1,
            window_size: 1,
            tack: true,
            send_seq,
            ack_seq,
            body,
        }
    }

    /// An ACK PDU on `frame_id`, version 1, window size 1.
    pub fn ack(frame_id: FrameId, dst: u16, src: u16, send_seq: u16, ack_seq: u16) -> AlarmRepr {
        AlarmRepr {
            frame_id,
            dst_endpoint: dst,
            src_endpoint: src,
            pdu_type: RtaPduType::ACK,
            version: 1,
            window_size: 1,
            tack: false,
            send_seq,
            ack_seq,
            body: RtaBody::Empty,
        }
    }

    /// Parses an alarm frame from its frame id on; bytes after VarPartLen are padding.
    pub fn parse(buf: &[u8]) -> Result<AlarmRepr, Error> {
        let frame_id = read_frame_id(buf)?;
        let mut r = Reader::new(&buf[2..]);
        let dst_endpoint = r.u16_be("AlarmDstEndpoint")?;
        let src_endpoint = r.u16_be("AlarmSrcEndpoint")?;
        let pdu = r.u8("PDUType")?;
        let flags = r.u8("AddFlags")?;
        let send_seq = r.u16_be("SendSeqNum")?;
        let ack_seq = r.u16_be("AckSeqNum")?;
        let var_len = usize::from(r.u16_be("VarPartLen")?);
        if var_len > r.remaining() {
            return Err(Error::Length {
                field: "VarPartLen",
                value: var_len,
                available: r.remaining(),
            });
        }
        let var = r.bytes(var_len, "RTA-SDU")?;
        let pdu_type = RtaPduType(pdu & 0x0F);
        let body = match pdu_type {
            RtaPduType::DATA => parse_data(var)?,
            RtaPduType::ERR => {
                let mut v = Reader::new(var);
                let s = v.bytes(4, "RTA ERR PNIOStatus")?;
                RtaBody::Error {
                    status: PnioStatus::new(s[0], s[1], s[2], s[3]),
                    vendor: v.rest().to_vec(),
                }
            }
            RtaPduType::ACK | RtaPduType::NACK if var.is_empty() => RtaBody::Empty,
            _ => RtaBody::Raw(var.to_vec()),
        };
        Ok(AlarmRepr {
            frame_id,
            dst_endpoint,
            src_endpoint,
            pdu_type,
            version: pdu >> 4,
            window_size: flags & 0x0F,
            tack: flags & 0x10 != 0,
            send_seq,
            ack_seq,
            body,
        })
    }

    /// The frame bytes (the Ethernet layer pads). A var part over 65535 bytes is
    /// [`Error::TooLong`]. The PDU type and body are written as given, consistent or not.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut var = Vec::new();
        match &self.body {
            RtaBody::Empty => {}
            RtaBody::Notification(n) => {
                let ty = if n.high {
                    block_type::NOTIFICATION_HIGH
                } else {
                    block_type::NOTIFICATION_LOW
                };
                let mut body = Vec::new();
                body.extend(n.alarm_type.0.to_be_bytes());
                body.extend(n.api.to_be_bytes());
                body.extend(n.slot.to_be_bytes());
                body.extend(n.subslot.to_be_bytes());
                body.extend(n.module_ident.to_be_bytes());
                body.extend(n.submodule_ident.to_be_bytes());
                body.extend(n.specifier.0.to_be_bytes());
                for item in &n.items {
                    item.emit(&mut body);
                }
                put_block(&mut var, ty, &body, "AlarmNotification")?;
            }
            RtaBody::Ack(a) => {
                let ty = if a.high {
                    block_type::ACK_HIGH
                } else {
                    block_type::ACK_LOW
                };
                let mut body = Vec::new();
                body.extend(a.alarm_type.0.to_be_bytes());
                body.extend(a.api.to_be_bytes());
                body.extend(a.slot.to_be_bytes());
                body.extend(a.subslot.to_be_bytes());
                body.extend(a.specifier.0.to_be_bytes());
                body.extend(a.status.to_bytes());
                put_block(&mut var, ty, &body, "AlarmAck")?;
            }
            RtaBody::Error { status, vendor } => {
                var.extend(status.to_bytes());
                var.extend(vendor);
            }
            RtaBody::Raw(v) => var.extend(v),
        }
        let var_len = u16::try_from(var.len()).map_err(|_| Error::TooLong {
            what: "RTA-SDU",
            len: var.len(),
            max: usize::from(u16::MAX),
        })?;
        let mut b = Vec::with_capacity(2 + RTA_HEADER_LEN + var.len());
        b.extend(self.frame_id.0.to_be_bytes());
        b.extend(self.dst_endpoint.to_be_bytes());
        b.extend(self.src_endpoint.to_be_bytes());
        b.push((self.version << 4) | (self.pdu_type.0 & 0x0F));
        b.push((self.window_size & 0x0F) | if self.tack { 0x10 } else { 0 });
        b.extend(self.send_seq.to_be_bytes());
        b.extend(self.ack_seq.to_be_bytes());
        b.extend(var_len.to_be_bytes());
        b.extend(var);
        Ok(b)
    }
}

fn put_block(out: &mut Vec<u8>, ty: u16, body: &[u8], what: &'static str) -> Result<(), Error> {
    let len = u16::try_from(body.len() + 2).map_err(|_| Error::TooLong {
        what,
        len: body.len() + 2,
        max: usize::from(u16::MAX),
    })?;
    out.extend(ty.to_be_bytes());
    out.extend(len.to_be_bytes());
    out.extend([1, 0]);
    out.extend(body);
    Ok(())
}

fn parse_data(var: &[u8]) -> Result<RtaBody, Error> {
    let mut r = Reader::new(var);
    let (ty, body) = block(&mut r, "alarm BlockType")?;
    r.finish("RTA-SDU")?;
    let mut b = Reader::new(body);
    let high = matches!(ty, block_type::NOTIFICATION_HIGH | block_type::ACK_HIGH);
    match ty {
        block_type::NOTIFICATION_HIGH | block_type::NOTIFICATION_LOW => {
            let alarm_type = AlarmType(b.u16_be("AlarmType")?);
            let api = b.u32_be("API")?;
            let slot = b.u16_be("SlotNumber")?;
            let subslot = b.u16_be("SubslotNumber")?;
            let module_ident = b.u32_be("ModuleIdentNumber")?;
            let submodule_ident = b.u32_be("SubmoduleIdentNumber")?;
            let specifier = AlarmSpecifier(b.u16_be("AlarmSpecifier")?);
            let mut items = Vec::new();
            while b.remaining() > 0 {
                items.push(AlarmItem::parse(&mut b)?);
            }
            Ok(RtaBody::Notification(AlarmNotification {
                high,
                alarm_type,
                api,
                slot,
                subslot,
                module_ident,
                submodule_ident,
                specifier,
                items,
            }))
        }
        block_type::ACK_HIGH | block_type::ACK_LOW => {
            let alarm_type = AlarmType(b.u16_be("AlarmType")?);
            let api = b.u32_be("API")?;
            let slot = b.u16_be("SlotNumber")?;
            let subslot = b.u16_be("SubslotNumber")?;
            let specifier = AlarmSpecifier(b.u16_be("AlarmSpecifier")?);
            let s = b.bytes(4, "PNIOStatus")?;
            b.finish("AlarmAck")?;
            Ok(RtaBody::Ack(AlarmAck {
                high,
                alarm_type,
                api,
                slot,
                subslot,
                specifier,
                status: PnioStatus::new(s[0], s[1], s[2], s[3]),
            }))
        }
        _ => Ok(RtaBody::Raw(var.to_vec())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A low-priority diagnosis alarm on slot 1, subslot 1 with one channel diagnosis of
    /// ChannelErrorType 164h (manufacturer range: 100h + 100, the shape of BU 0590 §P163's
    /// "ChannelErrorType = 0x100 + 50").
    fn diagnosis_frame() -> Vec<u8> {
        vec![
            0xFE, 0x01, // FrameID: alarm low
            0x00, 0x01, // AlarmDstEndpoint 1 (the controller's alarm reference)
            0x00, 0x02, // AlarmSrcEndpoint 2
            0x11, // PDUType: version 1, DATA
            0x11, // AddFlags: TACK, window size 1
            0x00, 0x00, // SendSeqNum 0
            0xFF, 0xFF, // AckSeqNum FFFFh (nothing received yet)
            0x00, 0x22, // VarPartLen 34
            0x00, 0x02, // BlockType AlarmNotification low
            0x00, 0x1E, // BlockLength 30
            0x01, 0x00, // BlockVersion 1.0
            0x00, 0x01, // AlarmType Diagnosis
            0x00, 0x00, 0x00, 0x00, // API 0
            0x00, 0x01, // SlotNumber 1
            0x00, 0x01, // SubslotNumber 1
            0x00, 0x00, 0x00, 0x10, // ModuleIdentNumber 10h
            0x00, 0x00, 0x00, 0x01, // SubmoduleIdentNumber 1
            0xA8, 0x01, // AlarmSpecifier: sequence 1, channel diag, submodule diag, AR diag
            0x80, 0x00, // USI ChannelDiagnosis
            0x80, 0x00, // ChannelNumber: whole submodule
            0x08, 0x00, // ChannelProperties: appears
            0x01, 0x64, // ChannelErrorType 164h
        ]
    }

    #[test]
    fn diagnosis_notification_fields_and_round_trip() {
        let b = diagnosis_frame();
        let a = AlarmRepr::parse(&b).unwrap();
        assert_eq!(a.frame_id, FrameId::ALARM_LOW);
        assert_eq!((a.dst_endpoint, a.src_endpoint), (1, 2));
        assert_eq!(
            (a.pdu_type, a.version, a.window_size, a.tack),
            (RtaPduType::DATA, 1, 1, true)
        );
        assert_eq!((a.send_seq, a.ack_seq), (0, 0xFFFF));
        let RtaBody::Notification(n) = &a.body else {
            panic!("{a:?}")
        };
        assert!(!n.high);
        assert_eq!(n.alarm_type, AlarmType::DIAGNOSIS);
        assert_eq!((n.api, n.slot, n.subslot), (0, 1, 1));
        assert_eq!((n.module_ident, n.submodule_ident), (0x10, 1));
        assert_eq!(n.specifier.sequence(), 1);
        assert!(n.specifier.channel_diagnosis() && n.specifier.submodule_diagnosis());
        assert!(n.specifier.ar_diagnosis() && !n.specifier.manufacturer_diagnosis());
        assert_eq!(
            n.items,
            [AlarmItem::ChannelDiagnosis(ChannelDiagnosis {
                channel: CHANNEL_WHOLE_SUBMODULE,
                properties: ChannelProperties::APPEARS,
                error_type: 0x164,
            })]
        );
        assert_eq!(ChannelProperties::APPEARS.specifier(), 1);
        assert_eq!(a.emit().unwrap(), b);
        // The same built by hand.
        let built = AlarmRepr::data(
            1,
            2,
            0,
            0xFFFF,
            RtaBody::Notification(AlarmNotification {
                high: false,
                alarm_type: AlarmType::DIAGNOSIS,
                api: 0,
                slot: 1,
                subslot: 1,
                module_ident: 0x10,
                submodule_ident: 1,
                specifier: AlarmSpecifier::new(
                    1,
                    AlarmSpecifier::CHANNEL_DIAGNOSIS
                        | AlarmSpecifier::SUBMODULE_DIAGNOSIS
                        | AlarmSpecifier::AR_DIAGNOSIS,
                ),
                items: n.items.clone(),
            }),
        );
        assert_eq!(built, a);
        // Padded to the Ethernet minimum: the padding is ignored.
        let mut padded = b.clone();
        padded.resize(60, 0);
        assert_eq!(AlarmRepr::parse(&padded).unwrap(), a);
    }

    #[test]
    fn alarm_ack_round_trip() {
        let b = [
            0xFE, 0x01, // FrameID: alarm low
            0x00, 0x02, // AlarmDstEndpoint 2 (the device)
            0x00, 0x01, // AlarmSrcEndpoint 1
            0x11, // version 1, DATA
            0x11, // TACK, window 1
            0x00, 0x00, // SendSeqNum 0
            0x00, 0x00, // AckSeqNum 0 (acknowledges the device's DATA 0)
            0x00, 0x16, // VarPartLen 22
            0x80, 0x02, // BlockType AlarmAck low
            0x00, 0x12, // BlockLength 18
            0x01, 0x00, // version 1.0
            0x00, 0x01, // AlarmType Diagnosis
            0x00, 0x00, 0x00, 0x00, // API 0
            0x00, 0x01, // Slot 1
            0x00, 0x01, // Subslot 1
            0xA8, 0x01, // AlarmSpecifier
            0x00, 0x00, 0x00, 0x00, // PNIOStatus OK
        ];
        let a = AlarmRepr::parse(&b).unwrap();
        let RtaBody::Ack(ack) = a.body else {
            panic!("{a:?}")
        };
        assert_eq!(ack.status, PnioStatus::OK);
        assert_eq!(ack.specifier, AlarmSpecifier(0xA801));
        assert_eq!(a.emit().unwrap(), b);
        let d = AlarmRepr::parse(&diagnosis_frame()).unwrap();
        let RtaBody::Notification(n) = d.body else {
            panic!()
        };
        assert_eq!(AlarmAck::of(&n, PnioStatus::OK), ack);
    }

    #[test]
    fn ack_err_and_items_round_trip() {
        // ACK on FC01h from 2 to 1, SendSeqNum FFFFh, AckSeqNum 0, no var part.
        let ack = AlarmRepr::ack(FrameId::ALARM_HIGH, 1, 2, 0xFFFF, 0);
        let b = ack.emit().unwrap();
        assert_eq!(
            b,
            [0xFC, 0x01, 0, 1, 0, 2, 0x13, 0x01, 0xFF, 0xFF, 0, 0, 0, 0]
        );
        assert_eq!(AlarmRepr::parse(&b).unwrap(), ack);

        // ERR: PNIOStatus CF 81 FD 05 and 2 vendor bytes.
        let err = AlarmRepr {
            pdu_type: RtaPduType::ERR,
            body: RtaBody::Error {
                status: rta_error(5),
                vendor: vec![0xAB, 0xCD],
            },
            ..ack.clone()
        };
        let b = err.emit().unwrap();
        assert_eq!(
            &b[6..],
            [0x14, 0x01, 0xFF, 0xFF, 0, 0, 0, 6, 0xCF, 0x81, 0xFD, 5, 0xAB, 0xCD]
        );
        assert_eq!(AlarmRepr::parse(&b).unwrap(), err);

        // Every item type, manufacturer data last.
        let d = ChannelDiagnosis {
            channel: 3,
            properties: ChannelProperties(0x2A00),
            error_type: 0x0101,
        };
        let e = ExtChannelDiagnosis {
            channel: d,
            ext_error_type: 0x8001,
            add_value: 0xDEAD_BEEF,
        };
        let n = AlarmNotification {
            high: true,
            alarm_type: AlarmType::PROCESS,
            api: 0,
            slot: 2,
            subslot: 1,
            module_ident: 7,
            submodule_ident: 8,
            specifier: AlarmSpecifier::new(2047, AlarmSpecifier::MANUFACTURER_DIAGNOSIS),
            items: vec![
                AlarmItem::Maintenance(3),
                AlarmItem::ChannelDiagnosis(d),
                AlarmItem::ExtChannelDiagnosis(e),
                AlarmItem::QualifiedChannelDiagnosis {
                    diagnosis: e,
                    qualifier: 1 << 7,
                },
                AlarmItem::Other {
                    usi: 0x0042,
                    data: vec![1, 2, 3],
                },
            ],
        };
        let a = AlarmRepr::data(1, 2, 5, 4, RtaBody::Notification(n));
        assert_eq!(a.frame_id, FrameId::ALARM_HIGH);
        let b = a.emit().unwrap();
        // The maintenance item: USI 8100h, block 0F00h length 8 version 1.0, padding, status 3.
        assert_eq!(
            &b[14 + 6 + 20..14 + 6 + 20 + 14],
            [0x81, 0x00, 0x0F, 0x00, 0, 8, 1, 0, 0, 0, 0, 0, 0, 3]
        );
        assert_eq!(AlarmRepr::parse(&b).unwrap(), a);
        assert_eq!(ChannelProperties(0x2A00).direction(), 1);
        assert_eq!(ChannelProperties(0x2A00).maintenance(), 1);
    }

    #[test]
    fn malformed_alarms_are_errors() {
        let b = diagnosis_frame();
        for cut in 0..b.len() {
            assert!(AlarmRepr::parse(&b[..cut]).is_err(), "cut {cut}");
        }
        // VarPartLen 35 with 34 bytes.
        let mut x = b.clone();
        x[13] = 35;
        assert_eq!(
            AlarmRepr::parse(&x),
            Err(Error::Length {
                field: "VarPartLen",
                value: 35,
                available: 34
            })
        );
        // BlockLength 31 in a 34-byte var part.
        let mut x = b.clone();
        x[17] = 0x1F;
        assert!(matches!(AlarmRepr::parse(&x), Err(Error::Length { .. })));
        // BlockLength 28: two bytes left in the var part after the block.
        let mut x = b.clone();
        x[17] = 0x1C;
        assert_eq!(
            AlarmRepr::parse(&x),
            Err(Error::Trailing {
                what: "RTA-SDU",
                extra: 2
            })
        );
        // Block version 2.0.
        let mut x = b.clone();
        x[18] = 2;
        assert_eq!(
            AlarmRepr::parse(&x),
            Err(Error::Invalid {
                field: "BlockVersion",
                value: 0x0200,
                why: "the typed blocks are version 1.0",
            })
        );
        // An unknown block type is kept raw.
        let mut x = b.clone();
        x[15] = 0x77;
        assert!(matches!(
            AlarmRepr::parse(&x).unwrap().body,
            RtaBody::Raw(_)
        ));
        // ChannelDiagnosis cut short inside a block that claims it.
        let mut x = b.clone();
        x[13] -= 2;
        x[17] -= 2;
        x.truncate(x.len() - 2);
        assert_eq!(
            AlarmRepr::parse(&x),
            Err(Error::Truncated {
                what: "ChannelErrorType",
                need: 2,
                got: 0
            })
        );
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn status() -> impl Strategy<Value = PnioStatus> {
            any::<[u8; 4]>().prop_map(|s| PnioStatus::new(s[0], s[1], s[2], s[3]))
        }

        fn channel() -> impl Strategy<Value = ChannelDiagnosis> {
            any::<(u16, u16, u16)>().prop_map(|(channel, p, error_type)| ChannelDiagnosis {
                channel,
                properties: ChannelProperties(p),
                error_type,
            })
        }

        fn ext() -> impl Strategy<Value = ExtChannelDiagnosis> {
            (channel(), any::<u16>(), any::<u32>()).prop_map(
                |(channel, ext_error_type, add_value)| ExtChannelDiagnosis {
                    channel,
                    ext_error_type,
                    add_value,
                },
            )
        }

        fn typed_item() -> impl Strategy<Value = AlarmItem> {
            prop_oneof![
                channel().prop_map(AlarmItem::ChannelDiagnosis),
                ext().prop_map(AlarmItem::ExtChannelDiagnosis),
                (ext(), any::<u32>()).prop_map(|(diagnosis, qualifier)| {
                    AlarmItem::QualifiedChannelDiagnosis {
                        diagnosis,
                        qualifier,
                    }
                }),
                any::<u32>().prop_map(AlarmItem::Maintenance),
            ]
        }

        /// Typed items, then at most one item of another USI (its data runs to the block's end).
        fn items() -> impl Strategy<Value = Vec<AlarmItem>> {
            const TYPED: [u16; 4] = [
                usi::CHANNEL_DIAGNOSIS,
                usi::EXT_CHANNEL_DIAGNOSIS,
                usi::QUALIFIED_CHANNEL_DIAGNOSIS,
                usi::MAINTENANCE,
            ];
            (
                vec(typed_item(), 0..4),
                proptest::option::of((
                    any::<u16>().prop_filter("typed USI", |u| !TYPED.contains(u)),
                    vec(any::<u8>(), 0..12),
                )),
            )
                .prop_map(|(mut items, other)| {
                    if let Some((usi, data)) = other {
                        items.push(AlarmItem::Other { usi, data });
                    }
                    items
                })
        }

        fn notification() -> impl Strategy<Value = AlarmNotification> {
            (
                any::<(bool, u16, u32, u16, u16)>(),
                any::<(u32, u32, u16)>(),
                items(),
            )
                .prop_map(
                    |(
                        (high, alarm_type, api, slot, subslot),
                        (module_ident, submodule_ident, spec),
                        items,
                    )| {
                        AlarmNotification {
                            high,
                            alarm_type: AlarmType(alarm_type),
                            api,
                            slot,
                            subslot,
                            module_ident,
                            submodule_ident,
                            specifier: AlarmSpecifier(spec),
                            items,
                        }
                    },
                )
        }

        fn ack() -> impl Strategy<Value = AlarmAck> {
            (any::<(bool, u16, u32, u16, u16, u16)>(), status()).prop_map(
                |((high, alarm_type, api, slot, subslot, spec), status)| AlarmAck {
                    high,
                    alarm_type: AlarmType(alarm_type),
                    api,
                    slot,
                    subslot,
                    specifier: AlarmSpecifier(spec),
                    status,
                },
            )
        }

        /// A PDU type with a body it carries: DATA a notification or an acknowledge, ERR its
        /// status and vendor bytes, ACK/NACK nothing or raw bytes, other types raw bytes.
        fn pdu() -> impl Strategy<Value = (RtaPduType, RtaBody)> {
            prop_oneof![
                notification().prop_map(|n| (RtaPduType::DATA, RtaBody::Notification(n))),
                ack().prop_map(|a| (RtaPduType::DATA, RtaBody::Ack(a))),
                (status(), vec(any::<u8>(), 0..8)).prop_map(|(status, vendor)| (
                    RtaPduType::ERR,
                    RtaBody::Error { status, vendor }
                )),
                prop_oneof![Just(RtaPduType::ACK), Just(RtaPduType::NACK)]
                    .prop_map(|t| (t, RtaBody::Empty)),
                (
                    prop_oneof![Just(RtaPduType::ACK), Just(RtaPduType::NACK)],
                    vec(any::<u8>(), 1..8)
                )
                    .prop_map(|(t, v)| (t, RtaBody::Raw(v))),
                (prop_oneof![Just(0u8), 5u8..=15], vec(any::<u8>(), 0..8))
                    .prop_map(|(t, v)| (RtaPduType(t), RtaBody::Raw(v))),
            ]
        }

        fn repr() -> impl Strategy<Value = AlarmRepr> {
            (
                any::<(u16, u16, u16)>(),
                pdu(),
                (0u8..=15, 0u8..=15, any::<bool>()),
                any::<(u16, u16)>(),
            )
                .prop_map(
                    |(
                        (frame_id, dst_endpoint, src_endpoint),
                        (pdu_type, body),
                        (version, window_size, tack),
                        (send_seq, ack_seq),
                    )| {
                        AlarmRepr {
                            frame_id: FrameId(frame_id),
                            dst_endpoint,
                            src_endpoint,
                            pdu_type,
                            version,
                            window_size,
                            tack,
                            send_seq,
                            ack_seq,
                            body,
                        }
                    },
                )
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in repr(), padding in 0usize..8) {
                let mut b = r.emit().unwrap();
                prop_assert_eq!(AlarmRepr::parse(&b), Ok(r.clone()));
                b.resize(b.len() + padding, 0);
                prop_assert_eq!(AlarmRepr::parse(&b), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..64)) {
                let _ = AlarmRepr::parse(&bytes);
            }

            #[test]
            fn parsing_an_arbitrary_var_part_never_panics(pdu in 0u8..=0x1F, var in vec(any::<u8>(), 0..64)) {
                // A valid RTA header over an arbitrary RTA-SDU (reaches the block parsers).
                let mut b = vec![0xFE, 0x01, 0, 1, 0, 2, pdu, 0x11, 0, 0, 0, 0];
                b.extend((var.len() as u16).to_be_bytes());
                b.extend(&var);
                let _ = AlarmRepr::parse(&b);
            }
        }
    }
}
