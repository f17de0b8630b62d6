//! The SK 550P's integrated EtherCAT interface as the manual defines it (BU 0620 §2.2, §3.6,
//! §4.2.1): identity, SyncManager and FMMU layout, process data objects and their mapping, the
//! CoE object dictionary of §2.2.7.1 and the NORD parameter objects of §2.2.7.
//!
//! Pure data, no wire format: the simulator's slave (`sim::ecat`), its SII EEPROM image and the
//! ESI XML writer are all built from this one definition, so they cannot disagree.
//!
//! What the manual does not give is an assumption, said so where it is made:
//! - product code [`PRODUCT_CODE`] and revision [`REVISION`] (§3.6.1 names the objects, not
//!   their values), device type [`DEVICE_TYPE`], the version strings;
//! - the SyncManager start addresses and mailbox sizes (the ESI file of §3.4 carries them, the
//!   manual does not);
//! - the objects the PDOs map: the control word, setpoints, status word and actual values of
//!   FI n are entries 1..6 of 7000h + 10h·(n−1) (outputs) and 6000h + 10h·(n−1) (inputs), the
//!   ETG.5001 modular-device convention; §2.2.7.1 lists the mapping objects only.
//!
//! Errata of the manual kept here (the code follows the standard):
//! - §2.2.3 figure 3 prints EtherType 0x88AB; EtherCAT is 0x88A4 (IEEE registry, ETG.1000.4).
//! - §2.2.6 says "up to 3 setpoints" and "up to 3 actual values"; §2.2.6.1 (the telegram table)
//!   and P873/P874 (§4.3) carry 5 each in 12 bytes per inverter, which this definition follows.
//! - §2.2.7.1 prints sub-index "0-4" for the mapping objects 1600h/1A00h, which hold 6 entries
//!   (control/status word + 5 values, 12 bytes); and sub-index "5" for 1C12h/1C13h, which hold
//!   one assigned PDO per inverter (sub-index 0 = the count, 1..8).
//! - §2.2.7.2 prints 06020002h for "write access to read-only object" and 06060047h for the
//!   internal incompatibility; CiA 301 defines 06010002h and 06040047h (see
//!   [`super::errors::ETHERCAT_ABORTS`]).

mod device;
mod od;
mod param;

pub use device::*;
pub use od::*;
pub use param::*;
