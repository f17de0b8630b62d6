//! Identity, SyncManager and FMMU layout, mailbox and SII facts of the SK 550P's EtherCAT
//! interface (BU 0620 §2.2, §3.6, §4.2.1; assumptions as stated in the module above).

/// Vendor ID of Getriebebau NORD GmbH & Co. KG (BU 0620 §2.2.7.1, object 1018h:01; §3.6.1).
pub const VENDOR_ID: u32 = 0x0000_0538;
/// Product code (1018h:02). The manual gives no value; 0550h ("SK 550P") is an assumption.
pub const PRODUCT_CODE: u32 = 0x0000_0550;
/// Revision number (1018h:03, "software version and revision number (2 × 16 bit)"): the
/// interface software V 1.1 R1 that the March 2020 edition describes (§1.1.2 document
/// history), coded as the POWERLINK modules' (BU 2200 §1.1.2, [`crate::nord::epl::revision`]).
pub const REVISION: u32 = 0x0001_0101;
/// Serial number (1018h:04): "Not supported" (§2.2.7.1), so 0.
pub const SERIAL_NUMBER: u32 = 0;
/// Device type (1000h). NORD's control and status words follow no CiA device profile, so
/// "no standard device profile" (CiA 301 §7.5.2.1: 0). An assumption: the manual gives none.
pub const DEVICE_TYPE: u32 = 0;
/// Device name (1008h) and the ESI/SII device name.
pub const DEVICE_NAME: &str = "NORDAC PRO SK 550P";
/// Hardware version (1009h). An assumption.
pub const HARDWARE_VERSION: &str = "1.0";
/// Software version (100Ah): V 1.1 R1, the version BU 0620 (March 2020) describes (§1.1.2).
pub const SOFTWARE_VERSION: &str = "V1.1 R1";
/// The device group of the ESI file and the SII general category.
pub const GROUP: &str = "NORD Frequency Inverter";
/// The order number ("type") of the ESI file.
pub const ORDER_NUMBER: &str = "SK 550P";
/// Vendor name of the ESI file.
pub const VENDOR_NAME: &str = "Getriebebau NORD GmbH & Co. KG";

/// Inverters the interface reaches: FI 1 plus up to 7 on the system bus (§2.2.7).
pub const MAX_INVERTERS: u8 = 8;
/// Process data words per inverter and direction (§2.2.6.1): control word + setpoints 1..5,
/// status word + actual values 1..5.
pub const WORDS_PER_INVERTER: u8 = 6;
/// Process data bytes per inverter and direction (§2.2.6.1: "12 bytes").
pub const BYTES_PER_INVERTER: u16 = 12;

/// "Second Address" for Hot Connect (§4.2.1 P850 under EtherCAT: 0…4096, factory 0, adopted at
/// POWER ON; §3.6.2). The parameter catalogue's P850 is EtherNet/IP's "IP address" (§4.2.2):
/// the SK 550P's P850 means one or the other with the protocol of P899.
pub const SECOND_ADDRESS_MAX: u16 = 4096;
/// The ESC register the master reads the Hot Connect ID from (§3.6.2: "ADO 0x134", the AL
/// status code register, ETG.1020 explicit device identification).
pub const HOT_CONNECT_ADO: u16 = 0x0134;

/// What a SyncManager is used for (ETG.1000.4 §6.7, ETG.2010 SII category SyncM "type").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum SmRole {
    /// Mailbox written by the master (receive mailbox of the slave).
    MailboxOut,
    /// Mailbox read by the master (send mailbox of the slave).
    MailboxIn,
    /// Process data outputs (written by the master, 3-buffer mode).
    Outputs,
    /// Process data inputs (read by the master, 3-buffer mode).
    Inputs,
}

impl SmRole {
    /// The communication type of object 1C00h and of the SII SyncM category: 1 mailbox out,
    /// 2 mailbox in, 3 outputs, 4 inputs (ETG.1000.6 §5.6.7.4.9, ETG.2010 table 7).
    pub fn com_type(self) -> u8 {
        match self {
            SmRole::MailboxOut => 1,
            SmRole::MailboxIn => 2,
            SmRole::Outputs => 3,
            SmRole::Inputs => 4,
        }
    }
}

/// One SyncManager's configuration as the master must write it (ESC registers 0800h + 8·n).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct SyncManager {
    /// SyncManager number 0..3.
    pub index: u8,
    /// Its use.
    pub role: SmRole,
    /// Physical start address in the ESC's process RAM.
    pub start: u16,
    /// Length in bytes (0 for process data without inverters).
    pub len: u16,
    /// Control byte (register 0804h + 8·n): bits 0–1 mode (10b mailbox, 00b 3-buffer), bits
    /// 2–3 direction (01b written by the master), bit 5 AL event, bit 6 watchdog trigger.
    pub control: u8,
    /// Enabled by default (ESI `Enable`).
    pub enable: bool,
}

