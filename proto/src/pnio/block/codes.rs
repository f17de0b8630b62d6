//! The open codes and bit fields of the PNIO-CM blocks (IEC 61158-6-10): ARType, IOCRType,
//! AlarmCRType, ModuleState, DataDescription, ControlCommand, the properties words and the
//! submodule state.

use crate::pnio::rpc::open_code;

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
