//! The PROFINET IO device of the SK 550P (BU 0620 §2.5) and the SK TU3-PNT (BU 0590), sans-IO:
//! DCP, the context management over RPC, the cyclic RT data, the data records and the alarms
//! around one [`crate::device::Device`].

pub mod records;