/// Receive mailbox (SM0): start 1000h, 128 bytes, control 26h (mailbox, written by the master,
/// AL event). Address and size are assumptions (the manual gives none).
pub const SM_MAILBOX_OUT: SyncManager = SyncManager {
    index: 0,
    role: SmRole::MailboxOut,
    start: 0x1000,
    len: 128,
    control: 0x26,
    enable: true,
};
/// Send mailbox (SM1): start 1080h, 128 bytes, control 22h (mailbox, read by the master, AL
/// event).
pub const SM_MAILBOX_IN: SyncManager = SyncManager {
    index: 1,
    role: SmRole::MailboxIn,
    start: 0x1080,
    len: 128,
    control: 0x22,
    enable: true,
};
/// Start of the outputs (SM2); 3-buffer mode takes 3 × the length, at most 3 × 96 bytes.
pub const OUTPUTS_START: u16 = 0x1100;
/// Control byte of SM2: 3-buffer, written by the master, AL event, watchdog trigger (64h).
pub const OUTPUTS_CONTROL: u8 = 0x64;
/// Start of the inputs (SM3), after the outputs' three buffers.
pub const INPUTS_START: u16 = 0x1400;
/// Control byte of SM3: 3-buffer, read by the master, AL event (20h).
pub const INPUTS_CONTROL: u8 = 0x20;
/// The bootstrap mailbox (SII words 14h–17h): the same area as the standard mailbox.
pub const BOOTSTRAP_MAILBOX: (SyncManager, SyncManager) = (SM_MAILBOX_OUT, SM_MAILBOX_IN);

/// The four SyncManagers of a device with `inverters` inverters (1..=8, clamped).
pub fn sync_managers(inverters: u8) -> [SyncManager; 4] {
    let len = process_data_len(inverters);
    [
        SM_MAILBOX_OUT,
        SM_MAILBOX_IN,
        SyncManager {
            index: 2,
            role: SmRole::Outputs,
            start: OUTPUTS_START,
            len,
            control: OUTPUTS_CONTROL,
            enable: len > 0,
        },
        SyncManager {
            index: 3,
            role: SmRole::Inputs,
            start: INPUTS_START,
            len,
            control: INPUTS_CONTROL,
            enable: len > 0,
        },
    ]
}

/// Bytes of process data each way for `inverters` inverters (12 each, §2.2.6.1).
pub fn process_data_len(inverters: u8) -> u16 {
    u16::from(inverters.clamp(1, MAX_INVERTERS)) * BYTES_PER_INVERTER
}

/// What an FMMU is used for (ETG.2010 SII category FMMU: 1 outputs, 2 inputs, 3 SyncM status).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum FmmuUse {
    /// Maps the outputs (SM2).
    Outputs,
    /// Maps the inputs (SM3).
    Inputs,
    /// Maps the send mailbox's status (SM1 status bit "mailbox full") for logical polling.
    MailboxState,
}

impl FmmuUse {
    /// The SII code.
    pub fn code(self) -> u8 {
        match self {
            FmmuUse::Outputs => 1,
            FmmuUse::Inputs => 2,
            FmmuUse::MailboxState => 3,
        }
    }
}

/// The FMMUs the interface offers and their use (ESI `Fmmu`, SII FMMU category).
pub const FMMUS: [FmmuUse; 3] = [FmmuUse::Outputs, FmmuUse::Inputs, FmmuUse::MailboxState];

/// The mailbox protocols supported: CoE only (§2.2.7: "a single SDO channel"). SII word 1Ch
/// bit 2 (ETG.2010 table 2).
pub const MAILBOX_PROTOCOLS: u16 = 0x0004;

/// The CoE services offered (ESI `CoE` attributes, SII general category "CoE details").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct CoeDetails {
    /// SDO upload/download.
    pub sdo: bool,
    /// SDO information service.
    pub sdo_info: bool,
    /// PDO assignment writable (1C12h/1C13h).
    pub pdo_assign: bool,
    /// PDO mapping writable (1600h/1A00h).
    pub pdo_config: bool,
    /// Complete access to an object's sub-indices at once.
    pub complete_access: bool,
}

/// The SK 550P's CoE: SDO with complete access; the mapping and assignment are fixed
/// ("The structure of EtherCAT process data is fixed", §2.2.6; every PDO object is RO,
/// §2.2.7.1). No SDO information service (the manual names none).
pub const COE: CoeDetails = CoeDetails {
    sdo: true,
    sdo_info: false,
    pdo_assign: false,
    pdo_config: false,
    complete_access: true,
};

/// SII EEPROM size in bytes (2 KiB = 16 Kbit, as ESCs commonly carry). An assumption.
pub const EEPROM_BYTES: u32 = 2048;
/// PDI control (SII word 0, ESC register 0140h): 80h, an on-chip bus to the application
/// controller (the netX of P872 bit 4). An assumption.
pub const PDI_CONTROL: u16 = 0x0080;
/// PDI configuration (SII word 1, register 0150h). An assumption.
pub const PDI_CONFIG: u16 = 0x0000;
