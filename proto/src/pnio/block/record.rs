//! The record-service headers (IODWriteReq/ResHeader, IODReadReq/ResHeader) and the
//! control blocks (IODControl, IOXControl, Release) (IEC 61158-6-10). Layouts in the table of
//! [`super`].

use super::*;

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
    pub(super) fn parse(
        r: &mut Reader<'_>,
        what: &'static str,
    ) -> Result<(RecordAddress, u32), Error> {
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

    pub(super) fn emit(&self, b: &mut Vec<u8>, record_data_length: u32) {
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

    pub(super) fn parse(block_type: BlockType, r: &mut Reader<'_>) -> Result<IodControl, Error> {
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

    pub(super) fn emit(&self, b: &mut Vec<u8>) {
        b.extend([0, 0]);
        b.extend(self.ar_uuid.0);
        put16(b, self.session_key);
        put16(b, self.alarm_sequence_number);
        put16(b, self.command.0);
        put16(b, self.properties);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pnio::block::vectors::*;

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
            Err(Error::Length {
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
                status: PnioStatus::record(true, crate::pnio::status::pniorw::ACCESS_DENIED),
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

    mod properties {
        use super::*;
        use crate::pnio::block::Block;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn uuid() -> impl Strategy<Value = Uuid> {
            any::<[u8; 16]>().prop_map(Uuid)
        }

        fn status() -> impl Strategy<Value = PnioStatus> {
            any::<[u8; 4]>().prop_map(|s| PnioStatus::new(s[0], s[1], s[2], s[3]))
        }

        fn addr() -> impl Strategy<Value = RecordAddress> {
            (any::<u16>(), uuid(), any::<(u32, u16, u16, u16)>()).prop_map(
                |(seq_number, ar_uuid, (api, slot, subslot, index))| RecordAddress {
                    seq_number,
                    ar_uuid,
                    api,
                    slot,
                    subslot,
                    index,
                },
            )
        }

        fn control_type() -> impl Strategy<Value = BlockType> {
            let mut t: Vec<u16> = (0x0110..=0x0114).chain(0x0116..=0x0118).collect();
            t.extend(t.clone().into_iter().map(|c| c | 0x8000));
            proptest::sample::select(t).prop_map(BlockType)
        }

        /// The record blocks and the control blocks, with their record data.
        fn block() -> impl Strategy<Value = Block> {
            prop_oneof![
                (addr(), vec(any::<u8>(), 0..32))
                    .prop_map(|(addr, data)| Block::WriteReq(IodWriteReq { addr, data })),
                (addr(), any::<u32>(), uuid()).prop_map(
                    |(addr, record_data_length, target_ar_uuid)| {
                        Block::ReadReq(IodReadReq {
                            addr,
                            record_data_length,
                            target_ar_uuid,
                        })
                    }
                ),
                (addr(), any::<(u32, u16, u16)>(), status()).prop_map(
                    |(addr, (len, v1, v2), status)| {
                        Block::WriteRes(IodWriteRes {
                            addr,
                            record_data_length: len,
                            additional_value1: v1,
                            additional_value2: v2,
                            status,
                        })
                    }
                ),
                (addr(), any::<(u16, u16)>(), vec(any::<u8>(), 0..32)).prop_map(
                    |(addr, (v1, v2), data)| {
                        Block::ReadRes(IodReadRes {
                            addr,
                            additional_value1: v1,
                            additional_value2: v2,
                            data,
                        })
                    }
                ),
                (control_type(), uuid(), any::<(u16, u16, u16, u16)>()).prop_map(
                    |(
                        block_type,
                        ar_uuid,
                        (session_key, alarm_sequence_number, command, properties),
                    )| {
                        Block::Control(IodControl {
                            block_type,
                            ar_uuid,
                            session_key,
                            alarm_sequence_number,
                            command: ControlCommand(command),
                            properties,
                        })
                    }
                ),
            ]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(b in block()) {
                let bytes = b.to_bytes().unwrap();
                prop_assert_eq!(Block::parse(&bytes), Ok((b, bytes.len())));
            }
        }
    }
}
