//! The blocks of a Connect call (IEC 61158-6-10 "IODConnectReq/Res"): ARBlockReq/Res,
//! IOCRBlockReq/Res, AlarmCRBlockReq/Res, ExpectedSubmoduleBlockReq, ModuleDiffBlock,
//! ARServerBlock. Layouts in the table of [`super`].

use super::*;

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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<ArBlockReq, Error> {
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

    pub(super) fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<ArBlockRes, Error> {
        Ok(ArBlockRes {
            ar_type: ArType(r.u16_be("ARBlockRes ARType")?),
            ar_uuid: uuid(r, "ARBlockRes ARUUID")?,
            session_key: r.u16_be("ARBlockRes SessionKey")?,
            responder_mac: mac(r, "ARBlockRes CMResponderMacAdd")?,
            udp_rt_port: r.u16_be("ARBlockRes CMResponderUDPRTPort")?,
        })
    }

    pub(super) fn emit(&self, b: &mut Vec<u8>) {
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<IocrEntry, Error> {
        Ok(IocrEntry {
            slot: r.u16_be("IOCRBlockReq SlotNumber")?,
            subslot: r.u16_be("IOCRBlockReq SubslotNumber")?,
            frame_offset: r.u16_be("IOCRBlockReq FrameOffset")?,
        })
    }

    pub(super) fn emit(&self, b: &mut Vec<u8>) {
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<IocrBlockReq, Error> {
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

    pub(super) fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<IocrBlockRes, Error> {
        Ok(IocrBlockRes {
            iocr_type: IocrType(r.u16_be("IOCRBlockRes IOCRType")?),
            reference: r.u16_be("IOCRBlockRes IOCRReference")?,
            frame_id: r.u16_be("IOCRBlockRes FrameID")?,
        })
    }

    pub(super) fn emit(&self, b: &mut Vec<u8>) {
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<AlarmCrBlockReq, Error> {
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

    pub(super) fn emit(&self, b: &mut Vec<u8>) {
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<AlarmCrBlockRes, Error> {
        Ok(AlarmCrBlockRes {
            alarm_cr_type: AlarmCrType(r.u16_be("AlarmCRBlockRes AlarmCRType")?),
            local_alarm_reference: r.u16_be("AlarmCRBlockRes LocalAlarmReference")?,
            max_alarm_data_length: r.u16_be("AlarmCRBlockRes MaxAlarmDataLength")?,
        })
    }

    pub(super) fn emit(&self, b: &mut Vec<u8>) {
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

    pub(super) fn parse(r: &mut Reader<'_>) -> Result<DataDescription, Error> {
        Ok(DataDescription {
            direction: DataDirection(r.u16_be("ExpectedSubmoduleBlockReq DataDescription")?),
            length: r.u16_be("ExpectedSubmoduleBlockReq SubmoduleDataLength")?,
            length_iocs: r.u8("ExpectedSubmoduleBlockReq LengthIOCS")?,
            length_iops: r.u8("ExpectedSubmoduleBlockReq LengthIOPS")?,
        })
    }

    pub(super) fn emit(&self, b: &mut Vec<u8>) {
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<ExpectedSubmoduleBlockReq, Error> {
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

    pub(super) fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
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
                        why: "not the count the submodule properties call for",
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<ModuleDiffBlock, Error> {
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

    pub(super) fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
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
    pub(super) fn parse(r: &mut Reader<'_>) -> Result<ArServerBlock, Error> {
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

    pub(super) fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
        put_name(b, &self.station_name, "CMResponderStationName")?;
        // The block so far: 6 header bytes, 2 length bytes, the name.
        let pad = (4 - (BLOCK_HEADER_LEN + 2 + self.station_name.len()) % 4) % 4;
        b.extend(std::iter::repeat_n(0, pad));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pnio::block::vectors::*;

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
                value: 1,
                why: "not the count the submodule properties call for",
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

    mod properties {
        use super::*;
        use crate::pnio::block::Block;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn uuid() -> impl Strategy<Value = Uuid> {
            any::<[u8; 16]>().prop_map(Uuid)
        }

        /// The fixed-layout Connect blocks (the AR block request with a station name of any
        /// bytes up to 240); IOCR requests, expected submodules and module diffs remain.
        fn block() -> impl Strategy<Value = Block> {
            prop_oneof![
                (
                    any::<u16>(),
                    uuid(),
                    any::<u16>(),
                    any::<[u8; 6]>(),
                    uuid(),
                    any::<(u32, u16, u16)>(),
                    vec(any::<u8>(), 0..=240),
                )
                    .prop_map(
                        |(
                            t,
                            ar_uuid,
                            session_key,
                            mac,
                            initiator_object,
                            (properties, f, port),
                            station_name,
                        )| {
                            Block::ArReq(ArBlockReq {
                                ar_type: ArType(t),
                                ar_uuid,
                                session_key,
                                initiator_mac: MacAddr(mac),
                                initiator_object,
                                properties,
                                activity_timeout_factor: f,
                                udp_rt_port: port,
                                station_name,
                            })
                        }
                    ),
                (
                    any::<u16>(),
                    uuid(),
                    any::<u16>(),
                    any::<[u8; 6]>(),
                    any::<u16>()
                )
                    .prop_map(|(t, ar_uuid, session_key, mac, udp_rt_port)| {
                        Block::ArRes(ArBlockRes {
                            ar_type: ArType(t),
                            ar_uuid,
                            session_key,
                            responder_mac: MacAddr(mac),
                            udp_rt_port,
                        })
                    }),
                any::<(u16, u16, u16)>().prop_map(|(t, reference, frame_id)| {
                    Block::IocrRes(IocrBlockRes {
                        iocr_type: IocrType(t),
                        reference,
                        frame_id,
                    })
                }),
                (
                    any::<(u16, u16, u32, u16, u16)>(),
                    any::<(u16, u16, u16, u16)>()
                )
                    .prop_map(
                        |((t, lt, properties, rta_timeout_factor, rta_retries), (l, m, h, lo))| {
                            Block::AlarmCrReq(AlarmCrBlockReq {
                                alarm_cr_type: AlarmCrType(t),
                                lt,
                                properties,
                                rta_timeout_factor,
                                rta_retries,
                                local_alarm_reference: l,
                                max_alarm_data_length: m,
                                tag_header_high: h,
                                tag_header_low: lo,
                            })
                        }
                    ),
                any::<(u16, u16, u16)>().prop_map(|(t, l, m)| {
                    Block::AlarmCrRes(AlarmCrBlockRes {
                        alarm_cr_type: AlarmCrType(t),
                        local_alarm_reference: l,
                        max_alarm_data_length: m,
                    })
                }),
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
