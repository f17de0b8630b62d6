//! Byte vectors shared by the block tests (layouts per Wireshark's packet-dcerpc-pn-io.c,
//! scapy's pnio_rpc.py and p-net's pf_block_reader.c).

use super::*;

/// ARUUID of the tests: 11223344-5566-7788-99AA-BBCCDDEEFF00 (big-endian in blocks).
pub(super) const AR: Uuid = Uuid([
    0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x99, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE, 0xFF, 0x00,
]);
pub(super) const MAC: MacAddr = MacAddr([0x00, 0x1B, 0x1B, 0x01, 0x02, 0x03]);

pub(super) fn one(bytes: &[u8]) -> Block {
    let (b, n) = Block::parse(bytes).unwrap();
    assert_eq!(n, bytes.len());
    assert_eq!(b.to_bytes().unwrap(), bytes, "{b:?}");
    b
}

pub(super) fn ar_block_req_bytes() -> Vec<u8> {
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

pub(super) fn iocr_req_bytes() -> Vec<u8> {
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

pub(super) fn alarm_cr_req_bytes() -> Vec<u8> {
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

pub(super) fn expected_bytes() -> Vec<u8> {
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

pub(super) fn write_req_bytes() -> Vec<u8> {
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
